//! Seed 004: the voxelizer.

use fieldkit::mesh_sdf::{MeshField, MeshSdf};
use fieldkit::metaball::MarchField;

use std::sync::Arc;

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

/// What the worker thread made for a change of settings, ready to draw.
pub(super) struct Started {
    settings: VoxelizerSettings,
    /// The mesh as loaded (before its spin), when the worker loaded it.
    loaded: Option<(String, Arc<Mesh>)>,
    grid: Grid,
    shown: Shown,
    /// The distance field's middle z slice as an image.
    slice: Option<Slice>,
    /// What each part took of the worker's CPU.
    readout: String,
    /// What draws the result, where the scene had none for its kind and depth direction.
    drawer: Option<(bool, Drawer)>,
}

/// What draws a shown result: the lit voxel view (attributes), the SDF march (the distance
/// field) or cubes (the other modes).
pub(super) enum Drawer {
    View(VoxelView),
    March(Box<Raymarcher>),
    Cubes(Cubes),
}

/// Which [`Drawer`] a mode's result needs.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum DrawerKind {
    View,
    March,
    Cubes,
}

impl DrawerKind {
    fn of(mode: VoxelMode) -> Self {
        match mode {
            VoxelMode::Surface(Separation::Conservative) => Self::View,
            VoxelMode::DistanceField => Self::March,
            _ => Self::Cubes,
        }
    }
}

impl Drawer {
    /// The drawer of `kind` for a depth test in `reversed` direction: pipelines made here.
    fn make(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kind: DrawerKind,
        reversed: bool,
    ) -> Result<Self, Error> {
        Ok(match kind {
            DrawerKind::View => Self::View(Self::view(device, reversed)?),
            DrawerKind::March => Self::March(Box::new(Self::march(device, queue, reversed)?)),
            DrawerKind::Cubes => Self::Cubes(Self::cubes(device, queue, reversed)?),
        })
    }

    /// The lit voxel view (no reversed depth yet: a typed error).
    fn view(device: &wgpu::Device, reversed: bool) -> Result<VoxelView, Error> {
        if reversed {
            return Err(invalid(
                "the voxel view draws with a depth test of Less (no reversed Z yet)",
            ));
        }
        VoxelView::new(device, COLOUR, DEPTH)
    }

    /// The SDF march of the distance field.
    fn march(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        reversed: bool,
    ) -> Result<Raymarcher, Error> {
        Raymarcher::new(device, queue, COLOUR, DEPTH, reversed)
    }

    /// The voxels as cubes.
    fn cubes(device: &wgpu::Device, queue: &wgpu::Queue, reversed: bool) -> Result<Cubes, Error> {
        let mut style = CubeStyle {
            colour: Vec4::new(0.85, 0.7, 0.45, 1.0),
            ..CubeStyle::default()
        };
        if reversed {
            style.depth_compare = flip(style.depth_compare);
        }
        Cubes::new(device, queue, COLOUR, DEPTH, style)
    }
}

/// An image of the distance field's middle z slice, its size and its band (voxels).
pub(super) type Slice = (wgpu::TextureView, [u32; 2], f32);

/// The objects the worker thread records with (shared with the frame, which draws what they
/// made).
#[derive(Clone)]
pub(super) struct Worker {
    device: wgpu::Device,
    queue: wgpu::Queue,
    voxelizer: Arc<Voxelizer>,
    mesh_sdf: Arc<MeshSdf>,
    balls: Arc<Metaballs>,
}

/// The voxelizer's state: voxelizing runs when the settings change, on a worker thread that
/// loads the mesh, records and submits the distance field and the voxels, reads them back and
/// makes what the frame draws (a bake's CPU work takes from a few to tens of milliseconds with
/// a large mesh: the frame never waits for it); the result is drawn every frame until the next
/// change.
pub struct VoxelizerScene {
    pub(super) worker: Worker,
    /// What draws each kind of result, made for the camera's depth direction on a worker
    /// thread (with the first result of its kind; on a worker of its own when the direction
    /// flips).
    pub(super) view: Latest<bool, VoxelView>,
    pub(super) marcher: Latest<bool, Raymarcher>,
    pub(super) cubes: Latest<bool, Cubes>,
    pub(super) blit: Blit,
    pub(super) slice: Option<Slice>,
    /// The last mesh loaded, by name (the worker loads a new one).
    pub(super) mesh: Option<(String, Arc<Mesh>)>,
    /// A change being made on the worker thread, for these settings.
    pub(super) starting: Option<(VoxelizerSettings, Job<Result<Started, Error>>)>,
    /// Settings the worker refused, and why: not tried again until they change.
    pub(super) failed: Option<(VoxelizerSettings, Error)>,
    pub(super) shown: Option<(VoxelizerSettings, Grid, Shown)>,
    /// What the last change took of the worker's CPU.
    pub(super) readout: Option<String>,
    /// Voxelizations that reached the screen.
    pub(super) voxelized: u64,
}

