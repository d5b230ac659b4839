//! The viewer's scenes, one per seed system and one composite. Each draws into the frame's
//! colour and depth targets through fieldkit's public API; their settings are fieldkit's own
//! settings structs, gathered in [`Saved`] (the settings file), never copied.

use fieldkit::Error;
use fieldkit::distance::{Distance2d, Method2d, Options2d, Variant, upload_mask};
use fieldkit::gpu::{Readback, Recorder, readback_texture};
use fieldkit::metaball::{Animation, Instances, Metaballs, Settings, packed_grid};
use fieldkit::metaball::{CubeStyle, Cubes, Direct, RaymarchSettings, Raymarcher};
use fieldkit::ocean::{LodSettings, select};
use fieldkit::ocean::{Look, OceanRenderer, Output as OceanOutput};
use fieldkit::ocean::{Wave, Waves};
use fieldkit::view::Targets;
use fieldkit::volume::{MarchSettings, TransferFunction, Volume, VolumeRenderer, fbm_cloud};
use fieldkit::voxelize::{Attributes, Grid, Mesh, PendingAttributes, Separation, Voxelizer};
use fieldkit::voxelize::{ColourBy, VoxelView};
use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

use super::camera::Camera;
use super::draw::{Blit, Lines};

/// Colour target format of every scene.
pub const COLOUR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Depth target format of every scene.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Most instances the voxel actor's builder makes (Extent / BlockSize per axis, multiplied).
pub const MAX_ACTOR_INSTANCES: u64 = 1 << 18;

/// The scenes, in the order the viewer lists them.
pub const NAMES: [&str; 6] = [
    "actor",
    "ocean",
    "volume",
    "distance2d",
    "voxelizer",
    "composite",
];

/// Everything a settings file holds: each scene's settings and the camera of each.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Saved {
    /// Seed 000: the voxel actor.
    pub actor: ActorSettings,
    /// Seed 001: the ocean.
    pub ocean: OceanSettings,
    /// Seed 002: the volume.
    pub volume: VolumeSettings,
    /// Seed 003: 2D distance.
    pub distance: DistanceSettings,
    /// Seed 004: the voxelizer.
    pub voxelizer: VoxelizerSettings,
    /// One camera per scene, in [`NAMES`] order.
    pub cameras: Vec<Camera>,
}

impl Default for Saved {
    fn default() -> Self {
        Self {
            actor: ActorSettings::default(),
            ocean: OceanSettings::default(),
            volume: VolumeSettings::default(),
            distance: DistanceSettings::default(),
            voxelizer: VoxelizerSettings::default(),
            cameras: NAMES.iter().map(|n| default_camera(n)).collect(),
        }
    }
}

impl Saved {
    /// Every scene's seed preset where it has one (the sources' settings), default cameras.
    pub fn seed() -> Self {
        Self {
            actor: ActorSettings::seed(),
            ocean: OceanSettings::seed(),
            volume: VolumeSettings::seed(),
            distance: DistanceSettings {
                options: Options2d {
                    seeds: fieldkit::distance::SeedRule::seed(),
                    ..Options2d::default()
                },
                ..DistanceSettings::default()
            },
            voxelizer: VoxelizerSettings {
                point_light: true,
                ..VoxelizerSettings::default()
            },
            ..Self::default()
        }
    }
}

/// Where each scene's camera starts.
pub fn default_camera(scene: &str) -> Camera {
    match scene {
        "actor" => Camera::orbit(Vec3::ZERO, 0.55, 0.4, 11.0, 200.0),
        "ocean" => Camera::orbit(Vec3::new(0.0, 0.0, 0.0), 0.3, 0.25, 40.0, 3000.0),
        "volume" => Camera::orbit(Vec3::ZERO, 0.6, 0.3, 1.8, 50.0),
        "voxelizer" => Camera::orbit(Vec3::ZERO, 0.5, 0.35, 2.6, 100.0),
        "composite" => Camera::orbit(Vec3::new(0.0, -1.0, 0.0), -0.165, 0.29, 31.5, 3000.0),
        _ => Camera::orbit(Vec3::ZERO, 0.0, 0.0, 1.0, 10.0),
    }
}

/// One frame: where to record and draw, and when.
pub struct Frame<'a, 'r> {
    /// Compute passes go through the recorder (timed when it profiles); render passes into
    /// `rec.encoder`.
    pub rec: &'a mut Recorder<'r>,
    /// The frame's colour and depth targets.
    pub targets: &'a Targets,
    /// Their size.
    pub size: [u32; 2],
    /// The camera.
    pub camera: Camera,
    /// Seconds since the scene started.
    pub time: f32,
    /// Frames drawn before this one.
    pub number: u32,
}

fn clear(frame: &mut Frame, colour: [f64; 3]) {
    let [r, g, b] = colour;
    frame.targets.clear(
        frame.rec.encoder,
        wgpu::Color { r, g, b, a: 1.0 },
        frame.camera.clear_depth(),
    );
}

fn invalid(what: impl Into<String>) -> Error {
    Error::Invalid {
        stage: "viewer",
        what: what.into(),
    }
}

// ---------------------------------------------------------------------------------------------
// Seed 000: the voxel actor.

/// What the actor draws.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ActorDraw {
    /// The raymarched SDF surface (or its debug view, `RaymarchSettings::output`).
    Surface,
    /// The debug cubes alone.
    Cubes,
    /// Surface and cubes.
    Both,
    /// The field traced directly, no SDF.
    Direct(Direct),
}

/// The voxel actor's settings: the source's grid builder (Extent, BlockSize), the field, the
/// march, the cubes and the animation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ActorSettings {
    /// The region the blocks fill, world units per axis.
    pub extent: [f32; 3],
    /// Block size: the voxel edge and the spacing.
    pub block: f32,
    /// How the voxels become a field.
    pub field: Settings,
    /// How the surface is marched and shaded.
    pub raymarch: RaymarchSettings,
    /// Debug cube style.
    pub cubes: CubeStyle,
    /// What is drawn.
    pub draw: ActorDraw,
    /// Animate (scale pulse and Lissajous offsets).
    pub animate: bool,
    /// The animation's frequencies, amplitudes, ratios and phase step.
    pub animation: Animation,
}

impl Default for ActorSettings {
    fn default() -> Self {
        Self {
            extent: [5.0, 4.0, 3.0],
            block: 1.0,
            field: Settings::default(),
            raymarch: RaymarchSettings::default(),
            cubes: CubeStyle::default(),
            draw: ActorDraw::Surface,
            animate: true,
            animation: Animation::default(),
        }
    }
}

