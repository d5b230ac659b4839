//! `cargo xtask bench voxelize`: GPU time of conservative surface voxelization (compute and
//! the write-up's raster path; `resident`: a `GpuMesh` uploaded once, the passes alone, as
//! cuda_voxelizer's kernel is timed; `refill`: the same into one surface kept across runs,
//! `encode_surface_placed_into`, its recorded clear included), solid fill and averaged attributes, for the mesh given
//! with `--mesh` (an OBJ file, read by tobj: the 69 451-triangle Stanford bunny the peers were
//! measured on; or the npm `bunny`'s `index.js` from `scripts/fetch-bunny.sh`, also split twice,
//! 59 k triangles) and a procedural torus of about a million triangles, in grids of 128³ to
//! 1024³ fitted to each mesh. Time: GPU timestamps around the whole encode (clear, passes, heavy-triangle work
//! list; for attributes both halves, without the read-back between them), median of the
//! timed runs. On a hardware adapter each timed submission follows a 20 ms spin kernel
//! (`heater`): the CPU side of a run leaves the GPU idle long enough for its clocks to fall.
//! Writes `voxelize.csv` and `voxelize.png` (time against the voxel edge relative to the mesh's
//! longest side).
//!
//! `--sizes 512,256,512` times those grid sizes in that order. `--replot voxelize.csv` draws
//! the chart from a saved table without measuring. Surface and solid rows also print each
//! pass's time (`Profiler::record` around `encode_surface_with`); `resident` and `refill`
//! rows the CPU's time to record and submit a run. With `FIELDKIT_BENCH_SHUFFLED` set, the split bunny
//! is also timed with its triangles in a
//! scattered order (neighbours in the list no longer neighbours on the surface). `--modes
//! empty,zeroed,cleared,loaded` adds the floor rows of `floor.rs`: an empty pass timed the same
//! way (`FIELDKIT_BENCH_FLOOR_THREADS` sets its threads).

use fieldkit::gpu::Context;
use fieldkit::voxelize::{Mesh, Surface, Voxelizer};
use glam::DVec3;

use crate::floor::EmptyPass;
use crate::measure::{Stamps, median};

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args)
}

/// An OBJ file (tobj), or the npm package `bunny`'s `index.js`.
fn load_bunny(path: &std::path::Path) -> Result<Mesh, String> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        return Mesh::load_obj(path).map_err(|e| e.to_string());
    }
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    Mesh::from_positions_cells(&text).map_err(|e| format!("{}: {e}", path.display()))
}

