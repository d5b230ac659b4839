//! `--soak FRAMES`: each technique runs FRAMES frames with its inputs changing every frame —
//! the metaballs animate, the ocean camera travels, a camera flies through the volume, the
//! voxelizer's mesh turns and is voxelized again — while the process's resident memory and the
//! GPU allocator's live allocations are sampled after every frame. A scene passes when no frame
//! returned an error or raised an uncaptured wgpu error, and memory is flat after warm-up.
//!
//! **Flat** means: after the warm-up (the first tenth of the frames, at least 20), the largest
//! value in the last quarter of the samples is no larger than the largest in the first quarter
//! plus the allowed drift ([`Drift::ALLOWED`]): 0 GPU allocations (the same buffers and
//! textures come and go every cycle, so any growth is a leak), 1% of the allocated bytes (the
//! voxelizer's grid, fitted to the turning mesh, changes size with the angle), and 4 MiB of
//! resident memory (the allocator of the process and the driver may keep a freed page or two;
//! a leak of a few hundred bytes a frame over 10 000 frames crosses it). A run too short to
//! have four post-warm-up samples is not judged.
//!
//! One driver defect is known and named ([`known_driver_growth`]): on lavapipe resident memory
//! grows with dispatches of some compute pipelines (the driver's JIT code is never freed). There
//! the soak reports resident growth and still requires flat GPU allocations; on every other
//! adapter resident memory is held to the limit.
//!
//! `cargo xtask soak` runs the full length (10 000 frames); the viewer's tests run a few hundred
//! frames at a small size.

use std::time::Instant;

use fieldkit::gpu::Context;
use fieldkit::view::Targets;
use glam::Vec3;

use super::scenes::{COLOUR, DEPTH, NAMES, Saved, Scenes};
use super::{draw_frame, frame_time};

/// A driver defect that makes resident memory grow on one adapter, with the evidence. Growth
/// there is reported and not counted as fieldkit's failure; GPU allocations must still be flat.
pub fn known_driver_growth(adapter: &str) -> Option<&'static str> {
    adapter.contains("llvmpipe").then_some(
        "lavapipe (Mesa 22.3, LLVM 15) JIT-compiles code on dispatches of some compute \
         pipelines (the SDF raymarch: ~570 KiB a dispatch, unbounded; the volume march and the \
         voxelizer less) and never frees it: heaptrack shows one MCJIT module per dispatch, none \
         of it fieldkit's; the same soak on an H100 is flat over 10 000 frames (docs/soak/h100.txt)",
    )
}

/// The scenes a soak runs, one per technique with something that changes every frame.
pub const SOAK_SCENES: [&str; 4] = ["actor", "ocean", "volume", "voxelizer"];

/// One sample, taken after a frame finished on the GPU.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sample {
    /// Resident set of the process, bytes (Linux: `/proc/self/status`; elsewhere `None`).
    pub rss: Option<u64>,
    /// Live GPU allocations (wgpu's allocator report; `None` where the backend has none).
    pub allocations: Option<u64>,
    /// Their bytes.
    pub allocated: Option<u64>,
    /// Bytes of the memory blocks they live in.
    pub reserved: Option<u64>,
}

/// Resident memory of this process, bytes.
pub fn rss() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Take a sample.
pub fn sample(device: &wgpu::Device) -> Sample {
    let report = device.generate_allocator_report();
    Sample {
        rss: rss(),
        allocations: report.as_ref().map(|r| r.allocations.len() as u64),
        allocated: report.as_ref().map(|r| r.total_allocated_bytes),
        reserved: report.as_ref().map(|r| r.total_reserved_bytes),
    }
}

/// Frames of warm-up in a run of `frames`: a tenth, at least 20.
pub fn warm_up(frames: usize) -> usize {
    (frames / 10).max(20)
}

/// Growth of one quantity after warm-up: the largest value of the last quarter of the samples
/// minus the largest of the first quarter (negative: it shrank).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drift {
    /// Resident memory, bytes.
    pub rss: Option<i64>,
    /// GPU allocations.
    pub allocations: Option<i64>,
    /// GPU bytes allocated.
    pub allocated: Option<i64>,
    /// The first quarter's peak of GPU bytes (what the per-cent allowance is of).
    pub allocated_base: Option<u64>,
}

impl Drift {
    /// The most growth a soak allows: GPU allocations, GPU bytes (per cent of the first
    /// quarter's peak), resident bytes.
    pub const ALLOWED: [i64; 3] = [0, 1, 4 << 20];