impl ActorSettings {
    /// The source's voxel actor: every `seed()` preset (field, march, cubes, animation), the
    /// same extent and block.
    pub fn seed() -> Self {
        Self {
            field: Settings::seed(),
            raymarch: RaymarchSettings::seed(),
            cubes: CubeStyle::seed(),
            animation: Animation::seed(),
            ..Self::default()
        }
    }

    /// Blocks per axis as the source's builder counts them: max(1, ⌊Extent / BlockSize⌋).
    pub fn counts(&self) -> Result<[u32; 3], Error> {
        if !(self.block.is_finite() && self.block > 0.0) {
            return Err(invalid(format!(
                "BlockSize must be finite and > 0, got {}",
                self.block
            )));
        }
        if !self.extent.iter().all(|e| e.is_finite() && *e >= 0.0) {
            return Err(invalid(format!(
                "Extent must be finite and ≥ 0, got {:?}",
                self.extent
            )));
        }
        let n = self
            .extent
            .map(|e| ((e / self.block).floor() as f64).clamp(1.0, u32::MAX as f64));
        let total = n.iter().product::<f64>();
        if total > MAX_ACTOR_INSTANCES as f64 {
            return Err(Error::Size {
                stage: "viewer: voxel actor",
                what: "instances (Extent / BlockSize per axis, multiplied)",
                got: total.min(u64::MAX as f64) as u64,
                max: MAX_ACTOR_INSTANCES,
            });
        }
        Ok(n.map(|v| v as u32))
    }
}

/// The voxel actor's GPU state.
pub struct Actor {
    balls: Metaballs,
    instances: Option<(Instances, usize)>,
    base: Option<([u32; 3], f32, Vec<glam::Vec4>)>,
    marcher: Option<(bool, Raymarcher)>,
    cubes: Option<(CubeStyle, Cubes)>,
}

impl Actor {
    fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            balls: Metaballs::new(device)?,
            instances: None,
            base: None,
            marcher: None,
            cubes: None,
        })
    }

    fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &ActorSettings,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        clear(frame, [0.09, 0.1, 0.12]);
        let counts = s.counts()?;
        if self.base.as_ref().map(|b| (b.0, b.1)) != Some((counts, s.block)) {
            self.base = Some((counts, s.block, packed_grid(counts, s.block)?));
        }
        let base = &self.base.as_ref().expect("set above").2;
        let voxels = if s.animate {
            s.animation.apply(base, s.block, frame.time)?
        } else {
            base.clone()
        };
        self.prepare(device, queue, &voxels, frame.camera.reversed_z)?;
        let reversed = frame.camera.reversed_z;
        let instances = &self.instances.as_ref().expect("prepared").0;
        let view = frame.camera.view(frame.size);
        let (cv, dv) = (&frame.targets.colour_view, &frame.targets.depth_view);
        let mut stats = vec![format!(
            "instances: {} ({}×{}×{})",
            voxels.len(),
            counts[0],
            counts[1],
            counts[2]
        )];
        if matches!(s.draw, ActorDraw::Cubes | ActorDraw::Both) {
            let mut style = s.cubes;
            if reversed {
                style.depth_compare = flip(style.depth_compare);
            }
            if self.cubes.as_ref().map(|c| c.0) != Some(style) {
                self.cubes = Some((style, Cubes::new(device, COLOUR, DEPTH, style)?));
            }
            let cubes = &self.cubes.as_ref().expect("set above").1;
            cubes.encode(
                device,
                frame.rec.encoder,
                cv,
                dv,
                instances,
                s.block,
                Mat4::IDENTITY,
                view.view_proj,
            )?;
        }
        let Some(grid) = s.field.fit_grid(&voxels, s.block)? else {
            return Ok(stats);
        };
        stats.push(format!(
            "grid: {}×{}×{}",
            grid.size[0], grid.size[1], grid.size[2]
        ));
        match s.draw {
            ActorDraw::Surface | ActorDraw::Both => self.surface(device, s, &grid, frame)?,
            ActorDraw::Direct(method) => {
                let bins = self
                    .balls
                    .encode_bins(device, frame.rec, instances, &grid, s.block, &s.field)?;
                let marcher = &self.marcher.as_ref().expect("prepared").1;
                if let Some(m) = marcher.encode_direct_march(
                    device,
                    frame.rec,
                    &bins,
                    method,
                    Mat4::IDENTITY,
                    &view,
                    &s.raymarch,
                )? {
                    marcher.encode_composite(device, frame.rec.encoder, cv, dv, &m)?;
                }
            }
            ActorDraw::Cubes => {}
        }
        Ok(stats)
    }
}

/// The same test for a reversed depth range.
fn flip(c: wgpu::CompareFunction) -> wgpu::CompareFunction {
    use wgpu::CompareFunction as C;
    match c {
        C::Less => C::Greater,
        C::LessEqual => C::GreaterEqual,
        C::Greater => C::Less,
        C::GreaterEqual => C::LessEqual,
        other => other,
    }
}

// ---------------------------------------------------------------------------------------------
// Seed 001: the ocean.

/// The ocean's settings: the waves table, steepness, look (detail layers, depth fade), LOD and
/// which target is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OceanSettings {
    /// The waves table.
    pub waves: Vec<Wave>,
    /// Steepness Q, shared as Qᵢ = Q / (wᵢ·Aᵢ·N).
    pub steepness: f32,
    /// Colours, light, detail layers, depth fade.
    pub look: Look,
    /// The patch quadtree's square and error target.
    pub lod: LodSettings,
    /// Fade the water's colour with the depth of the scene under it.
    pub fade: bool,
    /// Draw into the four G-buffer targets and show one of them (0–3) instead of forward.
    pub gbuffer: Option<usize>,
    /// Draw the patch quadtree over the water.
    pub overlay: bool,
    /// Depth target: written (default) or read only (the source's).
    #[serde(default)]
    pub depth_write: Option<bool>,
}

impl Default for OceanSettings {
    fn default() -> Self {
        let wave = |d: [f32; 2], a, l, s| Wave {
            direction: Vec2::from_array(d),
            amplitude: a,
            wavelength: l,
            speed: s,
        };
        Self {
            waves: vec![
                wave([1.0, 0.3], 0.35, 21.0, 5.7),
                wave([0.2, 1.0], 0.18, 9.5, 3.8),
                wave([-0.8, 0.5], 0.06, 4.1, 2.5),
            ],
            steepness: 0.7,
            look: Look {
                fade_distance: 3.0,
                sun_direction: Vec3::new(-0.4, 0.5, -0.75),
                ..Look::default()
            },
            lod: LodSettings::default(),
            fade: true,
            gbuffer: None,
            overlay: false,
            depth_write: None,
        }
    }
}

