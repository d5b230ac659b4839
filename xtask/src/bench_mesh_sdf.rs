//! `cargo xtask bench mesh-sdf`: a mesh's signed distance field, time against error.
//!
//! For the mesh given with `--mesh` (an OBJ file: the 69 451-triangle Stanford bunny, open at
//! its base) and three analytic meshes (a UV sphere and a torus of about 65 k triangles, a
//! 12-triangle box), in grids of 64³ to 512³ fitted to each (`--quick`: 32³, 64³):
//! - `mesh sdf`: `MeshSdf::encode`, band ±4 voxels, signed; GPU timestamps around the whole
//!   encode (clears, three passes), median of `--reps` timed runs with min–max, each after the
//!   heater (`heater`), and each pass's median;
//! - `voxel centres`: the path there was before, `Voxelizer::encode_solid` (closed meshes; the
//!   surface alone for open ones, unsigned) → `encode_volume` → `Distance3d::encode` (exact,
//!   band 4): distances to the nearest occupied voxel's centre, timed the same way;
//! - the Rust crate `mesh_to_sdf` 0.4 (CPU, every core of this machine, `SignMethod::Raycast`
//!   and `Normal`) up to 128³ (64³ with `--quick`): wall time of `generate_grid_sdf`, median of
//!   up to 5 runs;
//! - with `--peer CMD` (`python3 scripts/peers/warp_mesh_sdf.py`, NVIDIA Warp's GPU mesh
//!   queries), the command's bakes of the whole grid and of the band, timed by itself (CUDA
//!   events around the BVH build and the query; `--reps` runs up to 128³, 5 past it; the
//!   winding-number sign up to 64³, as it takes seconds a bake past it) and read back for the
//!   same comparison.
//!
//! Error against an f64 reference (brute-force nearest triangle; sign by the generalized
//! winding number, inside above ½) on up to 1 500 voxels the field puts within the band and
//! 500 it puts beyond, chosen by a fixed stride: max and RMS distance error inside the band,
//! in voxels, and the voxels signed otherwise than the winding number (beyond the band the
//! sign alone is compared). Writes `mesh_sdf.csv` (every mesh) and `mesh_sdf.png` (time against
//! max error for the first mesh).

use fieldkit::distance::{Distance3d, Settings3d};
use fieldkit::gpu::{Context, read_texture};
use fieldkit::mesh_sdf::{MeshSdf, Settings, cpu};
use fieldkit::shaders::mesh_sdf::mesh_sdf::Overrides;
use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
use glam::DVec3;

const BAND: f32 = 4.0;
const IN_BAND_SAMPLES: usize = 1500;
const BEYOND_SAMPLES: usize = 500;

struct Row {
    mesh: String,
    triangles: usize,
    n: u32,
    method: String,
    ms: f64,
    lo: f64,
    hi: f64,
    error: Error,
}

/// How a field compares with the reference on the samples.
#[derive(Clone, Copy, Default)]
struct Error {
    max: f64,
    rms: f64,
    /// Samples within the band by the reference, and those signed otherwise than it.
    in_band: usize,
    wrong_in_band: usize,
    /// Samples beyond the band, and those signed otherwise.
    beyond: usize,
    wrong_beyond: usize,
}