    /// The drift of `samples` (all frames, warm-up included), or `None` when too few remain
    /// after warm-up.
    pub fn of(samples: &[Sample]) -> Option<Drift> {
        let warm = warm_up(samples.len());
        let rest = samples.get(warm..)?;
        let quarter = rest.len() / 4;
        if quarter == 0 {
            return None;
        }
        let (first, last) = (&rest[..quarter], &rest[rest.len() - quarter..]);
        let growth = |f: fn(&Sample) -> Option<u64>| -> Option<i64> {
            let a = first.iter().map(f).max()??;
            let b = last.iter().map(f).max()??;
            Some(b as i64 - a as i64)
        };
        Some(Drift {
            rss: growth(|s| s.rss),
            allocations: growth(|s| s.allocations),
            allocated: growth(|s| s.allocated),
            allocated_base: first.iter().map(|s| s.allocated).max().flatten(),
        })
    }

    /// What exceeds [`Drift::ALLOWED`], in words.
    pub fn excess(&self) -> Vec<String> {
        let [alloc, percent, rss] = Self::ALLOWED;
        let bytes = self.allocated_base.map_or(0, |b| b as i64 * percent / 100);
        let mut out = Vec::new();
        let mut check = |what: &str, got: Option<i64>, allowed: i64| {
            if let Some(g) = got
                && g > allowed
            {
                out.push(format!("{what} grew by {g} (allowed {allowed})"));
            }
        };
        check("GPU allocations", self.allocations, alloc);
        check("GPU allocated bytes", self.allocated, bytes);
        check("resident bytes", self.rss, rss);
        out
    }
}

/// One scene's soak.
#[derive(Debug)]
pub struct SoakReport {
    /// The scene.
    pub scene: String,
    /// Frames drawn.
    pub frames: u32,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// A sample after every frame.
    pub samples: Vec<Sample>,
    /// Voxelizations that reached the screen (voxelizer only).
    pub voxelized: u64,
    /// Growth after warm-up (`None`: run too short to judge).
    pub drift: Option<Drift>,
}

/// Move the scene's inputs to frame `i`: the camera of the ocean travels and turns, the volume's
/// camera flies a figure of eight through the volume (the unit cube about the origin), the
/// voxelizer's mesh turns 0.05 rad a frame. The actor's metaballs animate with the frame time.
pub fn move_inputs(scene: &str, saved: &mut Saved, i: u32) {
    let Some(index) = NAMES.iter().position(|n| *n == scene) else {
        return;
    };
    let t = i as f32;
    let camera = &mut saved.cameras[index];
    match scene {
        "actor" => camera.yaw = 0.55 + t * 0.004,
        "ocean" => {
            camera.target = Vec3::new(t * 0.25, 0.0, (t * 0.01).sin() * 20.0);
            camera.yaw = 0.3 + t * 0.003;
            camera.pitch = 0.15 + 0.1 * (t * 0.007).sin().abs();
        }
        "volume" => {
            let theta = t * std::f32::consts::TAU / 600.0;
            let eye = Vec3::new(
                0.8 * theta.sin(),
                0.1 * theta.cos(),
                0.4 * (2.0 * theta).sin(),
            );
            let ahead = Vec3::new(
                0.8 * theta.cos(),
                -0.1 * theta.sin(),
                0.8 * (2.0 * theta).cos(),
            )
            .normalize();
            camera.fly = true;
            camera.distance = 0.5;
            camera.target = eye + ahead * camera.distance;
            camera.yaw = (-ahead.x).atan2(-ahead.z);
            camera.pitch = (-ahead.y).asin();
            camera.near = 0.01;
        }
        "voxelizer" => {
            let spin = (t * 0.05) % std::f32::consts::TAU;
            saved.voxelizer.spin = spin - std::f32::consts::PI;
        }
        _ => {}
    }
}

/// Run `scene` for `frames` frames at `size`, starting from `base` settings.
pub fn soak_scene(
    ctx: &Context,
    scene: &str,
    base: &Saved,
    size: [u32; 2],
    frames: u32,
) -> Result<SoakReport, String> {
    let device = &ctx.device;
    let queue = &ctx.queue;
    let start = Instant::now();
    let mut samples = Vec::with_capacity(frames as usize);
    let voxelized;
    {
        let targets = Targets::new(device, size, COLOUR, DEPTH);
        let mut scenes = Scenes::new();
        let mut saved = base.clone();
        for i in 0..frames {
            move_inputs(scene, &mut saved, i);
            let (report, _) = draw_frame(
                device,
                queue,
                &mut scenes,
                &saved,
                scene,
                &targets,
                size,
                frame_time(i),
                i,
                None,
            );
            if let Some(e) = report.error {
                return Err(format!("{scene}, frame {i}: {e}"));
            }
            // Wait for everything submitted, the frame's readbacks included (they are
            // submitted after the frame): a sample taken while a readback may or may not have
            // finished counts its staging buffer on some runs and not on others, and the
            // voxelizer starts its next job only once the last one is read — so waiting for
            // the frame alone made the live allocations at the sample depend on timing.
            // The voxelizer records its jobs on a worker thread: wait for it too.
            scenes.wait_for_workers();
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| format!("{scene}, frame {i}: {e}"))?;
            let uncaptured = ctx.take_uncaptured();
            if !uncaptured.is_empty() {
                return Err(format!("{scene}, frame {i}: {}", uncaptured.join("; ")));
            }
            samples.push(sample(device));
        }
        voxelized = scenes.voxelized();
    }
    Ok(SoakReport {
        scene: scene.into(),
        frames,
        seconds: start.elapsed().as_secs_f64(),
        drift: Drift::of(&samples),
        samples,
        voxelized,
    })
}

