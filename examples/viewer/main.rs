//! fieldkit's live viewer: every seed system running in a window, its settings editable, its
//! cost on screen — an eframe (egui + wgpu) application that uses fieldkit through its public
//! API only, so it is also the proof that the API is enough for a real render loop.
//!
//! ```sh
//! cargo run --release --example viewer                              # the window
//! cargo run --release --example viewer -- --scene ocean             # start on a scene
//! cargo run --release --example viewer -- --scene actor --frames 30 --screenshot actor.png
//! cargo run --release --example viewer -- --window --scene actor --frames 5 --screenshot a.png
//! cargo run --release --example viewer -- --scene volume --settings my.ron --frames 1 --screenshot v.png
//! ```
//!
//! `--screenshot` without `--window` renders offscreen (no display needed) and prints each
//! frame's cost; with `--window` the window draws `--frames` frames and saves the last one.
//! Either way the animation advances 1/60 s a frame, so the two agree. Settings files are RON:
//! the panel's "Save" writes one.
//!
//! Scenes: `actor` (seed 000, the voxel actor: grid builder, metaball surface, debug cubes),
//! `ocean` (seed 001), `volume` (seed 002), `distance2d` (seed 003: draw seeds with the left
//! button, erase with the right), `voxelizer` (seed 004; `--mesh PATH` loads an OBJ) and
//! `composite` (ocean, metaball island and cloud in one frame with one depth buffer).
//!
//! `--soak FRAMES` runs the four animated techniques (or `--scene`'s) for FRAMES frames each,
//! offscreen (`--size`, default 320×240), sampling memory after every frame, and fails when a
//! frame errs or memory grows after warm-up (see `soak.rs`; `cargo xtask soak` runs 10 000).
//! `--frame-cost FRAMES` measures what a frame of each scene (or `--scene`'s) costs at 1920×1080
//! (or `--size`): CPU to record and submit, submit → done, the GPU's compute passes, the loop's
//! floor, the first frame and a resize (see `frame.rs`; `cargo xtask bench frame` runs it).
//! `--pipeline-cache DIR` keeps fieldkit's pipeline cache there between launches (the window
//! keeps one in the user's cache folder unless given `off`), so that a second launch's first
//! frame does not compile its pipelines again.

pub mod camera;
pub mod changes;
pub mod draw;
pub mod frame;
pub mod made;
pub mod panels;
pub mod scene_panels;
pub mod scenes;
pub mod soak;
pub mod spans;
pub mod widgets;

use std::path::{Path, PathBuf};
use std::time::Instant;

use fieldkit::Error;
use fieldkit::gpu::{Profiler, Readback, Recorder};
use fieldkit::view::Targets;

use scenes::{COLOUR, DEPTH, Frame, NAMES, Saved, Scenes};

/// Command-line options.
#[derive(Clone, Debug, Default)]
pub struct Args {
    /// The scene to start on (or render headless).
    pub scene: Option<String>,
    /// Frames to draw before the screenshot.
    pub frames: Option<u32>,
    /// Where the screenshot goes.
    pub screenshot: Option<PathBuf>,
    /// A settings file to load.
    pub settings: Option<PathBuf>,
    /// An OBJ for the voxelizer.
    pub mesh: Option<String>,
    /// Draw in a window even with `--screenshot`.
    pub window: bool,
    /// Offscreen size.
    pub size: [u32; 2],
    /// `--size` was given.
    pub sized: bool,
    /// Soak: frames per scene.
    pub soak: Option<u32>,
    /// `--preset seed`: start from every scene's seed preset (the sources' settings).
    pub seed: bool,
    /// Frame cost: frames measured per scene.
    pub frame_cost: Option<u32>,
    /// Where `--frame-cost` writes `frame.csv`.
    pub out: Option<PathBuf>,
    /// `--pipeline-cache DIR`: where the pipeline cache is kept between launches
    /// (`--pipeline-cache off`: none). The window keeps one in the user's cache folder by
    /// default; `--frame-cost` only where asked.
    pub pipeline_cache: Option<PathBuf>,
    /// `--pipeline-cache off`.
    pub no_pipeline_cache: bool,
}

