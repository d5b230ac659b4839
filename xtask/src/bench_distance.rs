//! `cargo xtask bench distance`: GPU time against accuracy for every distance method, variant
//! and size, with the peer (cupyx's PBA+) timed on the same mask where it is installed.
//!
//! GPU time comes from timestamp queries around every pass: a run's time is from the start of its
//! first pass to the end of its last; the figure reported is the median of `--reps` runs after
//! `--warmup` runs. Errors are counted against the exact transform (itself checked against the
//! peer's distances, or the CPU reference in `--quick` mode).

use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

use fieldkit::distance::{
    ColumnPasses, Distance3d, Method, Settings3d, tile_columns, tile_columns_3d, upload_volume,
};
use fieldkit::distance::{Jfa2d, JfaSettings2d, Variant, cpu, upload_mask};
use fieldkit::gpu::{Context, read_buffer, read_texture};

use crate::measure::{Args, time_runs};

/// Memory bandwidth the pass figures are compared with (H100 SXM HBM3, rounded down).
const PEAK_BYTES_PER_S: f64 = 3.0e12;

/// The exact transform with its column passes in global memory (`ColumnPasses::Global`).
const GLOBAL: &str = "exact (global columns)";

/// The exact transform with its column passes in workgroup memory wherever a tile fits
/// (`ColumnPasses::Workgroup`), so both paths are timed at every size.
const WORKGROUP: &str = "exact (workgroup columns)";

/// The exact transform with the 3D row pass as a pass of its own (its field written, then read
/// by the y pass) where the default folds it into the y pass.
const ROWS_PASS: &str = "exact (rows pass)";

/// The exact transform without the resolving global z pass's sweep (`Distance3d::set_sweep`):
/// every workgroup builds the envelopes.
const UNSWEPT: &str = "exact (no z sweep)";

/// One method at one size.
#[derive(Debug)]
struct Row {
    dims: u32,
    size: String,
    voxels: u64,
    method: String,
    median_ms: f64,
    min_ms: f64,
    max_ms: f64,
    wrong: u64,
    max_err: f64,
    mean_err: f64,
    peer_ms: Option<f64>,
    passes: Vec<(String, f64, f64)>,
}

/// Deterministic mask: voxel i is a seed when splitmix64(i ^ salt) falls below the density.
fn random_mask(n: usize, density: f64, salt: u64) -> Vec<u8> {
    let cut = (density * u64::MAX as f64) as u64;
    (0..n as u64)
        .map(|i| {
            let mut z = (i ^ salt).wrapping_add(0x9e3779b97f4a7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
            z ^= z >> 31;
            u8::from(z < cut)
        })
        .collect()
}

/// Bytes a pass must move at least (reads + writes of the fields it touches, per cell), used for
/// the bandwidth figure. Neighbour reads of JFA that hit the cache are not counted.
fn pass_bytes(name: &str, cells: u64, dims: u32) -> f64 {
    let per = if name.starts_with("row words") {
        // Mask read once, 8 bytes written per 32 voxels.
        1.0 + 8.0 / 32.0
    } else if name.ends_with("from row words") && name.contains("workgroup") {
        // Each row word read once (the tile's columns share it), each answer written once.
        8.0 / 32.0 + 4.0
    } else if name.ends_with("from row words") {
        // As above, plus the envelope stack written and read back.
        8.0 / 32.0 + 4.0 + 8.0
    } else if name.ends_with("sweep + resolve") {
        // A resolving pass that sweeps: field read, answer and distance written (the sweep's
        // check reads the field once more; the rest, below, reads and writes again what the
        // sweep left to it).
        4.0 + 4.0 + 4.0
    } else if name.ends_with("+ resolve (rest)") {
        // Counted in the sweep's floor above.
        0.0
    } else if name.starts_with("rows") && dims == 3 {
        // The row is held in workgroup memory: mask read once, seed written once.
        1.0 + 4.0
    } else if name.starts_with("rows") {
        // A 2D row is held as a bitmask: mask read once, seed written once.
        1.0 + 4.0
    } else if name.contains("workgroup") && name.ends_with("+ resolve") {
        // The tile is read once and each answer written once, plus the distance.
        12.0
    } else if name.contains("workgroup") {
        // The tile is read once and each answer written once.
        8.0
    } else if name.starts_with("columns") && name.ends_with("+ resolve") {
        // As below, plus the distance written.
        20.0
    } else if name.starts_with("columns") {
        // Field read, envelope written and read back, answer written.
        16.0
    } else if name.starts_with("jump") {
        8.0
    } else if name.starts_with("seed") {
        5.0
    } else {
        // resolve: nearest read, distance written.
        8.0
    };
    per * cells as f64
}

/// Squared distance per cell from packed seeds (3D as `unpack_seed3`, 2D 16/16); u64::MAX for none.
fn d2_of(nearest: &[u32], size: [usize; 3], dims: u32) -> Vec<u64> {
    let (w, h) = (size[0], size[1]);
    nearest
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            if s == 0 {
                return u64::MAX;
            }
            let (x, y, z) = ((i % w) as i64, ((i / w) % h) as i64, (i / (w * h)) as i64);
            let (sx, sy, sz) = if dims == 3 {
                let [sx, sy, sz] = fieldkit::distance::unpack_seed3(s).expect("not NO_SEED");
                (sx as i64, sy as i64, sz as i64)
            } else {
                ((s & 0xffff) as i64 - 1, (s >> 16) as i64 - 1, 0)
            };
            ((sx - x).pow(2) + (sy - y).pow(2) + (sz - z).pow(2)) as u64
        })
        .collect()
}