impl OceanSettings {
    /// The source's sea: `Look::seed` (30 cm fade, no skirts) and depth read only, the same
    /// waves and sun.
    pub fn seed() -> Self {
        let d = Self::default();
        Self {
            look: Look {
                sun_direction: d.look.sun_direction,
                ..Look::seed()
            },
            depth_write: Some(false),
            ..d
        }
    }
}

/// The ocean's GPU state.
pub struct Ocean {
    renderer: Option<((bool, bool, bool), OceanRenderer)>,
    gbuffer: Option<([u32; 2], Vec<Targets>)>,
    lines: Lines,
}

impl Ocean {
    fn new(device: &wgpu::Device) -> Self {
        Self {
            renderer: None,
            gbuffer: None,
            lines: Lines::new(device, COLOUR),
        }
    }

    /// Draw the sea into the frame (over what it holds).
    fn draw(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &OceanSettings,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        let waves = Waves::new(s.waves.clone(), s.steepness)?;
        let camera = frame.camera.ocean(frame.size);
        let selection = select(&waves, &s.look, &camera, frame.size[1], &s.lod)?;
        let write = s.depth_write.unwrap_or(true);
        let key = (s.gbuffer.is_some(), frame.camera.reversed_z, write);
        if self.renderer.as_ref().map(|r| r.0) != Some(key) {
            let output = if key.0 {
                OceanOutput::GBuffer([COLOUR; 4])
            } else {
                OceanOutput::Forward(COLOUR)
            };
            let depth = fieldkit::ocean::DepthMode {
                write,
                ..Default::default()
            };
            self.renderer = Some((
                key,
                OceanRenderer::with_depth(device, queue, output, key.1, depth)?,
            ));
        }
        let renderer = &self.renderer.as_ref().expect("set above").1;
        let time = frame.time as f64;
        match s.gbuffer {
            None => renderer.encode(
                device,
                frame.rec.encoder,
                &waves,
                time,
                &camera,
                &s.look,
                &selection.patches,
                &[&frame.targets.colour_view],
                &frame.targets.depth,
                s.fade,
            )?,
            Some(shown) => {
                if shown > 3 {
                    return Err(invalid(format!("G-buffer target {shown} (0–3)")));
                }
                if self.gbuffer.as_ref().map(|g| g.0) != Some(frame.size) {
                    let g = (0..4)
                        .map(|_| Targets::new(device, frame.size, COLOUR, DEPTH))
                        .collect();
                    self.gbuffer = Some((frame.size, g));
                }
                let g = &self.gbuffer.as_ref().expect("set above").1;
                for t in g {
                    t.clear(frame.rec.encoder, wgpu::Color::BLACK, 1.0);
                }
                let views: Vec<&wgpu::TextureView> = g.iter().map(|t| &t.colour_view).collect();
                renderer.encode(
                    device,
                    frame.rec.encoder,
                    &waves,
                    time,
                    &camera,
                    &s.look,
                    &selection.patches,
                    &views,
                    &frame.targets.depth,
                    s.fade,
                )?;
                frame.rec.encoder.copy_texture_to_texture(
                    g[shown].colour.as_image_copy(),
                    frame.targets.colour.as_image_copy(),
                    frame.targets.colour.size(),
                );
            }
        }
        if s.overlay {
            let segments: Vec<[Vec3; 2]> = selection
                .patches
                .iter()
                .flat_map(|p| {
                    let (x0, z0) = (p.corner.x as f32, p.corner.y as f32);
                    let e = p.size as f32;
                    let c = [
                        Vec3::new(x0, 0.0, z0),
                        Vec3::new(x0 + e, 0.0, z0),
                        Vec3::new(x0 + e, 0.0, z0 + e),
                        Vec3::new(x0, 0.0, z0 + e),
                    ];
                    [[c[0], c[1]], [c[1], c[2]], [c[2], c[3]], [c[3], c[0]]]
                })
                .collect();
            let view = frame.camera.view(frame.size);
            self.lines.encode(
                device,
                queue,
                frame.rec.encoder,
                &frame.targets.colour_view,
                view.view_proj,
                &segments,
                Vec4::new(1.0, 0.85, 0.2, 1.0),
            );
        }
        Ok(vec![
            format!(
                "patches: {} ({} culled), triangles: {}",
                selection.patches.len(),
                selection.culled,
                selection.triangles
            ),
            format!("largest height error: {:.2} px", selection.max_error_px),
        ])
    }
}

// ---------------------------------------------------------------------------------------------
// Seed 002: the volume.

/// The volume's settings: the cloud, its transfer function and how it is marched.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VolumeSettings {
    /// Voxels per side of the fBm cloud.
    pub size: u32,
    /// The cloud's noise seed.
    pub seed: u32,
    /// Density → colour and opacity.
    pub tf: TransferFunction,
    /// Step, shadows, mode, skipping.
    pub march: MarchSettings,
    /// March the cloud as a function evaluated at every sample, as the source does
    /// (`CloudMarch`: seed 0, `size` cells per side for its bricks; a light volume becomes
    /// shadow rays), instead of the baked texture.
    pub function: bool,
}

impl VolumeSettings {
    /// The source's cloud: the fBm function evaluated per sample, shadowed by rays through it.
    pub fn seed() -> Self {
        let d = Self::default();
        Self {
            function: true,
            march: MarchSettings {
                shadow: fieldkit::volume::Shadow::Rays { step: 1.0 / 32.0 },
                ..d.march
            },
            ..d
        }
    }
}

impl Default for VolumeSettings {
    fn default() -> Self {
        Self {
            function: false,
            size: 96,
            seed: 7,
            tf: TransferFunction::cloud(),
            march: MarchSettings {
                step: 1.0 / 96.0,
                ..MarchSettings::default()
            },
        }
    }
}

/// The volume's GPU state.
pub struct VolumeScene {
    renderer: VolumeRenderer,
    volume: Option<((u32, u32), Volume, fieldkit::volume::Bricks)>,
    /// The cloud as a function, made on first use, and its bricks for a lattice size.
    cloud: Option<fieldkit::volume::CloudMarch>,
    cloud_bricks: Option<(u32, fieldkit::volume::Bricks)>,
}

