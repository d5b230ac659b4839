//! `cargo xtask bench metaball`: time per frame against surface error for three ways of drawing
//! the metaball field: sphere tracing the SDF texture (at several grid resolutions), sphere
//! tracing the field itself with a global Lipschitz bound, and segment tracing it; for 16³ and
//! 32³ voxel sets (8³ and 16³ with `--quick`) at 1920×1080 (480×270 quick).
//!
//! Time: GPU timestamps written in the command encoder, median of the timed runs: the build (SDF:
//! splat, seeds, JFA, resolve, pack; direct: the blob bins) and the frame (march + composite,
//! shaded into an 8-bit target cleared beforehand). Error: at up to 2048 pixels spread over the
//! image, the hit distance along the ray against an f64 reference (the analytic field marched in
//! 0.02-edge steps, then bisected), in voxel edges; pixels where one side hits and the other
//! does not are counted apart. Writes `metaball.csv` and `metaball.png`.

use std::io::Write;

use fieldkit::distance::Variant;
use fieldkit::distance::{Grid, Method};
use fieldkit::gpu::{Context, read_texture};
use fieldkit::metaball::{
    BlobBins, ExactSurface, MetaballField, Metaballs, Settings, animate, cpu, packed_grid,
};
use fieldkit::metaball::{Direct, Output, RaymarchSettings, Raymarcher};
use fieldkit::view::{Targets, View};
use glam::{DVec3, Mat4, Vec3, Vec4};

use crate::measure::{Stamps, median};

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args.quick, args.reps, args.warmup, args.band, &args.out)
}

/// One tracer on one voxel set.
struct Row {
    instances: usize,
    method: String,
    grid: String,
    build_ms: f64,
    /// Its frame.
    m: Measured,
}

