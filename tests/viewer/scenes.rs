//! The live viewer (`examples/viewer`): every scene renders offscreen and matches its reference
//! image; every scene renders in a real window under Xvfb and matches the offscreen render; bad
//! settings come back as fieldkit's typed errors (printed, exit 0); the animation moves and the
//! grid builder counts as the source's does.
//!
//! References: `tests/snapshots/viewer/<scene>.png`, rendered on llvmpipe; `FIELDKIT_BLESS=1`
//! rewrites them (look at them before committing).

use crate::viewer;

use std::path::{Path, PathBuf};

use crate::common;
use std::process::Command;

use viewer::scenes::{ActorSettings, NAMES, Saved, VoxelizerSettings};

/// Small enough for lavapipe on two cores.
const SIZE: [u32; 2] = [192, 108];

fn device() -> (wgpu::Device, wgpu::Queue) {
    let ctx = fieldkit::gpu::Context::new().unwrap_or_else(|e| {
        panic!("this test needs a GPU adapter (apt-get install -y mesa-vulkan-drivers): {e}")
    });
    (ctx.device.clone(), ctx.queue.clone())
}

/// Held by every test while it uses a GPU in this process: shared by most, whole by the two
/// that count GPU objects (the count is process-wide, and would take in other tests' objects)
/// and by the one that installs a pipeline cache (wgpu tells devices apart by their id within
/// their own instance, so another test's device of the same id would find that cache).
static GPU: std::sync::RwLock<()> = std::sync::RwLock::new(());

fn gpu_shared() -> std::sync::RwLockReadGuard<'static, ()> {
    GPU.read().unwrap_or_else(|e| e.into_inner())
}

fn gpu_whole() -> std::sync::RwLockWriteGuard<'static, ()> {
    GPU.write().unwrap_or_else(|e| e.into_inner())
}

/// Settings for the tests: the voxelizer on the built-in torus, so no file outside the
/// repository is read.
fn settings() -> Saved {
    let mut s = Saved::default();
    s.voxelizer.mesh = "torus".into();
    s.voxelizer.grid = 24;
    s.volume.size = 48;
    s.volume.march.step = 1.0 / 48.0;
    s
}

/// One frame of `scene` with settings `s` into `targets` (of [`SIZE`]), number `i`, drawn
/// and waited for.
fn waited_frame(
    (device, queue): (&wgpu::Device, &wgpu::Queue),
    scenes: &mut viewer::scenes::Scenes,
    s: &Saved,
    scene: &str,
    targets: &fieldkit::view::Targets,
    i: u32,
) -> viewer::FrameReport {
    let (report, index) = viewer::draw_frame(
        device,
        queue,
        scenes,
        s,
        scene,
        targets,
        SIZE,
        viewer::frame_time(i),
        i,
        None,
    );
    device
        .poll(wgpu::PollType::Wait {
            submission_index: Some(index),
            timeout: None,
        })
        .unwrap();
    report
}

/// (mean of the largest channel difference, pixels off by more than `far` levels).
fn compare(a: &[u8], b: &[u8], far: u8) -> (f64, usize) {
    assert_eq!(a.len(), b.len());
    let mut sum = 0u64;
    let mut off = 0;
    for (p, q) in a.chunks(4).zip(b.chunks(4)) {
        let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0);
        sum += d as u64;
        if d > far {
            off += 1;
        }
    }
    (sum as f64 / (a.len() / 4) as f64, off)
}

/// 4×4 block means of RGBA8 pixels (`size` divisible by 4): what the reference comparison
/// looks at, so a sparkle of the water or an edge pixel that lands one way on one GPU and the
/// other way on another averages out, while a missing or moved technique does not.
fn blocks(px: &[u8], [w, h]: [u32; 2]) -> Vec<u8> {
    let (bw, bh) = (w / 4, h / 4);
    let mut out = Vec::with_capacity((bw * bh * 4) as usize);
    for by in 0..bh {
        for bx in 0..bw {
            for c in 0..4 {
                let mut sum = 0u32;
                for y in 0..4 {
                    for x in 0..4 {
                        sum += px[(((by * 4 + y) * w + bx * 4 + x) * 4 + c) as usize] as u32;
                    }
                }
                out.push((sum / 16) as u8);
            }
        }
    }
    out
}

fn distinct(px: &[u8]) -> usize {
    px.chunks(4).collect::<std::collections::HashSet<_>>().len()
}