/// The reference at the sampled voxels: unsigned distance (voxels) and inside by winding number.
struct Samples {
    voxels: Vec<[u32; 3]>,
    distance: Vec<f64>,
    inside: Vec<bool>,
}

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    let (ctx, adapter, _) = crate::measure::bench_gpu()?;
    let heater = crate::heater::Heater::for_gpu(&ctx, 20.0)?;
    let sizes: Vec<u32> = if !args.sizes.is_empty() {
        args.sizes.iter().map(|&n| n as u32).collect()
    } else if args.quick {
        vec![32, 64]
    } else {
        vec![64, 128, 256, 512]
    };
    let peer_max = if args.quick { 64 } else { 128 };
    println!(
        "| mesh | triangles | grid | method | ms (min–max) | max error, voxels | RMS | wrong signs in the band / samples | beyond / samples |\n|---|---|---|---|---|---|---|---|---|"
    );
    let mut rows = Vec::new();
    // `FIELDKIT_BENCH_OURS_ONLY`: the given mesh's `mesh sdf` rows alone, in each layout of the
    // per-triangle pass (a quick look at a change): no analytic meshes, no voxel-centre path,
    // no peers.
    let ours_only = std::env::var_os("FIELDKIT_BENCH_OURS_ONLY").is_some();
    let mut meshes = meshes(args)?;
    if ours_only {
        meshes.truncate(1);
    }
    for (name, mesh, closed) in meshes {
        for &n in &sizes {
            let grid = Grid::fit(&mesh, n).map_err(|e| e.to_string())?;
            let what = (name.as_str(), mesh.triangles.len(), n);
            let (t, field) = time_mesh_sdf(
                &ctx,
                heater.as_ref(),
                args,
                &mesh,
                &grid,
                Overrides::default(),
            )?;
            let samples = reference(&mesh, &grid, &field)?;
            rows.push(report(
                what,
                "mesh sdf",
                t,
                compare(&samples, &grid, &field),
            ));
            if ours_only {
                // The per-triangle pass's other layouts, beside the default.
                for (method, layout) in layouts() {
                    let (t, field) =
                        time_mesh_sdf(&ctx, heater.as_ref(), args, &mesh, &grid, layout)?;
                    rows.push(report(what, method, t, compare(&samples, &grid, &field)));
                }
                continue;
            }
            let (t, field) = time_voxel_centres(&ctx, heater.as_ref(), args, &mesh, &grid, closed)?;
            let method = if closed {
                "voxel centres (solid)"
            } else {
                "voxel centres (surface, unsigned)"
            };
            rows.push(report(what, method, t, compare(&samples, &grid, &field)));
            if let Some(peer) = &args.peer {
                for (method, t, field) in run_peer(peer, args, &mesh, &grid)? {
                    rows.push(report(what, &method, t, compare(&samples, &grid, &field)));
                }
            }
            if n <= peer_max {
                for (method, sign) in [
                    ("mesh_to_sdf raycast", mesh_to_sdf::SignMethod::Raycast),
                    ("mesh_to_sdf normal", mesh_to_sdf::SignMethod::Normal),
                ] {
                    let (t, field) = time_peer(args, &mesh, &grid, sign);
                    rows.push(report(what, method, t, compare(&samples, &grid, &field)));
                }
            }
        }
    }
    let csv = crate::measure::write_table(
        &args.out,
        "mesh_sdf.csv",
        "adapter,mesh,triangles,grid,method,ms,ms_min,ms_max,max_error_voxels,rms_error_voxels,wrong_signs_in_band,in_band,wrong_signs_beyond,beyond",
        rows.iter().map(|r| {
            format!(
                "\"{adapter}\",\"{}\",{},{},\"{}\",{:.4},{:.4},{:.4},{:.3e},{:.3e},{},{},{},{}",
                r.mesh,
                r.triangles,
                r.n,
                r.method,
                r.ms,
                r.lo,
                r.hi,
                r.error.max,
                r.error.rms,
                r.error.wrong_in_band,
                r.error.in_band,
                r.error.wrong_beyond,
                r.error.beyond
            )
        }),
    )?;
    chart(&args.out, &adapter, &rows)?;
    println!("wrote {} and mesh_sdf.png", csv.display());
    Ok(())
}

/// The `--mesh` OBJ (open: its sign is compared, not required) and the analytic meshes.
fn meshes(args: &crate::measure::Args) -> Result<Vec<(String, Mesh, bool)>, String> {
    let mut meshes = Vec::new();
    match &args.mesh {
        Some(path) => {
            let mesh = Mesh::load_obj(path).map_err(|e| e.to_string())?;
            let name = path
                .file_stem()
                .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
            let closed = mesh.open_edge().is_none();
            meshes.push((name, mesh, closed));
        }
        None => println!("no --mesh: pass --mesh stanford-bunny.obj (the peers' mesh)"),
    }
    let (segments, rings) = if args.quick { (64, 32) } else { (256, 128) };
    meshes.push((
        format!("sphere {segments}×{rings}"),
        Mesh::uv_sphere(DVec3::ZERO, 1.0, segments, rings),
        true,
    ));
    meshes.push((
        format!("torus {segments}×{rings}"),
        Mesh::torus(DVec3::ZERO, 1.0, 0.35, segments, rings),
        true,
    ));
    meshes.push((
        "box".into(),
        Mesh::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.6, 0.3)),
        true,
    ));
    Ok(meshes)
}

type Timed = ((f64, f64, f64), Vec<f32>);