/// What is traced: the SDF texture, or the field from blob bins.
enum Source<'a> {
    Sdf(&'a MetaballField),
    Direct(&'a BlobBins, Direct),
}

fn draw(
    ctx: &Context,
    marcher: &Raymarcher,
    enc: &mut wgpu::CommandEncoder,
    targets: &Targets,
    source: &Source,
    view: &View,
    rs: &RaymarchSettings,
) -> Result<(), String> {
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    match source {
        Source::Sdf(field) => {
            marcher.encode(&ctx.device, enc, cv, dv, field, Mat4::IDENTITY, view, rs)
        }
        Source::Direct(bins, m) => {
            marcher.encode_direct(&ctx.device, enc, cv, dv, bins, *m, Mat4::IDENTITY, view, rs)
        }
    }
    .map(|_| ())
    .map_err(|e| e.to_string())
}

fn march_only(
    ctx: &Context,
    marcher: &Raymarcher,
    enc: &mut wgpu::CommandEncoder,
    source: &Source,
    view: &View,
    rs: &RaymarchSettings,
) -> Result<(), String> {
    match source {
        Source::Sdf(field) => marcher
            .encode_march(&ctx.device, enc, field, Mat4::IDENTITY, view, rs)
            .map(|_| ()),
        Source::Direct(bins, m) => marcher
            .encode_direct_march(&ctx.device, enc, bins, *m, Mat4::IDENTITY, view, rs)
            .map(|_| ()),
    }
    .map_err(|e| e.to_string())
}

fn bench(
    quick: bool,
    reps: usize,
    warmup: usize,
    band: f32,
    out: &std::path::Path,
) -> Result<(), String> {
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    let sides: &[u32] = if quick { &[8, 16] } else { &[16, 32] };
    let (width, height) = if quick { (480, 270) } else { (1920, 1080) };
    let grids: &[u32] = if quick { &[32, 64] } else { &[64, 128, 192] };
    let edge = 1.0;
    let settings = Settings {
        band,
        ..Settings::default()
    };
    println!("field band: {band} cells");
    let balls = Metaballs::new(&ctx.device).map_err(|e| e.to_string())?;
    // A raymarcher and full-size targets for one colour format.
    let pair = |format| -> Result<(Raymarcher, Targets), String> {
        let depth = wgpu::TextureFormat::Depth32Float;
        let marcher = Raymarcher::new(&ctx.device, &ctx.queue, format, depth, false)
            .map_err(|e| e.to_string())?;
        Ok((
            marcher,
            Targets::new(&ctx.device, [width, height], format, depth),
        ))
    };
    // Float targets for reading normals, hit distances and step counts back; and a frame as an
    // application draws it: shaded, into an 8-bit colour target.
    let (marcher, targets) = pair(wgpu::TextureFormat::Rgba32Float)?;
    let (frame_marcher, frame) = pair(wgpu::TextureFormat::Rgba8Unorm)?;
    let bar = indicatif::ProgressBar::new((sides.len() * (4 * grids.len() + 2)) as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}").unwrap(),
    );
    let mut rows = Vec::new();
    for &side in sides {
        let voxels = animate(
            &packed_grid([side; 3], edge).expect("a bench size"),
            edge,
            0.3,
            0.5,
            0.15,
        );
        let fitted = settings
            .fit_grid(&voxels, edge)
            .map_err(|e| e.to_string())?
            .ok_or("empty set")?;
        let inst = balls
            .upload(&ctx.device, &ctx.queue, &voxels)
            .map_err(|e| e.to_string())?;
        let extent = Vec3::from_array(fitted.size.map(|s| s as f32)) * fitted.voxel as f32;
        let centre = fitted.origin.as_vec3() + extent * 0.5;
        let proj = glam::camera::rh::proj::directx::perspective(
            0.8,
            width as f32 / height as f32,
            0.1,
            500.0,
        );
        let eye = centre + Vec3::new(0.55, 0.4, 0.9) * extent.max_element() * 1.1;
        let view = View {
            view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
            viewport: [width, height],
            reversed_z: false,
            origin: [0, 0],
        };
        let reference = Reference::new(&voxels, edge, &settings, &view, &fitted);
        let scene = Scene {
            ctx: &ctx,
            stamps: &stamps,
            marcher: &marcher,
            targets: &targets,
            frame_marcher: &frame_marcher,
            frame: &frame,
            view: &view,
            reference: &reference,
            warmup,
            reps,
        };
        if side == sides[0] {
            bar.suspend(|| {
                println!(
                    "| instances | method | grid | build ms | frame ms | of it march | steps mean | p95 | at cap | RMS err (edges) | max err | hit/miss off |"
                );
                println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
            });
        }
        let mut push = |method: &str, grid: String, build_ms: f64, m: Measured| {
            let row = Row {
                instances: voxels.len(),
                method: method.into(),
                grid,
                build_ms,
                m,
            };
            let line = format!(
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:.1} | {} | {:.2}% | {:.4} | {:.3} | {:.2}% |",
                row.instances,
                row.method,
                row.grid,
                row.build_ms,
                row.m.frame_ms,
                row.m.march_ms,
                row.m.steps.mean,
                row.m.steps.p95,
                row.m.steps.at_cap * 100.0,
                row.m.rms_err,
                row.m.max_err,
                row.m.mismatch
            );
            bar.suspend(|| println!("{line}"));
            rows.push(row);
            bar.inc(1);
        };
        for &n in grids {
            let cell = extent.max_element() / n as f32;
            let size = (extent / cell).ceil();
            let grid = Grid {
                size: [size.x as u32, size.y as u32, size.z as u32],
                voxel: cell as f64,
                origin: (centre - size * cell * 0.5).as_dvec3(),
            };
            let label = format!("{}×{}×{}", grid.size[0], grid.size[1], grid.size[2]);
            // The distance stage's two methods for sub-voxel seeds (see `Settings::method`),
            // each with the blobs read near the surface and the texture alone.
            for (name, method, exact_surface) in [
                ("SDF + blobs, lines", Method::Lines, ExactSurface::On),
                ("SDF texture alone, lines", Method::Lines, ExactSurface::Off),
                (
                    "SDF + blobs, JFA+2",
                    Method::Jfa(Variant::JfaPlus2),
                    ExactSurface::On,
                ),
                (
                    "SDF texture alone, JFA+2",
                    Method::Jfa(Variant::JfaPlus2),
                    ExactSurface::Off,
                ),
            ] {
                let s = Settings {
                    cells_per_edge: edge / cell,
                    method,
                    exact_surface,
                    ..settings
                };
                bar.set_message(format!("{} instances, {name} {label}", voxels.len()));
                let (build_ms, field) = scene.time_build(|enc| {
                    balls
                        .encode(&ctx.device, enc, &inst, &grid, edge, &s)
                        .map_err(|e| e.to_string())
                })?;
                let m =
                    scene.frames(&Source::Sdf(&field), RaymarchSettings::default().max_steps)?;
                push(name, label.clone(), build_ms, m);
                // Where the build's time goes: each pass on its own timestamps (the passes'
                // sum leaves out the gaps between them, which the build time above includes).
                let (_, _, _, passes) =
                    crate::measure::time_runs(&ctx, warmup, reps, None, |enc, p| {
                        balls
                            .encode(&ctx.device, &mut p.record(enc), &inst, &grid, edge, &s)
                            .expect("the same build ran above");
                    })?;
                let split = passes
                    .iter()
                    .map(|(n, ms)| format!("{n} {ms:.3}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                bar.suspend(|| println!("|   | per pass (ms): {split} |"));
            }
        }
        for (name, method) in [
            ("global-bound sphere", Direct::SphereGlobal),
            ("segment", Direct::Segment),
        ] {
            bar.set_message(format!("{} instances, {name}", voxels.len()));
            let (build_ms, bins) = scene.time_build(|enc| {
                balls
                    .encode_bins(&ctx.device, enc, &inst, &fitted, edge, &settings)
                    .map_err(|e| e.to_string())
            })?;
            let m = scene.frames(&Source::Direct(&bins, method), DIRECT_MAX_STEPS)?;
            push(name, "bins".into(), build_ms, m);
        }
    }
    bar.finish_and_clear();
    std::fs::create_dir_all(out).map_err(|e| e.to_string())?;
    let mut csv = std::fs::File::create(out.join("metaball.csv")).map_err(|e| e.to_string())?;
    writeln!(
        csv,
        "adapter,instances,method,grid,resolution,build_ms,frame_ms,march_ms,steps_mean,steps_p95,at_cap,hit_pixels,rms_err_edges,max_err_edges,hit_miss_off_pct"
    )
    .map_err(|e| e.to_string())?;
    for r in &rows {
        writeln!(
            csv,
            "\"{adapter}\",{},{},{},{width}x{height},{:.4},{:.4},{:.4},{:.2},{},{:.4},{},{:.5},{:.4},{:.3}",
            r.instances,
            r.method,
            r.grid,
            r.build_ms,
            r.m.frame_ms,
            r.m.march_ms,
            r.m.steps.mean,
            r.m.steps.p95,
            r.m.steps.at_cap,
            r.m.hits,
            r.m.rms_err,
            r.m.max_err,
            r.m.mismatch
        )
        .map_err(|e| e.to_string())?;
    }
    chart(&out.join("metaball.png"), &adapter, &rows)?;
    println!(
        "wrote {} and metaball.png",
        out.join("metaball.csv").display()
    );
    Ok(())
}

/// What a scene's timing and readback need.
struct Scene<'a> {
    ctx: &'a Context,
    stamps: &'a Stamps,
    marcher: &'a Raymarcher,
    targets: &'a Targets,
    frame_marcher: &'a Raymarcher,
    frame: &'a Targets,
    view: &'a View,
    reference: &'a Reference,
    warmup: usize,
    reps: usize,
}

