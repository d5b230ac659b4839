//! `cargo xtask bench grazing`: metaballs seen at grazing angles, every way of drawing them
//! graded pixel by pixel against an f64 reference of the analytic field, and timed.
//!
//! Scenes: two blobs merged into a capsule seen nearly along its axis (twice), a row of six
//! seen along the row, and 100 blobs at random seen low over the set. Methods: the SDF march
//! as built by default (the texture brings rays near the surface, the blobs decide within two
//! cells of it), the texture alone at 4, 6 and 8 cells per blob edge, and the two direct
//! tracers. Each pixel whose exact ray meets the surface is binned by the incidence of that hit
//! (below 2°, 2–10°, 10–30°, above 30°); a wrong pixel is on the silhouette's rim where a
//! 4-neighbour's exact answer differs, else off it. Depth error is the hit distance against the
//! exact one, in cells of the default grid (a quarter of a blob edge). Time: GPU timestamps,
//! median of the timed runs, of the build (field or bins) and of the frame (march + composite)
//! at 1920×1080 (480×270 with `--quick`); the grading is at a quarter of that size per axis.
//! Writes `grazing.csv`, `grazing_misses.png` and `grazing_depth.png`.

use std::io::Write;

use fieldkit::gpu::read_texture;
use fieldkit::metaball::{Direct, Metaballs, Output, RayEnd, RaymarchSettings, Raymarcher};
use fieldkit::metaball::{ExactSurface, Settings, cpu};
use fieldkit::view::{Targets, View};
use glam::{Mat4, Vec3, Vec4};

use crate::measure::median;

/// Incidence bins, degrees: below 2, 2–10, 10–30, 30 and above.
const BINS: [f64; 3] = [2.0, 10.0, 30.0];
const BIN_NAMES: [&str; 4] = ["<2°", "2–10°", "10–30°", "≥30°"];

fn bin_of(deg: f64) -> usize {
    BINS.iter().take_while(|&&b| deg >= b).count()
}

/// One scene: name, blobs (centre, scale; edge 1), eye, target.
type SceneDef = (String, Vec<Vec4>, Vec3, Vec3);

fn scenes() -> Vec<SceneDef> {
    let capsule = [-0.35f32, 0.35]
        .map(|x| Vec4::new(x, 0.0, 0.0, 1.0))
        .to_vec();
    let row = (0..6)
        .map(|i| Vec4::new(-1.25 + 0.5 * i as f32, 0.02 * i as f32, 0.0, 1.0))
        .collect();
    // 100 blobs at random (a fixed seed), about a radius apart.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32
    };
    let side = 100f32.cbrt() * 0.9;
    let many = (0..100)
        .map(|_| {
            let c = Vec3::new(next() - 0.5, (next() - 0.5) * 0.3, next() - 0.5) * side;
            c.extend(0.7 + 0.5 * next())
        })
        .collect();
    vec![
        (
            "capsule along its axis".into(),
            capsule.clone(),
            Vec3::new(3.2, 0.35, 0.25),
            Vec3::new(0.0, 0.1, 0.0),
        ),
        (
            "capsule from above its axis".into(),
            capsule,
            Vec3::new(2.6, 1.2, 0.1),
            Vec3::new(-0.2, 0.0, 0.0),
        ),
        (
            "a row of six along the row".into(),
            row,
            Vec3::new(4.0, 0.45, 0.3),
            Vec3::new(0.0, 0.1, 0.0),
        ),
        (
            "100 blobs, low".into(),
            many,
            Vec3::new(side * 2.2, 0.6, side * 0.7),
            Vec3::ZERO,
        ),
    ]
}

fn view(eye: Vec3, target: Vec3, size: [u32; 2]) -> View {
    let proj = glam::camera::rh::proj::directx::perspective(
        0.7,
        size[0] as f32 / size[1] as f32,
        0.05,
        40.0,
    );
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
        viewport: size,
        reversed_z: false,
        origin: [0, 0],
    }
}

