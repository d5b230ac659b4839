//! The viewer's scenes, one per seed system and one composite. Each draws into the frame's
//! colour and depth targets through fieldkit's public API; their settings are fieldkit's own
//! settings structs, gathered in [`Saved`] (the settings file), never copied.

use fieldkit::Error;
use fieldkit::distance::{Distance2d, Method2d, Settings2d, Variant, upload_mask};
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
use job::{Job, Latest};

mod actor;
mod culprit;
mod distance2d;
mod job;
mod legend;
mod ocean;
mod volume;
mod voxelizer;

pub use actor::{Actor, ActorDraw, ActorSettings};
pub use culprit::Control;
pub use distance2d::{
    Distance2dScene, DistanceSettings, EXACT_GROUP, field_rect, line, method_name, methods_2d,
};
pub use legend::{Legend, RAMP_SAMPLES, heat, sdf_colour};
pub use ocean::{Ocean, OceanSettings};
pub use volume::{VolumeScene, VolumeSettings};
pub use voxelizer::{BUNNY, VoxelMode, VoxelizerScene, VoxelizerSettings};

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
    /// `scene`'s settings and camera back to their defaults, the other scenes' kept; the
    /// voxelizer keeps its mesh (a `--mesh` given stays). The composite resets the ocean and
    /// volume settings it shows.
    pub fn reset_scene(&mut self, scene: &str) {
        let defaults = Saved::default();
        match scene {
            "actor" => self.actor = defaults.actor,
            "ocean" => self.ocean = defaults.ocean,
            "volume" => self.volume = defaults.volume,
            "distance2d" => self.distance = defaults.distance,
            "voxelizer" => {
                self.voxelizer = VoxelizerSettings {
                    mesh: std::mem::take(&mut self.voxelizer.mesh),
                    ..defaults.voxelizer
                }
            }
            _ => {
                self.ocean = defaults.ocean;
                self.volume = defaults.volume;
            }
        }
        if let Some(i) = NAMES.iter().position(|n| *n == scene)
            && let Some(c) = self.cameras.get_mut(i)
        {
            *c = default_camera(scene);
        }
    }

    /// Every scene's seed preset where it has one (the sources' settings), default cameras.
    pub fn seed() -> Self {
        Self {
            actor: ActorSettings::seed(),
            ocean: OceanSettings::seed(),
            volume: VolumeSettings::seed(),
            distance: DistanceSettings {
                options: Settings2d {
                    seeds: fieldkit::distance::SeedRule::seed(),
                    ..Settings2d::default()
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
        // The mesh is drawn with its longest side 2: its bounding sphere (up to √3) in view.
        "voxelizer" => Camera::orbit(Vec3::ZERO, 0.5, 0.35, 3.4, 100.0),
        "composite" => Camera::orbit(Vec3::new(0.0, -1.0, 0.0), -0.165, 0.29, 31.5, 3000.0),
        _ => Camera::orbit(Vec3::ZERO, 0.0, 0.0, 1.0, 10.0),
    }
}

/// One frame: where to record and draw, and when.
pub struct Frame<'a, 'r> {
    /// The app's device and queue.
    pub device: &'a wgpu::Device,
    pub queue: &'a wgpu::Queue,
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
    /// CPU milliseconds the scene spent inside fieldkit's calls this frame, where it times
    /// them ([`spent`]): the rest of its recording is the app's own (clears, overlays).
    pub fieldkit_ms: Option<f64>,
}

/// What a scene's frame shows in its panel: the lines, or the typed error that stopped it.
pub type PanelLines = Result<Vec<String>, Error>;

/// `slot`'s value, made by `make` the first time.
fn made<T>(slot: &mut Option<T>, make: impl FnOnce() -> Result<T, Error>) -> Result<&mut T, Error> {
    if slot.is_none() {
        *slot = Some(make()?);
    }
    Ok(slot.as_mut().expect("set above"))
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

/// Run `f`, adding the CPU milliseconds it took to `total` (a frame's
/// [`Frame::fieldkit_ms`]): what a scene spends inside fieldkit's calls, told apart from its
/// own work (clears, overlays).
pub(super) fn spent<T>(total: &mut Option<f64>, f: impl FnOnce() -> T) -> T {
    let start = std::time::Instant::now();
    let out = f();
    *total.get_or_insert(0.0) += start.elapsed().as_secs_f64() * 1e3;
    out
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
        let actor = |a: &Option<Actor>| a.as_ref().is_some_and(Actor::busy);
        let ocean = self.ocean.as_ref().is_some_and(|o| o.renderer.busy());
        // A cloud of a new size, or the cloud function, still being made on a worker thread.
        let volume = self.volume.as_ref().is_some_and(|v| v.busy());
        match scene {
            "actor" => actor(&self.actor),
            "ocean" => ocean,
            "volume" => volume,
            "distance2d" => self.distance.as_ref().is_none_or(|d| d.busy(&s.distance)),
            "voxelizer" => self.voxelizer.as_ref().is_none_or(|v| v.busy(&s.voxelizer)),
            _ => volume || ocean || actor(&self.island),
        }
    }

    /// Wait for the work the scenes do on worker threads (the voxelizer's jobs, the volume's
    /// cloud and cloud function); the next frame takes it.
    pub fn wait_for_workers(&mut self) {
        if let Some(v) = &mut self.voxelizer {
            v.wait_for_worker();
        }
        if let Some(v) = &mut self.volume {
            v.wait_for_cloud();
        }
        for a in [&mut self.actor, &mut self.island].into_iter().flatten() {
            a.wait_for_workers();
        }
        if let Some(o) = &mut self.ocean {
            o.renderer.wait();
        }
        if let Some(d) = &mut self.distance {
            d.wait_for_worker();
        }
    }

    /// The screen is now `size`: make the images the scenes' raymarchers and volume marches
    /// write at that size where the kept ones no longer serve it, as an app does where it
    /// remakes its own targets, so that the frame after a resize makes none.
    pub fn resized(&self, device: &wgpu::Device, size: [u32; 2]) -> Result<(), Error> {
        let actors = [&self.actor, &self.island].into_iter().flatten();
        let voxelizer = self.voxelizer.as_ref().and_then(|v| v.marcher.current());
        for m in actors.filter_map(|a| a.marcher.current()).chain(voxelizer) {
            m.reserve(device, size)?;
        }
        if let Some(v) = &self.volume {
            v.renderer.reserve(device, size)?;
            if let Some(c) = &v.cloud {
                c.reserve(device, size)?;
            }
        }
        Ok(())
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
    }

    /// Record `scene` into the frame; returns the lines its panel shows.
    pub fn encode(&mut self, scene: &str, s: &Saved, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
        match scene {
            "actor" => made(&mut self.actor, || Actor::new(device))?.encode(&s.actor, frame),
            "ocean" => {
                clear(frame, [0.55, 0.7, 0.85]);
                let ocean = self.ocean.get_or_insert_with(|| Ocean::new(device));
                ocean.draw(&s.ocean, frame)
            }
            "volume" => {
                clear(frame, [0.32, 0.52, 0.82]);
                let v = made(&mut self.volume, || VolumeScene::new(device, queue))?;
                let start = std::time::Instant::now();
                let lines = v.draw(&s.volume, Mat4::IDENTITY, frame);
                *frame.fieldkit_ms.get_or_insert(0.0) += ms(start);
                lines
            }
            "distance2d" => made(&mut self.distance, || Distance2dScene::new(device))?
                .encode(&s.distance, frame),
            "voxelizer" => made(&mut self.voxelizer, || VoxelizerScene::new(device, queue))?
                .encode(&s.voxelizer, frame),
            "composite" => {
                // One colour and one depth target: the island writes depth, the sea fades
                // against it and writes its own, the cloud stops at both.
                let t = std::time::Instant::now();
                let island = made(&mut self.island, || Actor::new(device))?;
                let mut island_s = island_settings(&s.actor);
                island_s.raymarch.output = fieldkit::metaball::Output::Shaded;
                let mut stats = island.encode_island(&island_s, frame)?;
                let island_ms = ms(t);
                let t = std::time::Instant::now();
                let ocean = self.ocean.get_or_insert_with(|| Ocean::new(device));
                stats.extend(ocean.draw(&s.ocean, frame)?);
                let sea_ms = ms(t);
                let t = std::time::Instant::now();
                let v = made(&mut self.volume, || VolumeScene::new(device, queue))?;
                let cloud = Mat4::from_translation(Vec3::new(-6.0, 11.0, -20.0))
                    * Mat4::from_scale(Vec3::new(40.0, 12.0, 24.0));
                let start = std::time::Instant::now();
                stats.extend(v.draw(&s.volume, cloud, frame)?);
                *frame.fieldkit_ms.get_or_insert(0.0) += ms(start);
                stats.push(format!(
                    "CPU to record: island {island_ms:.3} ms, sea {sea_ms:.3} ms, cloud {:.3} ms",
                    ms(t)
                ));
                Ok(stats)
            }
            other => Err(invalid(format!(
                "no scene {other:?}; the scenes are {}",
                NAMES.join(", ")
            ))),
        }
    }
}