pub(super) enum Shown {
    Attributes(Attributes),
    Cubes(Instances, usize),
    Field(MeshField),
}

impl VoxelizerScene {
    /// The scene's objects, their pipelines made on three threads at once (the voxelizer's,
    /// the mesh SDF's and the cubes' are independent): the first frame waits for the slowest.
    pub(super) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Self, Error> {
        let (voxelizer, mesh_sdf, balls) = std::thread::scope(|scope| {
            let voxelizer = scope.spawn(|| Voxelizer::new(device));
            let mesh_sdf = scope.spawn(|| MeshSdf::new(device));
            let balls = Metaballs::new(device);
            (join(voxelizer), join(mesh_sdf), balls)
        });
        Ok(Self {
            worker: Worker {
                device: device.clone(),
                queue: queue.clone(),
                voxelizer: Arc::new(voxelizer?),
                mesh_sdf: Arc::new(mesh_sdf?),
                balls: Arc::new(balls?),
            },
            view: Latest::default(),
            marcher: Latest::default(),
            cubes: Latest::default(),
            blit: Blit::new(device, COLOUR),
            slice: None,
            mesh: None,
            starting: None,
            failed: None,
            shown: None,
            readout: None,
            voxelized: 0,
        })
    }

    /// Work started and not yet shown.
    pub fn busy(&self, s: &VoxelizerSettings) -> bool {
        self.starting.is_some()
            || self.shown.as_ref().map(|x| &x.0) != Some(s)
            || self.view.busy()
            || self.marcher.busy()
            || self.cubes.busy()
    }

    /// Wait for the worker thread to finish (the soak samples memory at fixed points); the
    /// frame after takes its result.
    pub fn wait_for_worker(&mut self) {
        if let Some((s, job)) = self.starting.take() {
            self.starting = Some((s, job.wait()));
        }
        self.view.wait();
        self.marcher.wait();
        self.cubes.wait();
    }

    pub(super) fn encode(&mut self, s: &VoxelizerSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        clear(frame, [0.1, 0.11, 0.13]);
        self.take_started()?;
        // Drawers a flip of the depth direction asked for, which the shown result may no
        // longer need: taken when ready all the same.
        self.view.poll();
        self.marcher.poll();
        self.cubes.poll();
        if let Some((failed, e)) = &self.failed
            && failed == s
        {
            return Err(e.clone());
        }
        if self.starting.is_none() && self.shown.as_ref().map(|x| &x.0) != Some(s) {
            self.start(s, frame.camera.reversed_z);
        }
        let mut stats = Vec::new();
        self.draw_shown(device, queue, s, frame, &mut stats)?;
        if s.slice {
            self.draw_slice(device, queue, frame, &mut stats);
        }
        stats.extend(self.readout.clone());
        if self.starting.is_some() {
            stats.push("voxelizing…".into());
        }
        Ok(stats)
    }

    /// Start making what settings `s` (they changed) show, on the worker thread, with what
    /// draws it where the scene has none for the depth direction `reversed`.
    fn start(&mut self, s: &VoxelizerSettings, reversed: bool) {
        let (worker, settings, mesh) = (self.worker.clone(), s.clone(), self.mesh.clone());
        let kind = DrawerKind::of(s.mode);
        let have = match kind {
            DrawerKind::View => self.view.has(&reversed),
            DrawerKind::March => self.marcher.has(&reversed),
            DrawerKind::Cubes => self.cubes.has(&reversed),
        };
        let need = (!have).then_some((kind, reversed));
        self.failed = None;
        let job = Job::spawn(move || worker.start(settings, mesh, need));
        self.starting = Some((s.clone(), job));
    }