#[test]
fn every_scene_renders_offscreen_and_matches_its_reference() {
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let s = settings();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/viewer");
    let bless = std::env::var_os("FIELDKIT_BLESS").is_some();
    let mut failures = Vec::new();
    for scene in NAMES {
        let shot = viewer::render_offscreen(&device, &queue, scene, &s, SIZE, 2)
            .unwrap_or_else(|e| panic!("{scene}: {e}"));
        if let Some(e) = &shot.report.error {
            panic!("{scene} refused the default settings: {e}");
        }
        eprintln!("{scene}: {:?}", shot.report.stats);
        // Not a blank frame: each scene draws its technique over its background.
        assert!(
            distinct(&shot.pixels) > 40,
            "{scene}: only {} distinct colours",
            distinct(&shot.pixels)
        );
        let path = dir.join(format!("{scene}.png"));
        if bless {
            std::fs::create_dir_all(&dir).unwrap();
            viewer::save_png(&path, &shot.pixels, SIZE).unwrap();
            continue;
        }
        let want = image::open(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (FIELDKIT_BLESS=1 writes it)", path.display()))
            .to_rgba8();
        assert_eq!(want.dimensions(), (SIZE[0], SIZE[1]));
        // Compared in 4×4 block means. Set on llvmpipe (LLVM 15): against its own reference,
        // mean 0 and no block off. The margin is for other GPUs: raymarched edges and the
        // water's sparkle move by a pixel or a rounding step in places, which a block mean
        // turns into a few levels; a missing or misplaced technique moves far more than 3% of
        // the blocks by more than 24 levels.
        let (mean, off) = compare(
            &blocks(&shot.pixels, SIZE),
            &blocks(want.as_raw(), SIZE),
            24,
        );
        eprintln!("{scene}: block mean {mean:.3}, {off} blocks off by more than 24 levels");
        let n = (SIZE[0] * SIZE[1] / 16) as usize;
        if mean > 3.0 || off > n * 3 / 100 {
            failures.push(format!(
                "{scene}: block mean {mean:.3}, {off} of {n} blocks off"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The voxelizer's distance-field mode draws the mesh's signed distance field through the SDF
/// march: the same torus, placed the same way, covers about the pixels its surface voxels do
/// (the voxels, whole cubes around the surface, a little more).
#[test]
fn the_voxelizer_draws_the_mesh_distance_field() {
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let mut s = settings();
    let voxels = viewer::render_offscreen(&device, &queue, "voxelizer", &s, SIZE, 2).unwrap();
    s.voxelizer.mode = viewer::scenes::VoxelMode::DistanceField;
    s.voxelizer.slice = false;
    let field = viewer::render_offscreen(&device, &queue, "voxelizer", &s, SIZE, 2).unwrap();
    assert!(field.report.error.is_none(), "{:?}", field.report.error);
    assert!(
        field
            .report
            .stats
            .iter()
            .any(|l| l.contains("signed distance field")),
        "{:?}",
        field.report.stats
    );
    // Covered: away from the background (0.1, 0.11, 0.13) by more than 12 levels.
    let covered = |px: &[u8]| -> Vec<bool> {
        px.chunks(4)
            .map(|p| (0..3).any(|c| p[c].abs_diff([26, 28, 33][c]) > 12))
            .collect()
    };
    // The default frame's slice corner is left out of both.
    let (a, b) = (covered(&voxels.pixels), covered(&field.pixels));
    let in_view = |i: usize| {
        let (x, y) = ((i as u32) % SIZE[0], (i as u32) / SIZE[0]);
        !(x > SIZE[0] / 2 && y > SIZE[1] * 6 / 10)
    };
    let both = (0..a.len()).filter(|&i| in_view(i) && a[i] && b[i]).count();
    let either = (0..a.len())
        .filter(|&i| in_view(i) && (a[i] || b[i]))
        .count();
    let only_field = (0..a.len())
        .filter(|&i| in_view(i) && b[i] && !a[i])
        .count();
    eprintln!(
        "distance field: {both} of {either} covered pixels in both, {only_field} by the field alone"
    );
    // llvmpipe: 0.74 of the union in both, the rest the cubes' corners past the surface (at 24
    // voxels a side a cube reaches up to 0.87 voxels out); the field draws within the voxels
    // but for a few edge pixels.
    assert!(
        both > 500 && both as f64 > 0.6 * either as f64,
        "{both} of {either}"
    );
    assert!(
        only_field * 50 < both,
        "{only_field} pixels drawn by the field alone"
    );
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("fieldkit_viewer_{}_{name}", std::process::id()))
}

#[test]
fn every_scene_in_a_window_matches_the_offscreen_render() {
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let s = settings();
    let file = temp("window.ron");
    viewer::save_settings(&file, &s).unwrap();
    let frames = 2;
    for scene in NAMES {
        let shot = temp(&format!("{scene}.png"));
        let output = Command::new("xvfb-run")
            .args(["-a", "-s", "-screen 0 800x600x24"])
            .arg(common::example_binary("viewer"))
            .args([
                "--window", "--scene", scene, "--size", "240x160", "--frames",
            ])
            .arg(frames.to_string())
            .arg("--settings")
            .arg(&file)
            .arg("--screenshot")
            .arg(&shot)
            .output()
            .unwrap_or_else(|e| {
                panic!("this test runs the viewer under Xvfb: apt-get install -y xvfb ({e})")
            });
        let log = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "{scene}: the viewer failed: {log}");
        let got = image::open(&shot)
            .unwrap_or_else(|e| panic!("{scene}: no screenshot ({e}): {log}"))
            .to_rgba8();
        std::fs::remove_file(&shot).ok();
        // The window's scene area is whatever the layout left it; render offscreen at that size.
        let size = [got.width(), got.height()];
        let want = viewer::render_offscreen(&device, &queue, scene, &s, size, frames).unwrap();
        // Same adapter, same frames, same settings file: set on llvmpipe, where the two agree
        // to the bit; the margin is for a GPU whose window device differs from the offscreen
        // one (a rounding step in a few pixels).
        let (mean, off) = compare(got.as_raw(), &want.pixels, 8);
        eprintln!("{scene} at {size:?}: window against offscreen mean {mean:.4}, {off} off");
        assert!(mean <= 0.5, "{scene}: mean difference {mean}");
        assert!(
            off <= (size[0] * size[1]) as usize / 200,
            "{scene}: {off} pixels differ by more than 8 levels"
        );
        assert!(distinct(&want.pixels) > 40, "{scene}: a blank frame");
    }
    std::fs::remove_file(&file).ok();
}

/// Run the viewer headless with a settings file; returns (exit success, stdout).
fn headless_with(scene: &str, s: &Saved) -> (bool, String) {
    let file = temp(&format!("{scene}_bad.ron"));
    viewer::save_settings(&file, s).unwrap();
    let shot = temp(&format!("{scene}_bad.png"));
    let output = Command::new(common::example_binary("viewer"))
        .args([
            "--scene",
            scene,
            "--size",
            "64x36",
            "--frames",
            "1",
            "--settings",
        ])
        .arg(&file)
        .arg("--screenshot")
        .arg(&shot)
        .output()
        .expect("the viewer runs");
    std::fs::remove_file(&file).ok();
    std::fs::remove_file(&shot).ok();
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
    )
}

#[test]
fn bad_settings_come_back_as_typed_errors() {
    let _gpu = gpu_shared();
    // A NaN survives the settings file (RON writes it) and reaches fieldkit's own check.
    let mut s = settings();
    s.actor.field.threshold = f32::NAN;
    let (ok, out) = headless_with("actor", &s);
    assert!(ok, "{out}");
    assert!(
        out.contains("error: ") && out.contains("threshold"),
        "the metaball settings' NaN is named:\n{out}"
    );

    // An oversized voxel grid: the voxelizer refuses it by size.
    let mut s = settings();
    s.voxelizer.grid = 200_000;
    let (ok, out) = headless_with("voxelizer", &s);
    assert!(ok, "{out}");
    assert!(
        out.contains("error: ") && out.contains("grid side x is 200000"),
        "the voxelizer's size error is printed:\n{out}"
    );

    // An actor region that would make more blocks than the viewer builds.
    let mut s = settings();
    s.actor.extent = [1e6, 1e6, 1e6];
    let (ok, out) = headless_with("actor", &s);
    assert!(ok, "{out}");
    assert!(
        out.contains("error: ") && out.contains("instances"),
        "{out}"
    );

    // A wave with no wavelength: the ocean's typed error.
    let mut s = settings();
    s.ocean.waves[0].wavelength = 0.0;
    let (ok, out) = headless_with("ocean", &s);
    assert!(ok, "{out}");
    assert!(
        out.contains("error: ") && out.contains("wavelength"),
        "{out}"
    );
}

#[test]
fn the_animation_advances_and_the_builder_counts_as_the_source() {
    let _gpu = gpu_shared();
    // The source's builder: NX = max(1, floor(Extent / BlockSize)) per axis.
    let a = ActorSettings::default();
    assert_eq!(a.counts().unwrap(), [5, 4, 3]);
    let b = ActorSettings {
        extent: [5.0, 4.0, 3.0],
        block: 2.0,
        ..ActorSettings::default()
    };
    assert_eq!(b.counts().unwrap(), [2, 2, 1]);
    let c = ActorSettings {
        extent: [0.4, 10.0, 2.99],
        block: 1.0,
        ..ActorSettings::default()
    };
    assert_eq!(c.counts().unwrap(), [1, 10, 2]);
    assert!(
        ActorSettings {
            block: 0.0,
            ..ActorSettings::default()
        }
        .counts()
        .is_err()
    );

    // The rendered scene reports the builder's count, and its frames move.
    let (device, queue) = device();
    let mut s = settings();
    s.actor.block = 2.0;
    let first = viewer::render_offscreen(&device, &queue, "actor", &s, SIZE, 1).unwrap();
    assert!(
        first
            .report
            .stats
            .iter()
            .any(|l| l.starts_with("instances: 4 ")),
        "{:?}",
        first.report.stats
    );
    let s = settings();
    let first = viewer::render_offscreen(&device, &queue, "actor", &s, SIZE, 1).unwrap();
    let later = viewer::render_offscreen(&device, &queue, "actor", &s, SIZE, 31).unwrap();
    let (mean, off) = compare(&first.pixels, &later.pixels, 24);
    assert!(
        off > 50 && mean > 0.5,
        "half a second of animation moved {off} pixels (mean {mean})"
    );
    // With the animation off, the same frames are the same picture.
    let mut still = settings();
    still.actor.animate = false;
    let a = viewer::render_offscreen(&device, &queue, "actor", &still, SIZE, 1).unwrap();
    let b = viewer::render_offscreen(&device, &queue, "actor", &still, SIZE, 31).unwrap();
    assert_eq!(compare(&a.pixels, &b.pixels, 0), (0.0, 0));
}

/// The seed presets are a choice in the viewer: `Saved::seed` (and `--preset seed`) holds the
/// sources' settings, and the actor, ocean, volume and voxelizer render them, differently from
/// the defaults.
#[test]
fn seed_presets_are_a_choice_and_render() {
    let _gpu = gpu_shared();
    let seed = Saved::seed();
    assert_eq!(seed.actor.field, fieldkit::metaball::Settings::seed());
    assert_eq!(
        seed.actor.raymarch,
        fieldkit::metaball::RaymarchSettings::seed()
    );
    assert_eq!(seed.actor.animation, fieldkit::metaball::Animation::seed());
    assert_eq!(seed.ocean.look.fade_distance, 0.3);
    assert_eq!(seed.ocean.depth_write, Some(false));
    assert!(seed.volume.function);
    let (device, queue) = device();
    assert!(seed.voxelizer.point_light);
    for scene in ["actor", "ocean", "volume", "voxelizer"] {
        let mut s = Saved::seed();
        s.voxelizer = VoxelizerSettings {
            point_light: true,
            ..settings().voxelizer
        };
        let a = viewer::render_offscreen(&device, &queue, scene, &settings(), SIZE, 1).unwrap();
        let b = viewer::render_offscreen(&device, &queue, scene, &s, SIZE, 1).unwrap();
        assert!(b.report.error.is_none(), "{scene}: {:?}", b.report.error);
        let (mean, off) = compare(&a.pixels, &b.pixels, 24);
        assert!(
            off > 50,
            "{scene}: the seed preset moved {off} pixels (mean {mean})"
        );
    }
}

/// The CI soak: the four animated techniques for 300 frames each at a small size, in the
/// viewer's own process (a test binary's resident memory would include the tests beside it),
/// memory sampled after every frame. `cargo xtask soak` runs 10 000 frames.
#[test]
fn a_short_soak_stays_flat_and_errs_nowhere() {
    let _gpu = gpu_shared();
    let frames = 300;
    let file = temp("soak.ron");
    viewer::save_settings(&file, &settings()).unwrap();
    let output = Command::new(common::example_binary("viewer"))
        .args([
            "--soak",
            &frames.to_string(),
            "--size",
            "96x64",
            "--settings",
        ])
        .arg(&file)
        .output()
        .expect("the viewer runs");
    std::fs::remove_file(&file).ok();
    let out = String::from_utf8_lossy(&output.stdout);
    let err = String::from_utf8_lossy(&output.stderr);
    eprintln!("{out}");
    assert!(output.status.success(), "the soak failed:\n{out}\n{err}");
    for scene in viewer::soak::SOAK_SCENES {
        assert!(
            out.contains(&format!("{scene}: {frames} frames")),
            "{scene} did not run {frames} frames:\n{out}"
        );
    }
    // Judged (not "too few frames") and flat, once per scene: "flat: ok", or on lavapipe, whose
    // JIT code leaks (see `soak::known_driver_growth`), "GPU allocations flat: ok" after the
    // resident growth is reported. Resident memory is judged on hardware (`cargo xtask soak`).
    assert_eq!(out.matches("flat: ok").count(), 4, "{out}");
    // The voxelizer really voxelized the turning mesh again and again (a job takes a few
    // frames: record, submit, read back).
    let line = out
        .lines()
        .find(|l| l.starts_with("voxelizer:"))
        .expect("a voxelizer line");
    let n: u64 = line
        .split(", ")
        .find_map(|p| p.strip_suffix(" voxelizations"))
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no voxelization count in {line:?}"));
    assert!(n >= 30, "only {n} voxelizations in {frames} frames");
}

/// The soak's judge catches growth: a slow leak in any of the three quantities fails, noise
/// and a warm-up ramp do not.
#[test]
fn the_soak_judge_catches_a_leak() {
    let _gpu = gpu_shared();
    use viewer::soak::{Drift, Sample};
    let run = |f: &dyn Fn(u64) -> Sample| (0..1000).map(f).collect::<Vec<_>>();
    let flat = |i: u64| Sample {
        // A warm-up ramp over the first 50 frames, then noise of ±1 MiB and 3 allocations.
        rss: Some((100 << 20) + i.min(50) * (1 << 20) + (i % 3) * (1 << 19)),
        allocations: Some(40 + i % 4),
        allocated: Some(1 << 24),
        reserved: Some(1 << 26),
    };
    let d = Drift::of(&run(&flat)).expect("judged");
    assert!(d.excess().is_empty(), "{d:?}: {:?}", d.excess());
    // 8 KiB a frame of resident memory: the quarters' peaks are 675 frames apart, 5.3 MiB.
    let rss_leak = |i| Sample {
        rss: flat(i).rss.map(|r| r + i * 8192),
        ..flat(i)
    };
    assert_eq!(Drift::of(&run(&rss_leak)).unwrap().excess().len(), 1);
    // One GPU allocation of 1 MiB every 100 frames, kept.
    let gpu_leak = |i: u64| Sample {
        allocations: flat(i).allocations.map(|a| a + i / 100),
        allocated: flat(i).allocated.map(|a| a + (i / 100) * (1 << 20)),
        ..flat(i)
    };
    // GPU bytes that vary by under 1% (a grid fitted to a turning mesh) pass.
    let wobble = |i: u64| Sample {
        allocated: flat(i).allocated.map(|a| a + (i * 7919 % 100) * 1000),
        ..flat(i)
    };
    assert!(Drift::of(&run(&wobble)).unwrap().excess().is_empty());
    assert_eq!(Drift::of(&run(&gpu_leak)).unwrap().excess().len(), 2);
    // Too short to judge.
    assert!(Drift::of(&run(&flat)[..22]).is_none());
}

/// `--frame-cost` writes one row a scene whose parts hold together: each frame's wall time
/// contains its CPU time, so the medians do too; the first frame, the floor and the resized
/// frame all took time; the whole frame's GPU time holds its compute passes, which are timed on
/// a scene that has some; the objects a frame makes are counted (none can be negative); the
/// pipeline cache starts cold, and warm on the next run, where the adapter keeps one.
#[test]
fn frame_cost_measures_every_part_of_a_frame() {
    let _gpu = gpu_whole();
    let out = temp("frame-cost");
    let cache = out.join("pipeline-cache");
    let scenes = ["distance2d", "actor", "ocean"].map(String::from);
    viewer::frame::run(&scenes, &settings(), SIZE, 3, Some(&out), Some(&cache)).unwrap();
    let csv = std::fs::read_to_string(out.join("frame.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 3, "{csv}");
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |row: &[&str], name: &str| -> f64 {
        let i = header.iter().position(|h| *h == name).unwrap();
        // The adapter is quoted and may hold commas: count from the end.
        row[row.len() - (header.len() - i)].parse().unwrap()
    };
    for row in &rows {
        let (cpu, wall) = (col(row, "cpu_ms_median"), col(row, "wall_ms_median"));
        assert!(cpu > 0.0 && wall >= cpu, "{row:?}");
        assert!(col(row, "first_frame_ms") > 0.0, "{row:?}");
        // The whole scene arrives with its first frame or after it.
        assert!(
            col(row, "whole_scene_ms") >= col(row, "first_frame_ms"),
            "{row:?}"
        );
        assert!(col(row, "floor_ms_median") > 0.0, "{row:?}");
        // Parts of the frame's CPU time: finish + submit, and (where the scene times them,
        // the actor and the ocean) fieldkit's calls.
        let submit = col(row, "submit_ms_median");
        assert!(submit > 0.0 && submit <= cpu, "{row:?}");
        if row.contains(&"actor") || row.contains(&"ocean") {
            let fieldkit = col(row, "fieldkit_ms_median");
            assert!(fieldkit > 0.0 && fieldkit <= cpu, "{row:?}");
        }
        let floor_cpu = col(row, "floor_cpu_ms_median");
        assert!(
            floor_cpu > 0.0 && floor_cpu <= col(row, "floor_ms_median"),
            "{row:?}"
        );
        assert!(
            col(row, "resize_wall_ms") >= col(row, "resize_cpu_ms"),
            "{row:?}"
        );
        let grow_cpu = col(row, "grow_cpu_ms");
        assert!(
            grow_cpu > 0.0 && col(row, "grow_wall_ms") >= grow_cpu,
            "{row:?}"
        );
        // The whole frame on the GPU holds its timed passes (llvmpipe has timestamps inside
        // encoders; the viewer's blit and lines are timed as the techniques' passes are). Both
        // are medians of frames of their own: where the timed passes are most of the frame (the
        // ocean's surface, the 2D tool's blit), the two medians may come out either way.
        let gpu_frame = col(row, "gpu_frame_ms_median");
        assert!(gpu_frame > 0.0, "{row:?}");
        assert!(col(row, "gpu_compute_ms_median") > 0.0, "{row:?}");
    }
    const MADE: [&str; 4] = [
        "made_buffers",
        "made_textures",
        "made_views",
        "made_bind_groups",
    ];
    for row in &rows {
        for made in MADE {
            assert!(col(row, made) >= 0.0, "{made}: {row:?}");
        }
    }
    // Objects are counted as wgpu creates them (`no_scene_makes_a_gpu_object_a_frame` checks
    // the count): none a frame, as that test finds for every scene.
    for row in &rows {
        for made in MADE {
            assert_eq!(col(row, made), 0.0, "{made}: {row:?}");
        }
    }
    // Each settings change the panels offer, timed: one row each, the frame of the change
    // recorded and done, no change refused.
    let changes = std::fs::read_to_string(out.join("frame_settings.csv")).unwrap();
    for scene in &scenes {
        let offered = viewer::changes::setting_changes(scene, &settings());
        let timed: Vec<&str> = changes
            .lines()
            .filter(|l| l.contains(&format!(",{scene},")))
            .collect();
        assert_eq!(timed.len(), offered.len(), "{scene}: {changes}");
        for line in timed {
            let fields: Vec<&str> = line.rsplitn(5, ',').collect();
            let [error, after, wall, cpu] = [0, 1, 2, 3].map(|i| fields[i]);
            let [after, wall, cpu]: [f64; 3] = [after, wall, cpu].map(|x| x.parse().unwrap());
            assert!(cpu > 0.0 && wall >= cpu && after > 0.0, "{line}");
            assert_eq!(error, "\"\"", "{line}");
        }
    }
    // How the pipeline cache started: the second column (after the quoted adapter).
    let start = |csv: &str| -> String {
        let row = csv.lines().nth(1).unwrap();
        let after_adapter = row.rsplit_once('"').unwrap().1;
        after_adapter.split(',').nth(1).unwrap().to_string()
    };
    let ctx = fieldkit::gpu::Context::shared();
    let keeps = ctx
        .device
        .features()
        .contains(wgpu::Features::PIPELINE_CACHE)
        && ctx.adapter.as_ref().unwrap().get_info().backend == wgpu::Backend::Vulkan;
    assert_eq!(start(&csv), if keeps { "cold" } else { "none" }, "{csv}");
    let again = &scenes[..1];
    viewer::frame::run(again, &settings(), SIZE, 3, Some(&out), Some(&cache)).unwrap();
    let csv = std::fs::read_to_string(out.join("frame.csv")).unwrap();
    assert_eq!(start(&csv), if keeps { "warm" } else { "none" }, "{csv}");
    std::fs::remove_dir_all(&out).unwrap();
}

/// After a few frames of warm-up, a frame of every scene makes no GPU object: no buffer,
/// texture, view or bind group, counted as wgpu creates them (`viewer::made` reads wgpu-core's
/// own trace lines; the staging buffer inside `Queue::write_buffer` is wgpu's, not a
/// creation). The count itself is checked first on one object of each kind made on purpose.
#[test]
fn no_scene_makes_a_gpu_object_a_frame() {
    let _gpu = gpu_whole();
    use viewer::made::{Made, count};
    use viewer::scenes::{COLOUR, DEPTH, Scenes};
    let (device, queue) = device();
    let ((), made) = count(|| {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("counted"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM,
            mapped_at_creation: false,
        });
        let targets = fieldkit::view::Targets::new(&device, [4, 4], COLOUR, DEPTH);
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
            entries: &[],
        });
        let _group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &layout,
            entries: &[],
        });
        drop((buffer, targets));
    });
    // Targets: a colour and a depth texture, a view of each.
    let made = made.expect("no other logger in this test binary");
    assert_eq!(made.counts(), [1, 2, 2, 1], "{made:?}");
    let saved = settings();
    let targets = fieldkit::view::Targets::new(&device, SIZE, COLOUR, DEPTH);
    let frame = |scenes: &mut Scenes, scene: &str, i: u32| {
        let report = waited_frame((&device, &queue), scenes, &saved, scene, &targets, i);
        assert!(report.error.is_none(), "{scene}: {:?}", report.error);
    };
    for scene in NAMES {
        // Three frames, and on until what the scene makes on other threads has arrived.
        let mut scenes = Scenes::new();
        let mut warm = 0;
        while warm < 3 || scenes.busy(scene, &saved) {
            assert!(warm < 20, "{scene} still busy after {warm} frames");
            scenes.wait_for_workers();
            frame(&mut scenes, scene, warm.min(2));
            warm += 1;
        }
        let mut most = Made::default();
        for i in 3..6 {
            let ((), made) = count(|| frame(&mut scenes, scene, i));
            most = most.max(made.unwrap());
        }
        assert_eq!(
            most.counts(),
            [0; 4],
            "{scene} makes objects a frame: {most:?}"
        );
        assert_eq!(most.pipelines(), 0, "{scene} makes pipelines a frame");
    }
}

