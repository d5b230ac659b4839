//! `--frame-cost FRAMES`: what a frame of each scene costs the application, measured the way an
//! engine programmer profiles a frame: the CPU time to record and submit it, the wall time from
//! the start of recording to the GPU finishing it (record → done), the GPU time of the whole
//! frame (timestamps written into its encoder before its first pass and after its last, render
//! passes included) and of its timed passes alone (every compute pass, and the render passes
//! recorded through a `Recorder`: the ocean's), and the loop's own floor (an empty frame
//! submitted and waited for, the same way). Medians with min–max over FRAMES frames after 30
//! frames of warm-up; then the GPU objects (buffers, textures, views, bind groups) the most any
//! of 5 more frames creates, counted as wgpu-core creates them ([`super::made`]).
//!
//! Besides the steady frames it times the first frame of the scene and the time until the
//! scene draws whole (what it makes on worker threads arrived); the frames after the screen
//! shrinks and grows (the hitch a resize costs); and the frame after a size setting changes
//! and after each settings change the scene's panel offers ([`setting_changes`]), with the
//! most CPU of the frames until the scene settles.
//!
//! `cargo xtask bench frame` runs it for every scene and writes `frame.csv` and
//! `frame_settings.csv`; on its own it prints a table (`--out DIR` writes the CSVs there too).

use std::path::Path;
use std::time::Instant;

use fieldkit::gpu::{Context, PipelineCache, Profiler};
use fieldkit::view::Targets;

use super::changes::setting_changes;
use super::made::{self, Made};
use super::scenes::{COLOUR, DEPTH, NAMES, Saved, Scenes};
use super::{FrameShot, draw_frame, frame_time, record_frame, wait};

/// Frames drawn before the measured ones.
const WARM_UP: u32 = 30;

/// Frames whose GPU objects are counted, after the timed ones.
const COUNTED: u32 = 5;

/// The most frames timed after a size setting changes, waiting for the scene to settle.
const AFTER_CHANGE_MAX: u32 = 300;

/// Frames whose recording takes longer than this on the CPU are counted (a 144 Hz frame is
/// 6.9 ms in all).
const SLOW_CPU_MS: f64 = 2.0;

/// Median, min and max of a series, milliseconds.
#[derive(Clone, Copy, Debug, Default)]
pub struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    fn of(mut v: Vec<f64>) -> Self {
        if v.is_empty() {
            return Self::default();
        }
        v.sort_by(f64::total_cmp);
        Self {
            median: v[v.len() / 2],
            min: v[0],
            max: v[v.len() - 1],
        }
    }

    fn csv(&self) -> String {
        format!("{:.4},{:.4},{:.4}", self.median, self.min, self.max)
    }
}