impl VolumeScene {
    fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            renderer: VolumeRenderer::new(device, COLOUR)?,
            volume: None,
            cloud: None,
            cloud_bricks: None,
        })
    }

    /// March the cloud *function* (`VolumeSettings::function`) into the frame.
    fn draw_function(
        &mut self,
        device: &wgpu::Device,
        s: &VolumeSettings,
        local_to_world: Mat4,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        use fieldkit::volume::{CloudMarch, FunctionVolume, Shadow};
        if self.cloud.is_none() {
            self.cloud = Some(CloudMarch::cloud(device)?);
        }
        let cloud = self.cloud.as_ref().expect("set above");
        let lattice = FunctionVolume::unit(s.size.clamp(4, 512));
        if self.cloud_bricks.as_ref().map(|b| b.0) != Some(lattice.dims[0]) {
            let bricks = cloud.encode_bricks(device, frame.rec, &lattice)?;
            self.cloud_bricks = Some((lattice.dims[0], bricks));
        }
        let (_, bricks) = self.cloud_bricks.as_ref().expect("set above");
        let mut march = s.march;
        march.frame = frame.number;
        if let Shadow::LightVolume { step } = march.shadow {
            march.shadow = Shadow::Rays { step };
        }
        let view = frame.camera.view(frame.size);
        // The function's box is its unit cube of texture coordinates, centred as the texture.
        let placed = local_to_world * Mat4::from_translation(Vec3::splat(-0.5));
        if let Some(m) = cloud.encode_march(
            device,
            frame.rec,
            &lattice,
            bricks,
            &s.tf,
            placed,
            &view,
            Some(&frame.targets.depth_view),
            &march,
        )? {
            self.renderer.encode_composite(
                device,
                frame.rec.encoder,
                &frame.targets.colour_view,
                &m,
            )?;
        }
        Ok(vec![format!(
            "volume: the fBm function per sample (seed 0), bricks over {0}³ cells, {1:?}",
            lattice.dims[0], march.shadow
        )])
    }

    /// March the cloud under `local_to_world` into the frame, stopping at its depth.
    fn draw(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &VolumeSettings,
        local_to_world: Mat4,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        if s.function {
            return self.draw_function(device, s, local_to_world, frame);
        }
        if self.volume.as_ref().map(|v| v.0) != Some((s.size, s.seed)) {
            if !(4..=512).contains(&s.size) {
                return Err(Error::Size {
                    stage: "viewer: volume",
                    what: "cloud voxels per side (4 to 512)",
                    got: s.size as u64,
                    max: 512,
                });
            }
            let dims = [s.size; 3];
            let volume = Volume::upload(
                device,
                queue,
                &fbm_cloud(dims, s.seed),
                dims,
                wgpu::TextureFormat::R8Unorm,
                Vec3::splat(1.0 / s.size as f32),
                Vec3::splat(-0.5),
            )?;
            let bricks = self.renderer.encode_bricks(device, frame.rec, &volume)?;
            self.volume = Some(((s.size, s.seed), volume, bricks));
        }
        let (_, volume, bricks) = self.volume.as_ref().expect("set above");
        let mut march = s.march;
        march.frame = frame.number;
        let light = match march.shadow {
            fieldkit::volume::Shadow::LightVolume { .. } => Some(self.renderer.encode_light(
                device,
                frame.rec,
                volume,
                bricks,
                &s.tf,
                local_to_world,
                &march,
            )?),
            _ => None,
        };
        let view = frame.camera.view(frame.size);
        if let Some(m) = self.renderer.encode_march(
            device,
            frame.rec,
            volume,
            bricks,
            light.as_ref(),
            &s.tf,
            local_to_world,
            &view,
            Some(&frame.targets.depth_view),
            &march,
        )? {
            self.renderer.encode_composite(
                device,
                frame.rec.encoder,
                &frame.targets.colour_view,
                &m,
            )?;
        }
        Ok(vec![format!(
            "volume: {0}³, bricks {1}×{1}×{1}",
            s.size, bricks.count[0]
        )])
    }
}

// ---------------------------------------------------------------------------------------------
// Seed 003: 2D distance.

/// The 2D distance tool's settings: the seed texels, the method, and how the field is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DistanceSettings {
    /// Mask width and height, texels.
    pub size: [u32; 2],
    /// Exact (default) or a JFA variant; signed or not; texel size.
    pub options: Options2d,
    /// The seed texels.
    pub seeds: Vec<[u32; 2]>,
    /// Texels between iso-lines.
    pub iso_period: f32,
    /// Brush radius, texels.
    pub brush: u32,
}

impl Default for DistanceSettings {
    fn default() -> Self {
        // A sparse scatter (where JFA goes wrong) and a short wall.
        let mut seeds = Vec::new();
        let mut x = 12345u32;
        for _ in 0..24 {
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            let a = (x >> 8) % 200;
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            let b = (x >> 8) % 120;
            seeds.push([a, b]);
        }
        seeds.extend((60..140).map(|i| [i, 60]));
        Self {
            size: [200, 120],
            options: Options2d::default(),
            seeds,
            iso_period: 8.0,
            brush: 1,
        }
    }
}

impl DistanceSettings {
    /// The mask: 255 at every seed texel inside the size.
    pub fn mask(&self) -> Result<Vec<u8>, Error> {
        let [w, h] = self.size;
        if w == 0 || h == 0 || w as u64 * h as u64 > 4096 * 4096 {
            return Err(Error::Size {
                stage: "viewer: distance 2D",
                what: "mask texels (width × height, each side ≥ 1)",
                got: w as u64 * h as u64,
                max: 4096 * 4096,
            });
        }
        let mut mask = vec![0u8; (w * h) as usize];
        for &[x, y] in &self.seeds {
            if x < w && y < h {
                mask[(y * w + x) as usize] = 255;
            }
        }
        Ok(mask)
    }

    /// Add (or, `erase`, remove) seeds in a disc of the brush radius around texel `at`.
    pub fn paint(&mut self, at: [u32; 2], erase: bool) {
        let r = self.brush as i64;
        let inside = |p: [u32; 2]| {
            let (dx, dy) = (p[0] as i64 - at[0] as i64, p[1] as i64 - at[1] as i64);
            dx * dx + dy * dy <= r * r
        };
        if erase {
            self.seeds.retain(|&p| !inside(p));
            return;
        }
        for y in (at[1] as i64 - r)..=(at[1] as i64 + r) {
            for x in (at[0] as i64 - r)..=(at[0] as i64 + r) {
                if x < 0 || y < 0 || x >= self.size[0] as i64 || y >= self.size[1] as i64 {
                    continue;
                }
                let p = [x as u32, y as u32];
                if inside(p) && !self.seeds.contains(&p) {
                    self.seeds.push(p);
                }
            }
        }
    }
}

struct Pending2d {
    key: DistanceSettings,
    field: Readback<Vec<f32>>,
    exact: Readback<Vec<f32>>,
}

/// Fields recorded into a frame not yet submitted: read back once it is.
struct Recorded2d {
    key: DistanceSettings,
    field: wgpu::Texture,
    exact: wgpu::Texture,
}

