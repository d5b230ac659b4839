//! `cargo xtask bench octree`: the sparse voxel octree against the dense bitset, for the mesh
//! given with `--mesh` (an OBJ: the Stanford bunny) and a procedural torus of about a million
//! triangles, in grids fitted to each mesh from 128³ to 8192³ (`--sizes` picks; `--quick`: 64³
//! to 256³ and a smaller torus).
//!
//! Per grid: the GPU time of the whole build (fragment list and every level, with the list and
//! pool sized exactly by a first build), of the dense surface where a dense grid fits (sides up to
//! 4096 and 2³² voxels), and the bytes each keeps: the octree's pool (8 per node), the dense
//! bitset (a bit per voxel), and the build's transient peak (fragments, their cursors, the pool
//! it was built in). Then the render: a 1920×1080 first-hit frame of the largest grid's tree at
//! each level of detail and by footprint. Median of `--reps` runs (GPU timestamps), min–max beside;
//! on a hardware adapter a 20 ms spin before each timed submission keeps the clocks up.
//!
//! `--modes` limits the run to some of `build` (the build and dense timings), `render` and
//! `torus` (the procedural mesh); all by default.
//!
//! Writes `octree.csv`, `octree_render.csv`, `octree_memory.png` (bytes against grid side),
//! `octree_build.png` (build time against grid side) and `octree_render.png` (frame time
//! against level).

use fieldkit::gpu::Context;
use fieldkit::octree::{Lod, OctreeBuilder, OctreeCaster, RenderSettings};
use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
use glam::{DVec3, Vec3};

use crate::measure::{Stamps, median};

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args)
}

struct Row {
    mesh: String,
    n: u32,
    fragments: u64,
    voxels: u64,
    nodes: u64,
    pool_bytes: u64,
    peak_bytes: u64,
    dense_bytes: u64,
    build: (f64, f64, f64),
    dense: Option<(f64, f64, f64)>,
}

struct RenderRow {
    mesh: String,
    n: u32,
    lod: String,
    ms: (f64, f64, f64),
    covered: usize,
}

fn spread(times: Vec<f64>) -> (f64, f64, f64) {
    let lo = times.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = times.iter().cloned().fold(0.0, f64::max);
    (median(times), lo, hi)
}

fn timed(
    ctx: &Context,
    stamps: &Stamps,
    heater: Option<&crate::heater::Heater>,
    args: &crate::measure::Args,
    mut encode: impl FnMut(&mut wgpu::CommandEncoder) -> Result<(), String>,
) -> Result<(f64, f64, f64), String> {
    let start = std::time::Instant::now();
    let mut warm = 0;
    while warm < args.warmup.max(2) || start.elapsed() < crate::measure::WARMUP_TIME {
        stamps.time_after(ctx, heater, &mut encode)?;
        warm += 1;
    }
    let mut times = Vec::new();
    for _ in 0..args.reps {
        times.push(stamps.time_after(ctx, heater, &mut encode)?);
    }
    Ok(spread(times))
}