struct Row {
    mesh: String,
    triangles: usize,
    n: u32,
    mode: &'static str,
    ms: f64,
    ms_batched: f64,
    voxels: usize,
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// Encodes per submission for the back-to-back figure.
const BATCH: usize = 10;

fn bench(args: &crate::measure::Args) -> Result<(), String> {
    if let Some(csv) = &args.replot {
        let (adapter, rows) = read_table(csv)?;
        chart(&args.out, &adapter, &rows)?;
        println!("wrote {}", args.out.join("voxelize.png").display());
        return Ok(());
    }
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    // Each run transforms and uploads the mesh on the CPU, leaving the GPU mostly idle and its
    // clocks falling; a 20 ms spin before each timed submission keeps them up (`heater`). Not on
    // a software adapter, whose clocks are the CPU's.
    let heater = crate::heater::Heater::for_gpu(&ctx, 20.0)?;
    let mut v = Voxelizer::new(&ctx.device).map_err(|e| e.to_string())?;
    let empty = EmptyPass::new(&ctx);
    // `FIELDKIT_BENCH_FLOOR_THREADS=174000`: the floor rows' threads (default: one a triangle).
    let floor_threads = match std::env::var("FIELDKIT_BENCH_FLOOR_THREADS") {
        Ok(t) => Some(
            t.parse::<u64>()
                .map_err(|e| format!("FIELDKIT_BENCH_FLOOR_THREADS {t:?}: {e}"))?,
        ),
        Err(_) => None,
    };
    // `FIELDKIT_BENCH_LISTINGS=auto,16:4:0:64,4:4:1:32`: time the surface rows with each way
    // of cutting triangles into threads (light columns : chunk columns : sorted : workgroup;
    // `auto`, the default, picks per mesh).
    let listings = listings()?;
    let mut meshes = Vec::new();
    match &args.mesh {
        Some(path)
            if path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("obj")) =>
        {
            let mesh = load_bunny(path)?;
            let name = path
                .file_stem()
                .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
            meshes.push((name, mesh));
        }
        Some(path) => {
            let bunny = load_bunny(path)?;
            // The npm bunny is the 3.7 k-triangle scan; split twice it is the same surface in
            // 59 k triangles, the size of the 70 k original.
            let fine = bunny.subdivided().subdivided();
            meshes.push(("bunny".to_string(), bunny));
            if std::env::var_os("FIELDKIT_BENCH_SHUFFLED").is_some() {
                // The same triangles in a scattered order: neighbours in the list are then not
                // neighbours on the surface, so their atomics hit different words.
                let mut shuffled = fine.clone();
                let n = shuffled.triangles.len();
                let step = (0..)
                    .map(|k| n / 2 + 1 + k)
                    .find(|&s| gcd(s, n) == 1)
                    .unwrap_or(1);
                shuffled.triangles = (0..n).map(|i| fine.triangles[i * step % n]).collect();
                meshes.push(("bunny, split twice, shuffled".to_string(), shuffled));
            }
            meshes.push(("bunny, split twice".to_string(), fine));
        }
        None => println!(
            "no --mesh: pass --mesh stanford-bunny.obj (the peers' mesh), or run \
             scripts/fetch-bunny.sh and pass --mesh target/bunny/index.js"
        ),
    }
    let (segments, sides) = if args.quick { (200, 100) } else { (1000, 500) };
    // `FIELDKIT_BENCH_NO_TORUS`: the given mesh alone.
    if std::env::var_os("FIELDKIT_BENCH_NO_TORUS").is_none() {
        meshes.push((
            format!("torus {segments}×{sides}"),
            Mesh::torus(DVec3::ZERO, 1.0, 0.35, segments, sides),
        ));
    }
    let sizes: &[u32] = if args.quick {
        &[64, 128]
    } else {
        &[128, 256, 512, 1024]
    };
    println!(
        "| mesh | triangles | grid | mode | ms (min–max) | ms, {BATCH} back to back | voxels |\n|---|---|---|---|---|---|---|"
    );
    let mut rows = Vec::new();
    // `--sizes` picks sizes and their order (a size may repeat).
    let sizes: Vec<u32> = if args.sizes.is_empty() {
        sizes.to_vec()
    } else {
        args.sizes.iter().map(|&n| n as u32).collect()
    };
    for (listing, suffix) in &listings {
        v.set_listing(&ctx.device, *listing)
            .map_err(|e| e.to_string())?;
        for (name, mesh) in &meshes {
            let name = &format!("{name}{suffix}");
            for &n in &sizes {
                let grid = fieldkit::voxelize::Grid::fit(mesh, n).map_err(|e| e.to_string())?;
                // Uploaded once: the `resident` rows time the passes alone.
                let resident = fieldkit::voxelize::GpuMesh::upload(&ctx.device, mesh)
                    .map_err(|e| e.to_string())?;
                for mode in [
                    "surface",
                    "resident",
                    "refill",
                    "raster",
                    "solid",
                    "attributes",
                    "empty",
                    "zeroed",
                    "cleared",
                    "loaded",
                ] {
                    // The floor rows (`floor.rs`) only where named.
                    let floor = matches!(mode, "empty" | "zeroed" | "cleared" | "loaded");
                    if (args.modes.is_empty() && floor)
                        || (!args.modes.is_empty() && !args.modes.iter().any(|m| m == mode))
                    {
                        continue;
                    }
                    if floor {
                        let threads = floor_threads.unwrap_or(mesh.triangles.len() as u64);
                        let bytes = grid.voxels().div_ceil(32) * 4;
                        let kept = EmptyPass::buffer(&ctx, bytes);
                        let t = time_rows(&ctx, &stamps, heater.as_ref(), args, |enc| {
                            let fresh;
                            let words = if mode == "zeroed" {
                                fresh = EmptyPass::buffer(&ctx, bytes);
                                &fresh
                            } else {
                                &kept
                            };
                            if mode == "cleared" {
                                enc.clear_buffer(words, 0, None);
                            }
                            empty.record(&ctx, enc, words, threads, mode == "loaded")
                        })?;
                        let what = (name.as_str(), mesh.triangles.len(), n, mode);
                        let last = format!("{bytes} bytes, {threads} threads");
                        report(&mut rows, what, grid.size, t, 0, &last);
                        continue;
                    }
                    // A mode the mesh is refused for (attributes or a solid fill of an open
                    // mesh) is skipped with the reason, and the other rows still timed and written.
                    let skipped = |e: &dyn std::fmt::Display| {
                        println!("| {name} | {:?} | {mode} | skipped: {e} |", grid.size);
                    };
                    // The attribute list is sized from the occupied count, read once here.
                    let occupied = if mode == "attributes" {
                        match ctx.block_on(v.attributes(&ctx.device, &ctx.queue, mesh, &grid)) {
                            Ok(a) => a.count,
                            Err(e) => {
                                skipped(&e);
                                continue;
                            }
                        }
                    } else {
                        0
                    };
                    // `refill`: the resident mesh into one surface kept across runs.
                    let kept = std::cell::RefCell::new(None::<Surface>);
                    // `Ok(None)`: the run refilled `kept`.
                    let encode =
                        |enc: &mut wgpu::CommandEncoder| -> Result<Option<Surface>, String> {
                            let placed = [(&resident, glam::DMat4::IDENTITY)];
                            let conservative = fieldkit::voxelize::Separation::Conservative;
                            match mode {
                                "refill" => {
                                    let mut kept = kept.borrow_mut();
                                    return match kept.as_mut() {
                                        Some(s) => v.encode_surface_placed_into(
                                            &ctx.device,
                                            enc,
                                            &placed,
                                            &grid,
                                            conservative,
                                            s,
                                        ),
                                        None => v
                                            .encode_surface_placed(
                                                &ctx.device,
                                                enc,
                                                &placed,
                                                &grid,
                                                conservative,
                                            )
                                            .map(|s| *kept = Some(s)),
                                    }
                                    .map(|()| None)
                                    .map_err(|e| e.to_string());
                                }
                                "surface" => v.encode_surface(&ctx.device, enc, mesh, &grid),
                                "resident" => v.encode_surface_placed(
                                    &ctx.device,
                                    enc,
                                    &placed,
                                    &grid,
                                    conservative,
                                ),
                                "raster" => v.encode_surface_raster(&ctx.device, enc, mesh, &grid),
                                "solid" => v.encode_solid(&ctx.device, enc, mesh, &grid, true),
                                _ => v.encode_attributes(&ctx.device, enc, mesh, &grid).and_then(
                                    |p| {
                                        v.encode_resolve_attributes(&ctx.device, enc, p, occupied)
                                            .map(|a| a.surface)
                                    },
                                ),
                            }
                            .map(Some)
                            .map_err(|e| e.to_string())
                        };
                    if let Err(e) = encode(&mut ctx.encoder("probe")) {
                        skipped(&e);
                        continue;
                    }
                    let t = time_rows(&ctx, &stamps, heater.as_ref(), args, |enc| {
                        encode(enc).map(|_| ())
                    })?;
                    if mode == "resident" || mode == "refill" {
                        // What the CPU spends a frame: recording (buffers made here) and the
                        // submission (where wgpu records the zeroing of new buffers), the GPU's
                        // work waited for outside the time, the surface dropped after it.
                        let (host, lo, hi) = crate::measure::host_times(&ctx, args.reps, encode)?;
                        println!("  host (record + submit): {host:.4} ms ({lo:.4}–{hi:.4})");
                    }
                    if mode == "surface" || mode == "resident" || mode == "solid" {
                        // Each pass on its own (the clears between them are not passes).
                        let (total, _, _, passes) = crate::measure::time_runs(
                            &ctx,
                            args.warmup,
                            args.reps,
                            heater.as_ref(),
                            |enc, prof| {
                                let r = if mode == "surface" {
                                    v.encode_surface_with(
                                        &ctx.device,
                                        &mut prof.record(enc),
                                        mesh,
                                        &grid,
                                        fieldkit::voxelize::Separation::Conservative,
                                    )
                                } else if mode == "resident" {
                                    v.encode_surface_placed(
                                        &ctx.device,
                                        &mut prof.record(enc),
                                        &[(&resident, glam::DMat4::IDENTITY)],
                                        &grid,
                                        fieldkit::voxelize::Separation::Conservative,
                                    )
                                } else {
                                    v.encode_solid(
                                        &ctx.device,
                                        &mut prof.record(enc),
                                        mesh,
                                        &grid,
                                        true,
                                    )
                                };
                                r.expect("encode");
                            },
                        )?;
                        let list: Vec<String> = passes
                            .iter()
                            .map(|(n, ms)| format!("{n} {ms:.4}"))
                            .collect();
                        println!(
                            "  passes ({total:.4} ms first to last): {}",
                            list.join(", ")
                        );
                    }
                    let mut enc = ctx.encoder("count");
                    let s = encode(&mut enc)?;
                    ctx.submit_and_wait("count", enc)
                        .map_err(|e| e.to_string())?;
                    let kept = kept.borrow();
                    let voxels = s
                        .as_ref()
                        .or(kept.as_ref())
                        .ok_or("no surface to count")?
                        .read(&ctx.device, &ctx.queue)
                        .wait(&ctx)
                        .map_err(|e| e.to_string())?
                        .iter()
                        .filter(|&&o| o)
                        .count();
                    let what = (name.as_str(), mesh.triangles.len(), n, mode);
                    report(&mut rows, what, grid.size, t, voxels, &voxels.to_string());
                }
            }
        }
    }
    let csv = crate::measure::write_table(
        &args.out,
        "voxelize.csv",
        "adapter,mesh,triangles,grid,mode,ms,ms_back_to_back,voxels",
        rows.iter().map(|r| {
            format!(
                "\"{adapter}\",\"{}\",{},{},{},{:.4},{:.4},{}",
                r.mesh, r.triangles, r.n, r.mode, r.ms, r.ms_batched, r.voxels
            )
        }),
    )?;
    chart(&args.out, &adapter, &rows)?;
    println!("wrote {} and voxelize.png", csv.display());
    Ok(())
}