/// The 2D tool's state: the field is computed when the settings change, read back without
/// waiting, coloured on the CPU and shown until the next change.
pub struct Distance2dScene {
    distance: Distance2d,
    blit: Blit,
    recorded: Option<Recorded2d>,
    pending: Option<Pending2d>,
    shown: Option<(DistanceSettings, wgpu::Texture, usize, f32)>,
}

/// Where the field image sits in the frame: the largest rectangle of its aspect, centred
/// (fractions of the frame, y down).
pub fn field_rect(size: [u32; 2], field: [u32; 2]) -> [f32; 4] {
    let (fw, fh) = (size[0] as f32, size[1] as f32);
    let s = (fw / field[0] as f32).min(fh / field[1] as f32);
    let (w, h) = (field[0] as f32 * s / fw, field[1] as f32 * s / fh);
    [
        (1.0 - w) / 2.0,
        (1.0 - h) / 2.0,
        (1.0 + w) / 2.0,
        (1.0 + h) / 2.0,
    ]
}

impl Distance2dScene {
    fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            distance: Distance2d::new(device)?,
            blit: Blit::new(device, COLOUR),
            recorded: None,
            pending: None,
            shown: None,
        })
    }

    /// Work started and not yet shown.
    pub fn busy(&self, s: &DistanceSettings) -> bool {
        self.recorded.is_some()
            || self.pending.is_some()
            || self.shown.as_ref().map(|x| &x.0) != Some(s)
    }

    /// The frame that recorded the fields was submitted: start reading them.
    fn submitted(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        if let Some(r) = self.recorded.take() {
            self.pending = Some(Pending2d {
                key: r.key,
                field: readback_texture(device, queue, &r.field),
                exact: readback_texture(device, queue, &r.exact),
            });
        }
    }

    fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &DistanceSettings,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        clear(frame, [0.05, 0.05, 0.06]);
        // Take a finished readback.
        if let Some(p) = &mut self.pending
            && p.field.is_ready()
            && p.exact.is_ready()
        {
            let p = self.pending.take().expect("checked");
            let (mut field, mut exact) = (p.field, p.exact);
            let field = field.try_take().expect("ready")?;
            let exact = exact.try_take().expect("ready")?;
            let wrong = field
                .iter()
                .zip(&exact)
                .filter(|(a, b)| (*a - *b).abs() > 1e-3 * b.abs().max(1.0))
                .count();
            let worst = field
                .iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            let [w, h] = p.key.size;
            let pixels = colour_field(&field, &p.key);
            let texture = upload_rgba(device, queue, &pixels, w, h);
            self.shown = Some((p.key, texture, wrong, worst));
        }
        // Start a new computation when the settings changed and none is running.
        if self.pending.is_none()
            && self.recorded.is_none()
            && self.shown.as_ref().map(|x| &x.0) != Some(s)
        {
            let [w, h] = s.size;
            let mask = upload_mask(device, queue, &s.mask()?, w, h)?;
            let field = self.distance.encode(device, frame.rec, &mask, &s.options)?;
            let exact_options = Options2d {
                method: Method2d::Exact,
                ..s.options
            };
            let exact = self
                .distance
                .encode(device, frame.rec, &mask, &exact_options)?;
            self.recorded = Some(Recorded2d {
                key: s.clone(),
                field: field.distance,
                exact: exact.distance,
            });
        }
        let mut stats = vec![format!("seeds: {}", s.seeds.len())];
        if let Some((key, texture, wrong, worst)) = &self.shown {
            let view = texture.create_view(&Default::default());
            let rect = field_rect(frame.size, key.size);
            self.blit.encode(
                device,
                queue,
                frame.rec.encoder,
                &frame.targets.colour_view,
                frame.size,
                &view,
                rect,
            );
            stats.push(format!(
                "{}: {wrong} wrong texels against the exact transform (worst {worst:.2} texels)",
                method_name(key.options.method)
            ));
        }
        Ok(stats)
    }
}

/// A method's name for the panel.
pub fn method_name(m: Method2d) -> String {
    match m {
        Method2d::Exact => "exact".into(),
        Method2d::Jfa(v) => v.name().into(),
    }
}

/// The JFA variants and exact, for the panel.
pub fn methods_2d() -> Vec<Method2d> {
    let mut v = vec![Method2d::Exact];
    v.extend(
        [
            Variant::Jfa,
            Variant::JfaPlus1,
            Variant::JfaPlus2,
            Variant::OnePlusJfa,
            Variant::OnePlusJfaPlus2,
        ]
        .map(Method2d::Jfa),
    );
    v
}

/// Distance as colour: blue inside (signed), orange outside, dark iso-lines every
/// `iso_period` texels, white seeds.
fn colour_field(d: &[f32], s: &DistanceSettings) -> Vec<u8> {
    let texel = s.options.texel_size.max(f32::MIN_POSITIVE);
    d.iter()
        .flat_map(|&v| {
            let t = v / texel;
            if t == 0.0 {
                return [255, 255, 255, 255];
            }
            let k = (t.abs() / 64.0).min(1.0);
            let base = if t < 0.0 {
                [40.0 + 60.0 * k, 90.0 + 80.0 * k, 200.0]
            } else {
                [230.0 - 90.0 * k, 140.0 - 60.0 * k, 60.0]
            };
            let phase = (t.abs() / s.iso_period.max(0.5)).fract();
            let line = if !(0.08..=0.92).contains(&phase) {
                0.45
            } else {
                1.0
            };
            [
                (base[0] * line) as u8,
                (base[1] * line) as u8,
                (base[2] * line) as u8,
                255,
            ]
        })
        .collect()
}

fn upload_rgba(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    pixels: &[u8],
    w: u32,
    h: u32,
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("viewer field image"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOUR,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        pixels,
    )
}

// ---------------------------------------------------------------------------------------------
// Seed 004: the voxelizer.

/// How the voxelizer scene voxelizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum VoxelMode {
    /// Conservative or 6-separating surface (compute).
    Surface(Separation),
    /// Conservative surface through the hardware rasterizer.
    Raster,
    /// Solid: inside by parity, ORed with the surface.
    Solid,
}

/// The voxelizer's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoxelizerSettings {
    /// An OBJ path, or `torus` / `sphere` for a built-in mesh.
    pub mesh: String,
    /// Voxels along the mesh's longest side.
    pub grid: u32,
    /// Which voxelization.
    pub mode: VoxelMode,
    /// Cube colours of the conservative surface (the other modes draw plain cubes).
    pub colour_by: ColourBy,
    /// Show the mesh's distance field (exact, from the surface voxels) through the middle z
    /// slice, in the frame's lower-right corner.
    pub slice: bool,
    /// Radians the mesh turns about the y axis through its bounds' centre before voxelizing
    /// (the soak turns it every frame, so the mesh is voxelized again and again).
    pub spin: f32,
    /// Light the cubes with a point light above the front of the grid, as the source's demo
    /// scene (off: a directional light).
    #[serde(default)]
    pub point_light: bool,
}

