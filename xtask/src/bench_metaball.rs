//! `cargo xtask bench metaball`: SDF build and raymarch time against surface error, for grids of
//! several resolutions over a 32³ voxel set (16³ with `--quick`), at 1920×1080 (480×270 quick).
//!
//! Time: GPU timestamps written in the command encoder around the whole SDF build (splat, seeds,
//! JFA, resolve) and around the raymarch pass; median of the timed runs. Error: for up to 4096
//! hit pixels, the hit point's distance to the analytic iso-surface, (ρ − T)/|∇ρ| in f64, in
//! voxel edges.

use std::io::Write;
use std::process::ExitCode;

use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::metaball::render::{Output, RaymarchSettings, Raymarcher, Targets, View};
use fieldkit::metaball::{Metaballs, Settings, animate, cpu, packed_grid};
use glam::{DVec3, Mat4, Vec3};

struct Stamps {
    set: wgpu::QuerySet,
    buf: wgpu::Buffer,
    period: f64,
}

impl Stamps {
    fn new(ctx: &Context) -> Result<Self, String> {
        let need =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if !ctx.device.features().contains(need) {
            return Err(format!(
                "{} has no timestamp queries inside encoders",
                ctx.adapter_name()
            ));
        }
        Ok(Self {
            set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("bench stamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            buf: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bench stamps"),
                size: 16,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            period: ctx.queue.get_timestamp_period() as f64,
        })
    }