/// (wrong cells, max error, mean error) in voxels; with a band, distances are clamped to it first.
fn errors(got: &[u64], exact: &[u64], band: Option<f64>) -> (u64, f64, f64) {
    let clamp = |d2: u64| {
        let d = if d2 == u64::MAX {
            f64::INFINITY
        } else {
            (d2 as f64).sqrt()
        };
        band.map_or(d, |b| d.min(b))
    };
    let (mut wrong, mut max, mut sum) = (0u64, 0f64, 0f64);
    for (&g, &e) in got.iter().zip(exact) {
        // Equal values agree, "no seed" on both sides included (∞ − ∞ is NaN, not 0).
        if g == e {
            continue;
        }
        let err = clamp(g) - clamp(e);
        if err != 0.0 {
            wrong += 1;
            // "No seed" against a seed is an infinite error: the CSV and the table say `inf`,
            // and the chart draws it at its top.
            let err = if err.is_finite() {
                err.abs()
            } else {
                f64::INFINITY
            };
            max = max.max(err);
            sum += err;
        }
    }
    (wrong, max, sum / got.len() as f64)
}

struct Peer {
    ms: f64,
    /// Squared distances recovered from the peer's float32 distances (exact below 2^24).
    d2: Vec<u64>,
    json: String,
}