/// One scene's frame cost.
#[derive(Debug)]
pub struct FrameCost {
    pub scene: String,
    pub size: [u32; 2],
    /// The first frame: record + submit + done (what is made on worker threads arrives later).
    pub first_ms: f64,
    /// From the first frame's start to the end of the first frame that drew the whole scene
    /// (nothing left on worker threads), frames drawn back to back.
    pub whole_ms: f64,
    /// Record + submit, CPU.
    pub cpu: Spread,
    /// Of that, the encoder's `finish` and the queue's `submit`.
    pub submit: Spread,
    /// Of that, inside fieldkit's calls (`None`: the scene does not time them).
    pub fieldkit: Option<Spread>,
    /// Start of recording to the GPU done.
    pub wall: Spread,
    /// The whole frame on the GPU: every pass, render passes included, and the gaps between
    /// them (adapters with timestamps inside encoders).
    pub gpu_frame: Spread,
    /// The frame's timed passes on the GPU, summed: every compute pass, and the render passes
    /// recorded through a `Recorder`.
    pub gpu_compute: Spread,
    /// Frames whose CPU time passed [`SLOW_CPU_MS`].
    pub slow_frames: usize,
    /// The frame after the screen size changed: CPU, and wall.
    pub resize_cpu_ms: f64,
    pub resize_wall_ms: f64,
    /// The frame after the screen grows to 110 % of the first size (past what the images
    /// sized to the target were made for): CPU, and wall; and the CPU of the resize itself,
    /// outside the frame: the app's own targets, then the images fieldkit's renderers draw
    /// with (`Scenes::resized`).
    pub grow_cpu_ms: f64,
    pub grow_wall_ms: f64,
    pub grow_targets_ms: f64,
    pub grow_reserve_ms: f64,
    /// The frame after a size setting changed ([`size_change`]): CPU, and wall; and the most
    /// CPU any of the frames after it took (five, or until the scene settled: a new cloud made
    /// on a worker thread arrived).
    pub change_cpu_ms: f64,
    pub change_wall_ms: f64,
    pub after_change_cpu_ms: f64,
    /// The loop's floor: an empty encoder submitted and waited for.
    pub floor: Spread,
    /// The floor's CPU time: an empty encoder made, finished and submitted (what any frame
    /// pays before it records anything).
    pub floor_cpu: Spread,
    /// The scene's typed error, if it refused its settings.
    pub error: Option<String>,
    /// The timed passes of the last profiled frame, GPU ms each.
    pub passes: Vec<(String, f64)>,
    /// wgpu's own spans over the timed frames, where they are timed (`spans::on`).
    pub spans: Vec<String>,
    /// The most GPU objects any measured frame made (after warm-up).
    pub made: Made,
    /// What the scene reported of its last measured frame (patches, instances, grid).
    pub stats: Vec<String>,
    /// The scene's readouts on the frame after the screen size changed.
    pub resize_stats: Vec<String>,
    /// The scene's readouts on the frame after a size setting changed.
    pub change_stats: Vec<String>,
    /// Which of the frames after that one (five, or until the scene settled) took the most
    /// CPU, and its readouts.
    pub slowest_after_change: (u32, Vec<String>),
    /// Each settings change the scene's panel offers ([`setting_changes`]), timed as the size
    /// change is.
    pub settings: Vec<Hitch>,
}

/// A change and what the frames after it cost: the frame it is made on (CPU, and wall), and
/// the most CPU any of the frames after took (five, or until the scene settled).
#[derive(Debug)]
pub struct Hitch {
    pub name: String,
    pub cpu_ms: f64,
    pub wall_ms: f64,
    pub after_cpu_ms: f64,
    /// Which frame after the change that was (1: the next), and its readouts.
    pub slowest: (u32, Vec<String>),
    /// wgpu's spans in that frame, where they are timed (`spans::on`).
    pub spans: Vec<String>,
    /// The scene's error on the frame of the change or after, if it refused the settings.
    pub error: Option<String>,
}

impl FrameCost {
    /// The frames that follow a change, ms: the resized frame's CPU and wall, the size-changed
    /// frame's CPU and wall, and the most CPU of the frames after it (the table's and the CSV's
    /// order).
    fn hitches(&self) -> [f64; 5] {
        [
            self.resize_cpu_ms,
            self.resize_wall_ms,
            self.change_cpu_ms,
            self.change_wall_ms,
            self.after_change_cpu_ms,
        ]
    }
}