/// Each pixel's exact hit: distance from the near plane and incidence in degrees
/// (`cpu::ray_hit_near`: f64, steps of 0.004 edges, then bisection).
fn reference(view: &View, voxels: &[Vec4], s: &Settings) -> Vec<Option<(f64, f64)>> {
    let [w, h] = view.viewport;
    let pixel = |i: usize| -> Option<(f64, f64)> {
        let (o, d, len) = crate::measure::pixel_ray(view, i);
        let t = cpu::ray_hit_near(voxels, 1.0, s, o, d, len, 0.004)?;
        let n = cpu::gradient_at(voxels, 1.0, s, o + d * t).normalize();
        Some((t, n.dot(d).abs().asin().to_degrees()))
    };
    (0..(w * h) as usize).map(pixel).collect()
}

/// One method's grade on one scene.
#[derive(Default, Clone)]
struct Grade {
    hits: [usize; 4],
    false_misses: [usize; 4],
    off_rim_misses: usize,
    false_hits: usize,
    off_rim_hits: usize,
    /// Squared depth errors summed, their count, and the largest (cells), per incidence bin,
    /// over hits on the right surface.
    depth: [(f64, usize, f64); 4],
    /// Hits more than a cell from the exact one (a surface behind one the ray grazes), and of
    /// them off the rim (where no 4-neighbour's exact hit lies more than two cells away).
    wrong_surface: usize,
    off_rim_wrong_surface: usize,
    ran_out: usize,
}

fn grade(exact: &[Option<(f64, f64)>], got: &[[f32; 4]], size: [u32; 2], cell: f64) -> Grade {
    let [w, h] = size.map(|s| s as i64);
    let hit = |x: i64, y: i64| {
        (x >= 0 && y >= 0 && x < w && y < h).then(|| exact[(y * w + x) as usize].is_some())
    };
    let t_at = |x: i64, y: i64| {
        (x >= 0 && y >= 0 && x < w && y < h)
            .then(|| exact[(y * w + x) as usize].map(|e| e.0))
            .flatten()
    };
    let mut g = Grade {
        ran_out: RayEnd::count_ran_out(got),
        ..Grade::default()
    };
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let me = exact[i].is_some();
            let rim = [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|(dx, dy)| hit(x + dx, y + dy).is_some_and(|o| o != me));
            let mine = matches!(
                RayEnd::of(got[i]),
                Some(RayEnd::Hit | RayEnd::RanOutTakenAsHit)
            )
            .then_some(got[i][0] as f64);
            match (exact[i], mine) {
                (Some((t, deg)), m) => {
                    let b = bin_of(deg);
                    g.hits[b] += 1;
                    match m {
                        None => {
                            g.false_misses[b] += 1;
                            g.off_rim_misses += usize::from(!rim);
                        }
                        Some(u) => {
                            let e = (u - t).abs() / cell;
                            if e > 1.0 {
                                let edge =
                                    [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|(dx, dy)| {
                                        t_at(x + dx, y + dy)
                                            .is_some_and(|o| (o - t).abs() > 2.0 * cell)
                                    });
                                g.wrong_surface += 1;
                                g.off_rim_wrong_surface += usize::from(!edge);
                            } else {
                                let d = &mut g.depth[b];
                                *d = (d.0 + e * e, d.1 + 1, d.2.max(e));
                            }
                        }
                    }
                }
                (None, Some(_)) => {
                    g.false_hits += 1;
                    g.off_rim_hits += usize::from(!rim);
                }
                (None, None) => {}
            }
        }
    }
    g
}

/// How a method draws: the SDF march of a field built with these settings, or a direct tracer.
#[derive(Clone, Copy)]
enum How {
    Sdf(Settings),
    Direct(Direct),
}