impl Args {
    /// Where the window keeps its pipeline cache: `--pipeline-cache DIR`, else
    /// `$XDG_CACHE_HOME/fieldkit` or `~/.cache/fieldkit`.
    pub fn window_pipeline_cache(&self) -> Option<PathBuf> {
        if self.no_pipeline_cache {
            return None;
        }
        self.pipeline_cache.clone().or_else(|| {
            let base = std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
            Some(base.join("fieldkit"))
        })
    }
}

fn parse(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let mut a = Args {
        size: [1280, 720],
        ..Args::default()
    };
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--scene" => a.scene = Some(value()?),
            "--frames" => a.frames = Some(value()?.parse().map_err(|e| format!("--frames: {e}"))?),
            "--screenshot" => a.screenshot = Some(value()?.into()),
            "--settings" => a.settings = Some(value()?.into()),
            "--mesh" => a.mesh = Some(value()?),
            "--window" => a.window = true,
            "--preset" => match value()?.as_str() {
                "seed" => a.seed = true,
                "fieldkit" => a.seed = false,
                other => return Err(format!("--preset {other:?}: seed or fieldkit")),
            },
            "--soak" => a.soak = Some(value()?.parse().map_err(|e| format!("--soak: {e}"))?),
            "--frame-cost" => {
                a.frame_cost = Some(value()?.parse().map_err(|e| format!("--frame-cost: {e}"))?)
            }
            "--out" => a.out = Some(value()?.into()),
            "--pipeline-cache" => match value()?.as_str() {
                "off" => a.no_pipeline_cache = true,
                dir => a.pipeline_cache = Some(dir.into()),
            },
            "--size" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or("--size WxH")?;
                a.size = [
                    w.parse().map_err(|e| format!("--size: {e}"))?,
                    h.parse().map_err(|e| format!("--size: {e}"))?,
                ];
                a.sized = true;
            }
            "--help" | "-h" => return Err(HELP.into()),
            other => return Err(format!("unknown argument {other:?}\n{HELP}")),
        }
    }
    if let Some(s) = &a.scene
        && !NAMES.contains(&s.as_str())
    {
        return Err(format!(
            "no scene {s:?}; the scenes are {}",
            NAMES.join(", ")
        ));
    }
    Ok(a)
}

const HELP: &str = "viewer [--scene NAME] [--frames N] [--screenshot FILE.png] [--settings FILE.ron] \
[--mesh FILE.obj] [--size WxH] [--window] [--soak FRAMES] [--frame-cost FRAMES [--out DIR]] \
[--preset seed|fieldkit] [--pipeline-cache DIR|off]";

/// Read a settings file (RON). Missing fields take their defaults.
pub fn load_settings(path: &Path) -> Result<Saved, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    ron::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Write a settings file (RON).
pub fn save_settings(path: &Path, s: &Saved) -> Result<(), String> {
    let text = ron::ser::to_string_pretty(s, ron::ser::PrettyConfig::default())
        .map_err(|e| e.to_string())?;
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Seconds of animation at frame `i` of a fixed-step run.
pub fn frame_time(i: u32) -> f32 {
    i as f32 / 60.0
}

/// What one recorded frame reports.
pub struct FrameReport {
    /// The scene's readouts.
    pub stats: Vec<String>,
    /// The scene's typed error, if it refused its settings (the frame then holds what was
    /// recorded before the error).
    pub error: Option<Error>,
    /// CPU milliseconds the encoder's `finish` and the queue's `submit` took ([`draw_frame`]).
    pub submit_ms: f64,
    /// CPU milliseconds inside fieldkit's calls, where the scene times them
    /// ([`scenes::Frame::fieldkit_ms`]).
    pub fieldkit_ms: Option<f64>,
}

/// Record and submit one frame of `scene`; `profiler` times its compute passes.
#[allow(clippy::too_many_arguments)]
pub fn draw_frame(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scenes: &mut Scenes,
    saved: &Saved,
    scene: &str,
    targets: &Targets,
    size: [u32; 2],
    time: f32,
    number: u32,
    profiler: Option<&mut Profiler>,
) -> (FrameReport, wgpu::SubmissionIndex) {
    let mut encoder = device.create_command_encoder(&Default::default());
    let shot = FrameShot {
        scene,
        targets,
        size,
        time,
        number,
    };
    let mut report = record_frame(device, queue, scenes, saved, &shot, &mut encoder, profiler);
    let start = std::time::Instant::now();
    let index = queue.submit([encoder.finish()]);
    report.submit_ms = start.elapsed().as_secs_f64() * 1e3;
    scenes.submitted(device, queue);
    (report, index)
}

/// Which frame of which scene to record, into which targets.
pub struct FrameShot<'a> {
    pub scene: &'a str,
    pub targets: &'a Targets,
    pub size: [u32; 2],
    /// Seconds of animation.
    pub time: f32,
    pub number: u32,
}