/// The Stanford bunny of the benches, when this checkout sits beside `shared/`.
pub const BUNNY: &str = "../shared/meshes/stanford-bunny.obj";

impl Default for VoxelizerSettings {
    fn default() -> Self {
        Self {
            mesh: if std::path::Path::new(BUNNY).exists() {
                BUNNY.into()
            } else {
                "torus".into()
            },
            grid: 64,
            mode: VoxelMode::Surface(Separation::Conservative),
            colour_by: ColourBy::Normal,
            slice: true,
            spin: 0.0,
            point_light: false,
        }
    }
}

/// `mesh` turned `angle` radians about the y axis through its bounds' centre.
fn spun(mesh: &Mesh, angle: f32) -> Result<Mesh, Error> {
    if !angle.is_finite() {
        return Err(invalid(format!("voxelizer spin {angle} is not finite")));
    }
    let mut mesh = mesh.clone();
    if angle != 0.0 {
        let (lo, hi) = mesh.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let centre = (lo + hi) * 0.5;
        let turn = glam::DQuat::from_rotation_y(angle as f64);
        for p in &mut mesh.positions {
            *p = centre + turn * (*p - centre);
        }
    }
    Ok(mesh)
}

enum VoxelJob {
    /// Recorded into a frame not yet submitted.
    RecordedAttributes(PendingAttributes),
    RecordedSurface(fieldkit::voxelize::Surface),
    /// Reading back.
    Attributes(PendingAttributes, Readback<u32>),
    Bits(Readback<Vec<bool>>),
}

/// The voxelizer's state: voxelizing runs when the settings change; its result is drawn every
/// frame until the next change.
pub struct VoxelizerScene {
    voxelizer: Voxelizer,
    distance: fieldkit::distance::Distance3d,
    blit: Blit,
    /// The distance field recorded with the job (read back once submitted), then its slice.
    field: Option<wgpu::Texture>,
    field_read: Option<Readback<Vec<f32>>>,
    slice: Option<(wgpu::Texture, [u32; 2], f32)>,
    view: Option<(bool, VoxelView)>,
    cubes: Option<(bool, Cubes)>,
    balls: Metaballs,
    mesh: Option<(String, Mesh)>,
    job: Option<(VoxelizerSettings, Grid, VoxelJob)>,
    shown: Option<(VoxelizerSettings, Grid, Shown)>,
    /// Voxelizations that reached the screen.
    voxelized: u64,
}

enum Shown {
    Attributes(Attributes),
    Cubes(Instances, usize),
}