/// Measure `scenes` (all of them where empty) at `size`, print the table, write `frame.csv`
/// into `out` where given; with `cache`, every pipeline goes through the pipeline cache kept
/// there (loaded first, saved after the last scene).
pub fn run(
    scenes: &[String],
    saved: &Saved,
    size: [u32; 2],
    frames: u32,
    out: Option<&Path>,
    cache: Option<&Path>,
) -> Result<(), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    let adapter = ctx.adapter_name();
    let pipeline_cache = match (cache, &ctx.adapter) {
        (Some(dir), Some(a)) => PipelineCache::open(&ctx.device, &a.get_info(), dir)
            .map_err(|e| format!("pipeline cache {}: {e}", dir.display()))?,
        _ => None,
    };
    let loaded = pipeline_cache.as_ref().map(PipelineCache::loaded_bytes);
    let names: Vec<String> = if scenes.is_empty() {
        NAMES.iter().map(|s| s.to_string()).collect()
    } else {
        scenes.to_vec()
    };
    let mut costs = Vec::new();
    for scene in &names {
        let cost = measure(&ctx, scene, saved, size, frames.max(1)).map_err(|e| e.to_string())?;
        costs.push(cost);
    }
    print_table(&adapter, &costs);
    let start = match loaded {
        None => "none".to_string(),
        Some(0) => "cold".to_string(),
        Some(_) => "warm".to_string(),
    };
    if let Some(c) = &pipeline_cache {
        c.save()
            .map_err(|e| format!("saving the pipeline cache: {e}"))?;
        println!(
            "pipeline cache: started {start} ({} bytes), saved {} bytes",
            c.loaded_bytes(),
            c.data().map_or(0, |d| d.len())
        );
    }
    if let Some(dir) = out {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        write_csv(&dir.join("frame.csv"), &adapter, &start, &costs)?;
        write_settings_csv(&dir.join("frame_settings.csv"), &adapter, &start, &costs)?;
        println!(
            "wrote {} and frame_settings.csv",
            dir.join("frame.csv").display()
        );
    }
    Ok(())
}

/// Frame `at.number` of `scene`: (CPU record + submit ms, wall ms to done).
fn timed_frame(
    ctx: &Context,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    at: Shot,
    profiler: Option<&mut Profiler>,
) -> Result<Timed, fieldkit::Error> {
    let Shot {
        targets,
        size,
        number: i,
    } = at;
    let start = Instant::now();
    let (report, index) = draw_frame(
        &ctx.device,
        &ctx.queue,
        scenes,
        saved,
        scene,
        targets,
        size,
        frame_time(i),
        i,
        profiler,
    );
    let cpu = start.elapsed().as_secs_f64() * 1e3;
    let (submit, fieldkit) = (report.submit_ms, report.fieldkit_ms);
    ctx.device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(index),
            timeout: None,
        })
        .map_err(|e| fieldkit::Error::Readback(e.to_string()))?;
    let wall = start.elapsed().as_secs_f64() * 1e3;
    Ok(Timed {
        cpu,
        submit,
        fieldkit,
        wall,
        error: report.error.map(|e| e.to_string()),
        stats: report.stats,
    })
}

/// What [`timed_frame`] measured of a frame.
struct Timed {
    /// Record + submit, CPU ms.
    cpu: f64,
    /// The encoder's `finish` and the queue's `submit` alone, CPU ms.
    submit: f64,
    /// Inside fieldkit's calls, CPU ms, where the scene times them.
    fieldkit: Option<f64>,
    /// Start of recording to the GPU done, ms.
    wall: f64,
    error: Option<String>,
    stats: Vec<String>,
}