/// The per-triangle pass's layouts besides the default, by name: the crossings in the
/// triangle's workgroup, and every offer's atomic without a load first.
fn layouts() -> [(&'static str, Overrides); 2] {
    let default = Overrides::default();
    let in_workgroup = Overrides {
        cross_apart: false,
        ..default
    };
    let no_load = Overrides {
        load_first: false,
        ..default
    };
    [
        ("mesh sdf, crossings in the workgroup", in_workgroup),
        ("mesh sdf, no load first", no_load),
    ]
}

/// A peer's row: its method, its time (median, min, max) and its field.
type PeerRow = (String, (f64, f64, f64), Vec<f32>);

fn time_mesh_sdf(
    ctx: &Context,
    heater: Option<&crate::heater::Heater>,
    args: &crate::measure::Args,
    mesh: &Mesh,
    grid: &Grid,
    layout: Overrides,
) -> Result<Timed, String> {
    let sdf = MeshSdf::with_layout(&ctx.device, layout).map_err(|e| e.to_string())?;
    let settings = Settings {
        band: BAND,
        ..Default::default()
    };
    let (ms, lo, hi, passes) =
        crate::measure::time_runs(ctx, args.warmup, args.reps, heater, |enc, prof| {
            sdf.encode(&ctx.device, &mut prof.record(enc), mesh, grid, &settings)
                .expect("mesh sdf");
        })?;
    let list: Vec<String> = passes
        .iter()
        .map(|(n, ms)| format!("{n} {ms:.4}"))
        .collect();
    println!("  passes: {}", list.join(", "));
    let mut enc = ctx.encoder("mesh sdf");
    let field = sdf
        .encode(&ctx.device, &mut enc, mesh, grid, &settings)
        .map_err(|e| e.to_string())?;
    ctx.submit_and_wait("mesh sdf", enc)
        .map_err(|e| e.to_string())?;
    Ok((
        (ms, lo, hi),
        read_texture(ctx, &field.texture).map_err(|e| e.to_string())?,
    ))
}

fn time_voxel_centres(
    ctx: &Context,
    heater: Option<&crate::heater::Heater>,
    args: &crate::measure::Args,
    mesh: &Mesh,
    grid: &Grid,
    closed: bool,
) -> Result<Timed, String> {
    let voxelizer = Voxelizer::new(&ctx.device).map_err(|e| e.to_string())?;
    let distance = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    let settings = Settings3d {
        signed: closed,
        voxel_size: grid.voxel as f32,
        band: Some(BAND),
        ..Default::default()
    };
    let encode = |rec: &mut fieldkit::gpu::Recorder| -> Result<wgpu::Texture, fieldkit::Error> {
        let surface = if closed {
            voxelizer.encode_solid(&ctx.device, rec, mesh, grid, true)?
        } else {
            voxelizer.encode_surface(&ctx.device, rec, mesh, grid)?
        };
        let volume = voxelizer.encode_volume(&ctx.device, rec, &surface)?;
        Ok(distance
            .encode(&ctx.device, rec, &volume, &settings)?
            .distance)
    };
    let (ms, lo, hi, _) =
        crate::measure::time_runs(ctx, args.warmup, args.reps, heater, |enc, prof| {
            encode(&mut prof.record(enc)).expect("voxel centres");
        })?;
    let mut enc = ctx.encoder("voxel centres");
    let field =
        encode(&mut fieldkit::gpu::Record::recorder(&mut enc)).map_err(|e| e.to_string())?;
    ctx.submit_and_wait("voxel centres", enc)
        .map_err(|e| e.to_string())?;
    Ok((
        (ms, lo, hi),
        read_texture(ctx, &field).map_err(|e| e.to_string())?,
    ))
}

/// `mesh_to_sdf::generate_grid_sdf` on the same voxel centres, in fieldkit's voxel order.
fn time_peer(
    args: &crate::measure::Args,
    mesh: &Mesh,
    grid: &Grid,
    sign: mesh_to_sdf::SignMethod,
) -> ((f64, f64, f64), Vec<f32>) {
    let vertices: Vec<[f32; 3]> = mesh
        .positions
        .iter()
        .map(|p| p.as_vec3().to_array())
        .collect();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let first = grid.voxel_centre([0, 0, 0]).as_vec3().to_array();
    let size = grid.size.map(|s| s as usize);
    let peer_grid = mesh_to_sdf::Grid::new(first, [grid.voxel as f32; 3], size);
    let run = || {
        mesh_to_sdf::generate_grid_sdf(
            &vertices,
            mesh_to_sdf::Topology::TriangleList(Some(&indices)),
            &peer_grid,
            sign,
        )
    };
    let mut times = Vec::new();
    let mut out = Vec::new();
    for _ in 0..args.reps.clamp(1, 5) {
        let start = std::time::Instant::now();
        out = run();
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    let (lo, hi) = times
        .iter()
        .fold((f64::MAX, 0f64), |(l, h), &t| (l.min(t), h.max(t)));
    let mut field = vec![0f32; out.len()];
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                field[(z * size[1] + y) * size[0] + x] = out[peer_grid.get_cell_idx(&[x, y, z])];
            }
        }
    }
    ((crate::measure::median(times), lo, hi), field)
}