/// Every settings change the panels offer (`changes::setting_changes`: draw modes, methods,
/// outputs, targets, switches, seed presets, the camera's depth convention) makes no pipeline
/// on the frame it is made on, nor on the frames after it until the scene has settled: what a
/// change needs is made on a worker thread (the frame keeps drawing what it drew) or was made
/// up front; and once settled, a frame of the new settings makes no GPU object at all. Only
/// the frame's own thread is counted.
#[test]
fn no_setting_change_makes_a_pipeline_on_a_frame() {
    let _gpu = gpu_whole();
    use viewer::changes::setting_changes;
    use viewer::made::{Made, count_here};
    use viewer::scenes::{COLOUR, DEPTH, Scenes};
    let (device, queue) = device();
    let saved = settings();
    let targets = fieldkit::view::Targets::new(&device, SIZE, COLOUR, DEPTH);
    let frame = |scenes: &mut Scenes, s: &Saved, scene: &str, i: u32| {
        waited_frame((&device, &queue), scenes, s, scene, &targets, i)
    };
    // Frames of `s` until the scene has settled; the most any made, and the first error.
    let settle = |scenes: &mut Scenes, s: &Saved, scene: &str, what: &str, counted: bool| {
        let (mut most, mut error) = (Made::default(), None);
        for k in 0..40 {
            if k >= 3 && !scenes.busy(scene, s) {
                return (most, error);
            }
            if k >= 3 {
                scenes.wait_for_workers();
            }
            let (report, made) = if counted {
                count_here(|| frame(scenes, s, scene, k))
            } else {
                (frame(scenes, s, scene, k), Some(Made::default()))
            };
            most = most.max(made.expect("no other logger in this test binary"));
            error = error.or(report.error.map(|e| e.to_string()));
        }
        panic!("{scene}, {what}: still busy after 40 frames");
    };
    let mut failed = Vec::new();
    let mut changes = 0;
    for scene in NAMES {
        let mut scenes = Scenes::new();
        let (_, error) = settle(&mut scenes, &saved, scene, "first frames", false);
        assert!(error.is_none(), "{scene}: {error:?}");
        for (name, changed) in setting_changes(scene, &saved) {
            changes += 1;
            let (made, error) = settle(&mut scenes, &changed, scene, &name, true);
            if made.pipelines() != 0 || error.is_some() {
                failed.push(format!("{scene}, {name}: {made:?} {error:?}"));
            }
            // Settled, a frame of the new settings makes nothing (the debug cubes' draw, a
            // G-buffer output, a march mode, the patch overlay, a field by jump flooding).
            let (_, made) = count_here(|| frame(&mut scenes, &changed, scene, 50));
            let made = made.expect("counted above");
            if made != Made::default() {
                failed.push(format!("{scene}, {name}, a frame after: {made:?}"));
            }
            settle(
                &mut scenes,
                &saved,
                scene,
                &format!("back from {name}"),
                false,
            );
        }
    }
    // Each scene offers several.
    assert!(changes >= 40, "{changes} changes");
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// The volume's function mode makes its pipelines on a worker thread, the march's for the
/// scene's settings included (`DensityMarch::prepare`): the frame the cloud function arrives
/// on marches without making a pipeline. The count sees pipelines: making the cloud function
/// makes its bricks and bake pipelines.
#[test]
fn the_cloud_function_arrives_with_its_march_pipeline_made() {
    let _gpu = gpu_whole();
    use viewer::made::count;
    use viewer::scenes::{COLOUR, DEPTH, Scenes};
    let (device, queue) = device();
    let (cloud, made) = count(|| fieldkit::volume::CloudMarch::cloud(&device, &queue).unwrap());
    let made = made.expect("no other logger in this test binary");
    assert!(made.compute_pipelines >= 2, "{made:?}");
    drop(cloud);
    let mut saved = settings();
    saved.volume.function = true;
    let targets = fieldkit::view::Targets::new(&device, SIZE, COLOUR, DEPTH);
    let frame = |scenes: &mut Scenes, i: u32| {
        waited_frame((&device, &queue), scenes, &saved, "volume", &targets, i)
    };
    let mut scenes = Scenes::new();
    let first = frame(&mut scenes, 0);
    assert!(first.error.is_none(), "{:?}", first.error);
    assert!(
        scenes.busy("volume", &saved),
        "the function was made on the frame"
    );
    scenes.wait_for_workers();
    let (report, made) = count(|| frame(&mut scenes, 1));
    assert!(report.error.is_none(), "{:?}", report.error);
    assert!(!scenes.busy("volume", &saved));
    assert!(
        report
            .stats
            .iter()
            .any(|l| l.contains("fBm function per sample")),
        "the function was not marched: {:?}",
        report.stats
    );
    assert_eq!(made.unwrap().compute_pipelines, 0);
}

/// The 2D tool draws the texels a JFA variant got wrong in magenta on the image, as many as it
/// counts (none for the exact transform).
#[test]
fn the_2d_tool_draws_its_wrong_texels() {
    use fieldkit::distance::{Method2d, Variant};
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let mut s = settings();
    // Scattered single-texel seeds, where plain JFA loses a few texels.
    let mut r = 12345u64;
    let [w, h] = s.distance.size;
    s.distance.seeds = (0..400)
        .map(|_| {
            r = r
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            [((r >> 33) % w as u64) as u32, ((r >> 13) % h as u64) as u32]
        })
        .collect();
    s.distance.brush = 0;
    let magenta = |px: &[u8]| px.chunks(4).filter(|p| p[..3] == [255, 0, 255]).count();
    let mut counts = Vec::new();
    for method in [Method2d::Jfa(Variant::Jfa), Method2d::Exact] {
        s.distance.options.method = method;
        let size = [s.distance.size[0] * 2, s.distance.size[1] * 2];
        let shot = viewer::render_offscreen(&device, &queue, "distance2d", &s, size, 3).unwrap();
        let line = shot
            .report
            .stats
            .iter()
            .find(|l| l.contains("wrong texels"))
            .unwrap_or_else(|| panic!("{:?}", shot.report.stats))
            .clone();
        let wrong: usize = line
            .split(": ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{line}"));
        eprintln!("{line}; {} magenta pixels", magenta(&shot.pixels));
        counts.push((wrong, magenta(&shot.pixels)));
    }
    let (jfa, exact) = (counts[0], counts[1]);
    assert!(
        jfa.0 > 0,
        "plain JFA on scattered seeds gets some texels wrong: {jfa:?}"
    );
    // Drawn at twice the field's size: each wrong texel covers about four pixels.
    assert!(jfa.1 >= jfa.0, "{jfa:?}");
    assert_eq!(exact, (0, 0));
}

