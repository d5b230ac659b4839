//! fieldkit dropped into an application that owns its device: the device is opened here the way
//! an app opens it (`wgpu::Limits::default()`, no optional features), and every technique runs
//! through the public API alone, with no `fieldkit::gpu::Context`:
//!
//! - 2D signed distance of a mask (the exact transform, the 2D default);
//! - a torus voxelized solid, then its signed distance field (the exact 3D transform);
//! - one frame holding a metaball island in a Gerstner sea under an fBm cloud, all three
//!   testing and writing one depth buffer, as in a user's renderer.
//!
//! ```sh
//! cargo run --release --example own_device [-- OUT.png]
//! ```
//!
//! Writes one PNG (the frame on top; the 2D field and the SDF slice below). `tests/api/examples.rs`
//! runs the same code on lavapipe and checks the numbers against CPU references.

use fieldkit::Error;
use fieldkit::distance::{Distance2d, Distance3d, Settings2d, Settings3d, upload_mask};
use fieldkit::gpu::{Readback, readback_texture};
use fieldkit::metaball::{Metaballs, Settings, packed_grid};
use fieldkit::metaball::{RaymarchSettings, Raymarcher};
use fieldkit::ocean::{Look, OceanCamera, OceanRenderer, Output, Patch};
use fieldkit::ocean::{Wave, Waves};
use fieldkit::view::{Targets, View};
use fieldkit::volume::{MarchSettings, TransferFunction, Volume, VolumeRenderer, fbm_cloud};
use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
use glam::{DVec2, DVec3, Mat4, Vec2, Vec3, Vec4};

/// Frame size.
pub const FRAME: [u32; 2] = [320, 180];
/// 2D mask size.
pub const MASK: [u32; 2] = [96, 48];
/// Voxels along the torus's longest side.
pub const GRID: u32 = 40;

/// The cloud bank's box: its low corner and extent, metres.
pub const CLOUD: (Vec3, Vec3) = (Vec3::new(-14.0, 1.0, -34.0), Vec3::new(28.0, 10.0, 20.0));

/// The frame's camera, for the sea (f64) and for everything else.
pub fn camera() -> (OceanCamera, View) {
    let [w, h] = FRAME;
    let eye = DVec3::new(-5.0, 8.0, 30.0);
    let proj = glam::camera::rh::proj::directx::perspective(0.8, w as f32 / h as f32, 0.1, 500.0);
    let camera = OceanCamera::look_at(eye, DVec3::new(0.0, -1.0, 0.0), proj);
    let view = View {
        view_proj: proj * camera.view.as_mat4(),
        viewport: FRAME,
        reversed_z: false,
        origin: [0, 0],
    };
    (camera, view)
}

/// What one run produced, read back for the PNG and for the test.
pub struct Report {
    /// The adapter, as wgpu names it.
    pub adapter: String,
    /// The 2D mask (non-zero = inside), `MASK` texels, x fastest.
    pub mask: Vec<u8>,
    /// Its signed distance, negative inside.
    pub distance_2d: Vec<f32>,
    /// The grid the torus was voxelized in.
    pub grid: Grid,
    /// Solid voxels of the torus, x fastest.
    pub solid: Vec<bool>,
    /// The torus's own signed distance field on the same grid (`mesh_sdf`: each voxel's
    /// distance to its nearest triangle, exact within 4 voxels), world units.
    pub mesh_sdf: Vec<f32>,
    /// Their signed distance in world units, negative inside.
    pub sdf: Vec<f32>,
    /// The frame's colour (RGBA8) and depth.
    pub colour: Vec<[u8; 4]>,
    /// Depth after every technique drew (1 where nothing did).
    pub depth: Vec<f32>,
    /// The frame with the island and the sea only (no cloud), to show what the cloud added.
    pub colour_without_cloud: Vec<[u8; 4]>,
}

/// Open the default adapter as a typical application does: WebGPU's default limits and no
/// optional features.
pub fn open_device() -> Result<(wgpu::Device, wgpu::Queue, String), String> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        ..Default::default()
    }))
    .map_err(|e| {
        format!(
            "no GPU adapter ({e}); without a GPU install the software Vulkan driver: \
             apt-get install -y mesa-vulkan-drivers"
        )
    })?;
    let name = adapter.get_info().name;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("own_device"),
        required_features: wgpu::Features::empty(),
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    }))
    .map_err(|e| format!("{name}: {e}"))?;
    Ok((device, queue, name))
}

/// The application's own blocking wait for a readback (an offline tool may block; a frame loop
/// would call `try_take` once a frame instead).
fn wait<T: 'static>(device: &wgpu::Device, mut readback: Readback<T>) -> Result<T, Error> {
    loop {
        if let Some(result) = readback.try_take() {
            return result;
        }
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Readback(e.to_string()))?;
    }
}

fn encoder(device: &wgpu::Device, label: &str) -> wgpu::CommandEncoder {
    device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
}

