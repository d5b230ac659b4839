//! Seed 004: the voxelizer.

use fieldkit::mesh_sdf::{MeshField, MeshSdf};
use fieldkit::metaball::MarchField;

use super::*;

/// How the voxelizer scene voxelizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum VoxelMode {
    /// Conservative or 6-separating surface (compute).
    Surface(Separation),
    /// Conservative surface through the hardware rasterizer.
    Raster,
    /// Solid: inside by parity, ORed with the surface.
    Solid,
    /// The mesh's signed distance field (`mesh_sdf`), its surface drawn by the SDF march.
    DistanceField,
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
    /// Show the mesh's signed distance field (`mesh_sdf`) through the middle z slice, in the
    /// frame's lower-right corner.
    pub slice: bool,
    /// Half-width of the distance field's exact band, voxels.
    pub band: f32,
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
            band: 4.0,
            spin: 0.0,
            point_light: false,
        }
    }
}

/// `mesh` turned `angle` radians about the y axis through its bounds' centre.
pub(super) fn spun(mesh: &Mesh, angle: f32) -> Result<Mesh, Error> {
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

pub(super) enum VoxelJob {
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
    pub(super) voxelizer: Voxelizer,
    pub(super) mesh_sdf: MeshSdf,
    /// The SDF march of the distance-field mode, made for the camera's depth direction.
    pub(super) marcher: Option<(bool, Raymarcher)>,
    pub(super) blit: Blit,
    /// The distance field recorded with the job (read back once submitted), then its slice.
    pub(super) field: Option<wgpu::Texture>,
    pub(super) field_read: Option<Readback<Vec<f32>>>,
    pub(super) slice: Option<(wgpu::TextureView, [u32; 2], f32)>,
    pub(super) view: Option<(bool, VoxelView)>,
    pub(super) cubes: Option<(bool, Cubes)>,
    pub(super) balls: Metaballs,
    pub(super) mesh: Option<(String, Mesh)>,
    pub(super) job: Option<(VoxelizerSettings, Grid, VoxelJob)>,
    pub(super) shown: Option<(VoxelizerSettings, Grid, Shown)>,
    /// Voxelizations that reached the screen.
    pub(super) voxelized: u64,
}

pub(super) enum Shown {
    Attributes(Attributes),
    Cubes(Instances, usize),
    Field(MeshField),
}

impl VoxelizerScene {
    pub(super) fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            voxelizer: Voxelizer::new(device)?,
            mesh_sdf: MeshSdf::new(device)?,
            marcher: None,
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
    pub(super) fn submitted(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
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

    pub(super) fn mesh(&mut self, name: &str) -> Result<&Mesh, Error> {
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

    pub(super) fn encode(&mut self, s: &VoxelizerSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        clear(frame, [0.1, 0.11, 0.13]);
        self.advance_job(device, queue, frame)?;
        let mut stats = Vec::new();
        if self.job.is_none() && self.shown.as_ref().map(|x| &x.0) != Some(s) {
            stats.push(self.start_job(device, s, frame)?);
        }
        self.take_slice(device, queue)?;
        self.draw_shown(device, queue, s, frame, &mut stats)?;
        if s.slice {
            self.draw_slice(device, queue, frame, &mut stats);
        }
        if self.job.is_some() {
            stats.push("voxelizing…".into());
        }
        Ok(stats)
    }

    /// Advance a running job: a result read back is shown.
    fn advance_job(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &mut Frame,
    ) -> Result<(), Error> {
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
        Ok(())
    }

    /// Start a job for settings `s` (they changed), with the distance slice if asked for;
    /// returns what each part took of the CPU.
    fn start_job(
        &mut self,
        device: &wgpu::Device,
        s: &VoxelizerSettings,
        frame: &mut Frame,
    ) -> Result<String, Error> {
        let (mut mesh_ms, mut sdf_ms, mut job_ms) = (None, None, None);
        let mesh = spent(&mut mesh_ms, || spun(self.mesh(&s.mesh)?, s.spin))?;
        let grid = spent(&mut mesh_ms, || Grid::fit(&mesh, s.grid))?;
        self.slice = None;
        let sdf_settings = fieldkit::mesh_sdf::Settings {
            band: s.band,
            march: s.mode == VoxelMode::DistanceField,
            ..Default::default()
        };
        let field = if s.slice || sdf_settings.march {
            let field = spent(&mut sdf_ms, || {
                self.mesh_sdf
                    .encode(device, frame.rec, &mesh, &grid, &sdf_settings)
            })?;
            if s.slice {
                self.field = Some(field.texture.clone());
            }
            Some(field)
        } else {
            None
        };
        let readout = |job_ms: Option<f64>| {
            let ms = |t: Option<f64>| t.map_or("—".into(), |t| format!("{t:.2} ms"));
            format!(
                "started: CPU for the mesh {}, its distance field {}, the voxels {}",
                ms(mesh_ms),
                ms(sdf_ms),
                ms(job_ms)
            )
        };
        let start = std::time::Instant::now();
        let job = match s.mode {
            VoxelMode::DistanceField => {
                // Nothing to read back: the field is drawn from the next frame on.
                let field = field.expect("made for the march");
                self.shown = Some((s.clone(), grid, Shown::Field(field)));
                self.voxelized += 1;
                return Ok(readout(None));
            }
            VoxelMode::Surface(Separation::Conservative) => VoxelJob::RecordedAttributes(
                self.voxelizer
                    .encode_attributes(device, frame.rec, &mesh, &grid)?,
            ),
            VoxelMode::Surface(sep) => VoxelJob::RecordedSurface(
                self.voxelizer
                    .encode_surface_with(device, frame.rec, &mesh, &grid, sep)?,
            ),
            VoxelMode::Raster => VoxelJob::RecordedSurface(self.voxelizer.encode_surface_raster(
                device,
                frame.rec.encoder,
                &mesh,
                &grid,
            )?),
            VoxelMode::Solid => VoxelJob::RecordedSurface(
                self.voxelizer
                    .encode_solid(device, frame.rec, &mesh, &grid, true)?,
            ),
        };
        *job_ms.get_or_insert(0.0) += start.elapsed().as_secs_f64() * 1e3;
        self.job = Some((s.clone(), grid, job));
        Ok(readout(job_ms))
    }

    /// The distance field's middle z slice, once read back, as an image to blit.
    fn take_slice(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), Error> {
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
                // Signed voxels: outside warm, inside cool, fading out to the band; a dark
                // line at every whole voxel of distance, the surface white.
                let band = self.shown.as_ref().map_or(4.0, |x| x.0.band);
                let px: Vec<u8> = plane
                    .iter()
                    .flat_map(|&v| slice_colour(v / grid.voxel as f32, band))
                    .collect();
                let texture = upload_rgba(device, queue, &px, w, h);
                self.slice = Some((texture.create_view(&Default::default()), [w, h], band));
            }
        }
        Ok(())
    }

    /// The shown voxels, lit by attributes or drawn as cubes, centred with longest side 2.
    fn draw_shown(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &VoxelizerSettings,
        frame: &mut Frame,
        stats: &mut Vec<String>,
    ) -> Result<(), Error> {
        let reversed = frame.camera.reversed_z;
        let view = frame.camera.view(frame.size);
        let (cv, dv) = (&frame.targets.colour_view, &frame.targets.depth_view);
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
                    v.encode(
                        device,
                        &mut *frame.rec,
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
                Shown::Field(field) => {
                    if self.marcher.as_ref().map(|m| m.0) != Some(reversed) {
                        let marcher = Raymarcher::new(device, queue, COLOUR, DEPTH, reversed)?;
                        self.marcher = Some((reversed, marcher));
                    }
                    let marcher = &self.marcher.as_ref().expect("set above").1;
                    let march = MarchField {
                        march: field.march.as_ref().expect("made with its march copy"),
                        grid: field.grid,
                        band: field.settings.band * field.grid.voxel as f32,
                        threshold: 0.0,
                        blobs: None,
                    };
                    let settings = RaymarchSettings::default();
                    let marched = marcher.encode_march_field(
                        device,
                        &mut *frame.rec,
                        &march,
                        model,
                        &view,
                        &settings,
                    )?;
                    if let Some(m) = marched {
                        marcher.encode_composite(device, &mut *frame.rec, cv, dv, &m)?;
                    }
                    stats.push(format!(
                        "signed distance field, exact within ±{} voxels, drawn by the SDF march",
                        field.settings.band
                    ));
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
                        &mut *frame.rec,
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
        Ok(())
    }

    /// The distance slice in the lower-right corner, a third of the frame's height.
    fn draw_slice(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &mut Frame,
        stats: &mut Vec<String>,
    ) {
        if let Some((view, [w, h], max)) = &self.slice {
            // Lower-right corner, a third of the frame's height, the slice's aspect.
            let fh = 1.0 / 3.0;
            let fw = fh * (*w as f32 / *h as f32) * frame.size[1] as f32 / frame.size[0] as f32;
            self.blit.encode(
                device,
                queue,
                &mut *frame.rec,
                &frame.targets.colour_view,
                frame.size,
                view,
                [1.0 - fw - 0.01, 1.0 - fh - 0.01, 0.99, 0.99],
            );
            stats.push(format!(
                "signed distance, middle z slice ({w}×{h}): surface white, outside orange, \
                 inside blue, to ±{max:.1} voxels, a line every voxel"
            ));
        }
    }
}

/// The slice's colour of a signed distance `d` (voxels) away from the surface and its lines:
/// orange outside, blue inside, darker toward ±`band`.
pub fn slice_base(d: f32, band: f32) -> [u8; 3] {
    let near = 1.0 - 0.6 * (d.abs() / band).min(1.0);
    let rgb = if d > 0.0 {
        [1.0, 0.55, 0.2]
    } else {
        [0.25, 0.5, 1.0]
    };
    rgb.map(|c: f32| (255.0 * c * near) as u8)
}

/// The slice's colour of a signed distance `d` (voxels) in a field clamped to ±`band`.
fn slice_colour(d: f32, band: f32) -> [u8; 4] {
    if d.abs() < 0.25 {
        return [255, 255, 255, 255];
    }
    let line = if d.abs().fract() < 0.12 { 0.55 } else { 1.0 };
    slice_base(d, band)
        .map(|c| (c as f32 * line) as u8)
        .into_iter()
        .chain([255])
        .collect::<Vec<_>>()
        .try_into()
        .expect("four channels")
}

/// World centres (scale 1) of the set bits of a surface voxelized in `grid`.
pub(super) fn voxel_centres(bits: &[bool], grid: &Grid) -> Vec<glam::Vec4> {
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