/// Record one frame of `shot.scene` into `encoder` (the caller submits it, then calls
/// `scenes.submitted`); `profiler` times its compute passes.
pub fn record_frame(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scenes: &mut Scenes,
    saved: &Saved,
    shot: &FrameShot,
    encoder: &mut wgpu::CommandEncoder,
    profiler: Option<&mut Profiler>,
) -> FrameReport {
    let index = NAMES.iter().position(|n| *n == shot.scene).unwrap_or(0);
    let camera = saved
        .cameras
        .get(index)
        .copied()
        .unwrap_or_else(|| scenes::default_camera(shot.scene));
    let result = {
        let mut rec = match profiler {
            Some(p) => p.record(encoder),
            None => Recorder {
                encoder,
                profiler: None,
            },
        };
        let mut frame = Frame {
            device,
            queue,
            rec: &mut rec,
            targets: shot.targets,
            size: shot.size,
            camera,
            time: shot.time,
            number: shot.number,
            fieldkit_ms: None,
        };
        let lines = scenes.encode(shot.scene, saved, &mut frame);
        (lines, frame.fieldkit_ms)
    };
    match result {
        (Ok(stats), fieldkit_ms) => FrameReport {
            stats,
            error: None,
            submit_ms: 0.0,
            fieldkit_ms,
        },
        (Err(e), fieldkit_ms) => FrameReport {
            stats: Vec::new(),
            error: Some(e),
            submit_ms: 0.0,
            fieldkit_ms,
        },
    }
}

/// RGBA8 pixels of the colour target, blocking (screenshots only).
pub fn read_colour(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    targets: &Targets,
) -> Result<Vec<u8>, Error> {
    let readback = fieldkit::gpu::readback_texture::<[u8; 4]>(device, queue, &targets.colour);
    Ok(wait(device, readback)?.concat())
}

/// Block until `readback` is ready (headless runs and screenshots only).
pub fn wait<T: 'static>(device: &wgpu::Device, mut readback: Readback<T>) -> Result<T, Error> {
    loop {
        if let Some(r) = readback.try_take() {
            return r;
        }
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Readback(e.to_string()))?;
    }
}

/// A headless run's result.
pub struct Shot {
    /// The last frame, RGBA8, `size`.
    pub pixels: Vec<u8>,
    /// Its size.
    pub size: [u32; 2],
    /// The last frame's report.
    pub report: FrameReport,
    /// Milliseconds per frame, submit to finished, each frame.
    pub frame_ms: Vec<f64>,
    /// The passes of the last frame (compute and render) with their GPU milliseconds (adapters with
    /// timestamp queries).
    pub passes: Vec<(String, f64)>,
}

/// Draw `frames` frames of `scene` offscreen (then as many more, at the last frame's time, as
/// its readbacks need to reach the screen) and return the last.
pub fn render_offscreen(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &str,
    saved: &Saved,
    size: [u32; 2],
    frames: u32,
) -> Result<Shot, Error> {
    let targets = Targets::new(device, size, COLOUR, DEPTH);
    let mut scenes = Scenes::new();
    let mut profiler = Profiler::new(device, queue, 256);
    let mut frame_ms = Vec::new();
    let mut report;
    let mut passes = Vec::new();
    let frames = frames.max(1);
    let mut i = 0;
    let mut extra = 0;
    loop {
        let last = i + 1 >= frames;
        let time = frame_time(i.min(frames - 1));
        let start = Instant::now();
        let (r, index) = draw_frame(
            device,
            queue,
            &mut scenes,
            saved,
            scene,
            &targets,
            size,
            time,
            i,
            profiler.as_mut().filter(|_| last),
        );
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| Error::Readback(e.to_string()))?;
        frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        if last && let Some(p) = profiler.as_mut() {
            // The profiler's queries were resolved into the frame only if it was passed in;
            // resolve them in a small submission of their own.
            let mut enc = device.create_command_encoder(&Default::default());
            p.resolve(&mut enc);
            queue.submit([enc.finish()]);
            passes = wait(device, p.read(device, queue))?.0;
        }
        let busy = r.error.is_none() && scenes.busy(scene, saved);
        report = Some(r);
        i += 1;
        if i >= frames && !busy {
            break;
        }
        if i >= frames {
            // Past the frames asked for: wait for what the scene makes on worker threads.
            scenes.wait_for_workers();
            extra += 1;
            if extra > 200 {
                return Err(Error::Invalid {
                    stage: "viewer",
                    what: format!("scene {scene} still busy 200 frames after the last"),
                });
            }
        }
    }
    Ok(Shot {
        pixels: read_colour(device, queue, &targets)?,
        size,
        report: report.expect("at least one frame"),
        frame_ms,
        passes,
    })
}