fn mib(b: i64) -> String {
    format!("{:+.2} MiB", b as f64 / (1024.0 * 1024.0))
}

/// Run the soak over `scenes` and print a table; `Err` lists what failed.
pub fn run(scenes: &[String], base: &Saved, size: [u32; 2], frames: u32) -> Result<(), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    println!(
        "soak on {}: {frames} frames a scene at {}×{}; allowed growth after warm-up: {} GPU \
         allocations, {}% of GPU bytes, {} resident",
        ctx.adapter_name(),
        size[0],
        size[1],
        Drift::ALLOWED[0],
        Drift::ALLOWED[1],
        mib(Drift::ALLOWED[2]),
    );
    let mut failures = Vec::new();
    for scene in scenes {
        if !SOAK_SCENES.contains(&scene.as_str()) {
            return Err(format!(
                "--soak: no soak for scene {scene:?} (one of {SOAK_SCENES:?})"
            ));
        }
        let r = match soak_scene(&ctx, scene, base, size, frames) {
            Ok(r) => r,
            Err(e) => {
                println!("{scene}: FAILED: {e}");
                failures.push(e);
                continue;
            }
        };
        let warm = warm_up(r.samples.len()).min(r.samples.len().saturating_sub(1));
        let (w, end) = (r.samples[warm], r.samples[r.samples.len() - 1]);
        let fmt = |v: Option<u64>, mb: bool| match v {
            Some(v) if mb => format!("{:.1} MiB", v as f64 / (1024.0 * 1024.0)),
            Some(v) => v.to_string(),
            None => "n/a".into(),
        };
        let peak = |f: fn(&Sample) -> Option<u64>| r.samples[warm..].iter().filter_map(f).max();
        println!(
            "{scene}: {} frames in {:.1} s ({:.2} ms/frame){}",
            r.frames,
            r.seconds,
            r.seconds * 1e3 / r.frames.max(1) as f64,
            if scene == "voxelizer" {
                format!(", {} voxelizations", r.voxelized)
            } else {
                String::new()
            }
        );
        println!(
            "  after warm-up (frame {warm}) → end (peak): resident {} → {} ({}), GPU allocations {} → {} ({}), \
             GPU bytes {} → {} ({}), blocks {} → {}",
            fmt(w.rss, true),
            fmt(end.rss, true),
            fmt(peak(|s| s.rss), true),
            fmt(w.allocations, false),
            fmt(end.allocations, false),
            fmt(peak(|s| s.allocations), false),
            fmt(w.allocated, false),
            fmt(end.allocated, false),
            fmt(peak(|s| s.allocated), false),
            fmt(w.reserved, false),
            fmt(end.reserved, false),
        );
        match r.drift {
            None => println!("  drift: too few frames to judge"),
            Some(d) => {
                let show = |v: Option<i64>| v.map_or("n/a".into(), |v| v.to_string());
                println!(
                    "  drift (last quarter's peak − first quarter's): resident {}, GPU allocations {}, GPU bytes {}",
                    d.rss.map_or("n/a".into(), mib),
                    show(d.allocations),
                    show(d.allocated),
                );
                let mut excess = d.excess();
                let known = known_driver_growth(&ctx.adapter_name());
                if let Some(why) = known
                    && excess.iter().all(|e| e.starts_with("resident"))
                    && !excess.is_empty()
                {
                    println!("  resident growth: known driver leak: {why}");
                    excess.clear();
                    println!("  GPU allocations flat: ok");
                } else if excess.is_empty() {
                    println!("  flat: ok");
                }
                if !excess.is_empty() {
                    let e = format!("{scene}: {}", excess.join(", "));
                    println!("  NOT FLAT: {e}");
                    failures.push(e);
                }
            }
        }
        if scene == "voxelizer" && r.voxelized < 2 {
            let e = format!(
                "voxelizer: voxelized {} times in {frames} frames",
                r.voxelized
            );
            println!("  {e}");
            failures.push(e);
        }
    }
    if failures.is_empty() {
        println!("soak: ok");
        Ok(())
    } else {
        Err(format!("soak failed: {}", failures.join("; ")))
    }
}