/// The `--peer` command on the same mesh and grid, the whole grid (band 0) and a band of
/// BAND voxels: its rows (`ROW method|ms|min|max|query ms|field file`), each field read back.
fn run_peer(
    peer: &str,
    args: &crate::measure::Args,
    mesh: &Mesh,
    grid: &Grid,
) -> Result<Vec<PeerRow>, String> {
    let dir = std::env::temp_dir();
    let mesh_file = dir.join(format!("fieldkit_mesh_sdf_{}.bin", std::process::id()));
    let mut bytes = Vec::new();
    bytes.extend((mesh.positions.len() as u32).to_le_bytes());
    bytes.extend((mesh.triangles.len() as u32).to_le_bytes());
    for p in &mesh.positions {
        bytes.extend(bytemuck::cast_slice(&p.as_vec3().to_array()));
    }
    for t in &mesh.triangles {
        bytes.extend(bytemuck::cast_slice(t));
    }
    std::fs::write(&mesh_file, bytes).map_err(|e| e.to_string())?;
    let mut rows = Vec::new();
    for band in [0.0, BAND] {
        let out = dir.join(format!("fieldkit_mesh_sdf_{}", std::process::id()));
        let o = grid.origin;
        let [nx, ny, nz] = grid.size;
        // A whole-grid bake at 512³ takes the peer seconds: 5 runs past 128³. Its winding
        // number took 1.7 s at 64³ and 10 s at 128³ on the H200 (the bunny): 64³ and below.
        let side = nx.max(ny).max(nz);
        let reps = if side > 128 {
            args.reps.min(5)
        } else {
            args.reps
        };
        let methods = if side > 64 {
            "normal"
        } else {
            "winding,normal"
        };
        let command = format!(
            "{peer} --mesh {} --origin={},{},{} --voxel {} --size {nx},{ny},{nz} --band {band} --reps {reps} --methods {methods} --out {}",
            mesh_file.display(),
            o.x,
            o.y,
            o.z,
            grid.voxel,
            out.display()
        );
        let output = crate::measure::stdout_of(
            std::process::Command::new("sh").args(["-c", &command]),
            &command,
        )?;
        for line in output.lines() {
            let Some(row) = line.strip_prefix("ROW ") else {
                continue;
            };
            let f: Vec<&str> = row.split('|').collect();
            let [name, ms, lo, hi, query, path] = f[..] else {
                return Err(format!("peer row {line:?}"));
            };
            let num = |s: &str| s.parse::<f64>().map_err(|e| format!("{line:?}: {e}"));
            let field: Vec<f32> = std::fs::read(path)
                .map_err(|e| format!("{path}: {e}"))?
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            std::fs::remove_file(path).ok();
            let which = if band > 0.0 {
                format!("band {BAND}")
            } else {
                "whole grid".into()
            };
            println!("  {name}, {which}: query alone {query} ms");
            rows.push((
                format!("{name} ({which})"),
                (num(ms)?, num(lo)?, num(hi)?),
                field,
            ));
        }
    }
    std::fs::remove_file(&mesh_file).ok();
    Ok(rows)
}