/// A tracer's frame figures.
struct Measured {
    frame_ms: f64,
    march_ms: f64,
    steps: StepStats,
    hits: usize,
    rms_err: f64,
    max_err: f64,
    /// Sampled pixels where the tracer and the reference disagree on hit or miss, %.
    mismatch: f64,
}

impl Scene<'_> {
    /// Median GPU time of `build`, and what its last run made.
    fn time_build<T>(
        &self,
        mut build: impl FnMut(&mut wgpu::CommandEncoder) -> Result<T, String>,
    ) -> Result<(f64, T), String> {
        let mut times = Vec::new();
        let mut made = None;
        for i in 0..self.warmup + self.reps {
            let ms = self.stamps.time(self.ctx, |enc| {
                made = Some(build(enc)?);
                Ok(())
            })?;
            if i >= self.warmup {
                times.push(ms);
            }
        }
        Ok((median(times), made.ok_or("no build ran")?))
    }

    /// Frame and march times, step counts and error of one tracer.
    fn frames(&self, src: &Source, max_steps: u32) -> Result<Measured, String> {
        let (ctx, view) = (self.ctx, self.view);
        let shaded = RaymarchSettings {
            max_steps,
            ..RaymarchSettings::default()
        };
        let (mut frame_ms, mut march_ms) = (Vec::new(), Vec::new());
        for i in 0..self.warmup + self.reps {
            // Clearing is the application's part of the frame: submitted before the timing.
            let mut enc = ctx.encoder("bench clear");
            self.frame.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
            ctx.submit_and_wait("bench clear", enc)
                .map_err(|e| e.to_string())?;
            let ms = self.stamps.time(ctx, |enc| {
                draw(ctx, self.frame_marcher, enc, self.frame, src, view, &shaded)
            })?;
            let march = self.stamps.time(ctx, |enc| {
                march_only(ctx, self.frame_marcher, enc, src, view, &shaded)
            })?;
            if i >= self.warmup {
                frame_ms.push(ms);
                march_ms.push(march);
            }
        }
        let read = |output: Output| -> Result<Vec<[f32; 4]>, String> {
            let rs = RaymarchSettings { output, ..shaded };
            let mut enc = ctx.encoder("bench readback");
            self.targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
            draw(ctx, self.marcher, &mut enc, self.targets, src, view, &rs)?;
            ctx.submit_and_wait("bench readback", enc)
                .map_err(|e| e.to_string())?;
            read_texture(ctx, &self.targets.colour).map_err(|e| e.to_string())
        };
        let steps = step_stats(&read(Output::Steps)?, max_steps);
        let normals = read(Output::Normal)?;
        let (rms_err, max_err, mismatch) = self.reference.compare(&normals);
        Ok(Measured {
            frame_ms: median(frame_ms),
            march_ms: median(march_ms),
            steps,
            hits: normals.iter().filter(|p| p[3] != 0.0).count(),
            rms_err,
            max_err,
            mismatch,
        })
    }
}