fn bench(args: &crate::measure::Args) -> Result<(), String> {
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    let heater = crate::heater::Heater::for_gpu(&ctx, 20.0)?;
    let e = |e: fieldkit::Error| e.to_string();
    let voxelizer = Voxelizer::new(&ctx.device).map_err(e)?;
    let builder = OctreeBuilder::new(&ctx.device).map_err(e)?;
    let caster = OctreeCaster::new();
    let mut meshes = Vec::new();
    if let Some(path) = &args.mesh {
        let mesh = Mesh::load_obj(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let name = path
            .file_stem()
            .map_or("mesh".into(), |s| s.to_string_lossy().into_owned());
        meshes.push((name, mesh));
    } else {
        println!("no --mesh: pass --mesh stanford-bunny.obj for the bunny");
    }
    let wants = |m: &str| args.modes.is_empty() || args.modes.iter().any(|x| x == m);
    let (segments, sides) = if args.quick { (200, 100) } else { (1000, 500) };
    if wants("torus") {
        meshes.push((
            format!("torus {segments}×{sides}"),
            Mesh::torus(DVec3::ZERO, 1.0, 0.35, segments, sides),
        ));
    }
    let sizes: Vec<u32> = if !args.sizes.is_empty() {
        args.sizes.iter().map(|&n| n as u32).collect()
    } else if args.quick {
        vec![64, 128, 256]
    } else {
        vec![128, 256, 512, 1024, 2048, 4096, 8192]
    };
    println!(
        "| mesh | grid | fragments | voxels | nodes | octree MiB | build peak MiB | dense MiB | build ms (min–max) | dense surface ms (min–max) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut rows = Vec::new();
    let mut renders = Vec::new();
    for (name, mesh) in &meshes {
        let mut largest = None;
        for &n in &sizes {
            let grid = Grid::fit(mesh, n).map_err(e)?;
            // A first build sizes the list and the pool exactly.
            let octree = match ctx.block_on(builder.voxelize(
                &ctx.device,
                &ctx.queue,
                &voxelizer,
                mesh,
                &grid,
                Separation::Conservative,
            )) {
                Ok(o) => o,
                Err(err) => {
                    println!("| {name} | {n}³ | skipped: {err} |");
                    continue;
                }
            };
            let tree = octree.read(&ctx.device, &ctx.queue).wait(&ctx).map_err(e)?;
            let mut enc = ctx.encoder("fragment count");
            let fragments = voxelizer
                .encode_fragments(
                    &ctx.device,
                    &mut enc,
                    mesh,
                    &grid,
                    Separation::Conservative,
                    None,
                )
                .map_err(e)?;
            ctx.submit_and_wait("fragment count", enc).map_err(e)?;
            // Every part's exact count: the longest sizes each part's list in the timed runs.
            let totals = fragments
                .totals(&ctx.device, &ctx.queue)
                .wait(&ctx)
                .map_err(e)?;
            let count: u64 = totals.iter().map(|&t| t as u64).sum();
            let longest = totals.iter().copied().max().unwrap_or(1).max(1);
            drop(fragments);
            let pool = tree.pool.len() as u32;
            let build = if !wants("build") {
                (0.0, 0.0, 0.0)
            } else {
                timed(&ctx, &stamps, heater.as_ref(), args, |enc| {
                    let f = voxelizer
                        .encode_fragments(
                            &ctx.device,
                            enc,
                            mesh,
                            &grid,
                            Separation::Conservative,
                            Some(longest),
                        )
                        .map_err(|e| e.to_string())?;
                    builder
                        .encode(&ctx.device, enc, &f, pool)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                })?
            };
            let dense = if wants("build")
                && grid.voxels() <= fieldkit::voxelize::MAX_VOXELS
                && grid.size.iter().all(|&s| s <= fieldkit::voxelize::MAX_SIDE)
                && grid.voxels() / 8 <= ctx.device.limits().max_storage_buffer_binding_size
            {
                Some(timed(&ctx, &stamps, heater.as_ref(), args, |enc| {
                    voxelizer
                        .encode_surface(&ctx.device, enc, mesh, &grid)
                        .map(|_| ())
                        .map_err(|e| e.to_string())
                })?)
            } else {
                None
            };
            let voxels: u64 = tree
                .pool
                .get(tree.starts[tree.leaf_level as usize] as usize..)
                .unwrap_or(&[])
                .iter()
                .map(|b| (b[0].count_ones() + b[1].count_ones()) as u64)
                .sum();
            let row = Row {
                mesh: name.clone(),
                n,
                fragments: count,
                voxels,
                nodes: pool as u64,
                pool_bytes: pool as u64 * 8,
                peak_bytes: count * 12 + pool as u64 * 8,
                dense_bytes: grid.voxels().div_ceil(8),
                build,
                dense,
            };
            let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
            let fmt = |t: (f64, f64, f64)| format!("{:.3} ({:.3}–{:.3})", t.0, t.1, t.2);
            println!(
                "| {name} | {:?} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {} | {} |",
                grid.size,
                row.fragments,
                row.voxels,
                row.nodes,
                mib(row.pool_bytes),
                mib(row.peak_bytes),
                mib(row.dense_bytes),
                fmt(row.build),
                row.dense.map_or("— (no dense grid)".into(), fmt),
            );
            rows.push(row);
            largest = Some((n, grid, octree));
        }
        // The render of the largest tree at every level and by footprint.
        let Some((n, grid, octree)) = largest else {
            continue;
        };
        if !wants("render") {
            continue;
        }
        let extent = grid.size.map(|s| s as f64 * grid.voxel);
        let centre = (grid.origin + DVec3::from(extent) * 0.5).as_vec3();
        let radius = DVec3::from(extent).length() as f32 * 0.5;
        let eye = centre + Vec3::new(0.9, 0.5, 1.3).normalize() * radius * 2.2;
        let view = fieldkit::view::View {
            view_proj: glam::camera::rh::proj::directx::perspective(
                0.7,
                1920.0 / 1080.0,
                radius * 0.05,
                radius * 6.0,
            ) * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
            viewport: [1920, 1080],
            reversed_z: false,
            origin: [0, 0],
        };
        let mut lods: Vec<Lod> = (2..=octree.log_side).map(Lod::Level).collect();
        lods.push(Lod::Footprint(1.0));
        for lod in lods {
            let settings = RenderSettings {
                lod,
                ..Default::default()
            };
            let ms = timed(&ctx, &stamps, heater.as_ref(), args, |enc| {
                caster
                    .encode_render(&ctx.device, enc, &octree, &grid, &view, &settings)
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            })?;
            let mut enc = ctx.encoder("coverage");
            let image = caster
                .encode_render(&ctx.device, &mut enc, &octree, &grid, &view, &settings)
                .map_err(e)?;
            ctx.submit_and_wait("coverage", enc).map_err(e)?;
            let px: Vec<[u8; 4]> =
                fieldkit::gpu::readback_texture(&ctx.device, &ctx.queue, &image.colour)
                    .wait(&ctx)
                    .map_err(e)?;
            let covered = px.iter().filter(|p| p[3] == 255).count();
            let label = match lod {
                Lod::Level(l) => format!("level {l}"),
                Lod::Footprint(p) => format!("footprint {p} px"),
            };
            println!(
                "  render {name} {n}³, {label}: {:.3} ms ({:.3}–{:.3}), {covered} pixels",
                ms.0, ms.1, ms.2
            );
            renders.push(RenderRow {
                mesh: name.clone(),
                n,
                lod: label,
                ms,
                covered,
            });
        }
    }
    let csv = crate::measure::write_table(
        &args.out,
        "octree.csv",
        "adapter,mesh,grid,fragments,voxels,nodes,octree_bytes,build_peak_bytes,dense_bytes,build_ms,build_min,build_max,dense_ms,dense_min,dense_max",
        rows.iter().map(|r| {
            let d = r
                .dense
                .map_or(",,".into(), |d| format!("{:.4},{:.4},{:.4}", d.0, d.1, d.2));
            format!(
                "\"{adapter}\",\"{}\",{},{},{},{},{},{},{},{:.4},{:.4},{:.4},{d}",
                r.mesh,
                r.n,
                r.fragments,
                r.voxels,
                r.nodes,
                r.pool_bytes,
                r.peak_bytes,
                r.dense_bytes,
                r.build.0,
                r.build.1,
                r.build.2
            )
        }),
    )?;
    crate::measure::write_table(
        &args.out,
        "octree_render.csv",
        "adapter,mesh,grid,lod,ms,min,max,covered_pixels",
        renders.iter().map(|r| {
            format!(
                "\"{adapter}\",\"{}\",{},{},{:.4},{:.4},{:.4},{}",
                r.mesh, r.n, r.lod, r.ms.0, r.ms.1, r.ms.2, r.covered
            )
        }),
    )?;
    charts(&args.out, &adapter, &rows, &renders)?;
    println!(
        "wrote {}, octree_render.csv, octree_memory.png, octree_build.png, octree_render.png",
        csv.display()
    );
    Ok(())
}

fn charts(
    out: &std::path::Path,
    adapter: &str,
    rows: &[Row],
    renders: &[RenderRow],
) -> Result<(), String> {
    let mut series: Vec<crate::chart::Series> = Vec::new();
    let mut times: Vec<crate::chart::Series> = Vec::new();
    let mut meshes: Vec<&str> = Vec::new();
    for mesh in rows
        .iter()
        .map(|r| r.mesh.as_str())
        .chain(renders.iter().map(|r| r.mesh.as_str()))
    {
        if !meshes.contains(&mesh) {
            meshes.push(mesh);
        }
    }
    for mesh in &meshes {
        let of = |f: &dyn Fn(&Row) -> Option<f64>| -> Vec<(f64, f64)> {
            rows.iter()
                .filter(|r| r.mesh == *mesh)
                .filter_map(|r| f(r).map(|y| (r.n as f64, y)))
                .collect()
        };
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        series.push((format!("{mesh}: octree"), of(&|r| Some(mib(r.pool_bytes)))));
        series.push((
            format!("{mesh}: octree build peak"),
            of(&|r| Some(mib(r.peak_bytes))),
        ));
        times.push((format!("{mesh}: octree build"), of(&|r| Some(r.build.0))));
        times.push((
            format!("{mesh}: dense surface"),
            of(&|r| r.dense.map(|d| d.0)),
        ));
    }
    series.push((
        "dense bitset".into(),
        rows.iter()
            .filter(|r| Some(r.mesh.as_str()) == meshes.first().copied())
            .map(|r| (r.n as f64, r.dense_bytes as f64 / (1u64 << 20) as f64))
            .collect(),
    ));
    // `--modes render` alone: no build rows to chart.
    if !rows.is_empty() {
        crate::chart::log_log(
            &out.join("octree_memory.png"),
            &format!("sparse voxel octree vs dense bitset: MiB kept, {adapter}"),
            "grid side (voxels, log)",
            "MiB (log)",
            &series,
        )?;
        crate::chart::log_log(
            &out.join("octree_build.png"),
            &format!("octree build vs dense surface: GPU ms (median), {adapter}"),
            "grid side (voxels, log)",
            "GPU ms (log)",
            &times,
        )?;
    }
    if renders.is_empty() {
        return Ok(());
    }
    let mut series: Vec<crate::chart::Series> = Vec::new();
    for mesh in meshes {
        let pts: Vec<(f64, f64)> = renders
            .iter()
            .filter(|r| r.mesh == mesh)
            .filter_map(|r| {
                r.lod
                    .strip_prefix("level ")
                    .and_then(|l| l.parse::<f64>().ok())
                    .map(|l| (2f64.powf(l), r.ms.0))
            })
            .collect();
        let n = renders.iter().find(|r| r.mesh == mesh).map_or(0, |r| r.n);
        series.push((format!("{mesh} ({n}³), 1920×1080"), pts));
    }
    crate::chart::log_log(
        &out.join("octree_render.png"),
        &format!("octree first-hit render: frame ms vs level of detail, {adapter}"),
        "cells per side at the level (2^level, log)",
        "GPU ms (median, log)",
        &series,
    )
}