fn measure(
    ctx: &Context,
    scene: &str,
    saved: &Saved,
    size: [u32; 2],
    frames: u32,
) -> Result<FrameCost, fieldkit::Error> {
    let targets = Targets::new(&ctx.device, size, COLOUR, DEPTH);
    let mut scenes = Scenes::new();
    let first = Shot {
        targets: &targets,
        size,
        number: 0,
    };
    let (first_ms, whole_ms) = warm_up(ctx, &mut scenes, saved, scene, first)?;
    let (mut cpu, mut wall, mut submit, mut error) = (Vec::new(), Vec::new(), Vec::new(), None);
    let mut fieldkit = Vec::new();
    let mut stats = Vec::new();
    super::spans::reset();
    for i in WARM_UP..WARM_UP + frames {
        let t = timed_frame(ctx, &mut scenes, saved, scene, first.then(i), None)?;
        cpu.push(t.cpu);
        submit.push(t.submit);
        fieldkit.extend(t.fieldkit);
        wall.push(t.wall);
        error = error.or(t.error);
        stats = t.stats;
    }
    let spans = super::spans::lines(frames);
    let at = first.then(WARM_UP + frames);
    let made = counted(ctx, &mut scenes, saved, scene, &at)?;
    let (gpu, last_passes) = timed_passes(ctx, &mut scenes, saved, scene, &at, frames.min(20))?;
    let gpu_frame = gpu_frame_times(ctx, &mut scenes, saved, scene, &targets, size, frames)?;
    // A new screen size: the targets a window's resize hands over, then one frame.
    let resized = [size[0] * 9 / 10, size[1] * 9 / 10];
    let small = Targets::new(&ctx.device, resized, COLOUR, DEPTH);
    let n = WARM_UP + 2 * frames;
    let at = Shot {
        targets: &small,
        size: resized,
        number: n,
    };
    let resized_frame = timed_frame(ctx, &mut scenes, saved, scene, at, None)?;
    let (resize_cpu_ms, resize_wall_ms) = (resized_frame.cpu, resized_frame.wall);
    // A size setting changes (the grid, the mask, the cloud): that frame, then a few more.
    let changed = size_change(scene, saved);
    let n = n + 1;
    let at = at.then(1);
    let (change, change_stats) = hitch(ctx, &mut scenes, &changed, scene, &at, "size")?;
    let slowest_after_change = change.slowest.clone();
    // Each settings change the panel offers, from the saved settings and back.
    let mut settings = Vec::new();
    let changes = setting_changes(scene, saved);
    let grow_at = n + (changes.len() as u32 + 1) * 2 * AFTER_CHANGE_MAX;
    for (k, (name, changed)) in changes.into_iter().enumerate() {
        let at = at.then((k as u32 + 1) * 2 * AFTER_CHANGE_MAX);
        settings.push(hitch(ctx, &mut scenes, &changed, scene, &at, &name)?.0);
        let back = at.then(AFTER_CHANGE_MAX);
        hitch(ctx, &mut scenes, saved, scene, &back, "back")?;
    }
    // The window grows past its first size: the app remakes its targets and has the
    // renderers make the images they draw with at the new size (outside the frame), then
    // draws.
    let grown = [size[0] * 11 / 10, size[1] * 11 / 10];
    let start = Instant::now();
    let big = Targets::new(&ctx.device, grown, COLOUR, DEPTH);
    let grow_targets_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    scenes.resized(&ctx.device, grown)?;
    let grow_reserve_ms = start.elapsed().as_secs_f64() * 1e3;
    let at = Shot {
        targets: &big,
        size: grown,
        number: grow_at,
    };
    let grown_frame = timed_frame(ctx, &mut scenes, saved, scene, at, None)?;
    let floor = empty_submits(ctx, frames)?;
    Ok(FrameCost {
        scene: scene.to_string(),
        size,
        first_ms,
        whole_ms,
        slow_frames: cpu.iter().filter(|&&c| c > SLOW_CPU_MS).count(),
        cpu: Spread::of(cpu),
        submit: Spread::of(submit),
        fieldkit: (!fieldkit.is_empty()).then(|| Spread::of(fieldkit)),
        wall: Spread::of(wall),
        gpu_frame: Spread::of(gpu_frame),
        gpu_compute: Spread::of(gpu),
        resize_cpu_ms,
        resize_wall_ms,
        grow_cpu_ms: grown_frame.cpu,
        grow_wall_ms: grown_frame.wall,
        grow_targets_ms,
        grow_reserve_ms,
        change_cpu_ms: change.cpu_ms,
        change_wall_ms: change.wall_ms,
        after_change_cpu_ms: change.after_cpu_ms,
        floor: Spread::of(floor.iter().map(|f| f.1).collect()),
        floor_cpu: Spread::of(floor.iter().map(|f| f.0).collect()),
        error,
        passes: last_passes,
        spans,
        made,
        stats,
        resize_stats: resized_frame.stats,
        change_stats,
        slowest_after_change,
        settings,
    })
}