/// Samples chosen from `field` (world units): up to IN_BAND_SAMPLES voxels it puts within the
/// band and BEYOND_SAMPLES beyond, by a fixed stride, each measured against the f64 reference
/// on every core.
fn reference(mesh: &Mesh, grid: &Grid, field: &[f32]) -> Result<Samples, String> {
    let local = mesh.to_grid(grid).map_err(|e| e.to_string())?;
    let triangles = cpu::triangles(&local);
    // Beyond the band a field holds ±band rounded to f32, which may lie a rounding below the
    // f64 band: a thousandth of it apart tells them from the band's own voxels.
    let band = BAND as f64 * grid.voxel * 0.999;
    let near: Vec<usize> = (0..field.len())
        .filter(|&i| (field[i] as f64).abs() < band)
        .collect();
    let far: Vec<usize> = (0..field.len())
        .filter(|&i| (field[i] as f64).abs() >= band)
        .collect();
    let pick = |from: &[usize], k: usize| -> Vec<usize> {
        let step = (from.len() / k.max(1)).max(1);
        from.iter().step_by(step).take(k).copied().collect()
    };
    let mut chosen = pick(&near, IN_BAND_SAMPLES);
    chosen.extend(pick(&far, BEYOND_SAMPLES));
    let [nx, ny, _] = grid.size;
    let voxels: Vec<[u32; 3]> = chosen
        .iter()
        .map(|&i| {
            let i = i as u32;
            [i % nx, (i / nx) % ny, i / (nx * ny)]
        })
        .collect();
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let chunk = voxels.len().div_ceil(threads).max(1);
    let measured: Vec<(f64, bool)> = std::thread::scope(|s| {
        let handles: Vec<_> = voxels
            .chunks(chunk)
            .map(|part| {
                let triangles = &triangles;
                s.spawn(move || {
                    part.iter()
                        .map(|&v| {
                            let p = cpu::centre(v);
                            (
                                cpu::distance(p, triangles),
                                cpu::winding_number(p, triangles) > 0.5,
                            )
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("reference thread"))
            .collect()
    });
    Ok(Samples {
        voxels,
        distance: measured.iter().map(|m| m.0).collect(),
        inside: measured.iter().map(|m| m.1).collect(),
    })
}

/// `field` (world units) against the reference: distance error within the band (voxels), and
/// signs at every sample off the surface.
fn compare(samples: &Samples, grid: &Grid, field: &[f32]) -> Error {
    let [nx, ny, _] = grid.size;
    let band = BAND as f64;
    let mut e = Error::default();
    let mut squares = 0.0;
    for ((v, &d), &inside) in samples
        .voxels
        .iter()
        .zip(&samples.distance)
        .zip(&samples.inside)
    {
        let i = ((v[2] * ny + v[1]) * nx + v[0]) as usize;
        let value = field[i] as f64 / grid.voxel;
        // A centre on the surface has no side.
        let wrong = d > 1e-3 && (value < 0.0) != inside;
        if d < band {
            let err = (value.abs() - d).abs();
            e.max = e.max.max(err);
            squares += err * err;
            e.in_band += 1;
            e.wrong_in_band += wrong as usize;
        } else {
            e.beyond += 1;
            e.wrong_beyond += wrong as usize;
        }
    }
    e.rms = (squares / e.in_band.max(1) as f64).sqrt();
    e
}

fn report(what: (&str, usize, u32), method: &str, t: (f64, f64, f64), error: Error) -> Row {
    let (mesh, triangles, n) = what;
    let (ms, lo, hi) = t;
    println!(
        "| {mesh} | {triangles} | {n}³ | {method} | {ms:.4} ({lo:.4}–{hi:.4}) | {:.2e} | {:.2e} | {} / {} | {} / {} |",
        error.max, error.rms, error.wrong_in_band, error.in_band, error.wrong_beyond, error.beyond
    );
    Row {
        mesh: mesh.to_string(),
        triangles,
        n,
        method: method.to_string(),
        ms,
        lo,
        hi,
        error,
    }
}

/// Time against max error, one colour a method, for the first mesh (the `--mesh` given, the
/// peers' bunny; every mesh's rows are in the table).
fn chart(out: &std::path::Path, adapter: &str, rows: &[Row]) -> Result<(), String> {
    let Some(first) = rows.first().map(|r| r.mesh.clone()) else {
        return Ok(());
    };
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .filter(|r| r.mesh == first)
        .map(|r| crate::chart::Point {
            group: r.method.clone(),
            ms: r.ms,
            err: r.error.max,
            label: format!("{}³", r.n),
        })
        .collect();
    let axes = crate::chart::Axes {
        caption: format!(
            "{first}: distance field, time vs max error in the ±4-voxel band, {adapter}"
        ),
        x: "time, ms (median, log; GPU timestamps, mesh_to_sdf CPU wall)",
        y: "max |error|, voxels (log)",
        floor: 1e-6,
    };
    crate::chart::time_vs_error(&out.join("mesh_sdf.png"), &axes, &points)
}
