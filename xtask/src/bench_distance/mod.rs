//! `cargo xtask bench distance`: GPU time against accuracy for every distance method, variant
//! and size, with the peer (cupyx's PBA+) timed on the same mask where it is installed.
//!
//! GPU time comes from timestamp queries around every pass: a run's time is from the start of its
//! first pass to the end of its last; the figure reported is the median of `--reps` runs after
//! `--warmup` runs. Errors are counted against the exact transform (itself checked against the
//! peer's distances, or the CPU reference in `--quick` mode).

mod report;
mod rig;
mod three;
mod two;

use fieldkit::gpu::{Context, read_buffer};

use crate::measure::Args;
#[cfg(test)]
use report::{TABLE_HEADER, chart, read_table};
use rig::Rig;

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
    let out = crate::measure::stdout_of(
        std::process::Command::new(program)
            .args(parts)
            .arg("--mask")
            .arg(&mask_path)
            .arg("--shape")
            .args(shape.iter().map(|s| s.to_string()))
            .arg("--write-dist")
            .arg(&dist_path),
        &format!("the peer `{cmd}`"),
    )?;
    let json = out.lines().last().unwrap_or_default().to_string();
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

pub fn run(args: &Args) -> Result<(), String> {
    distance(args)
}

/// The whole sweep: the peer first (see [`peers`]), then every 3D and 2D size on this
/// process's device, then the tables, the chart and the column passes' floors.
fn distance(args: &Args) -> Result<(), String> {
    if let Some(csv) = &args.replot {
        return report::replot(args, csv);
    }
    let (sizes3, sizes2) = sizes(args);
    let (mut peers3, mut peers2) = peers(args, &sizes3, &sizes2)?;
    let rig = Rig::open(args)?;
    rig.print_paths(&sizes3, &sizes2);
    let methods3 = rig::methods3(args);
    let variants2: &[fieldkit::distance::Variant] = if args.exact_only {
        &[]
    } else {
        &fieldkit::distance::Variant::ALL
    };
    let total = (sizes3.len() * methods3.len() + sizes2.len() * (1 + variants2.len())) as u64;
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed} {msg}").unwrap(),
    );
    let mut rows: Vec<Row> = Vec::new();
    let mut floors: Vec<three::Floor> = Vec::new();
    for &size in &sizes3 {
        let peer = peers3.remove(&size);
        rig.bench_3d(size, &methods3, peer.as_ref(), &bar, &mut rows, &mut floors)?;
        if let Some(p) = &peer {
            bar.println(format!("peer {}: {}", label3(size), p.json));
        }
    }
    for &n in &sizes2 {
        let peer = peers2.remove(&n);
        rig.bench_2d(n, variants2, peer.as_ref(), &bar, &mut rows)?;
        if let Some(p) = &peer {
            bar.println(format!("peer {n}²: {}", p.json));
        }
    }
    bar.finish_with_message("done");
    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
    report::write_csv(&args.out, &rig.adapter, &rows).map_err(|e| e.to_string())?;
    report::chart(
        &args.out.join("distance.png"),
        &rig.adapter,
        &rows,
        (1000, 640),
    )?;
    report::print_table(&rows);
    println!();
    report::print_floors(&rows, &floors);
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The 3D grids as (x, y, z) (the sweep's cubes, or the shapes asked for, and then no 2D) and
/// the 2D sides.
fn sizes(args: &Args) -> (Vec<[usize; 3]>, Vec<usize>) {
    let pick = |all: &[usize]| -> Vec<usize> {
        all.iter()
            .copied()
            .filter(|n| args.sizes.is_empty() || args.sizes.contains(n))
            .collect()
    };
    if !args.shapes.is_empty() {
        return (args.shapes.clone(), Vec::new());
    }
    let cubes = pick(if args.quick {
        &[32, 64]
    } else {
        &[128, 256, 512, 1024]
    });
    let squares = pick(if args.quick {
        &[256, 512]
    } else {
        &[2048, 4096, 8192, 16384]
    });
    (cubes.into_iter().map(|n| [n; 3]).collect(), squares)
}

/// A 3D grid's mask. A cube's is seeded by its edge, as before shapes were taken, so its
/// figures stay comparable with earlier commands'.
fn mask3(args: &Args, [x, y, z]: [usize; 3]) -> Vec<u8> {
    let seed = if x == y && y == z {
        x as u64
    } else {
        ((x as u64) << 40) ^ ((y as u64) << 20) ^ z as u64
    };
    random_mask(x * y * z, args.density, seed)
}

/// A square's mask.
fn mask2(args: &Args, n: usize) -> Vec<u8> {
    random_mask(n * n, args.density, 1000 + n as u64)
}

type Peers<K> = std::collections::HashMap<K, Peer>;

/// The peer's run of every size, before this process opens its device. On the H100 a CUDA
/// process started while our Vulkan device was open left every later run of this process
/// slower: 512³ exact took 16.05 ms after it against 6.95 ms in a fresh process, although the
/// peer had exited (smaller sizes were not affected).
fn peers(
    args: &Args,
    sizes3: &[[usize; 3]],
    sizes2: &[usize],
) -> Result<(Peers<[usize; 3]>, Peers<usize>), String> {
    let (mut peers3, mut peers2) = (Peers::new(), Peers::new());
    if let Some(cmd) = &args.peer {
        for &size in sizes3 {
            let [x, y, z] = size;
            eprintln!("peer {}", label3(size));
            let tag = format!("{x}_{y}_{z}c");
            peers3.insert(size, run_peer(cmd, &mask3(args, size), &[z, y, x], &tag)?);
        }
        for &n in sizes2 {
            eprintln!("peer {n}²");
            peers2.insert(
                n,
                run_peer(cmd, &mask2(args, n), &[n, n], &format!("{n}s"))?,
            );
        }
    }
    Ok((peers3, peers2))
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