    /// Run `record` between two timestamps; returns milliseconds.
    fn time(
        &self,
        ctx: &Context,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<(), String>,
    ) -> Result<f64, String> {
        let mut enc = ctx.encoder("bench");
        enc.write_timestamp(&self.set, 0);
        record(&mut enc)?;
        enc.write_timestamp(&self.set, 1);
        enc.resolve_query_set(&self.set, 0..2, &self.buf, 0);
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let b = read_buffer(ctx, &self.buf).map_err(|e| e.to_string())?;
        let t: &[u64] = bytemuck::cast_slice(&b);
        Ok(t[1].saturating_sub(t[0]) as f64 * self.period / 1e6)
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

pub fn run(quick: bool, reps: usize, warmup: usize, out: &std::path::Path) -> ExitCode {
    match bench(quick, reps, warmup, out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench metaball: {e}");
            ExitCode::FAILURE
        }
    }
}

fn bench(quick: bool, reps: usize, warmup: usize, out: &std::path::Path) -> Result<(), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    let adapter = ctx.adapter_name();
    println!("adapter: {adapter}");
    let stamps = Stamps::new(&ctx)?;
    let side = if quick { 16 } else { 32 };
    let (width, height) = if quick { (480, 270) } else { (1920, 1080) };
    let grids: &[u32] = if quick { &[32, 64] } else { &[64, 128, 192] };
    let edge = 1.0;
    let voxels = animate(&packed_grid([side; 3], edge), edge, 0.3, 0.5, 0.15);
    let settings = Settings::default();
    let fitted = settings
        .fit_grid(&voxels, edge)
        .map_err(|e| e.to_string())?
        .ok_or("empty set")?;
    let balls = Metaballs::new(&ctx.device).map_err(|e| e.to_string())?;
    let inst = balls.upload(&ctx, &voxels).map_err(|e| e.to_string())?;
    let extent = Vec3::from_array(fitted.size.map(|s| s as f32)) * fitted.voxel_size;
    let centre = fitted.origin + extent * 0.5;
    let proj =
        glam::camera::rh::proj::directx::perspective(0.8, width as f32 / height as f32, 0.1, 500.0);
    let eye = centre + Vec3::new(0.55, 0.4, 0.9) * extent.max_element() * 1.1;
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
        viewport: [width, height],
        reversed_z: false,
    };
    let marcher = Raymarcher::new(
        &ctx.device,
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
        false,
    )
    .map_err(|e| e.to_string())?;
    let targets = Targets::new(
        &ctx.device,
        [width, height],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let mut csv = std::fs::File::create(out.join("metaball.csv")).map_err(|e| e.to_string())?;
    writeln!(csv, "adapter,instances,grid,resolution,sdf_ms,raymarch_ms,hit_pixels,max_err_edges,rms_err_edges")
        .map_err(|e| e.to_string())?;
    println!("| grid | SDF build ms | raymarch ms | hit pixels | max err (edges) | RMS err |");
    println!("|---|---|---|---|---|---|");
    for &n in grids {
        let cell = extent.max_element() / n as f32;
        let size = (extent / cell).ceil();
        let grid = fieldkit::distance::volume::Grid3 {
            size: [size.x as u32, size.y as u32, size.z as u32],
            voxel_size: cell,
            origin: centre - size * cell * 0.5,
        };
        let s = Settings {
            cells_per_edge: edge / cell,
            ..settings
        };
        let mut field = None;
        let mut sdf_ms = Vec::new();
        for i in 0..warmup + reps {
            let ms = stamps.time(&ctx, |enc| {
                field = Some(
                    balls
                        .encode(&ctx.device, enc, &inst, &grid, edge, &s)
                        .map_err(|e| e.to_string())?,
                );
                Ok(())
            })?;
            if i >= warmup {
                sdf_ms.push(ms);
            }
        }
        let field = field.unwrap();
        let rs = RaymarchSettings {
            output: Output::Normal,
            ..RaymarchSettings::default()
        };
        let mut ray_ms = Vec::new();
        for i in 0..warmup + reps {
            let ms = stamps.time(&ctx, |enc| {
                targets.clear(enc, wgpu::Color::TRANSPARENT, 1.0);
                marcher
                    .encode(
                        &ctx.device,
                        enc,
                        &cv,
                        &dv,
                        &field,
                        Mat4::IDENTITY,
                        &view,
                        &rs,
                    )
                    .map_err(|e| e.to_string())?;
                Ok(())
            })?;
            if i >= warmup {
                ray_ms.push(ms);
            }
        }
        // Error at up to 4096 hit pixels spread over the image.
        let px: Vec<[f32; 4]> = read_texture(&ctx, &targets.colour).map_err(|e| e.to_string())?;
        let hits: Vec<usize> = (0..px.len()).filter(|&i| px[i][3] != 0.0).collect();
        let stride = (hits.len() / 4096).max(1);
        let inv = view.view_proj.as_dmat4().inverse();
        let (mut max, mut sum2, mut k) = (0.0f64, 0.0f64, 0usize);
        for &i in hits.iter().step_by(stride) {
            let (x, y) = ((i % width as usize) as f64, (i / width as usize) as f64);
            let ndc = glam::DVec2::new(
                (x + 0.5) / width as f64 * 2.0 - 1.0,
                1.0 - (y + 0.5) / height as f64 * 2.0,
            );
            let near = inv.project_point3(ndc.extend(0.0));
            let far = inv.project_point3(ndc.extend(1.0));
            let p: DVec3 = near + (far - near).normalize() * (px[i][3] as f64 - 1.0);
            let r = cpu::density_at(&voxels, edge, &s, p) - s.threshold as f64;
            let g = cpu::gradient_at(&voxels, edge, &s, p).length();
            if g > 1e-9 {
                let e = (r / g).abs() / edge as f64;
                max = max.max(e);
                sum2 += e * e;
                k += 1;
            }
        }
        let rms = (sum2 / k.max(1) as f64).sqrt();
        let (sdf, ray) = (median(sdf_ms), median(ray_ms));
        println!(
            "| {}×{}×{} | {sdf:.3} | {ray:.3} | {} | {max:.3} | {rms:.4} |",
            grid.size[0],
            grid.size[1],
            grid.size[2],
            hits.len()
        );
        writeln!(
            csv,
            "\"{adapter}\",{},{}x{}x{},{width}x{height},{sdf:.4},{ray:.4},{},{max:.4},{rms:.5}",
            voxels.len(),
            grid.size[0],
            grid.size[1],
            grid.size[2],
            hits.len()
        )
        .map_err(|e| e.to_string())?;
    }
    println!("wrote {}", out.join("metaball.csv").display());
    Ok(())
}