impl VoxelizerScene {
    fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            voxelizer: Voxelizer::new(device)?,
            distance: fieldkit::distance::Distance3d::new(device)?,
            blit: Blit::new(device, COLOUR),
            field: None,
            field_read: None,
            slice: None,
            view: None,
            cubes: None,
            balls: Metaballs::new(device)?,
            mesh: None,
            job: None,
            shown: None,
            voxelized: 0,
        })
    }

    /// Work started and not yet shown.
    pub fn busy(&self, s: &VoxelizerSettings) -> bool {
        self.job.is_some()
            || self.field.is_some()
            || self.field_read.is_some()
            || self.shown.as_ref().map(|x| &x.0) != Some(s)
    }

    /// The frame that recorded the job was submitted: start reading its result.
    fn submitted(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        if let Some(f) = self.field.take() {
            self.field_read = Some(readback_texture(device, queue, &f));
        }
        self.job = self.job.take().map(|(key, grid, job)| {
            let job = match job {
                VoxelJob::RecordedAttributes(p) => {
                    let count = p.occupied(device, queue);
                    VoxelJob::Attributes(p, count)
                }
                VoxelJob::RecordedSurface(s) => VoxelJob::Bits(s.read(device, queue)),
                other => other,
            };
            (key, grid, job)
        });
    }

    fn mesh(&mut self, name: &str) -> Result<&Mesh, Error> {
        if self.mesh.as_ref().map(|m| m.0.as_str()) != Some(name) {
            let mesh = match name {
                "torus" => Mesh::torus(DVec3::ZERO, 1.0, 0.4, 48, 24),
                "sphere" => Mesh::uv_sphere(DVec3::ZERO, 1.0, 32, 16),
                path => Mesh::load_obj(path)?,
            };
            self.mesh = Some((name.into(), mesh));
        }
        Ok(&self.mesh.as_ref().expect("set above").1)
    }

    fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &VoxelizerSettings,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        clear(frame, [0.1, 0.11, 0.13]);
        // Advance a running job.
        if let Some((key, grid, job)) = self.job.take() {
            match job {
                VoxelJob::Attributes(pending, mut count) => match count.try_take() {
                    Some(n) => {
                        let attrs = self
                            .voxelizer
                            .encode_resolve_attributes(device, frame.rec, pending, n?)?;
                        self.shown = Some((key, grid, Shown::Attributes(attrs)));
                        self.voxelized += 1;
                    }
                    None => self.job = Some((key, grid, VoxelJob::Attributes(pending, count))),
                },
                VoxelJob::Bits(mut bits) => match bits.try_take() {
                    Some(bits) => {
                        let bits = bits?;
                        let centres = voxel_centres(&bits, &grid);
                        let n = centres.len();
                        let instances = self.balls.upload(device, queue, &centres)?;
                        self.shown = Some((key, grid, Shown::Cubes(instances, n)));
                        self.voxelized += 1;
                    }
                    None => self.job = Some((key, grid, VoxelJob::Bits(bits))),
                },
                recorded => self.job = Some((key, grid, recorded)),
            }
        }
        // Start one when the settings changed.
        if self.job.is_none() && self.shown.as_ref().map(|x| &x.0) != Some(s) {
            let mesh = spun(self.mesh(&s.mesh)?, s.spin)?;
            let grid = Grid::fit(&mesh, s.grid)?;
            let job = match s.mode {
                VoxelMode::Surface(Separation::Conservative) => VoxelJob::RecordedAttributes(
                    self.voxelizer
                        .encode_attributes(device, frame.rec, &mesh, &grid)?,
                ),
                VoxelMode::Surface(sep) => VoxelJob::RecordedSurface(
                    self.voxelizer
                        .encode_surface_with(device, frame.rec, &mesh, &grid, sep)?,
                ),
                VoxelMode::Raster => {
                    VoxelJob::RecordedSurface(self.voxelizer.encode_surface_raster(
                        device,
                        frame.rec.encoder,
                        &mesh,
                        &grid,
                    )?)
                }
                VoxelMode::Solid => VoxelJob::RecordedSurface(
                    self.voxelizer
                        .encode_solid(device, frame.rec, &mesh, &grid, true)?,
                ),
            };
            self.slice = None;
            if s.slice {
                // The exact distance to the conservative surface voxels, in voxels.
                let surface = self
                    .voxelizer
                    .encode_surface(device, frame.rec, &mesh, &grid)?;
                let volume = self.voxelizer.encode_volume(device, frame.rec, &surface)?;
                let field = self.distance.encode(
                    device,
                    frame.rec,
                    &volume,
                    &fieldkit::distance::Options3d::default(),
                )?;
                self.field = Some(field.distance);
            }
            self.job = Some((s.clone(), grid, job));
        }
        if let Some(r) = &mut self.field_read
            && let Some(d) = r.try_take()
        {
            self.field_read = None;
            let d = d?;
            let grid = (self.job.as_ref().map(|j| j.1)).or(self.shown.as_ref().map(|j| j.1));
            if let Some(grid) = grid {
                let [w, h, depth] = grid.size;
                let z = depth / 2;
                let plane = &d[(z * w * h) as usize..((z + 1) * w * h) as usize];
                let max = plane.iter().copied().fold(1.0f32, f32::max);
                let px: Vec<u8> = plane
                    .iter()
                    .flat_map(|&v| {
                        let t = v / max;
                        let line = if (v / 2.0).fract() < 0.15 { 0.6 } else { 1.0 };
                        if v == 0.0 {
                            [255, 255, 255, 255]
                        } else {
                            [
                                (255.0 * t * line) as u8,
                                (90.0 * line) as u8,
                                (255.0 * (1.0 - t) * line) as u8,
                                255,
                            ]
                        }
                    })
                    .collect();
                self.slice = Some((upload_rgba(device, queue, &px, w, h), [w, h], max));
            }
        }
        let reversed = frame.camera.reversed_z;
        let view = frame.camera.view(frame.size);
        let (cv, dv) = (&frame.targets.colour_view, &frame.targets.depth_view);
        let mut stats = Vec::new();
        if let Some((key, grid, shown)) = &self.shown {
            // Centre the grid on the origin, longest side 2.
            let side = grid.size.into_iter().max().unwrap_or(1) as f32 * grid.voxel as f32;
            let scale = 2.0 / side;
            let centre = grid.origin.as_vec3()
                + Vec3::from_array(grid.size.map(|n| n as f32)) * grid.voxel as f32 * 0.5;
            let model = Mat4::from_scale(Vec3::splat(scale)) * Mat4::from_translation(-centre);
            stats.push(format!(
                "grid {}×{}×{}",
                grid.size[0], grid.size[1], grid.size[2]
            ));
            match shown {
                Shown::Attributes(attrs) => {
                    if self.view.as_ref().map(|v| v.0) != Some(reversed) {
                        let mut v = VoxelView::new(device, COLOUR, DEPTH);
                        if reversed {
                            v = Err(invalid(
                                "the voxel view draws with a depth test of Less (no reversed Z yet)",
                            ));
                        }
                        self.view = Some((reversed, v?));
                    }
                    let v = &self.view.as_ref().expect("set above").1;
                    let light = if s.point_light {
                        let size = glam::DVec3::from(grid.size.map(f64::from)) * grid.voxel;
                        let centre = (grid.origin + size * 0.5).as_vec3();
                        let radius = size.max_element() as f32 * 0.5;
                        fieldkit::voxelize::Light::Point {
                            position: centre + Vec3::new(0.6, 1.2, 1.0) * radius,
                            range: radius * 3.5,
                        }
                    } else {
                        fieldkit::voxelize::Light::Directional(Vec3::new(0.4, 0.8, 0.5))
                    };
                    v.encode_lit(
                        device,
                        frame.rec.encoder,
                        cv,
                        dv,
                        attrs,
                        grid,
                        view.view_proj * model,
                        light,
                        key.colour_by,
                    )?;
                    stats.push(format!("occupied voxels: {}", attrs.count));
                }
                Shown::Cubes(instances, n) => {
                    if self.cubes.as_ref().map(|c| c.0) != Some(reversed) {
                        let mut style = CubeStyle {
                            colour: Vec4::new(0.85, 0.7, 0.45, 1.0),
                            ..CubeStyle::default()
                        };
                        if reversed {
                            style.depth_compare = flip(style.depth_compare);
                        }
                        self.cubes = Some((reversed, Cubes::new(device, COLOUR, DEPTH, style)?));
                    }
                    let c = &self.cubes.as_ref().expect("set above").1;
                    c.encode(
                        device,
                        frame.rec.encoder,
                        cv,
                        dv,
                        instances,
                        grid.voxel as f32,
                        model,
                        view.view_proj,
                    )?;
                    stats.push(format!("occupied voxels: {n}"));
                }
            }
        }
        if let Some((texture, [w, h], max)) = &self.slice
            && s.slice
        {
            // Lower-right corner, a third of the frame's height, the slice's aspect.
            let fh = 1.0 / 3.0;
            let fw = fh * (*w as f32 / *h as f32) * frame.size[1] as f32 / frame.size[0] as f32;
            let view = texture.create_view(&Default::default());
            self.blit.encode(
                device,
                queue,
                frame.rec.encoder,
                &frame.targets.colour_view,
                frame.size,
                &view,
                [1.0 - fw - 0.01, 1.0 - fh - 0.01, 0.99, 0.99],
            );
            stats.push(format!(
                "distance, middle z slice ({w}×{h}): 0 (white) to {max:.1} voxels, lines every 2"
            ));
        }
        if self.job.is_some() {
            stats.push("voxelizing…".into());
        }
        Ok(stats)
    }
}

