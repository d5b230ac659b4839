//! How the benchmarks measure: the command-line settings they share, GPU timestamps around a
//! recorded run ([`Stamps`]), timed runs after a warm-up with per-pass times ([`time_runs`]),
//! the heater that keeps clocks up between them, medians and CSV tables. Every `bench_*`
//! module builds on this one and on none of the others.

use std::path::PathBuf;

use fieldkit::gpu::{Context, Profiler, read_buffer};

use crate::heater::Heater;

/// Settings of `cargo xtask bench`, shared by every technique.
#[derive(clap::Args)]
pub struct Args {
    /// Small sizes for software adapters (3D 32³, 64³; 2D 256², 512²) instead of the full sweep.
    #[arg(long)]
    pub quick: bool,
    /// Timed runs per point; the median is reported.
    #[arg(long, default_value_t = 20)]
    pub reps: usize,
    /// Untimed runs first: at least this many, and at least 2 s of them (`measure::WARMUP_TIME`).
    #[arg(long, default_value_t = 3)]
    pub warmup: usize,
    /// Fraction of cells that are seeds.
    #[arg(long, default_value_t = 0.01)]
    pub density: f64,
    /// Narrow band (voxels) of the banded JFA entry; for `metaball`, the field's band (cells).
    #[arg(long, default_value_t = 8.0)]
    pub band: f32,
    /// Peer command, run on the same mask (e.g. `python3 .gpu/peers/edt_cupyx.py`).
    #[arg(long)]
    pub peer: Option<String>,
    /// Where the tables and charts go.
    #[arg(long, default_value = "bench")]
    pub out: PathBuf,
    /// Only the exact transform (and the peer).
    #[arg(long)]
    pub exact_only: bool,
    /// Bands per column in the exact transform (1, 2, 4, 8, 16, 32); by grid size if absent.
    #[arg(long)]
    pub column_bands: Option<u32>,
    /// Columns per tile (at least) of the y pass where the exact transform splits a field
    /// too large for one binding (1024³); 4 if absent.
    #[arg(long)]
    pub split_columns: Option<u32>,
    /// Split the exact transform's field across bindings of at most this many bytes (to
    /// time the split path at sizes one binding holds); the device's binding size if absent.
    #[arg(long)]
    pub split_bytes: Option<u64>,
    /// `distance`: open the device with this `max_compute_workgroup_storage_size` (bytes)
    /// instead of the adapter's, to time the column-pass tiles each limit gives.
    #[arg(long)]
    pub workgroup_storage: Option<u32>,
    /// Only these edge lengths (3D edges from the sweep's 3D sizes, 2D from its 2D sizes;
    /// comma-separated), e.g. `--sizes 512` for one point. `volume` and `voxelize` take
    /// any sizes, in the order given.
    #[arg(long, value_delimiter = ',')]
    pub sizes: Vec<usize>,
    /// `distance`: 3D grids of these shapes (`XxYxZ`, comma-separated, e.g.
    /// `128x128x1024`) instead of the cubes; no 2D sizes then.
    #[arg(long, value_delimiter = ',', value_parser = crate::parse_shape)]
    pub shapes: Vec<[usize; 3]>,
    /// `voxelize`, `octree`: a mesh to time beside the torus: an OBJ file (the peers'
    /// Stanford bunny, `stanford-bunny.obj`); for `voxelize` also the npm bunny's `index.js`
    /// from `scripts/fetch-bunny.sh` (timed as it is and split twice).
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// `voxelize`: only these modes (surface, resident, raster, solid, attributes; comma-separated;
    /// `empty`, `zeroed`, `cleared` and `loaded`, an empty pass's floor, only where named).
    #[arg(long, value_delimiter = ',')]
    pub modes: Vec<String>,
    /// `voxelize`, `distance`: draw `voxelize.png` / `distance.png` into `--out` from this
    /// saved `voxelize.csv` / `distance.csv` instead of measuring (for a run cut short
    /// after its table was saved, or the tables of several runs joined into one file).
    #[arg(long)]
    pub replot: Option<PathBuf>,
}