fn run_peer(cmd: &str, mask: &[u8], shape: &[usize], tag: &str) -> Result<Peer, String> {
    let dir = std::env::temp_dir();
    let mask_path = dir.join(format!("fieldkit_mask_{tag}.u8"));
    let dist_path = dir.join(format!("fieldkit_dist_{tag}.f32"));
    std::fs::write(&mask_path, mask).map_err(|e| e.to_string())?;
    let mut parts = cmd.split_whitespace();
    let program = parts.next().ok_or("empty --peer")?;
    let out = std::process::Command::new(program)
        .args(parts)
        .arg("--mask")
        .arg(&mask_path)
        .arg("--shape")
        .args(shape.iter().map(|s| s.to_string()))
        .arg("--write-dist")
        .arg(&dist_path)
        .output()
        .map_err(|e| format!("could not start the peer `{cmd}`: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "peer failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let json = String::from_utf8_lossy(&out.stdout)
        .lines()
        .last()
        .unwrap_or_default()
        .to_string();
    let v: serde_json::Value =
        serde_json::from_str(&json).map_err(|e| format!("peer printed `{json}`: {e}"))?;
    let ms = v["ms_median"]
        .as_f64()
        .ok_or("peer JSON has no ms_median")?;
    let bytes = std::fs::read(&dist_path).map_err(|e| e.to_string())?;
    let d2 = bytemuck::cast_slice::<u8, f32>(&bytes)
        .iter()
        .map(|&d| ((d as f64) * (d as f64)).round() as u64)
        .collect();
    let _ = std::fs::remove_file(&dist_path);
    let _ = std::fs::remove_file(&mask_path);
    Ok(Peer { ms, d2, json })
}

/// A 3D grid's name in the tables: `512³` for a cube, `128×128×1024` otherwise.
fn label3([x, y, z]: [usize; 3]) -> String {
    if x == y && y == z {
        format!("{x}³")
    } else {
        format!("{x}×{y}×{z}")
    }
}

fn words(ctx: &Context, b: &wgpu::Buffer) -> Result<Vec<u32>, String> {
    Ok(bytemuck::cast_slice::<u8, u32>(&read_buffer(ctx, b).map_err(|e| e.to_string())?).to_vec())
}

pub fn run(args: &Args) -> ExitCode {
    match distance(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench distance: {e}");
            ExitCode::FAILURE
        }
    }
}

fn distance(args: &Args) -> Result<(), String> {
    if let Some(csv) = &args.replot {
        let (adapter, rows) = read_table(csv)?;
        std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
        let png = args.out.join("distance.png");
        chart(&png, &adapter, &rows, (1000, 640))?;
        println!("wrote {}", png.display());
        return Ok(());
    }
    let pick = |all: &[usize]| -> Vec<usize> {
        all.iter()
            .copied()
            .filter(|n| args.sizes.is_empty() || args.sizes.contains(n))
            .collect()
    };
    // 3D grids as (x, y, z): the sweep's cubes, or the shapes asked for (and then no 2D).
    let sizes3: Vec<[usize; 3]> = if args.shapes.is_empty() {
        pick(if args.quick {
            &[32, 64]
        } else {
            &[128, 256, 512, 1024]
        })
        .into_iter()
        .map(|n| [n; 3])
        .collect()
    } else {
        args.shapes.clone()
    };
    let sizes2 = if args.shapes.is_empty() {
        pick(if args.quick {
            &[256, 512]
        } else {
            &[2048, 4096, 8192, 16384]
        })
    } else {
        Vec::new()
    };
    // A cube's mask is seeded by its edge, as before shapes were taken, so its figures stay
    // comparable with earlier commands'.
    let mask3 = |[x, y, z]: [usize; 3]| {
        let seed = if x == y && y == z {
            x as u64
        } else {
            ((x as u64) << 40) ^ ((y as u64) << 20) ^ z as u64
        };
        random_mask(x * y * z, args.density, seed)
    };
    let mask2 = |n: usize| random_mask(n * n, args.density, 1000 + n as u64);
    // The peer runs first, every size, before this process opens its device. On the H100 a CUDA
    // process started while our Vulkan device was open left every later run of this process
    // slower: 512³ exact took 16.05 ms after it against 6.95 ms in a fresh process, although the
    // peer had exited (smaller sizes were not affected).
    let mut peers3 = std::collections::HashMap::new();
    let mut peers2 = std::collections::HashMap::new();
    if let Some(cmd) = &args.peer {
        for &size in &sizes3 {
            let [x, y, z] = size;
            eprintln!("peer {}", label3(size));
            peers3.insert(
                size,
                run_peer(cmd, &mask3(size), &[z, y, x], &format!("{x}_{y}_{z}c"))?,
            );
        }
        for &n in &sizes2 {
            eprintln!("peer {n}²");
            peers2.insert(n, run_peer(cmd, &mask2(n), &[n, n], &format!("{n}s"))?);
        }
    }
    let mut ctx = Context::new().map_err(|e| e.to_string())?;
    if let Some(bytes) = args.workgroup_storage {
        let adapter = ctx.adapter.take().expect("Context::new opens an adapter");
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("bench distance"),
            required_features: ctx.device.features(),
            required_limits: wgpu::Limits {
                max_compute_workgroup_storage_size: bytes,
                ..adapter.limits()
            },
            ..Default::default()
        }))
        .map_err(|e| format!("--workgroup-storage {bytes}: {e}"))?;
        ctx = Context::from_device(device, queue);
        ctx.adapter = Some(adapter);
    }
    let info = ctx
        .adapter
        .as_ref()
        .expect("Context::new opens an adapter")
        .get_info();
    let adapter = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
    println!("adapter: {adapter}");
    let mut d3 = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    d3.set_column_bands(args.column_bands)
        .map_err(|e| e.to_string())?;
    d3.set_split_columns(args.split_columns)
        .map_err(|e| e.to_string())?;
    d3.set_split_bytes(args.split_bytes);
    // The same transform with the column passes in global memory, for comparison in one command.
    let mut d3_global = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    d3_global.set_column_passes(ColumnPasses::Global);
    d3_global
        .set_column_bands(args.column_bands)
        .map_err(|e| e.to_string())?;
    let mut d3_workgroup = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    d3_workgroup.set_column_passes(ColumnPasses::Workgroup);
    let mut d3_rows = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    d3_rows.set_fold_rows(false);
    let mut d3_unswept = Distance3d::new(&ctx.device).map_err(|e| e.to_string())?;
    d3_unswept.set_sweep(false);
    d3_unswept
        .set_column_bands(args.column_bands)
        .map_err(|e| e.to_string())?;
    let storage = ctx.device.limits().max_compute_workgroup_storage_size;
    // What Auto takes per pass: 3D y up to AUTO_TILE_MAX_LENGTH_Y, 3D z and 2D by `tile_columns`.
    let path = |c: Option<u32>| c.map_or("global".to_string(), |c| format!("{c} columns"));
    println!(
        "workgroup memory: {storage} bytes; column passes by length: {}",
        sizes3
            .iter()
            .map(|&size| {
                let edge = size.map(|s| s as u32);
                let y_path = tile_columns_3d(storage, edge, 1);
                let z_path = tile_columns_3d(storage, edge, 2);
                format!("{} y {}, z {}", label3(size), path(y_path), path(z_path))
            })
            .chain(
                sizes2
                    .iter()
                    .map(|&n| format!("{n}² {}", path(tile_columns(storage, n as u32, 2))))
            )
            .collect::<Vec<_>>()
            .join("; ")
    );
    // Clocks held up as the volume and voxelize benches hold them: a 20 ms spin before every
    // run (outside the timestamps), on hardware adapters.
    let heater = if ctx.is_software() {
        None
    } else {
        Some(crate::heater::Heater::new(&ctx, 20.0)?)
    };
    let heater = heater.as_ref();
    let jfa2 = Jfa2d::new(&ctx.device).map_err(|e| e.to_string())?;
    let banded = format!("JFA+2 band {}", args.band);
    let methods3: Vec<(String, Settings3d)> =
        std::iter::once(("exact".to_string(), Settings3d::default()))
            .chain(std::iter::once((GLOBAL.to_string(), Settings3d::default())))
            .chain(std::iter::once((
                WORKGROUP.to_string(),
                Settings3d::default(),
            )))
            .chain(std::iter::once((
                ROWS_PASS.to_string(),
                Settings3d::default(),
            )))
            .chain(std::iter::once((
                UNSWEPT.to_string(),
                Settings3d::default(),
            )))
            .chain(Variant::ALL.into_iter().map(|v| {
                (
                    v.name().to_string(),
                    Settings3d {
                        method: Method::Jfa(v),
                        ..Settings3d::default()
                    },
                )
            }))
            .chain(std::iter::once((
                banded.clone(),
                Settings3d {
                    method: Method::Jfa(Variant::JfaPlus2),
                    band: Some(args.band),
                    ..Settings3d::default()
                },
            )))
            .take(if args.exact_only { 5 } else { usize::MAX })
            .collect();
    let variants2: &[Variant] = if args.exact_only { &[] } else { &Variant::ALL };
    let total = (sizes3.len() * methods3.len() + sizes2.len() * (1 + variants2.len())) as u64;
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}").unwrap(),
    );
    let mut rows: Vec<Row> = Vec::new();
    // The column passes' load/store floors: (size, the pass's name as the per-pass table has
    // it, its copy's median ms, and for the resolving z pass its copy's with the distance store).
    let mut floors: Vec<(String, &str, f64, Option<f64>)> = Vec::new();

    // Fields larger than one storage binding (1024³ is 4 GiB) are split across bindings, which
    // only the exact transform's workgroup-memory passes do, always from the row words: the
    // other exact rows would time the same passes or none, and JFA refuses the size.
    let binding = ctx
        .device
        .limits()
        .max_storage_buffer_binding_size
        .min(args.split_bytes.unwrap_or(u64::MAX));
    for &size in &sizes3 {
        let label = label3(size);
        let cells = size.iter().product::<usize>() as u64;
        let split = cells * 4 > binding;
        let mask = mask3(size);
        let volume = upload_volume(&ctx.device, &ctx.queue, &mask, size.map(|s| s as u32))
            .map_err(|e| e.to_string())?;
        let peer = peers3.remove(&size);
        let mut exact_d2: Vec<u64> = Vec::new();
        let mut reference: Option<Vec<u64>> = None;
        for (name, opts) in &methods3 {
            bar.set_message(format!("{label} {name}"));
            let d3 = match name.as_str() {
                GLOBAL => &d3_global,
                WORKGROUP => &d3_workgroup,
                ROWS_PASS => &d3_rows,
                UNSWEPT => &d3_unswept,
                _ => &d3,
            };
            // JFA takes fields of one binding only; a split field has no row pass of its own.
            if split && (name == ROWS_PASS || name == UNSWEPT || opts.method != Method::Exact) {
                bar.inc(1);
                continue;
            }
            // Where no tile fits (or the path is the one Auto takes anyway: both passes in
            // workgroup memory), no row.
            if name == WORKGROUP
                && (d3
                    .encode(&ctx.device, &mut ctx.encoder("probe"), &volume, opts)
                    .is_err()
                    || [1, 2].iter().all(|&axis| {
                        tile_columns_3d(storage, size.map(|s| s as u32), axis).is_some()
                    }))
            {
                bar.inc(1);
                continue;
            }
            let (med, min, max, passes) =
                time_runs(&ctx, args.warmup, args.reps, heater, |enc, prof| {
                    d3.encode(&ctx.device, &mut prof.record(enc), &volume, opts)
                        .expect("encode");
                })?;
            if name == "exact" {
                // What a loop that runs the transform every frame spends on the CPU.
                let (host, lo, hi) = crate::measure::host_times(&ctx, args.reps, |enc| {
                    d3.encode(&ctx.device, enc, &volume, opts)
                        .map_err(|e| e.to_string())
                })?;
                println!("  host (record + submit) {name} {label}: {host:.3} ms ({lo:.3}–{hi:.3})");
                // The same with each run's field recycled for the next (`Distance3d::recycle`).
                let last = std::cell::RefCell::new(None);
                let (host, lo, hi) = crate::measure::host_times(&ctx, args.reps, |enc| {
                    if let Some(field) = last.borrow_mut().take() {
                        d3.recycle(field);
                    }
                    let field = d3
                        .encode(&ctx.device, enc, &volume, opts)
                        .map_err(|e| e.to_string())?;
                    *last.borrow_mut() = Some(field);
                    Ok(())
                })?;
                println!(
                    "  host (record + submit) {name} {label}, recycled: {host:.3} ms ({lo:.3}–{hi:.3})"
                );
            }
            let mut enc = ctx.encoder("bench readback");
            let field = d3
                .encode(&ctx.device, &mut enc, &volume, opts)
                .map_err(|e| e.to_string())?;
            ctx.submit_and_wait("bench", enc)
                .map_err(|e| e.to_string())?;
            let d2 = d2_of(
                &field
                    .nearest
                    .read(&ctx.device, &ctx.queue)
                    .wait(&ctx)
                    .map_err(|e| e.to_string())?,
                size,
                3,
            );
            let (wrong, max_err, mean_err, peer_ms) = if opts.method == Method::Exact {
                // Both exact rows against the reference: the peer's distances, or the CPU
                // transform in quick mode.
                let reference = reference.get_or_insert_with(|| match &peer {
                    Some(p) => p.d2.clone(),
                    None => {
                        cpu::edt_3d_squared(&mask.iter().map(|&m| m != 0).collect::<Vec<_>>(), size)
                    }
                });
                let (w, mx, mean) = errors(&d2, reference, None);
                if name == "exact" {
                    exact_d2 = d2;
                }
                (w, mx, mean, peer.as_ref().map(|p| p.ms))
            } else {
                let (w, mx, mean) = errors(&d2, &exact_d2, opts.band.map(|b| b as f64));
                (w, mx, mean, None)
            };
            rows.push(Row {
                dims: 3,
                size: label.clone(),
                voxels: cells,
                method: name.clone(),
                median_ms: med,
                min_ms: min,
                max_ms: max,
                wrong,
                max_err,
                mean_err,
                peer_ms,
                // A split field runs a pass once per part or slab: each moves its share.
                passes: {
                    let count = |p: &str| passes.iter().filter(|(q, _)| q == p).count() as f64;
                    passes
                        .iter()
                        .map(|(p, ms)| (p.clone(), *ms, pass_bytes(p, cells, 3) / count(p)))
                        .collect()
                },
            });
            bar.inc(1);
        }
        // The floor of each column pass: its loads and stores alone, without the envelopes
        // (of a field in one binding): the tile copy where the pass runs in workgroup memory,
        // else the global copy, which reads the row words as the y pass does.
        if !split {
            let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("bench copy"),
                size: cells * 4,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            });
            let mut enc = ctx.encoder("bench row words");
            let words = d3
                .encode_row_words(
                    &ctx.device,
                    &mut enc,
                    &volume,
                    Settings3d::default().inside,
                    false,
                )
                .map_err(|e| e.to_string())?;
            ctx.submit_and_wait("bench row words", enc)
                .map_err(|e| e.to_string())?;
            // The z pass resolves: its copy is timed again with the distance store as well.
            let edge = size.map(|s| s as u32);
            let distance = fieldkit::gpu::texture(
                &ctx.device,
                "bench copy distance",
                [edge[0], edge[1], edge[2]],
                wgpu::TextureDimension::D3,
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::STORAGE_BINDING,
            );
            for axis in [1u32, 2] {
                let mut tile = false;
                let mut copy = |store: Option<&wgpu::Texture>| {
                    time_runs(&ctx, args.warmup, args.reps, heater, |enc, prof| {
                        let rec = &mut prof.record(enc);
                        tile = d3
                            .encode_tile_copy(&ctx.device, rec, &buffer, edge, axis, store)
                            .expect("encode")
                            .is_some();
                        if !tile {
                            let words = (axis == 1).then_some(&words);
                            d3.encode_global_copy(
                                &ctx.device,
                                rec,
                                &buffer,
                                words,
                                edge,
                                axis,
                                store,
                            )
                            .expect("encode");
                        }
                    })
                };
                let timing = copy(None)?;
                let stored = if axis == 2 {
                    Some(copy(Some(&distance))?.0)
                } else {
                    None
                };
                let tag = match (axis, tile) {
                    (1, true) => "columns (y, workgroup)",
                    (_, true) => "columns (z, workgroup)",
                    (1, false) => "columns (y) from row words",
                    (_, false) => "columns (z)",
                };
                floors.push((label.clone(), tag, timing.0, stored));
            }
        }
        if let Some(p) = &peer {
            bar.println(format!("peer {label}: {}", p.json));
        }
    }

    for &n in &sizes2 {
        let size = [n, n, 1];
        let cells = (n * n) as u64;
        let mask = mask2(n);
        let tex = upload_mask(&ctx.device, &ctx.queue, &mask, n as u32, n as u32)
            .map_err(|e| e.to_string())?;
        let peer = peers2.remove(&n);
        // Exact.
        bar.set_message(format!("{n}² exact"));
        let opts = Settings3d::default();
        let (med, min, max, passes) =
            time_runs(&ctx, args.warmup, args.reps, heater, |enc, prof| {
                d3.encode_exact_2d(&ctx.device, &mut prof.record(enc), &tex, &opts)
                    .expect("encode");
            })?;
        let global = time_runs(&ctx, args.warmup, args.reps, heater, |enc, prof| {
            d3_global
                .encode_exact_2d(&ctx.device, &mut prof.record(enc), &tex, &opts)
                .expect("encode");
        })?;
        let mut enc = ctx.encoder("bench readback");
        let field = d3
            .encode_exact_2d(&ctx.device, &mut enc, &tex, &opts)
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let exact_d2 = d2_of(&words(&ctx, &field.nearest)?, size, 2);
        let reference = match &peer {
            Some(p) => p.d2.clone(),
            None => cpu::edt_2d_squared(&mask.iter().map(|&m| m != 0).collect::<Vec<_>>(), n, n),
        };
        let (wrong, max_err, mean_err) = errors(&exact_d2, &reference, None);
        let mut enc = ctx.encoder("bench readback");
        let field = d3_global
            .encode_exact_2d(&ctx.device, &mut enc, &tex, &opts)
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let global_errors = errors(
            &d2_of(&words(&ctx, &field.nearest)?, size, 2),
            &reference,
            None,
        );
        let pass_rows = |passes: Vec<(String, f64)>| {
            passes
                .into_iter()
                .map(|(p, ms)| {
                    let b = pass_bytes(&p, cells, 2);
                    (p, ms, b)
                })
                .collect()
        };
        rows.push(Row {
            dims: 2,
            size: format!("{n}²"),
            voxels: cells,
            method: "exact".into(),
            median_ms: med,
            min_ms: min,
            max_ms: max,
            wrong,
            max_err,
            mean_err,
            peer_ms: peer.as_ref().map(|p| p.ms),
            passes: pass_rows(passes),
        });
        rows.push(Row {
            dims: 2,
            size: format!("{n}²"),
            voxels: cells,
            method: GLOBAL.into(),
            median_ms: global.0,
            min_ms: global.1,
            max_ms: global.2,
            wrong: global_errors.0,
            max_err: global_errors.1,
            mean_err: global_errors.2,
            peer_ms: peer.as_ref().map(|p| p.ms),
            passes: pass_rows(global.3),
        });
        bar.inc(1);
        for &v in variants2 {
            bar.set_message(format!("{n}² {}", v.name()));
            let opts = JfaSettings2d {
                variant: v,
                ..JfaSettings2d::default()
            };
            let (med, min, max, passes) =
                time_runs(&ctx, args.warmup, args.reps, heater, |enc, prof| {
                    jfa2.encode(&ctx.device, &mut prof.record(enc), &tex, &opts)
                        .expect("encode");
                })?;
            let mut enc = ctx.encoder("bench readback");
            let field = jfa2
                .encode(&ctx.device, &mut enc, &tex, &opts)
                .map_err(|e| e.to_string())?;
            ctx.submit_and_wait("bench", enc)
                .map_err(|e| e.to_string())?;
            let nearest: Vec<u32> =
                read_texture(&ctx, &field.nearest).map_err(|e| e.to_string())?;
            let (wrong, max_err, mean_err) = errors(&d2_of(&nearest, size, 2), &exact_d2, None);
            rows.push(Row {
                dims: 2,
                size: format!("{n}²"),
                voxels: cells,
                method: v.name().into(),
                median_ms: med,
                min_ms: min,
                max_ms: max,
                wrong,
                max_err,
                mean_err,
                peer_ms: None,
                passes: pass_rows(passes),
            });
            bar.inc(1);
        }
        if let Some(p) = &peer {
            bar.println(format!("peer {n}²: {}", p.json));
        }
    }
    bar.finish_with_message("done");

    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
    write_csv(&args.out, &adapter, &rows).map_err(|e| e.to_string())?;
    chart(&args.out.join("distance.png"), &adapter, &rows, (1000, 640))?;
    print_table(&rows);
    println!();
    // Two floors for the resolving z pass: its copy as the prototype's mode 1 makes it (the
    // answers' loads and stores), and with the distance store the pass makes too.
    println!(
        "| size | column pass | ms (median) | load/store only ms | ratio | with the distance store ms | ratio |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (size, tag, floor, stored) in &floors {
        // "columns (z)" also names "columns (z) + resolve" and a sweep's two dispatches
        // ("columns (z) sweep + resolve", "columns (z) + resolve (rest)"), summed; not
        // "columns (z, workgroup)".
        let times: Vec<f64> = rows
            .iter()
            .filter(|r| &r.size == size && r.method == "exact")
            .flat_map(|r| &r.passes)
            .filter(|p| p.0.starts_with(tag))
            .map(|p| p.1)
            .collect();
        if !times.is_empty() {
            let ms: f64 = times.iter().sum();
            let with_store = stored.map_or("| — | — |".to_string(), |s| {
                format!("| {s:.3} | {:.2} |", ms / s)
            });
            println!(
                "| {size} | {tag} | {ms:.3} | {floor:.3} | {:.2} {with_store}",
                ms / floor
            );
        }
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The header of `distance.csv`.
const TABLE_HEADER: &str = "adapter,dims,size,cells,method,median_ms,min_ms,max_ms,wrong,wrong_fraction,max_err_voxels,mean_err_voxels,peer_ms,ratio_to_peer";

fn write_csv(dir: &Path, adapter: &str, rows: &[Row]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(dir.join("distance.csv"))?;
    writeln!(f, "{TABLE_HEADER}")?;
    for r in rows {
        let peer = r.peer_ms.map_or(String::new(), |p| format!("{p:.4}"));
        let ratio = r
            .peer_ms
            .map_or(String::new(), |p| format!("{:.3}", r.median_ms / p));
        writeln!(
            f,
            "\"{adapter}\",{},{},{},\"{}\",{:.4},{:.4},{:.4},{},{:.3e},{:.4},{:.3e},{peer},{ratio}",
            r.dims,
            r.size,
            r.voxels,
            r.method,
            r.median_ms,
            r.min_ms,
            r.max_ms,
            r.wrong,
            r.wrong as f64 / r.voxels as f64,
            r.max_err,
            r.mean_err
        )?;
    }
    let mut f = std::fs::File::create(dir.join("distance_passes.csv"))?;
    writeln!(
        f,
        "adapter,size,method,pass,median_ms,bytes,gb_per_s,fraction_of_3tb_s"
    )?;
    for r in rows {
        for (p, ms, bytes) in &r.passes {
            let bw = bytes / (ms / 1e3);
            writeln!(
                f,
                "\"{adapter}\",{},\"{}\",\"{p}\",{ms:.4},{bytes:.0},{:.1},{:.3}",
                r.size,
                r.method,
                bw / 1e9,
                bw / PEAK_BYTES_PER_S
            )?;
        }
    }
    Ok(())
}

fn print_table(rows: &[Row]) {
    println!(
        "| size | method | ms (median) | min–max | spread (max/min) | peer ms | ratio | wrong | max err | bytes/voxel (floor) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let peer = r.peer_ms.map_or("".into(), |p| format!("{p:.3}"));
        let ratio = r
            .peer_ms
            .map_or("".into(), |p| format!("{:.2}", r.median_ms / p));
        let bytes: f64 = r.passes.iter().map(|p| p.2).sum::<f64>() / r.voxels as f64;
        println!(
            "| {} | {} | {:.3} | {:.3}–{:.3} | {:.2} | {peer} | {ratio} | {} | {:.3} | {bytes:.0} |",
            r.size,
            r.method,
            r.median_ms,
            r.min_ms,
            r.max_ms,
            r.max_ms / r.min_ms,
            r.wrong,
            r.max_err
        );
    }
    println!();
    println!("| size | method | pass | ms (median) | bytes/voxel (floor) | GB/s at the floor |");
    println!("|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.method.starts_with("exact")) {
        for (pass, ms, bytes) in &r.passes {
            println!(
                "| {} | {} | {pass} | {ms:.3} | {:.0} | {:.0} |",
                r.size,
                r.method,
                bytes / r.voxels as f64,
                bytes / (ms * 1e-3) / 1e9
            );
        }
    }
}

/// GPU time against max error, log-log, a point per method and size, 3D and 2D side by side.
/// Zero error cannot sit on a log axis: those points are drawn in a band at the bottom
/// (below 5e-3, staggered per method so their labels can be read). The peer is a hollow point.
fn chart(path: &Path, adapter: &str, rows: &[Row], (w, h): (u32, u32)) -> Result<(), String> {
    use plotters::prelude::*;
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(
            &format!("distance: GPU time vs max error, {adapter}"),
            ("sans-serif", 15),
        )
        .map_err(|e| e.to_string())?;
    let panels = root.split_evenly((1, 2));
    let floor = 1e-3;
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let y_of = |r: &Row| {
        if r.max_err > 0.0 {
            // An infinite error (a voxel left without its seed) on a log axis has no place:
            // drawn at a million voxels, past any grid's diagonal (a log range to ∞ never ends).
            r.max_err.clamp(5e-3, 1e6)
        } else {
            floor * 1.18f64.powi(methods.iter().position(|m| *m == r.method).unwrap_or(0) as i32)
        }
    };
    for (panel, dims) in panels.iter().zip([3u32, 2]) {
        let sel: Vec<&Row> = rows.iter().filter(|r| r.dims == dims).collect();
        if sel.is_empty() {
            continue;
        }
        let times: Vec<f64> = sel
            .iter()
            .flat_map(|r| std::iter::once(r.median_ms).chain(r.peer_ms))
            .collect();
        let (tmin, tmax) = times
            .iter()
            .fold((f64::INFINITY, 0f64), |(a, b), &t| (a.min(t), b.max(t)));
        let emax = sel.iter().map(|r| y_of(r)).fold(1.0, f64::max);
        let mut c = ChartBuilder::on(panel)
            .caption(if dims == 3 { "3D" } else { "2D" }, ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(
                (tmin / 1.6..tmax * 2.2).log_scale(),
                (floor / 1.5..emax * 2.0).log_scale(),
            )
            .map_err(|e| e.to_string())?;
        c.configure_mesh()
            .x_desc("GPU time, ms (median, log)")
            .y_desc("max error, voxels (log; bottom band = 0)")
            .x_labels(6)
            .y_labels(5)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(|e| e.to_string())?;
        c.draw_series(std::iter::once(PathElement::new(
            vec![(tmin / 1.6, 4.2e-3), (tmax * 2.2, 4.2e-3)],
            BLACK.mix(0.3),
        )))
        .map_err(|e| e.to_string())?;
        let mut sizes: Vec<&str> = sel.iter().map(|r| r.size.as_str()).collect();
        sizes.dedup();
        for (i, size) in sizes.iter().enumerate() {
            let color = Palette99::pick(i + if dims == 2 { 4 } else { 0 }).to_rgba();
            let pts: Vec<&Row> = sel.iter().copied().filter(|r| r.size == *size).collect();
            c.draw_series(
                pts.iter()
                    .map(|r| Circle::new((r.median_ms, y_of(r)), 4, color.filled())),
            )
            .map_err(|e| e.to_string())?
            .label(size.to_string())
            .legend(move |(x, y)| Circle::new((x, y), 4, color.filled()));
            c.draw_series(pts.iter().map(|r| {
                Text::new(
                    format!(" {}", r.method),
                    (r.median_ms, y_of(r)),
                    ("sans-serif", 10).into_font().color(&color),
                )
            }))
            .map_err(|e| e.to_string())?;
            let peer: Vec<f64> = pts.iter().filter_map(|r| r.peer_ms).collect();
            c.draw_series(
                peer.iter()
                    .map(|&p| Circle::new((p, floor), 6, color.stroke_width(2))),
            )
            .map_err(|e| e.to_string())?;
            c.draw_series(peer.iter().map(|&p| {
                Text::new(
                    " peer (PBA+)".to_string(),
                    (p, floor / 1.2),
                    ("sans-serif", 10).into_font().color(&color),
                )
            }))
            .map_err(|e| e.to_string())?;
        }
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 11))
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// `--replot`: the adapter and rows of a `distance.csv`, or of several joined into one file
/// (their header lines repeated), all from one adapter. Per-pass times are not in it.
fn read_table(path: &Path) -> Result<(String, Vec<Row>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut adapter: Option<String> = None;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line == TABLE_HEADER || line.is_empty() {
            continue;
        }
        let bad = |what: &str| format!("{} line {}: {what}: {line}", path.display(), i + 1);
        let fields = crate::measure::csv_fields(line);
        let [
            a,
            dims,
            size,
            cells,
            method,
            median,
            min,
            max,
            wrong,
            _,
            max_err,
            mean_err,
            peer,
            _,
        ] = &fields[..]
        else {
            return Err(bad("not the 14 fields of distance.csv"));
        };
        match &adapter {
            Some(first) if first != a => {
                return Err(bad(&format!("a second adapter ({first} before)")));
            }
            _ => adapter = Some(a.clone()),
        }
        let num = |v: &str, name: &str| v.parse::<f64>().map_err(|_| bad(name));
        let int = |v: &str, name: &str| v.parse::<u64>().map_err(|_| bad(name));
        rows.push(Row {
            dims: int(dims, "dims")? as u32,
            size: size.clone(),
            voxels: int(cells, "cells")?,
            method: method.clone(),
            median_ms: num(median, "median_ms")?,
            min_ms: num(min, "min_ms")?,
            max_ms: num(max, "max_ms")?,
            wrong: int(wrong, "wrong")?,
            max_err: num(max_err, "max_err_voxels")?,
            mean_err: num(mean_err, "mean_err_voxels")?,
            peer_ms: if peer.is_empty() {
                None
            } else {
                Some(num(peer, "peer_ms")?)
            },
            passes: Vec::new(),
        });
    }
    let adapter = adapter.ok_or_else(|| format!("{}: no rows", path.display()))?;
    Ok((adapter, rows))
}

#[cfg(test)]
mod tests {
    /// "No seed" on both sides (a mask with none) agrees; "no seed" against a distance, or two
    /// distances apart, is wrong; a band clamps both sides first.
    #[test]
    fn errors_count_only_disagreements() {
        let none = u64::MAX;
        assert_eq!(super::errors(&[none, 4], &[none, 4], None), (0, 0.0, 0.0));
        let (wrong, max, mean) = super::errors(&[none, 9, 1], &[4, 4, 1], None);
        assert_eq!((wrong, max, mean), (2, f64::INFINITY, f64::INFINITY));
        assert_eq!(super::errors(&[9], &[4], None).0, 1);
        assert_eq!(
            super::errors(&[none, 25], &[16, 9], Some(2.0)),
            (0, 0.0, 0.0)
        );
    }

    /// A row whose error is infinite (a voxel left without its seed) still charts: drawn at
    /// the axis's top, where a log range up to it would never end.
    #[test]
    fn an_infinite_error_charts() {
        let (dir, png) = crate::measure::scratch_file("chart-distance", "distance.png");
        let row = |method: &str, max_err: f64| super::Row {
            dims: 3,
            size: "1×300×2".into(),
            voxels: 600,
            method: method.into(),
            median_ms: 5.6,
            min_ms: 5.5,
            max_ms: 5.7,
            wrong: u64::from(max_err > 0.0) * 600,
            max_err,
            mean_err: max_err,
            peer_ms: None,
            passes: Vec::new(),
        };
        let rows = [row("exact", f64::INFINITY), row("JFA", 0.5)];
        super::chart(&png, "GPU", &rows, (400, 300)).unwrap();
        assert!(std::fs::metadata(&png).unwrap().len() > 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// `--replot` reads back two joined tables: the quoted adapter keeps its commas, an empty
    /// peer is none, and a short line or a second adapter is an error naming its line.
    #[test]
    fn replot_reads_joined_tables() {
        let (dir, csv) = crate::measure::scratch_file("replot-distance", "distance.csv");
        let table = format!(
            "{h}\n\"GPU (Vulkan, 1.2)\",3,512³,134217728,\"exact\",2.9350,2.9150,2.9560,0,0.000e0,0.0000,0.000e0,8.5190,0.345\n\
             {h}\n\"GPU (Vulkan, 1.2)\",2,8192²,67108864,\"JFA+2\",1.2000,1.1000,1.3000,12,1.788e-7,2.2361,2.000e-8,,\n",
            h = super::TABLE_HEADER
        );
        std::fs::write(&csv, &table).unwrap();
        let (adapter, rows) = super::read_table(&csv).unwrap();
        assert_eq!(adapter, "GPU (Vulkan, 1.2)");
        let got: Vec<_> = rows
            .iter()
            .map(|r| {
                (
                    r.dims,
                    r.size.as_str(),
                    r.voxels,
                    r.method.as_str(),
                    r.median_ms,
                    r.wrong,
                    r.max_err,
                    r.peer_ms,
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (3, "512³", 134217728, "exact", 2.935, 0, 0.0, Some(8.519)),
                (2, "8192²", 67108864, "JFA+2", 1.2, 12, 2.2361, None),
            ]
        );
        std::fs::write(&csv, format!("{}\n\"GPU\",3,512³\n", super::TABLE_HEADER)).unwrap();
        let e = super::read_table(&csv).unwrap_err();
        assert!(e.contains("line 2"), "{e}");
        std::fs::write(&csv, table.replacen("GPU (Vulkan, 1.2)", "Other GPU", 1)).unwrap();
        let e = super::read_table(&csv).unwrap_err();
        assert!(e.contains("line 4") && e.contains("second adapter"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