fn methods() -> Vec<(String, How, RaymarchSettings)> {
    let texture = |cells: f32| Settings {
        cells_per_edge: cells,
        exact_surface: ExactSurface::Off,
        ..Settings::default()
    };
    let shell = |shell: f32, margin: f32| RaymarchSettings {
        exact_shell: shell,
        exact_margin: margin,
        ..RaymarchSettings::default()
    };
    let rs = RaymarchSettings::default();
    let mut out: Vec<(String, How, RaymarchSettings)> = vec![(
        "SDF + blobs near the surface (default: shell 2, margin 1.5 cells)".into(),
        How::Sdf(Settings::default()),
        rs,
    )];
    for (sh, m) in [(1.0, 0.75), (1.5, 1.0), (3.0, 2.0)] {
        out.push((
            format!("SDF + blobs, shell {sh}, margin {m} cells"),
            How::Sdf(Settings::default()),
            shell(sh, m),
        ));
    }
    for cells in [4.0, 6.0, 8.0] {
        out.push((
            format!("SDF texture alone, {cells} cells/edge"),
            How::Sdf(texture(cells)),
            rs,
        ));
    }
    out.push((
        "direct, global bound".into(),
        How::Direct(Direct::SphereGlobal),
        rs,
    ));
    out.push((
        "direct, segment tracing".into(),
        How::Direct(Direct::Segment),
        rs,
    ));
    out
}

struct Row {
    scene: String,
    method: String,
    build_ms: f64,
    frame_ms: f64,
    grade: Grade,
}

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    let timed: [u32; 2] = if args.quick { [480, 270] } else { [1920, 1080] };
    let graded = timed.map(|s| s / 4);
    let depth = wgpu::TextureFormat::Depth32Float;
    let make = |format, size| -> Result<(Raymarcher, Targets), String> {
        Ok((
            Raymarcher::new(&ctx.device, &ctx.queue, format, depth, false)
                .map_err(|e| e.to_string())?,
            Targets::new(&ctx.device, size, format, depth),
        ))
    };
    let rig = Rig {
        balls: Metaballs::new(&ctx.device).map_err(|e| e.to_string())?,
        frame: make(wgpu::TextureFormat::Rgba8Unorm, timed)?,
        read: make(wgpu::TextureFormat::Rgba32Float, graded)?,
        ctx: &ctx,
        stamps: &stamps,
        args,
    };
    let cell = 1.0 / Settings::default().cells_per_edge as f64;
    let mut rows = Vec::new();
    println!(
        "| scene | method | build ms | frame ms | false misses {} | off rim | false hits (off rim) | wrong surface (off rim) | depth RMS / max, cells {} | ran out |",
        BIN_NAMES.join(" / "),
        BIN_NAMES.join(" / ")
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (scene, voxels, eye, target) in scenes() {
        let exact = reference(&view(eye, target, graded), &voxels, &Settings::default());
        let inst = rig
            .balls
            .upload(&ctx.device, &ctx.queue, &voxels)
            .map_err(|e| e.to_string())?;
        for (method, how, rs) in methods() {
            let (build_ms, made) = rig.time_build(&inst, &voxels, how)?;
            let frame_ms = rig.time_frames(&made, &view(eye, target, timed), &rs)?;
            let numbers = RaymarchSettings {
                output: Output::Distance,
                ..rs
            };
            let (marcher, targets) = &rig.read;
            let mut enc = ctx.encoder("bench readback");
            targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
            made.draw(
                &ctx,
                marcher,
                targets,
                &view(eye, target, graded),
                &numbers,
                &mut enc,
            )?;
            ctx.submit_and_wait("bench readback", enc)
                .map_err(|e| e.to_string())?;
            let got: Vec<[f32; 4]> =
                read_texture(&ctx, &targets.colour).map_err(|e| e.to_string())?;
            let row = Row {
                scene: scene.clone(),
                method,
                build_ms,
                frame_ms,
                grade: grade(&exact, &got, graded, cell),
            };
            println!("{}", table_line(&row));
            rows.push(row);
        }
    }
    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
    write_csv(
        &args.out.join("grazing.csv"),
        &adapter,
        timed,
        graded,
        &rows,
    )?;
    charts(&args.out, &adapter, &rows)?;
    println!("wrote {}", args.out.join("grazing.csv").display());
    Ok(())
}