/// Distance of the colour `p` to the polyline through `ramp` (RGB levels).
fn off_ramp(p: [u8; 3], ramp: &[[u8; 3]]) -> f32 {
    let v = |c: [u8; 3]| glam::Vec3::from_array(c.map(f32::from));
    let p = v(p);
    ramp.windows(2)
        .map(|w| {
            let (a, b) = (v(w[0]), v(w[1]));
            let t = ((p - a).dot(b - a) / (b - a).length_squared().max(1e-6)).clamp(0.0, 1.0);
            (p - (a + t * (b - a))).length()
        })
        .fold(f32::INFINITY, f32::min)
}

/// The debug views draw the colours their legends show: every pixel of the actor's step and
/// SDF views is the background or lies on the legend's ramp.
#[test]
fn debug_views_draw_the_colours_of_their_legends() {
    use fieldkit::metaball::Output;
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let mut s = settings();
    s.actor.animate = false;
    // The actor's background, [0.09, 0.1, 0.12] in Rgba8Unorm.
    let background = [23u8, 26, 31];
    for output in [Output::Steps, Output::Sdf] {
        s.actor.raymarch.output = output;
        let legend = &s.legends("actor")[0];
        let shot = viewer::render_offscreen(&device, &queue, "actor", &s, SIZE, 1).unwrap();
        assert!(shot.report.error.is_none(), "{:?}", shot.report.error);
        let (mut on, mut off) = (0, Vec::new());
        for p in shot.pixels.chunks(4) {
            let rgb = [p[0], p[1], p[2]];
            if (0..3).all(|c| rgb[c].abs_diff(background[c]) <= 2) {
                continue;
            }
            // Within 3 levels of the ramp: the shader's f32 colour rounded to 8 bits (llvmpipe;
            // every adapter rounds or truncates within one level).
            match off_ramp(rgb, &legend.ramp) {
                d if d <= 3.0 => on += 1,
                _ => off.push(rgb),
            }
        }
        eprintln!("{output:?}: {on} pixels on the ramp, {} off", off.len());
        assert!(on > 2000, "{output:?}: {on} pixels drawn");
        assert!(
            off.is_empty(),
            "{output:?}: off the legend's ramp: {:?}",
            &off[..off.len().min(8)]
        );
    }
}