/// `frames` empty command buffers submitted one at a time: each one's (CPU ms to submit, wall
/// ms to done), the floor under every frame's figures.
fn empty_submits(ctx: &Context, frames: u32) -> Result<Vec<(f64, f64)>, fieldkit::Error> {
    (0..frames)
        .map(|_| {
            let start = Instant::now();
            let enc = ctx.device.create_command_encoder(&Default::default());
            let index = ctx.queue.submit([enc.finish()]);
            let cpu = start.elapsed().as_secs_f64() * 1e3;
            ctx.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(index),
                    timeout: None,
                })
                .map_err(|e| fieldkit::Error::Readback(e.to_string()))?;
            Ok((cpu, start.elapsed().as_secs_f64() * 1e3))
        })
        .collect()
}

/// The scene's first frames: the first one's record → done, and the time from its start to
/// the end of the first frame that drew the whole scene; then warm-up frames, and on until
/// what the scene makes on other threads has arrived, so that the measured frames draw it all.
fn warm_up(
    ctx: &Context,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    first: Shot,
) -> Result<(f64, f64), fieldkit::Error> {
    let start = Instant::now();
    let first_ms = timed_frame(ctx, scenes, saved, scene, first, None)?.wall;
    let mut whole_ms = (!scenes.busy(scene, saved)).then_some(first_ms);
    for i in 1..WARM_UP + AFTER_CHANGE_MAX {
        if i >= WARM_UP {
            if !scenes.busy(scene, saved) {
                break;
            }
            scenes.wait_for_workers();
        }
        timed_frame(ctx, scenes, saved, scene, first.then(i), None)?;
        if whole_ms.is_none() && !scenes.busy(scene, saved) {
            whole_ms = Some(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    Ok((first_ms, whole_ms.unwrap_or(f64::NAN)))
}

/// The most GPU objects any of [`COUNTED`] frames makes, in frames of their own: counting
/// them costs CPU time.
fn counted(
    ctx: &Context,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    at: &Shot,
) -> Result<Made, fieldkit::Error> {
    let mut made = Made::default();
    for i in 0..COUNTED {
        let frame = || timed_frame(ctx, scenes, saved, scene, at.then(i), None);
        let (t, m) = made::count(frame);
        t?;
        made = made.max(m.ok_or_else(|| {
            fieldkit::Error::invalid("frame cost", "another logger is installed")
        })?);
    }
    Ok(made)
}

/// The timed passes' GPU time over `frames` frames, in frames of their own (timestamp
/// queries change what they measure): each frame's sum, and the last frame's passes.
type Passes = (Vec<f64>, Vec<(String, f64)>);

fn timed_passes(
    ctx: &Context,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    at: &Shot,
    frames: u32,
) -> Result<Passes, fieldkit::Error> {
    let (mut gpu, mut last) = (Vec::new(), Vec::new());
    let Some(mut profiler) = Profiler::new(&ctx.device, &ctx.queue, 256) else {
        return Ok((gpu, last));
    };
    for i in 0..frames {
        timed_frame(ctx, scenes, saved, scene, at.then(i), Some(&mut profiler))?;
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        profiler.resolve(&mut enc);
        ctx.queue.submit([enc.finish()]);
        let (passes, _) = wait(&ctx.device, profiler.read(&ctx.device, &ctx.queue))?;
        gpu.push(passes.iter().fold(0.0, |t, p| t + p.1));
        last = passes;
    }
    Ok((gpu, last))
}

/// Where the frames after a change are drawn: the targets, their size, the first frame's
/// number.
#[derive(Clone, Copy)]
struct Shot<'a> {
    targets: &'a Targets,
    size: [u32; 2],
    number: u32,
}

impl Shot<'_> {
    /// The same targets, `k` frames on.
    fn then(self, k: u32) -> Self {
        Self {
            number: self.number + k,
            ..self
        }
    }
}

/// Draw `changed` from frame `at.number` on: the frame of the change, then five more and on
/// until what the scene makes elsewhere for it (a cloud, a pipeline on a worker thread) has
/// arrived and been drawn. What they cost; the change frame's readouts, and which later frame
/// took the most CPU with its readouts (in the `Hitch`).
fn hitch(
    ctx: &Context,
    scenes: &mut Scenes,
    changed: &Saved,
    scene: &str,
    at: &Shot,
    name: &str,
) -> Result<(Hitch, Vec<String>), fieldkit::Error> {
    let frame =
        |scenes: &mut Scenes, k: u32| timed_frame(ctx, scenes, changed, scene, at.then(k), None);
    let change = frame(scenes, 0)?;
    let mut error = change.error.clone();
    let mut after = Vec::new();
    for k in 1..=AFTER_CHANGE_MAX {
        super::spans::reset();
        let t = frame(scenes, k)?;
        error = error.or(t.error);
        after.push((t.cpu, k, t.stats, super::spans::lines(1)));
        if k >= 5 && !scenes.busy(scene, changed) {
            break;
        }
    }
    let (after_cpu_ms, slowest, slowest_stats, spans) = after
        .into_iter()
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .expect("five frames");
    let hitch = Hitch {
        spans,
        name: name.to_string(),
        cpu_ms: change.cpu,
        wall_ms: change.wall,
        after_cpu_ms,
        slowest: (slowest, slowest_stats),
        error,
    };
    Ok((hitch, change.stats))
}

/// `saved` with the size setting of `scene` changed, as a user drags a slider: the actor's
/// extent (its grid), the cloud's voxels, the 2D tool's mask and the voxelizer's grid each
/// grow by a little over a tenth; the ocean's LOD error halves; the composite takes the
/// actor's and the cloud's changes.
pub fn size_change(scene: &str, saved: &Saved) -> Saved {
    let mut s = saved.clone();
    let grow = |n: u32| n + n / 10 + 1;
    match scene {
        "actor" => s.actor.extent = s.actor.extent.map(|e| e * 1.1),
        "ocean" => s.ocean.lod.max_error_px *= 0.5,
        "volume" => s.volume.size = grow(s.volume.size),
        "distance2d" => s.distance.size = s.distance.size.map(grow),
        "voxelizer" => s.voxelizer.grid = grow(s.voxelizer.grid),
        _ => {
            s.actor.extent = s.actor.extent.map(|e| e * 1.1);
            s.volume.size = grow(s.volume.size);
        }
    }
    s
}

/// The GPU time of whole frames, each in a submission of its own: timestamps written into the
/// frame's encoder before its first pass and after its last. Empty where the adapter has no
/// timestamps inside encoders.
fn gpu_frame_times(
    ctx: &Context,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    targets: &Targets,
    size: [u32; 2],
    frames: u32,
) -> Result<Vec<f64>, fieldkit::Error> {
    let need = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
    if !ctx.device.features().contains(need) {
        return Ok(Vec::new());
    }
    let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("frame cost stamps"),
        ty: wgpu::QueryType::Timestamp,
        count: 2,
    });
    let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("frame cost stamps"),
        size: 16,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let period = ctx.queue.get_timestamp_period() as f64;
    let mut times = Vec::new();
    for i in 0..frames.min(20) {
        let number = WARM_UP + frames + 20 + i;
        let shot = FrameShot {
            scene,
            targets,
            size,
            time: frame_time(number),
            number,
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.write_timestamp(&set, 0);
        record_frame(
            &ctx.device,
            &ctx.queue,
            scenes,
            saved,
            &shot,
            &mut encoder,
            None,
        );
        encoder.write_timestamp(&set, 1);
        encoder.resolve_query_set(&set, 0..2, &resolved, 0);
        ctx.queue.submit([encoder.finish()]);
        scenes.submitted(&ctx.device, &ctx.queue);
        let ticks = wait(
            &ctx.device,
            fieldkit::gpu::readback_buffer(&ctx.device, &ctx.queue, &resolved),
        )?;
        let t: &[u64] = bytemuck::cast_slice(&ticks);
        times.push(t[1].saturating_sub(t[0]) as f64 * period / 1e6);
    }
    Ok(times)
}