/// What every method is measured with: the field builder, a raymarcher and targets for the
/// timed frame (8-bit, full size) and for the graded readback (float, a quarter per axis).
struct Rig<'a> {
    ctx: &'a fieldkit::gpu::Context,
    stamps: &'a crate::measure::Stamps,
    args: &'a crate::measure::Args,
    balls: Metaballs,
    frame: (Raymarcher, Targets),
    read: (Raymarcher, Targets),
}

impl Rig<'_> {
    /// The build of `how` (a field, or the bins), timed: its median ms, and what the last run
    /// made.
    fn time_build(
        &self,
        inst: &fieldkit::metaball::Instances,
        voxels: &[Vec4],
        how: How,
    ) -> Result<(f64, Made), String> {
        let (ctx, balls) = (self.ctx, &self.balls);
        let s = match how {
            How::Sdf(s) => s,
            How::Direct(_) => Settings::default(),
        };
        let grid = s
            .fit_grid(voxels, 1.0)
            .map_err(|e| e.to_string())?
            .ok_or("an empty scene")?;
        let mut builds = Vec::new();
        let mut made = None;
        for i in 0..self.args.warmup + self.args.reps {
            let ms = self.stamps.time(ctx, |enc| {
                let e = |e: fieldkit::Error| e.to_string();
                made = Some(match how {
                    How::Sdf(_) => Made::Field(Box::new(
                        balls
                            .encode(&ctx.device, enc, inst, &grid, 1.0, &s)
                            .map_err(e)?,
                    )),
                    How::Direct(m) => Made::Bins(
                        balls
                            .encode_bins(&ctx.device, enc, inst, &grid, 1.0, &s)
                            .map_err(e)?,
                        m,
                    ),
                });
                Ok(())
            })?;
            if i >= self.args.warmup {
                builds.push(ms);
            }
        }
        Ok((median(builds), made.ok_or("no build ran")?))
    }

    /// The frame (march + composite) into cleared targets, timed: its median ms.
    fn time_frames(&self, made: &Made, view: &View, rs: &RaymarchSettings) -> Result<f64, String> {
        let ctx = self.ctx;
        let (marcher, targets) = &self.frame;
        let mut frames = Vec::new();
        for i in 0..self.args.warmup + self.args.reps {
            // Clearing is the application's part of the frame: submitted before the timing.
            let mut enc = ctx.encoder("bench clear");
            targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
            ctx.submit_and_wait("bench clear", enc)
                .map_err(|e| e.to_string())?;
            let ms = self
                .stamps
                .time(ctx, |enc| made.draw(ctx, marcher, targets, view, rs, enc))?;
            if i >= self.args.warmup {
                frames.push(ms);
            }
        }
        Ok(median(frames))
    }
}

/// What a build made: a field for the SDF march, or bins for a direct tracer.
enum Made {
    Field(Box<fieldkit::metaball::MetaballField>),
    Bins(fieldkit::metaball::BlobBins, Direct),
}