/// Print a row of the table, (mesh, triangles, grid edge, mode) `what` with timing `t` (median,
/// min, max, back to back) and `last` in the last column, and keep it.
fn report(
    rows: &mut Vec<Row>,
    what: (&str, usize, u32, &'static str),
    size: [u32; 3],
    t: (f64, f64, f64, f64),
    voxels: usize,
    last: &str,
) {
    let (mesh, triangles, n, mode) = what;
    let (ms, lo, hi, ms_batched) = t;
    println!(
        "| {mesh} | {triangles} | {size:?} | {mode} | {ms:.4} ({lo:.4}–{hi:.4}) | {ms_batched:.4} | {last} |"
    );
    rows.push(Row {
        mesh: mesh.to_string(),
        triangles,
        n,
        mode,
        ms,
        ms_batched,
        voxels,
    });
}

/// Median, min and max of `args.reps` timed runs of `record` (each its own submission after
/// the heater), after a warm-up of at least WARMUP_TIME, and the median time per run of BATCH
/// runs recorded into one submission.
fn time_rows(
    ctx: &Context,
    stamps: &Stamps,
    heater: Option<&crate::heater::Heater>,
    args: &crate::measure::Args,
    record: impl Fn(&mut wgpu::CommandEncoder) -> Result<(), String>,
) -> Result<(f64, f64, f64, f64), String> {
    // Sub-millisecond rows read up to 3× slow after a few runs while the clocks are still low.
    let start = std::time::Instant::now();
    let mut warm = 0;
    while warm < args.warmup.max(3) || start.elapsed() < crate::measure::WARMUP_TIME {
        stamps.time_after(ctx, heater, &record)?;
        warm += 1;
    }
    let mut times = Vec::new();
    for _ in 0..args.reps {
        times.push(stamps.time_after(ctx, heater, &record)?);
    }
    let (lo, hi) = times
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), &t| (l.min(t), h.max(t)));
    let ms = median(times);
    // The same runs BATCH times in one submission: the GPU never idles between runs, so this
    // is the steady rate, free of clock ramps and submit gaps.
    let mut batched = Vec::new();
    for _ in 0..args.reps.div_ceil(BATCH).max(3) {
        let total =
            stamps.time_after(ctx, heater, |enc| (0..BATCH).try_for_each(|_| record(enc)))?;
        batched.push(total / BATCH as f64);
    }
    Ok((ms, lo, hi, median(batched)))
}