    /// The worker's result, once ready: shown from this frame on.
    fn take_started(&mut self) -> Result<(), Error> {
        let Some((settings, job)) = &mut self.starting else {
            return Ok(());
        };
        let Some(started) = job.try_take() else {
            return Ok(());
        };
        let started = started.unwrap_or_else(|| Err(worker_stopped()));
        let settings = settings.clone();
        self.starting = None;
        let started = started.inspect_err(|e| self.failed = Some((settings, e.clone())))?;
        if started.loaded.is_some() {
            self.mesh = started.loaded;
        }
        self.readout = Some(started.readout);
        match started.drawer {
            Some((reversed, Drawer::View(v))) => self.view.put(reversed, v),
            Some((reversed, Drawer::March(m))) => self.marcher.put(reversed, *m),
            Some((reversed, Drawer::Cubes(c))) => self.cubes.put(reversed, c),
            None => {}
        }
        self.slice = started.slice;
        self.shown = Some((started.settings, started.grid, started.shown));
        self.voxelized += 1;
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
                    // The voxel view has no reversed Z: a result being replaced by one that
                    // draws otherwise is not drawn meanwhile.
                    if reversed && self.starting.is_some() {
                        return Ok(());
                    }
                    let d = device.clone();
                    let Some(v) = self
                        .view
                        .get(&reversed, move || Drawer::view(&d, reversed))?
                    else {
                        return Ok(());
                    };
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
                    let (d, q) = (device.clone(), queue.clone());
                    let make = move || Drawer::march(&d, &q, reversed);
                    self.marcher.get(&reversed, make)?;
                    // One for the other depth direction draws nothing until this one arrives.
                    let Some(marcher) = self.marcher.ready(&reversed) else {
                        return Ok(());
                    };
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
                    let (d, q) = (device.clone(), queue.clone());
                    let make = move || Drawer::cubes(&d, &q, reversed);
                    let Some(c) = self.cubes.get(&reversed, make)? else {
                        return Ok(());
                    };
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

/// `readback`'s result, waited for on a worker thread by polling the device without blocking
/// it: a blocking poll holds wgpu's fence until the GPU is done, and the frame's own submission
/// would wait for it (on llvmpipe, hundreds of milliseconds).
fn settle<T: 'static>(device: &wgpu::Device, mut readback: Readback<T>) -> Result<T, Error> {
    loop {
        if let Some(r) = readback.try_take() {
            return r;
        }
        device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| Error::Readback(e.to_string()))?;
        std::thread::sleep(std::time::Duration::from_micros(250));
    }
}

/// A scoped thread's result, its panic passed on.
fn join<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

fn worker_stopped() -> Error {
    invalid("the voxelizer's worker thread stopped before recording its job")
}

/// The mesh called `name`: `torus`, `sphere` or an OBJ path.
fn load_mesh(name: &str) -> Result<Mesh, Error> {
    Ok(match name {
        "torus" => Mesh::torus(DVec3::ZERO, 1.0, 0.4, 48, 24),
        "sphere" => Mesh::uv_sphere(DVec3::ZERO, 1.0, 32, 16),
        path => Mesh::load_obj(path)?,
    })
}

impl Worker {
    /// Make what settings `s` show: record and submit the distance field (if asked for) and
    /// the voxels, wait for them, and make the frame's images and instances from them; `mesh`
    /// is the last mesh loaded, by name.
    fn start(
        &self,
        s: VoxelizerSettings,
        mesh: Option<(String, Arc<Mesh>)>,
        need: Option<(DrawerKind, bool)>,
    ) -> Result<Started, Error> {
        let (device, queue) = (&self.device, &self.queue);
        let (mut mesh_ms, mut sdf_ms, mut job_ms) = (None, None, None);
        let loaded = match mesh {
            Some((name, mesh)) if name == s.mesh => (None, mesh),
            _ => {
                let mesh = Arc::new(spent(&mut mesh_ms, || load_mesh(&s.mesh))?);
                (Some((s.mesh.clone(), mesh.clone())), mesh)
            }
        };
        let mesh = spent(&mut mesh_ms, || spun(&loaded.1, s.spin))?;
        let grid = spent(&mut mesh_ms, || Grid::fit(&mesh, s.grid))?;
        let mut encoder = device.create_command_encoder(&Default::default());
        let sdf_settings = fieldkit::mesh_sdf::Settings {
            band: s.band,
            march: s.mode == VoxelMode::DistanceField,
            ..Default::default()
        };
        let field = if s.slice || sdf_settings.march {
            Some(spent(&mut sdf_ms, || {
                self.mesh_sdf
                    .encode(device, &mut encoder, &mesh, &grid, &sdf_settings)
            })?)
        } else {
            None
        };
        let recorded = spent(&mut job_ms, || {
            self.record(&mut encoder, &mesh, &grid, s.mode)
        })?;
        queue.submit([encoder.finish()]);
        let slice = match field.as_ref().filter(|_| s.slice) {
            Some(f) => Some(slice_image(
                device,
                queue,
                settle(device, readback_texture(device, queue, &f.texture))?,
                &grid,
                s.band,
            )),
            None => None,
        };
        let shown = match recorded {
            Some(recorded) => self.finish(recorded, &grid, &mut job_ms)?,
            None => Shown::Field(field.expect("made for the march")),
        };
        let ms = |t: Option<f64>| t.map_or("—".into(), |t| format!("{t:.2} ms"));
        let readout = format!(
            "voxelized on a worker thread: CPU for the mesh {}, its distance field {}, the \
             voxels {}",
            ms(mesh_ms),
            ms(sdf_ms),
            ms(job_ms)
        );
        let drawer = match need {
            Some((kind, reversed)) => {
                Some((reversed, Drawer::make(device, queue, kind, reversed)?))
            }
            None => None,
        };
        Ok(Started {
            settings: s,
            loaded: loaded.0,
            grid,
            shown,
            slice,
            readout,
            drawer,
        })
    }