impl Made {
    fn draw(
        &self,
        ctx: &fieldkit::gpu::Context,
        marcher: &Raymarcher,
        targets: &Targets,
        v: &View,
        rs: &RaymarchSettings,
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<(), String> {
        let (cv, dv) = (&targets.colour_view, &targets.depth_view);
        let m = Mat4::IDENTITY;
        match self {
            Made::Field(f) => marcher.encode(&ctx.device, enc, cv, dv, f, m, v, rs),
            Made::Bins(b, d) => marcher.encode_direct(&ctx.device, enc, cv, dv, b, *d, m, v, rs),
        }
        .map(|_| ())
        .map_err(|e| e.to_string())
    }
}

fn rms(d: (f64, usize, f64)) -> f64 {
    (d.0 / d.1.max(1) as f64).sqrt()
}

fn table_line(r: &Row) -> String {
    let g = &r.grade;
    let per_bin = |f: &dyn Fn(usize) -> String| (0..4).map(f).collect::<Vec<_>>().join(" / ");
    format!(
        "| {} | {} | {:.3} | {:.3} | {} | {} | {} ({}) | {} ({}) | {} | {} |",
        r.scene,
        r.method,
        r.build_ms,
        r.frame_ms,
        per_bin(&|b| format!("{} of {}", g.false_misses[b], g.hits[b])),
        g.off_rim_misses,
        g.false_hits,
        g.off_rim_hits,
        g.wrong_surface,
        g.off_rim_wrong_surface,
        per_bin(&|b| format!("{:.3}/{:.3}", rms(g.depth[b]), g.depth[b].2)),
        g.ran_out
    )
}

fn write_csv(
    path: &std::path::Path,
    adapter: &str,
    timed: [u32; 2],
    graded: [u32; 2],
    rows: &[Row],
) -> Result<(), String> {
    let mut csv = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let e = |e: std::io::Error| e.to_string();
    writeln!(
        csv,
        "adapter,timed_at,graded_at,scene,method,build_ms,frame_ms,incidence,exact_hits,false_misses,depth_rms_cells,depth_max_cells,off_rim_misses,false_hits,off_rim_hits,wrong_surface,off_rim_wrong_surface,ran_out"
    )
    .map_err(e)?;
    for r in rows {
        let g = &r.grade;
        for (b, bin) in BIN_NAMES.iter().enumerate() {
            writeln!(
                csv,
                "\"{adapter}\",{}x{},{}x{},{},{},{:.4},{:.4},{},{},{},{:.5},{:.5},{},{},{},{},{},{}",
                timed[0],
                timed[1],
                graded[0],
                graded[1],
                r.scene,
                r.method,
                r.build_ms,
                r.frame_ms,
                bin,
                g.hits[b],
                g.false_misses[b],
                rms(g.depth[b]),
                g.depth[b].2,
                g.off_rim_misses,
                g.false_hits,
                g.off_rim_hits,
                g.wrong_surface,
                g.off_rim_wrong_surface,
                g.ran_out
            )
            .map_err(e)?;
        }
    }
    Ok(())
}

/// Per method and scene: build + frame time against (a) false misses below 10° and every
/// wrong pixel off the rim, per 1 000 exact hits below 10°, and (b) RMS depth error.
fn charts(out: &std::path::Path, adapter: &str, rows: &[Row]) -> Result<(), String> {
    let point = |r: &Row, err: f64| crate::chart::Point {
        group: r.scene.clone(),
        ms: r.build_ms + r.frame_ms,
        err,
        label: r.method.clone(),
    };
    let misses: Vec<_> = rows
        .iter()
        .map(|r| {
            let g = &r.grade;
            let low = g.hits[0] + g.hits[1];
            let wrong = g.false_misses[0]
                + g.false_misses[1]
                + g.off_rim_misses
                + g.off_rim_hits
                + g.off_rim_wrong_surface;
            point(r, 1000.0 * wrong as f64 / low.max(1) as f64)
        })
        .collect();
    crate::chart::time_vs_error(
        &out.join("grazing_misses.png"),
        &crate::chart::Axes {
            caption: format!(
                "metaballs at grazing angles: build + frame vs wrong pixels, {adapter}"
            ),
            x: "build + frame, ms (median, log)",
            y: "false misses below 10° and wrong pixels off the rim, per 1 000 hits below 10° (log)",
            floor: 0.1,
        },
        &misses,
    )?;
    let depth: Vec<_> = rows
        .iter()
        .map(|r| {
            let all = r.grade.depth.iter().fold((0.0, 0, 0.0f64), |a, d| {
                (a.0 + d.0, a.1 + d.1, a.2.max(d.2))
            });
            point(r, rms(all))
        })
        .collect();
    crate::chart::time_vs_error(
        &out.join("grazing_depth.png"),
        &crate::chart::Axes {
            caption: format!(
                "metaballs at grazing angles: build + frame vs depth error, {adapter}"
            ),
            x: "build + frame, ms (median, log)",
            y: "RMS hit distance error, cells of the default grid (log)",
            floor: 1e-4,
        },
        &depth,
    )
}