/// Steps per ray for direct tracing: global-bound sphere tracing needs thousands.
const DIRECT_MAX_STEPS: u32 = 4096;

struct StepStats {
    mean: f64,
    p95: u32,
    /// Fraction of marched pixels that used every step.
    at_cap: f64,
}

/// Steps per marched pixel (pixels whose ray enters the box), from an `Output::Steps` image
/// (r + g + b = 3 × steps / max_steps).
fn step_stats(px: &[[f32; 4]], max_steps: u32) -> StepStats {
    let mut steps: Vec<u32> = px
        .iter()
        .filter(|p| p[3] != 0.0)
        .map(|p| ((p[0] + p[1] + p[2]) as f64 / 3.0 * max_steps as f64).round() as u32)
        .collect();
    if steps.is_empty() {
        return StepStats {
            mean: 0.0,
            p95: 0,
            at_cap: 0.0,
        };
    }
    steps.sort_unstable();
    let n = steps.len() as f64;
    StepStats {
        mean: steps.iter().map(|&s| s as f64).sum::<f64>() / n,
        p95: steps[(steps.len() * 95 / 100).min(steps.len() - 1)],
        at_cap: steps.iter().filter(|&&s| s >= max_steps).count() as f64 / n,
    }
}

/// The f64 reference: first crossing of the analytic field along sampled pixels' rays, with the
/// blobs binned on the CPU so each sample sums only nearby blobs.
struct Reference {
    /// (pixel index, first hit distance from the near plane in world units).
    samples: Vec<(usize, Option<f64>)>,
}