/// Write `header` and `lines` to `dir/name`; returns the path.
pub(crate) fn write_table(
    dir: &std::path::Path,
    name: &str,
    header: &str,
    lines: impl IntoIterator<Item = String>,
) -> Result<PathBuf, String> {
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    let path = dir.join(name);
    let mut text = format!("{header}\n");
    for line in lines {
        text.push_str(&line);
        text.push('\n');
    }
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(path)
}

/// The fields of one line of a table [`write_table`] wrote, split at commas outside double
/// quotes (adapter and mesh names hold commas); the quotes are dropped. For `--replot`.
pub(crate) fn csv_fields(line: &str) -> Vec<String> {
    let mut fields = vec![String::new()];
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(String::new()),
            _ => fields.last_mut().expect("one field").push(c),
        }
    }
    fields
}

/// A fresh folder under the system's temporary one for a test's files (named after `tag` and
/// this process), and the path of `file` in it; the test removes the folder.
#[cfg(test)]
pub(crate) fn scratch_file(tag: &str, file: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("fieldkit-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let path = dir.join(file);
    (dir, path)
}

/// Least wall time of warm-up before the timed runs. GPU clocks fall while the CPU checks the
/// previous point: on the H100, 2048² exact measured 1.19 ms after three warm-up runs that
/// followed the 512³ sweep, and 0.26 ms once warmed up for longer. And a variant timed after
/// another at the same size (whose large buffers were just dropped) ran its first few timed
/// runs up to 2× slow after half a second of warm-up (one of three `bench distance --sizes 512`
/// runs on the H100, 2026-11-26), never after 2 s (five runs).
pub(crate) const WARMUP_TIME: std::time::Duration = std::time::Duration::from_millis(2000);

/// A timed run this many times the median is reported as slow.
const SLOW: f64 = 1.25;

/// The CPU's time to record `record` into a fresh encoder and submit it, `reps` times (at
/// least 20): median, fastest and slowest ms. Each submission's GPU work is waited for outside
/// the time, and what `record` returns is dropped after the wait, as a loop that runs the
/// stage every frame would.
pub(crate) fn host_times<T>(
    ctx: &Context,
    reps: usize,
    record: impl Fn(&mut wgpu::CommandEncoder) -> Result<T, String>,
) -> Result<(f64, f64, f64), String> {
    let mut host = Vec::new();
    for _ in 0..reps.max(20) {
        let mut enc = ctx.encoder("host");
        let start = std::time::Instant::now();
        let made = record(&mut enc)?;
        let index = ctx.queue.submit([enc.finish()]);
        host.push(start.elapsed().as_secs_f64() * 1e3);
        ctx.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| e.to_string())?;
        drop(made);
    }
    let (lo, hi) = host
        .iter()
        .fold((f64::MAX, 0.0f64), |(l, h), &t| (l.min(t), h.max(t)));
    Ok((median(host), lo, hi))
}

/// Median, fastest and slowest total ms, and each pass's median ms.
pub(crate) type Timing = (f64, f64, f64, Vec<(String, f64)>);

/// Time `reps` runs of `record` (after at least `warmup` runs and `WARMUP_TIME`), each recording
/// its passes into a fresh encoder; with `heater`, run before each submission.
pub(crate) fn time_runs(
    ctx: &Context,
    warmup: usize,
    reps: usize,
    heater: Option<&Heater>,
    mut record: impl FnMut(&mut wgpu::CommandEncoder, &mut Profiler),
) -> Result<Timing, String> {
    let mut prof = Profiler::new(&ctx.device, &ctx.queue, 64)
        .ok_or("the adapter has no timestamp queries; the benchmark needs them")?;
    let mut totals = Vec::new();
    let mut times = Vec::new();
    let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
    let start = std::time::Instant::now();
    let mut warm = 0;
    let mut timed = 0;
    while timed < reps {
        let mut enc = ctx.encoder("bench");
        record(&mut enc, &mut prof);
        prof.resolve(&mut enc);
        if let Some(h) = heater {
            h.run(ctx)?;
        }
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let (passes, total) = prof
            .read(&ctx.device, &ctx.queue)
            .wait(ctx)
            .map_err(|e| e.to_string())?;
        if warm < warmup || start.elapsed() < WARMUP_TIME {
            warm += 1;
            continue;
        }
        timed += 1;
        totals.push(total);
        times.push(start.elapsed().as_secs_f64());
        if per_pass.is_empty() {
            per_pass = passes
                .iter()
                .map(|(n, _)| (n.clone(), Vec::new()))
                .collect();
        }
        for (slot, (_, ms)) in per_pass.iter_mut().zip(&passes) {
            slot.1.push(*ms);
        }
    }
    let min = totals.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = totals.iter().cloned().fold(0.0, f64::max);
    let med = median(totals.clone());
    // Where a run is far off the median, say which: its index among the timed runs, and when it
    // ran. On the H100 (2026-11-26, four runs of `bench distance --sizes 512`) every such
    // run was one of the first three timed runs of a variant that followed another at the same
    // size, never in the first (the default path); warming up for half a second after the first
    // run instead of from the start moved nothing; warming up for 2 s (WARMUP_TIME) did.
    for (i, (&t, at)) in totals.iter().zip(&times).enumerate() {
        if t > SLOW * med {
            eprintln!(
                "  slow run: #{i} of {reps}, {t:.3} ms against a median of {med:.3} \
                 ({:.2} s after the first timed run)",
                at - times[0]
            );
        }
    }
    Ok((
        med,
        min,
        max,
        per_pass.into_iter().map(|(n, v)| (n, median(v))).collect(),
    ))
}