fn print_table(adapter: &str, costs: &[FrameCost]) {
    println!("frame cost on {adapter}");
    println!(
        "| scene | size | CPU record + submit ms | of which in fieldkit's calls ms | of which finish + submit ms | record → done ms | GPU frame ms | GPU timed passes ms | loop floor CPU / wall ms | frames > {SLOW_CPU_MS} ms CPU | first frame / whole scene ms | resize frame CPU / wall ms, shrunk; grown (the resize itself, CPU: the app's targets + fieldkit's images) | size change CPU / wall ms, then CPU at most | made a frame: buffers / textures / views / bind groups |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let s = |x: &Spread| format!("{:.3} ({:.3}–{:.3})", x.median, x.min, x.max);
    for c in costs {
        let [r_cpu, r_wall, c_cpu, c_wall, after] = c.hitches();
        let made = c.made.counts().map(|n| n.to_string()).join(" / ");
        let floor = format!("{} / {}", s(&c.floor_cpu), s(&c.floor));
        let error = c
            .error
            .as_ref()
            .map_or(String::new(), |e| format!(" error: {e}"));
        println!(
            "| {} | {}×{} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} / {:.1} | {r_cpu:.2} / {r_wall:.2}; {:.2} / {:.2} ({:.2} + {:.2}) | {c_cpu:.2} / {c_wall:.2}, {after:.2} | {made} |{error}",
            c.scene,
            c.size[0],
            c.size[1],
            s(&c.cpu),
            c.fieldkit.as_ref().map_or("—".into(), s),
            s(&c.submit),
            s(&c.wall),
            s(&c.gpu_frame),
            s(&c.gpu_compute),
            floor,
            c.slow_frames,
            c.first_ms,
            c.whole_ms,
            c.grow_cpu_ms,
            c.grow_wall_ms,
            c.grow_targets_ms,
            c.grow_reserve_ms,
        );
    }
    for c in costs.iter().filter(|c| !c.settings.is_empty()) {
        let worst = |f: fn(&Hitch) -> f64| {
            c.settings
                .iter()
                .max_by(|a, b| f(a).total_cmp(&f(b)))
                .map_or(String::new(), |h| format!("{:.2} ms ({})", f(h), h.name))
        };
        println!(
            "{} settings changes ({}): the most CPU on the frame of one {}, on a frame after {}",
            c.scene,
            c.settings.len(),
            worst(|h| h.cpu_ms),
            worst(|h| h.after_cpu_ms)
        );
        for h in &c.settings {
            let error = h
                .error
                .as_ref()
                .map_or(String::new(), |e| format!(" error: {e}"));
            println!(
                "  {}: CPU {:.2} ms, wall {:.2} ms, then CPU at most {:.2} ms (frame {} after: {}){error}",
                h.name,
                h.cpu_ms,
                h.wall_ms,
                h.after_cpu_ms,
                h.slowest.0,
                h.slowest.1.join("; ")
            );
            for line in h.spans.iter().take(12) {
                println!("    {line}");
            }
        }
    }
    for c in costs.iter().filter(|c| !c.passes.is_empty()) {
        let passes: Vec<String> = c
            .passes
            .iter()
            .map(|(n, ms)| format!("{n} {ms:.3}"))
            .collect();
        println!("{} timed passes (ms): {}", c.scene, passes.join(", "));
    }
    for c in costs.iter().filter(|c| !c.spans.is_empty()) {
        println!("{} wgpu's spans, a frame (inclusive):", c.scene);
        for line in &c.spans {
            println!("  {line}");
        }
    }
    for c in costs.iter().filter(|c| !c.stats.is_empty()) {
        println!("{}: {}", c.scene, c.stats.join("; "));
        println!("{} after a resize: {}", c.scene, c.resize_stats.join("; "));
        println!(
            "{} after a size change: {}",
            c.scene,
            c.change_stats.join("; ")
        );
        let (k, stats) = &c.slowest_after_change;
        println!(
            "{} the slowest frame after that one (the {k}th): {}",
            c.scene,
            stats.join("; ")
        );
    }
}

/// `start`: how the pipeline cache started (none, cold, warm).
fn write_csv(path: &Path, adapter: &str, start: &str, costs: &[FrameCost]) -> Result<(), String> {
    let mut text = String::from(
        "adapter,pipeline_cache,scene,width,height,cpu_ms_median,cpu_ms_min,cpu_ms_max,wall_ms_median,wall_ms_min,\
         wall_ms_max,gpu_frame_ms_median,gpu_frame_ms_min,gpu_frame_ms_max,gpu_compute_ms_median,gpu_compute_ms_min,gpu_compute_ms_max,floor_ms_median,\
         floor_ms_min,floor_ms_max,slow_cpu_frames,first_frame_ms,resize_cpu_ms,resize_wall_ms,\
         change_cpu_ms,change_wall_ms,after_change_cpu_ms,made_buffers,made_textures,made_views,made_bind_groups,\
         floor_cpu_ms_median,floor_cpu_ms_min,floor_cpu_ms_max,submit_ms_median,submit_ms_min,submit_ms_max,\
         fieldkit_ms_median,fieldkit_ms_min,fieldkit_ms_max,whole_scene_ms,grow_cpu_ms,grow_wall_ms,grow_targets_ms,grow_reserve_ms\n",
    );
    for c in costs {
        text += &format!(
            "\"{adapter}\",{start},{},{},{},{},{},{},{},{},{},{:.3},{},{},{},{},{},{:.3},{:.4},{:.4},{:.4},{:.4}\n",
            c.scene,
            c.size[0],
            c.size[1],
            c.cpu.csv(),
            c.wall.csv(),
            c.gpu_frame.csv(),
            c.gpu_compute.csv(),
            c.floor.csv(),
            c.slow_frames,
            c.first_ms,
            c.hitches().map(|ms| format!("{ms:.4}")).join(","),
            c.made.counts().map(|n| n.to_string()).join(","),
            c.floor_cpu.csv(),
            c.submit.csv(),
            c.fieldkit.as_ref().map_or(",,".into(), Spread::csv),
            c.whole_ms,
            c.grow_cpu_ms,
            c.grow_wall_ms,
            c.grow_targets_ms,
            c.grow_reserve_ms,
        );
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Each settings change of each scene: the frame it is made on and the most CPU after.
fn write_settings_csv(
    path: &Path,
    adapter: &str,
    start: &str,
    costs: &[FrameCost],
) -> Result<(), String> {
    let mut text =
        String::from("adapter,pipeline_cache,scene,change,cpu_ms,wall_ms,after_cpu_ms,error\n");
    for c in costs {
        for h in &c.settings {
            text += &format!(
                "\"{adapter}\",{start},{},\"{}\",{:.4},{:.4},{:.4},\"{}\"\n",
                c.scene,
                h.name.replace('"', "'"),
                h.cpu_ms,
                h.wall_ms,
                h.after_cpu_ms,
                h.error.as_deref().unwrap_or("").replace('"', "'"),
            );
        }
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}