/// A disc and a bar, non-zero inside.
pub fn mask_2d() -> Vec<u8> {
    let [w, h] = MASK;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
            let disc = (x - 28.0).powi(2) + (y - 24.0).powi(2) < 15.0f32.powi(2);
            let bar = (55.0..88.0).contains(&x) && (18.0..30.0).contains(&y);
            if disc || bar { 255 } else { 0 }
        })
        .collect()
}

/// Run every technique on `device` and `queue`.
pub fn run(device: &wgpu::Device, queue: &wgpu::Queue, adapter: String) -> Result<Report, Error> {
    // 2D: the exact transform is the default method.
    let [mw, mh] = MASK;
    let mask = mask_2d();
    let seeds = upload_mask(device, queue, &mask, mw, mh)?;
    let distance_2d = Distance2d::new(device)?;
    let mut enc = encoder(device, "2d distance");
    let field = distance_2d.encode(device, &mut enc, &seeds, &Settings2d::signed())?;
    queue.submit([enc.finish()]);
    let distance_2d = wait(
        device,
        readback_texture::<f32>(device, queue, &field.distance),
    )?;

    // Voxelize → 3D signed distance.
    let torus = Mesh::torus(DVec3::ZERO, 1.0, 0.4, 48, 24);
    let grid = Grid::fit(&torus, GRID)?;
    let voxelizer = Voxelizer::new(device)?;
    let distance_3d = Distance3d::new(device)?;
    let mut enc = encoder(device, "voxelize");
    let solid = voxelizer.encode_solid(device, &mut enc, &torus, &grid, true)?;
    let occupancy = voxelizer.encode_volume(device, &mut enc, &solid)?;
    let sdf = distance_3d.encode(
        device,
        &mut enc,
        &occupancy,
        &Settings3d {
            signed: true,
            voxel_size: grid.voxel as f32,
            ..Settings3d::default()
        },
    )?;
    queue.submit([enc.finish()]);
    let solid_bits = wait(device, solid.read(device, queue))?;
    let sdf = wait(
        device,
        readback_texture::<f32>(device, queue, &sdf.distance),
    )?;

    // The torus's own distance field: to its triangles, not to the voxels.
    let mut enc = encoder(device, "mesh sdf");
    let field = fieldkit::mesh_sdf::MeshSdf::new(device)?.encode(
        device,
        &mut enc,
        &torus,
        &grid,
        &fieldkit::mesh_sdf::Settings::default(),
    )?;
    queue.submit([enc.finish()]);
    let mesh_sdf = wait(
        device,
        readback_texture::<f32>(device, queue, &field.texture),
    )?;

    // One frame: island, sea and cloud against one depth buffer.
    let (colour, depth) = frame(device, queue, true)?;
    let (colour_without_cloud, _) = frame(device, queue, false)?;
    Ok(Report {
        adapter,
        mask,
        distance_2d,
        grid,
        mesh_sdf,
        solid: solid_bits,
        sdf,
        colour,
        depth,
        colour_without_cloud,
    })
}