/// The benches' device: a context of fieldkit's choosing, its adapter's name (printed), and
/// timestamp queries on it.
pub(crate) fn bench_gpu() -> Result<(Context, String, Stamps), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    let adapter = ctx.adapter_name();
    println!("adapter: {adapter}");
    let stamps = Stamps::new(&ctx)?;
    Ok((ctx, adapter, stamps))
}

pub(crate) struct Stamps {
    set: wgpu::QuerySet,
    buf: wgpu::Buffer,
    period: f64,
}

impl Stamps {
    pub(crate) fn new(ctx: &Context) -> Result<Self, String> {
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
    pub(crate) fn time(
        &self,
        ctx: &Context,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<(), String>,
    ) -> Result<f64, String> {
        self.time_after(ctx, None, record)
    }

    /// [`Self::time`] with `heater` run (and waited for) between encoding `record` and
    /// submitting it, so the timed work starts at full clocks.
    pub(crate) fn time_after(
        &self,
        ctx: &Context,
        heater: Option<&Heater>,
        record: impl FnOnce(&mut wgpu::CommandEncoder) -> Result<(), String>,
    ) -> Result<f64, String> {
        let mut enc = ctx.encoder("bench");
        enc.write_timestamp(&self.set, 0);
        record(&mut enc)?;
        enc.write_timestamp(&self.set, 1);
        enc.resolve_query_set(&self.set, 0..2, &self.buf, 0);
        if let Some(h) = heater {
            h.run(ctx)?;
        }
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let b = read_buffer(ctx, &self.buf).map_err(|e| e.to_string())?;
        let t: &[u64] = bytemuck::cast_slice(&b);
        Ok(t[1].saturating_sub(t[0]) as f64 * self.period / 1e6)
    }
}

/// Pixel `i`'s ray (row-major over `view`'s viewport, through the pixel's centre): where it
/// leaves the near plane, its unit direction, and its length to the far plane, in f64.
pub(crate) fn pixel_ray(view: &fieldkit::view::View, i: usize) -> (glam::DVec3, glam::DVec3, f64) {
    let [w, h] = view.viewport.map(|s| s as usize);
    let inv = view.view_proj.as_dmat4().inverse();
    let (x, y) = ((i % w) as f64, (i / w) as f64);
    let ndc = glam::DVec2::new(
        (x + 0.5) / w as f64 * 2.0 - 1.0,
        1.0 - (y + 0.5) / h as f64 * 2.0,
    );
    let near = inv.project_point3(ndc.extend(0.0));
    let far = inv.project_point3(ndc.extend(1.0));
    (near, (far - near).normalize(), (far - near).length())
}

pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

/// Run `command` to its end: its standard output, or an error naming `what` with its standard
/// error where it could not start or failed.
pub fn stdout_of(command: &mut std::process::Command, what: &str) -> Result<String, String> {
    let out = command
        .output()
        .map_err(|e| format!("could not start {what}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{what} failed ({}):\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}