/// `FIELDKIT_BENCH_LISTINGS`, or the default listing alone (no suffix on the mesh names).
fn listings() -> Result<Vec<(Option<fieldkit::voxelize::Listing>, String)>, String> {
    let Ok(text) = std::env::var("FIELDKIT_BENCH_LISTINGS") else {
        return Ok(vec![(None, String::new())]);
    };
    text.split(',')
        .map(|item| {
            if item.trim() == "auto" {
                return Ok((None, " [auto]".to_string()));
            }
            let f: Vec<u32> = item
                .split(':')
                .map(|x| x.trim().parse::<u32>())
                .collect::<Result<_, _>>()
                .map_err(|e| format!("FIELDKIT_BENCH_LISTINGS {item:?}: {e}"))?;
            let [light, chunk, sort, workgroup] = f[..] else {
                return Err(format!(
                    "FIELDKIT_BENCH_LISTINGS {item:?}: light:chunk:sort:workgroup"
                ));
            };
            Ok((
                Some(fieldkit::voxelize::Listing {
                    light,
                    chunk,
                    sort: sort != 0,
                    workgroup,
                }),
                format!(
                    " [L{light} C{chunk}{} wg{workgroup}]",
                    if sort != 0 { " sorted" } else { "" }
                ),
            ))
        })
        .collect()
}