/// Save RGBA8 pixels as a PNG.
pub fn save_png(path: &Path, pixels: &[u8], [w, h]: [u32; 2]) -> Result<(), String> {
    image::save_buffer(path, pixels, w, h, image::ExtendedColorType::Rgba8)
        .map_err(|e| format!("{}: {e}", path.display()))
}

fn headless(args: &Args, saved: &Saved) -> Result<(), String> {
    let ctx = fieldkit::gpu::Context::new().map_err(|e| e.to_string())?;
    let scene = args.scene.clone().unwrap_or_else(|| "actor".into());
    let frames = args.frames.unwrap_or(1);
    let shot = render_offscreen(&ctx.device, &ctx.queue, &scene, saved, args.size, frames)
        .map_err(|e| e.to_string())?;
    println!(
        "{scene} on {} at {}×{}, {} frames",
        ctx.adapter_name(),
        args.size[0],
        args.size[1],
        shot.frame_ms.len()
    );
    for line in &shot.report.stats {
        println!("  {line}");
    }
    let mut ms = shot.frame_ms.clone();
    ms.sort_by(f64::total_cmp);
    println!(
        "  frame (submit to done): median {:.3} ms, min {:.3}, max {:.3}",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1]
    );
    if !shot.passes.is_empty() {
        let total: f64 = shot.passes.iter().map(|p| p.1).sum();
        println!("  passes of the last frame (compute and render): {total:.3} ms");
        for (name, t) in &shot.passes {
            println!("    {name}: {t:.3} ms");
        }
    }
    if let Some(e) = &shot.report.error {
        // The typed error is the scene's answer to its settings: print it, exit 0.
        println!("  error: {e}");
    }
    if let Some(path) = &args.screenshot {
        save_png(path, &shot.pixels, shot.size)?;
        println!("  wrote {}", path.display());
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    spans::install();
    let args = match parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return std::process::ExitCode::from(2);
        }
    };
    let mut saved = if args.seed {
        Saved::seed()
    } else {
        Saved::default()
    };
    let mut load_error = None;
    if let Some(path) = &args.settings {
        match load_settings(path) {
            Ok(s) => saved = s,
            Err(e) => load_error = Some(e),
        }
    }
    if let Some(mesh) = &args.mesh {
        saved.voxelizer.mesh = mesh.clone();
    }
    let result = if let Some(frames) = args.frame_cost {
        if let Some(e) = &load_error {
            eprintln!("settings: {e}");
            return std::process::ExitCode::from(2);
        }
        let scenes: Vec<String> = args.scene.iter().cloned().collect();
        let size = if args.sized { args.size } else { [1920, 1080] };
        let cache = args
            .pipeline_cache
            .as_deref()
            .filter(|_| !args.no_pipeline_cache);
        frame::run(&scenes, &saved, size, frames, args.out.as_deref(), cache)
    } else if let Some(frames) = args.soak {
        if let Some(e) = &load_error {
            eprintln!("settings: {e}");
            return std::process::ExitCode::from(2);
        }
        let scenes: Vec<String> = match &args.scene {
            Some(s) => vec![s.clone()],
            None => soak::SOAK_SCENES.iter().map(|s| s.to_string()).collect(),
        };
        let size = if args.sized { args.size } else { [320, 240] };
        soak::run(&scenes, &saved, size, frames)
    } else if args.screenshot.is_some() && !args.window {
        if let Some(e) = &load_error {
            eprintln!("settings: {e}");
            return std::process::ExitCode::from(2);
        }
        headless(&args, &saved)
    } else {
        panels::run_window(args, saved, load_error)
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            std::process::ExitCode::FAILURE
        }
    }
}