/// World centres (scale 1) of the set bits of a surface voxelized in `grid`.
fn voxel_centres(bits: &[bool], grid: &Grid) -> Vec<glam::Vec4> {
    let [nx, ny, _] = grid.size.map(|n| n as usize);
    bits.iter()
        .enumerate()
        .filter(|(_, b)| **b)
        .map(|(i, _)| {
            let v = DVec3::new(
                (i % nx) as f64 + 0.5,
                ((i / nx) % ny) as f64 + 0.5,
                (i / (nx * ny)) as f64 + 0.5,
            );
            let p = grid.origin + v * grid.voxel;
            p.as_vec3().extend(1.0)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// All scenes.

/// Every scene's GPU state, made on first use.
#[derive(Default)]
pub struct Scenes {
    actor: Option<Actor>,
    ocean: Option<Ocean>,
    volume: Option<VolumeScene>,
    distance: Option<Distance2dScene>,
    voxelizer: Option<VoxelizerScene>,
    island: Option<Actor>,
}

/// The composite's island: the actor's builder over a wide, low region, sunk half into the sea.
fn island_settings(actor: &ActorSettings) -> ActorSettings {
    ActorSettings {
        extent: [39.0, 9.0, 27.0],
        block: 3.0,
        draw: ActorDraw::Surface,
        animate: false,
        ..actor.clone()
    }
}

impl Scenes {
    /// No GPU state yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Work the scene started that has not reached the screen yet (readbacks in flight).
    pub fn busy(&self, scene: &str, s: &Saved) -> bool {
        match scene {
            "distance2d" => self.distance.as_ref().is_none_or(|d| d.busy(&s.distance)),
            "voxelizer" => self.voxelizer.as_ref().is_none_or(|v| v.busy(&s.voxelizer)),
            _ => false,
        }
    }

    /// Voxelizations the voxelizer scene has shown.
    pub fn voxelized(&self) -> u64 {
        self.voxelizer.as_ref().map_or(0, |v| v.voxelized)
    }

    /// The frame was submitted: readbacks of what it recorded may start.
    pub fn submitted(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        if let Some(d) = &mut self.distance {
            d.submitted(device, queue);
        }
        if let Some(v) = &mut self.voxelizer {
            v.submitted(device, queue);
        }
    }

    /// Record `scene` into the frame; returns the lines its panel shows.
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &str,
        s: &Saved,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        match scene {
            "actor" => {
                if self.actor.is_none() {
                    self.actor = Some(Actor::new(device)?);
                }
                let actor = self.actor.as_mut().expect("set above");
                actor.encode(device, queue, &s.actor, frame)
            }
            "ocean" => {
                clear(frame, [0.55, 0.7, 0.85]);
                let ocean = self.ocean.get_or_insert_with(|| Ocean::new(device));
                ocean.draw(device, queue, &s.ocean, frame)
            }
            "volume" => {
                clear(frame, [0.32, 0.52, 0.82]);
                if self.volume.is_none() {
                    self.volume = Some(VolumeScene::new(device)?);
                }
                let v = self.volume.as_mut().expect("set above");
                v.draw(device, queue, &s.volume, Mat4::IDENTITY, frame)
            }
            "distance2d" => {
                if self.distance.is_none() {
                    self.distance = Some(Distance2dScene::new(device)?);
                }
                let d = self.distance.as_mut().expect("set above");
                d.encode(device, queue, &s.distance, frame)
            }
            "voxelizer" => {
                if self.voxelizer.is_none() {
                    self.voxelizer = Some(VoxelizerScene::new(device)?);
                }
                let v = self.voxelizer.as_mut().expect("set above");
                v.encode(device, queue, &s.voxelizer, frame)
            }
            "composite" => {
                // One colour and one depth target: the island writes depth, the sea fades
                // against it and writes its own, the cloud stops at both.
                if self.island.is_none() {
                    self.island = Some(Actor::new(device)?);
                }
                let island = self.island.as_mut().expect("set above");
                let mut island_s = island_settings(&s.actor);
                island_s.raymarch.output = fieldkit::metaball::Output::Shaded;
                let mut stats = island.encode_island(device, queue, &island_s, frame)?;
                let ocean = self.ocean.get_or_insert_with(|| Ocean::new(device));
                stats.extend(ocean.draw(device, queue, &s.ocean, frame)?);
                if self.volume.is_none() {
                    self.volume = Some(VolumeScene::new(device)?);
                }
                let v = self.volume.as_mut().expect("set above");
                let cloud = Mat4::from_translation(Vec3::new(-6.0, 11.0, -20.0))
                    * Mat4::from_scale(Vec3::new(40.0, 12.0, 24.0));
                stats.extend(v.draw(device, queue, &s.volume, cloud, frame)?);
                Ok(stats)
            }
            other => Err(invalid(format!(
                "no scene {other:?}; the scenes are {}",
                NAMES.join(", ")
            ))),
        }
    }
}

impl Actor {
    /// Upload (or update in place) the voxels, and make the raymarcher for this depth
    /// convention if the last one was made for the other.
    fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxels: &[glam::Vec4],
        reversed: bool,
    ) -> Result<(), Error> {
        match &mut self.instances {
            Some((inst, n)) if *n == voxels.len() => self.balls.update(queue, inst, voxels)?,
            _ => self.instances = Some((self.balls.upload(device, queue, voxels)?, voxels.len())),
        }
        if self.marcher.as_ref().map(|m| m.0) != Some(reversed) {
            self.marcher = Some((reversed, Raymarcher::new(device, COLOUR, DEPTH, reversed)?));
        }
        Ok(())
    }

    /// The field of the prepared voxels on `grid`, marched and composited into the frame.
    fn surface(
        &self,
        device: &wgpu::Device,
        s: &ActorSettings,
        grid: &fieldkit::distance::Grid3,
        frame: &mut Frame,
    ) -> Result<(), Error> {
        let instances = &self.instances.as_ref().expect("prepared").0;
        let marcher = &self.marcher.as_ref().expect("prepared").1;
        let view = frame.camera.view(frame.size);
        let field = self
            .balls
            .encode(device, frame.rec, instances, grid, s.block, &s.field)?;
        if let Some(m) = marcher.encode_march(
            device,
            frame.rec,
            &field,
            Mat4::IDENTITY,
            &view,
            &s.raymarch,
        )? {
            marcher.encode_composite(
                device,
                frame.rec.encoder,
                &frame.targets.colour_view,
                &frame.targets.depth_view,
                &m,
            )?;
        }
        Ok(())
    }

    /// The actor drawn as the composite's island: sky cleared, the blocks sunk by half their
    /// height.
    fn encode_island(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &ActorSettings,
        frame: &mut Frame,
    ) -> Result<Vec<String>, Error> {
        let saved_clear = [0.55, 0.7, 0.85];
        clear(frame, saved_clear);
        let counts = s.counts()?;
        let voxels: Vec<glam::Vec4> = packed_grid(counts, s.block)?
            .into_iter()
            .map(|v| v - glam::Vec4::new(0.0, 3.5, 0.0, 0.0))
            .filter(|v| {
                let r = (v.x * v.x + 1.6 * v.z * v.z).sqrt();
                r < 19.0 - 4.0 * (v.y + 3.5)
            })
            .collect();
        self.prepare(device, queue, &voxels, frame.camera.reversed_z)?;
        if let Some(grid) = s.field.fit_grid(&voxels, s.block)? {
            self.surface(device, s, &grid, frame)?;
        }
        Ok(vec![format!("island instances: {}", voxels.len())])
    }
}