impl Reference {
    fn new(voxels: &[Vec4], edge: f32, s: &Settings, view: &View, grid: &Grid) -> Self {
        let radius = |v: &Vec4| s.radius(edge, v.w) as f64;
        let r_max = voxels.iter().map(radius).fold(0.0, f64::max).max(1e-6);
        let lo = grid.origin;
        let hi = lo + glam::DVec3::from_array(grid.size.map(|n| n as f64)) * grid.voxel;
        let n = ((hi - lo) / r_max).ceil().max(glam::DVec3::ONE);
        let dims = [n.x as usize, n.y as usize, n.z as usize];
        let mut bins: Vec<Vec<(DVec3, f64)>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
        let bin_of = |p: DVec3| -> [usize; 3] {
            let b = ((p - lo) / r_max).floor();
            [0, 1, 2].map(|k| (b[k].max(0.0) as usize).min(dims[k] - 1))
        };
        for v in voxels.iter().filter(|v| v.w > 0.0) {
            let (c, r) = (v.truncate().as_dvec3(), radius(v));
            let (a, b) = (bin_of(c - r), bin_of(c + r));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        bins[(z * dims[1] + y) * dims[0] + x].push((c, r));
                    }
                }
            }
        }
        let field = |p: DVec3| -> f64 {
            let b = bin_of(p);
            bins[(b[2] * dims[1] + b[1]) * dims[0] + b[0]]
                .iter()
                .map(|&(c, r)| cpu::falloff((p - c).length_squared(), r))
                .sum()
        };
        let [w, h] = view.viewport;
        let total = (w * h) as usize;
        let stride = (total / 2048).max(1);
        let t_iso = s.threshold as f64;
        let step = 0.02 * edge as f64;
        let samples = (0..total)
            .step_by(stride)
            .map(|i| {
                let (near, dir, len) = crate::measure::pixel_ray(view, i);
                // The box along the ray.
                let inv_d = dir.recip();
                let (a, b) = ((lo - near) * inv_d, (hi - near) * inv_d);
                let t0 = a.min(b).max_element().max(0.0);
                let t1 = a.max(b).min_element().min(len);
                let f = |t: f64| field(near + dir * t) - t_iso;
                let mut hit = None;
                let mut t = t0;
                while t < t1 {
                    let u = (t + step).min(t1);
                    if f(u) >= 0.0 {
                        let (mut p, mut q) = (t, u);
                        for _ in 0..50 {
                            let m = 0.5 * (p + q);
                            if f(m) >= 0.0 { q = m } else { p = m }
                        }
                        hit = Some(0.5 * (p + q));
                        break;
                    }
                    t = u;
                }
                (i, hit)
            })
            .collect();
        Self { samples }
    }

    /// RMS and max hit-distance error (edges, pixels both hit) and the % of samples where one
    /// side hits and the other does not, for an `Output::Normal` image (alpha = 1 + distance).
    fn compare(&self, px: &[[f32; 4]]) -> (f64, f64, f64) {
        let (mut sum2, mut max, mut both, mut off) = (0.0, 0.0f64, 0usize, 0usize);
        for &(i, hit) in &self.samples {
            let got = (px[i][3] != 0.0).then(|| px[i][3] as f64 - 1.0);
            match (hit, got) {
                (Some(a), Some(b)) => {
                    let e = (a - b).abs();
                    sum2 += e * e;
                    max = max.max(e);
                    both += 1;
                }
                (None, None) => {}
                _ => off += 1,
            }
        }
        (
            (sum2 / both.max(1) as f64).sqrt(),
            max,
            100.0 * off as f64 / self.samples.len().max(1) as f64,
        )
    }
}

/// Frame time against RMS error, log axes: a point per tracer (and grid), a colour per voxel set.
fn chart(path: &std::path::Path, adapter: &str, rows: &[Row]) -> Result<(), String> {
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .map(|r| crate::chart::Point {
            group: format!("{} instances", r.instances),
            ms: r.m.frame_ms,
            err: r.m.rms_err,
            label: if r.grid == "bins" {
                format!("{} ({:.0} steps)", r.method, r.m.steps.mean)
            } else {
                let how = r.method.trim_start_matches("SDF ");
                format!("SDF {how} {} ({:.0} steps)", r.grid, r.m.steps.mean)
            },
        })
        .collect();
    let axes = crate::chart::Axes {
        caption: format!("metaball: frame time vs RMS hit error, {adapter}"),
        x: "frame time, ms (march + composite, median, log)",
        y: "RMS hit distance error, voxel edges (log)",
        floor: 1e-4,
    };
    crate::chart::time_vs_error(path, &axes, &points)
}