    /// Record the voxelization `mode` asks for (none for the distance-field mode).
    fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mesh: &Mesh,
        grid: &Grid,
        mode: VoxelMode,
    ) -> Result<Option<Recorded>, Error> {
        let (device, v) = (&self.device, &self.voxelizer);
        Ok(Some(match mode {
            VoxelMode::DistanceField => return Ok(None),
            VoxelMode::Surface(Separation::Conservative) => {
                Recorded::Attributes(Box::new(v.encode_attributes(device, encoder, mesh, grid)?))
            }
            VoxelMode::Surface(sep) => {
                Recorded::Surface(v.encode_surface_with(device, encoder, mesh, grid, sep)?)
            }
            VoxelMode::Raster => {
                Recorded::Surface(v.encode_surface_raster(device, encoder, mesh, grid)?)
            }
            VoxelMode::Solid => {
                Recorded::Surface(v.encode_solid(device, encoder, mesh, grid, true)?)
            }
        }))
    }

    /// Read back a submitted voxelization and make what the frame draws of it: the attributes
    /// resolved for the voxels occupied, or cubes at the voxels set.
    fn finish(
        &self,
        recorded: Recorded,
        grid: &Grid,
        job_ms: &mut Option<f64>,
    ) -> Result<Shown, Error> {
        let (device, queue) = (&self.device, &self.queue);
        match recorded {
            Recorded::Attributes(pending) => {
                let n = settle(device, pending.occupied(device, queue))?;
                spent(job_ms, || {
                    let mut encoder = device.create_command_encoder(&Default::default());
                    let attrs = (self.voxelizer).encode_resolve_attributes(
                        device,
                        &mut encoder,
                        *pending,
                        n,
                    )?;
                    queue.submit([encoder.finish()]);
                    Ok(Shown::Attributes(attrs))
                })
            }
            Recorded::Surface(surface) => {
                let bits = settle(device, surface.read(device, queue))?;
                spent(job_ms, || {
                    let centres = voxel_centres(&bits, grid);
                    let instances = self.balls.upload(device, queue, &centres)?;
                    Ok(Shown::Cubes(instances, centres.len()))
                })
            }
        }
    }
}

/// A voxelization recorded and not yet read back.
enum Recorded {
    Attributes(Box<PendingAttributes>),
    Surface(fieldkit::voxelize::Surface),
}

/// The distance field's middle z slice as an image: signed voxels, outside warm, inside cool,
/// fading out to the band; a dark line at every whole voxel of distance, the surface white.
fn slice_image(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    field: Vec<f32>,
    grid: &Grid,
    band: f32,
) -> Slice {
    let [w, h, depth] = grid.size;
    let z = depth / 2;
    let plane = &field[(z * w * h) as usize..((z + 1) * w * h) as usize];
    let px: Vec<u8> = plane
        .iter()
        .flat_map(|&v| slice_colour(v / grid.voxel as f32, band))
        .collect();
    let texture = upload_rgba(device, queue, &px, w, h);
    (texture.create_view(&Default::default()), [w, h], band)
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