/// The composited frame: colour and depth.
fn frame(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    cloud: bool,
) -> Result<(Vec<[u8; 4]>, Vec<f32>), Error> {
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, FRAME, colour_format, depth_format);
    let (camera, view) = camera();
    let mut enc = encoder(device, "frame");
    let sky = wgpu::Color {
        r: 0.55,
        g: 0.7,
        b: 0.85,
        a: 1.0,
    };
    targets.clear(&mut enc, sky, 1.0);

    // The island: metaballs on a shelf just under the water.
    let edge = 3.0;
    let voxels: Vec<Vec4> = packed_grid([13, 3, 9], edge)?
        .into_iter()
        .map(|v| v - Vec4::new(0.0, 3.5, 0.0, 0.0))
        .filter(|v| (v.x * v.x + 1.6 * v.z * v.z).sqrt() < 19.0 - 4.0 * (v.y + 3.5))
        .collect();
    let balls = Metaballs::new(device)?;
    let instances = balls.upload(device, queue, &voxels)?;
    let settings = Settings::default();
    if let Some(grid) = settings.fit_grid(&voxels, edge)? {
        let field = balls.encode(device, &mut enc, &instances, &grid, edge, &settings)?;
        let marcher = Raymarcher::new(device, queue, colour_format, depth_format, false)?;
        marcher.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &field,
            Mat4::IDENTITY,
            &view,
            &RaymarchSettings::default(),
        )?;
    }

    // The sea, fading with the depth of the water over the shelf.
    let waves = Waves::new(
        vec![
            Wave {
                direction: Vec2::new(1.0, 0.3),
                amplitude: 0.35,
                wavelength: 21.0,
                speed: 5.7,
            },
            Wave {
                direction: Vec2::new(0.2, 1.0),
                amplitude: 0.18,
                wavelength: 9.5,
                speed: 3.8,
            },
        ],
        0.7,
    )?;
    let look = Look {
        fade_distance: 3.0,
        sun_direction: Vec3::new(-0.4, 0.5, -0.75),
        ..Look::default()
    };
    let patches: Vec<Patch> = (0..100)
        .map(|k| {
            let corner = DVec2::new(
                -160.0 + 32.0 * (k % 10) as f64,
                -160.0 + 32.0 * (k / 10) as f64,
            );
            Patch::new(corner, 32.0)
        })
        .collect();
    let sea = OceanRenderer::new(device, queue, Output::Forward(colour_format), false)?;
    sea.encode(
        device,
        &mut enc,
        &waves,
        4.0,
        &camera,
        &look,
        &patches,
        &[&targets.colour_view],
        &targets.depth,
        true,
    )?;

    // A cloud bank behind the island, 28 × 10 × 20 m, marched against the scene's depth.
    if cloud {
        let dims = [48; 3];
        let volume = Volume::upload(
            device,
            queue,
            &fbm_cloud(dims, 7),
            dims,
            wgpu::TextureFormat::R8Unorm,
            CLOUD.1 / 48.0,
            CLOUD.0,
        )?;
        let renderer = VolumeRenderer::new(device, queue, colour_format)?;
        let tf = TransferFunction::cloud();
        let march = MarchSettings {
            step: 0.25,
            ..MarchSettings::default()
        };
        let bricks = renderer.encode_bricks(device, &mut enc, &volume)?;
        let light = renderer.encode_light(
            device,
            &mut enc,
            &volume,
            &bricks,
            &tf,
            Mat4::IDENTITY,
            &march,
        )?;
        if let Some(marched) = renderer.encode_march(
            device,
            &mut enc,
            &volume,
            &bricks,
            Some(&light),
            &tf,
            Mat4::IDENTITY,
            &view,
            Some(&targets.depth_view),
            &march,
        )? {
            renderer.encode_composite(device, &mut enc, &targets.colour_view, &marched)?;
        }
    }
    queue.submit([enc.finish()]);
    let colour = wait(
        device,
        readback_texture::<[u8; 4]>(device, queue, &targets.colour),
    )?;
    let depth = wait(
        device,
        readback_texture::<f32>(device, queue, &targets.depth),
    )?;
    Ok((colour, depth))
}

/// Blue outside, orange inside, darker bands every `period` units.
fn colour_map(d: f32, period: f32) -> [u8; 4] {
    let band = 0.75 + 0.25 * (d.abs() / period * std::f32::consts::TAU).cos();
    let base = if d < 0.0 {
        [1.0, 0.55, 0.2]
    } else {
        [0.3, 0.55, 1.0]
    };
    let fade = (1.0 - (d.abs() / (period * 6.0)).min(1.0) * 0.6) * band;
    [
        (base[0] * fade * 255.0) as u8,
        (base[1] * fade * 255.0) as u8,
        (base[2] * fade * 255.0) as u8,
        255,
    ]
}

/// The report as one picture: the frame on top; the 2D field (×1.5) and the SDF's middle slice
/// below.
pub fn picture(report: &Report) -> (Vec<u8>, u32, u32) {
    let [fw, fh] = FRAME;
    let (w, h) = (fw, fh + 4 + 80);
    let mut px = vec![[24u8, 26, 30, 255]; (w * h) as usize];
    for (i, c) in report.colour.iter().enumerate() {
        px[i] = *c;
    }
    let [mw, mh] = MASK;
    for y in 0..mh {
        for x in 0..mw {
            let d = report.distance_2d[(y * mw + x) as usize];
            px[((fh + 4 + y) * w + 4 + x) as usize] = colour_map(d, 4.0);
        }
    }
    // The SDF through the torus's middle (y is its axis), doubled.
    let [nx, ny, nz] = report.grid.size;
    let y = ny / 2;
    for z in 0..(nz * 2).min(80) {
        for x in 0..(nx * 2).min(w - mw - 16) {
            let d = report.sdf[(((z / 2) * ny + y) * nx + x / 2) as usize];
            let voxel = report.grid.voxel as f32;
            px[((fh + 4 + z) * w + mw + 16 + x) as usize] = colour_map(d / voxel, 2.0);
        }
    }
    (px.concat(), w, h)
}

fn main() -> std::process::ExitCode {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "own_device.png".into());
    let (device, queue, adapter) = match open_device() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("error: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    eprintln!("adapter: {adapter} (default limits, no optional features)");
    match run(&device, &queue, adapter) {
        Ok(report) => {
            let (rgba, w, h) = picture(&report);
            if let Err(e) = image::save_buffer(&out, &rgba, w, h, image::ExtendedColorType::Rgba8) {
                eprintln!("error: {out}: {e}");
                return std::process::ExitCode::FAILURE;
            }
            println!("{out}");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