fn chart(out: &std::path::Path, adapter: &str, rows: &[Row]) -> Result<(), String> {
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .map(|r| crate::chart::Point {
            group: format!("{}, {}", r.mesh, r.mode),
            ms: r.ms,
            err: 1.0 / r.n as f64,
            label: format!("{}³", r.n),
        })
        .collect();
    let axes = crate::chart::Axes {
        caption: format!("voxelization: GPU time vs voxel edge, {adapter}"),
        x: "GPU time, ms (median, log)",
        y: "voxel edge / longest side of the mesh (log)",
        floor: 1e-4,
    };
    crate::chart::time_vs_error(&out.join("voxelize.png"), &axes, &points)
}

/// `--replot`: the adapter and rows of a `voxelize.csv`.
fn read_table(path: &std::path::Path) -> Result<(String, Vec<Row>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut adapter = String::new();
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let fields = crate::measure::csv_fields(line);
        let bad = || format!("{} line {}: {line}", path.display(), i + 1);
        let [a, mesh, triangles, n, mode, ms, ms_batched, voxels] = &fields[..] else {
            return Err(bad());
        };
        let mode = ["surface", "resident", "raster", "solid", "attributes"]
            .into_iter()
            .find(|m| m == mode)
            .ok_or_else(bad)?;
        adapter.clone_from(a);
        rows.push(Row {
            mesh: mesh.clone(),
            triangles: triangles.parse().map_err(|_| bad())?,
            n: n.parse().map_err(|_| bad())?,
            mode,
            ms: ms.parse().map_err(|_| bad())?,
            ms_batched: ms_batched.parse().map_err(|_| bad())?,
            voxels: voxels.parse().map_err(|_| bad())?,
        });
    }
    Ok((adapter, rows))
}

#[cfg(test)]
mod tests {
    /// `--replot` reads back what the bench writes: quoted adapter and mesh names keep their
    /// commas, and a malformed line is an error naming it.
    #[test]
    fn replot_reads_the_written_table() {
        let (dir, csv) = crate::measure::scratch_file("replot-voxelize", "voxelize.csv");
        std::fs::write(
            &csv,
            "adapter,mesh,triangles,grid,mode,ms,ms_back_to_back,voxels\n\
             \"GPU (Vulkan, DiscreteGpu)\",\"bunny, split twice\",58784,512,surface,0.110,0.111,841648\n",
        )
        .unwrap();
        let (adapter, rows) = super::read_table(&csv).unwrap();
        assert_eq!(adapter, "GPU (Vulkan, DiscreteGpu)");
        assert_eq!(rows.len(), 1);
        let r = &rows[0];
        assert_eq!(
            (
                r.mesh.as_str(),
                r.triangles,
                r.n,
                r.mode,
                r.ms,
                r.ms_batched,
                r.voxels
            ),
            (
                "bunny, split twice",
                58784,
                512,
                "surface",
                0.110,
                0.111,
                841648
            )
        );
        std::fs::write(&csv, "header\n\"a\",\"b\",1,2,sideways,0.1,0.1,3\n").unwrap();
        let e = super::read_table(&csv)
            .err()
            .expect("an unknown mode is refused");
        assert!(e.contains("line 2"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