/// The 2D tool times each method it compares under the method's name, so that the panel adds
/// up what each costs.
#[test]
fn the_2d_tool_times_each_method_it_compares() {
    use fieldkit::distance::{Method2d, Variant};
    use viewer::scenes::{COLOUR, DEPTH, EXACT_GROUP, Scenes};
    let _gpu = gpu_shared();
    let (device, queue) = device();
    let Some(mut profiler) = fieldkit::gpu::Profiler::new(&device, &queue, 256) else {
        panic!("this adapter has no timestamp queries; lavapipe (mesa-vulkan-drivers) has them");
    };
    let mut s = settings();
    s.distance.options.method = Method2d::Jfa(Variant::JfaPlus1);
    let targets = fieldkit::view::Targets::new(&device, [64, 48], COLOUR, DEPTH);
    let mut scenes = Scenes::new();
    let draw = |scenes: &mut Scenes, profiler| {
        let size = [64, 48];
        viewer::draw_frame(
            &device,
            &queue,
            scenes,
            &s,
            "distance2d",
            &targets,
            size,
            0.0,
            0,
            profiler,
        )
    };
    // The first frame asks a worker thread for the methods' pipelines; the frame after they
    // arrive records the fields.
    let (report, _) = draw(&mut scenes, None);
    assert!(report.error.is_none(), "{:?}", report.error);
    scenes.wait_for_workers();
    let (report, _) = draw(&mut scenes, Some(&mut profiler));
    assert!(report.error.is_none(), "{:?}", report.error);
    let mut enc = device.create_command_encoder(&Default::default());
    profiler.resolve(&mut enc);
    queue.submit([enc.finish()]);
    let (passes, _) = viewer::wait(&device, profiler.read(&device, &queue)).unwrap();
    let seen: Vec<(String, f64, u64)> = passes.into_iter().map(|(n, ms)| (n, ms, 1)).collect();
    let groups: Vec<String> = viewer::widgets::group_totals(&seen)
        .into_iter()
        .map(|g| g.0)
        .collect();
    assert_eq!(groups, ["JFA+1", EXACT_GROUP], "{seen:?}");
}
