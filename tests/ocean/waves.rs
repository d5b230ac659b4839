//! Gerstner waves (`ocean/surface`, `fieldkit::ocean`): the GPU sum against the f64 reference,
//! far from the origin and late in time, the trochoid and its cusp, the Jacobian bound for
//! aligned waves, steepness past 1 refused or clamped, bugs seen in public ports, the CPU query
//! for floating objects, waves shared between threads, and bad input.
//!
//! Tolerances were set on llvmpipe (f32 `sin`/`cos` of phases up to about 100 rad).

use fieldkit::Error;
use fieldkit::gpu::{Context, read_buffer};
use fieldkit::harness::Summary;
use fieldkit::ocean::{MAX_WAVES, SharedWaves, Wave, WaveGrid, Waves};
use glam::{DVec2, DVec3, Vec2, Vec4};

fn wave(dx: f32, dz: f32, amplitude: f32, wavelength: f32, speed: f32) -> Wave {
    Wave {
        direction: Vec2::new(dx, dz),
        amplitude,
        wavelength,
        speed,
    }
}

fn sea() -> Vec<Wave> {
    vec![
        wave(1.0, 0.15, 0.8, 31.0, 7.0),
        wave(0.4, 1.0, 0.35, 13.5, 4.6),
        wave(-0.7, 0.6, 0.12, 5.3, 2.9),
    ]
}

/// GPU grid: positions (relative to `origin`) and normals.
fn gpu_grid(
    ctx: &Context,
    waves: &Waves,
    origin: DVec2,
    time: f64,
    start: Vec2,
    spacing: Vec2,
    size: [u32; 2],
) -> (Vec<Vec4>, Vec<Vec4>) {
    let grid = WaveGrid::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("waves");
    let out = grid
        .encode(
            &ctx.device,
            &mut enc,
            &waves.gpu(origin, time),
            start,
            spacing,
            size,
        )
        .unwrap();
    ctx.submit_and_wait("waves", enc).unwrap();
    let read = |b| bytemuck::cast_slice::<u8, Vec4>(&read_buffer(ctx, b).unwrap()).to_vec();
    (read(&out.positions), read(&out.normals))
}

/// Largest position and normal difference between the GPU grid and the f64 reference.
fn worst_against_reference(
    ctx: &Context,
    waves: &Waves,
    origin: DVec2,
    time: f64,
    start: Vec2,
    spacing: Vec2,
    size: [u32; 2],
) -> (f64, f64) {
    let (pos, nrm) = gpu_grid(ctx, waves, origin, time, start, spacing, size);
    let (mut dp, mut dn) = (0f64, 0f64);
    for (i, (p, n)) in pos.iter().zip(&nrm).enumerate() {
        let (x, z) = ((i as u32 % size[0]) as f32, (i as u32 / size[0]) as f32);
        let local = start + Vec2::new(x, z) * spacing;
        let s = waves.surface(origin + local.as_dvec2(), time);
        let gpu = p.truncate().as_dvec3() + DVec3::new(origin.x, 0.0, origin.y);
        dp = dp.max((gpu - s.position).length());
        dn = dn.max((n.truncate().as_dvec3() - s.normal).length());
    }
    (dp, dn)
}

#[test]
fn gpu_matches_the_f64_reference_near_and_far() {
    let ctx = Context::shared();
    let waves = Waves::new(sea(), 0.75).unwrap();
    let (start, spacing, size) = (Vec2::new(-40.0, -30.0), Vec2::new(1.3, 1.1), [64, 56]);
    // Near the origin, early.
    let (dp, dn) = worst_against_reference(&ctx, &waves, DVec2::ZERO, 2.5, start, spacing, size);
    // llvmpipe: 5.6e-6 m and 1.1e-6 near, 5.8e-6 m and 8.4e-7 far.
    println!("near: position {dp:.2e} m, normal {dn:.2e}");
    assert!(dp < 1e-4 && dn < 1e-4, "near: {dp} m, normal {dn}");
    // 100 km out, an hour in: the phases are folded in f64, so f32 keeps millimetres.
    let far = DVec2::new(1.0e5, -7.3e4);
    let (dp, dn) = worst_against_reference(&ctx, &waves, far, 3600.5, start, spacing, size);
    println!("far: position {dp:.2e} m, normal {dn:.2e}");
    assert!(dp < 1e-3 && dn < 1e-3, "far: {dp} m, normal {dn}");
}

/// What the folded phases avoid: the same far grid given to f32 in world coordinates (origin at
/// the world origin, start 100 km out, where an f32 step is 8 mm) is off by more than the
/// millimetres asked for (llvmpipe: 0.014 m, against 6e-6 m above).
#[test]
fn world_coordinates_in_f32_lose_the_far_sea() {
    let ctx = Context::shared();
    let waves = Waves::new(sea(), 0.75).unwrap();
    let far = Vec2::new(1.0e5, -7.3e4);
    let (dp, _) = worst_against_reference(
        &ctx,
        &waves,
        DVec2::ZERO,
        3600.5,
        far + Vec2::new(-40.0, -30.0),
        Vec2::new(1.3, 1.1),
        [64, 56],
    );
    println!("f32 world coordinates 100 km out: {dp:.3} m");
    assert!(dp > 0.005, "expected more than 5 mm of error, got {dp} m");
}

/// One wave is a trochoid: X = x + (Q/w) cos θ, Y = A sin θ. dX/dx = 1 − Q sin θ (B.x) falls to
/// 1 − Q at the crest: a cusp (0) at Q = 1, rounded crests below.
#[test]
fn single_wave_is_a_trochoid_with_a_cusp_at_q_one() {
    let ctx = Context::shared();
    let (a, l) = (0.5f32, 8.0f32);
    for q in [1.0f32, 0.8, 0.4] {
        let waves = Waves::new(vec![wave(1.0, 0.0, a, l, 0.0)], q).unwrap();
        let size = [1024, 1];
        let (pos, _) = gpu_grid(
            &ctx,
            &waves,
            DVec2::ZERO,
            0.0,
            Vec2::ZERO,
            Vec2::new(l / 1024.0, 1.0),
            size,
        );
        // dX/dx from neighbouring points, and the trochoid's own shape.
        let mut min_dx = f32::MAX;
        for k in 1..pos.len() {
            min_dx = min_dx.min((pos[k].x - pos[k - 1].x) / (l / 1024.0));
        }
        let w = std::f32::consts::TAU / l;
        for (k, p) in pos.iter().enumerate() {
            let x = k as f32 * l / 1024.0;
            let theta = w * x;
            assert!(
                (p.x - (x + q / w * theta.cos())).abs() < 1e-4,
                "Q {q} point {k}: x"
            );
            assert!(
                (p.y - a * theta.sin()).abs() < 1e-5,
                "Q {q} point {k}: height"
            );
        }
        println!("Q {q}: smallest dX/dx {min_dx:.4}");
        assert!(
            (min_dx - (1.0 - q)).abs() < 2e-3,
            "Q {q}: smallest dX/dx {min_dx}"
        );
    }
}

/// Aligned waves: the horizontal Jacobian B.x·T.z − B.z·T.x = 1 − Σ Qᵢ Aᵢ wᵢ sin θᵢ ≥ 1 − Q.
#[test]
fn aligned_waves_keep_the_jacobian_above_one_minus_q() {
    let ctx = Context::shared();
    let q = 0.9;
    let waves = Waves::new(
        vec![
            wave(0.6, 0.8, 0.7, 20.0, 5.0),
            wave(0.6, 0.8, 0.3, 7.0, 3.0),
            wave(0.6, 0.8, 0.2, 3.1, 2.0),
        ],
        q,
    )
    .unwrap();
    let (pos, _) = gpu_grid(
        &ctx,
        &waves,
        DVec2::ZERO,
        1.7,
        Vec2::splat(-30.0),
        Vec2::splat(0.25),
        [240, 240],
    );
    let mut min_j = f64::MAX;
    for iz in 0..240 {
        for ix in 0..240 {
            let p = DVec2::new(-30.0 + 0.25 * ix as f64, -30.0 + 0.25 * iz as f64);
            min_j = min_j.min(waves.surface(p, 1.7).horizontal_jacobian());
        }
    }
    println!("smallest Jacobian {min_j:.4} (bound {:.2})", 1.0 - q);
    assert!(min_j >= 1.0 - q as f64 - 1e-12);
    // And on the GPU: neighbouring points never cross along the waves' direction.
    let d = Vec2::new(0.6, 0.8);
    for iz in 0..240 {
        for ix in 1..240 {
            let (a, b) = (pos[iz * 240 + ix - 1], pos[iz * 240 + ix]);
            let along = Vec2::new(b.x - a.x, b.z - a.z).dot(d);
            assert!(along > 0.0, "points ({ix}, {iz}) crossed: {along}");
        }
    }
}

#[test]
fn steepness_past_one_is_refused_or_clamped() {
    let err = Waves::new(sea(), 1.3).unwrap_err();
    assert!(
        matches!(&err, Error::Invalid { what, .. } if what.contains("loops")),
        "{err}"
    );
    let (w, clamped) = Waves::new_clamped(sea(), 1.3).unwrap();
    let c = clamped.expect("a diagnostic");
    assert_eq!((c.requested, c.used), (1.3, 1.0));
    assert_eq!(w.steepness(), 1.0);
    let (_, none) = Waves::new_clamped(sea(), 0.5).unwrap();
    assert!(none.is_none());
}

/// A port that wrote w = 2/L (π dropped) gets a period of πL: the height must repeat after L
/// and change sign after L/2.
#[test]
fn regression_pi_in_the_frequency() {
    let ctx = Context::shared();
    let l = 10.0f32;
    let waves = Waves::new(vec![wave(1.0, 0.0, 1.0, l, 0.0)], 0.0).unwrap();
    let (pos, _) = gpu_grid(
        &ctx,
        &waves,
        DVec2::ZERO,
        0.0,
        Vec2::new(1.3, 0.0),
        Vec2::new(l / 2.0, 1.0),
        [3, 1],
    );
    assert!(pos[0].y.abs() > 0.5, "a point off the zero crossing");
    assert!(
        (pos[1].y + pos[0].y).abs() < 1e-5,
        "half a wavelength on: {pos:?}"
    );
    assert!(
        (pos[2].y - pos[0].y).abs() < 1e-5,
        "a wavelength on: {pos:?}"
    );
}

/// A port that wrote φ = 2S/L moves crests at S/π: a crest must travel S·Δt in Δt.
#[test]
fn regression_pi_in_the_phase_speed() {
    let ctx = Context::shared();
    let (l, s) = (12.0f32, 3.0f32);
    let waves = Waves::new(vec![wave(1.0, 0.0, 1.0, l, s)], 0.0).unwrap();
    let at = |t: f64, x: f32| {
        gpu_grid(
            &ctx,
            &waves,
            DVec2::ZERO,
            t,
            Vec2::new(x, 0.0),
            Vec2::ONE,
            [1, 1],
        )
        .0[0]
            .y
    };
    // The crest at x = L/4 at t = 0 is at L/4 − S·Δt later (θ = w·x + φ·t, so it runs toward −x).
    let dt = 0.7;
    let later = at(dt as f64, l / 4.0 - s * dt);
    assert!((at(0.0, l / 4.0) - 1.0).abs() < 1e-5);
    assert!(
        (later - 1.0).abs() < 1e-4,
        "crest height after {dt} s: {later}"
    );
}

/// A port that wrote Q / w * A * N instead of Q / (w A N) scales the sideways motion by A·N:
/// one wave must move points sideways by exactly Q/w, whatever its amplitude.
#[test]
fn regression_steepness_precedence() {
    let ctx = Context::shared();
    let (l, q) = (12.0f32, 0.8f32);
    for a in [0.5f32, 2.0] {
        let waves = Waves::new(vec![wave(1.0, 0.0, a, l, 0.0)], q).unwrap();
        let (pos, _) = gpu_grid(
            &ctx,
            &waves,
            DVec2::ZERO,
            0.0,
            Vec2::ZERO,
            Vec2::new(l / 256.0, 1.0),
            [256, 1],
        );
        let most = pos
            .iter()
            .enumerate()
            .map(|(k, p)| (p.x - k as f32 * l / 256.0).abs())
            .fold(0.0, f32::max);
        let want = q * l / std::f32::consts::TAU;
        assert!(
            (most - want).abs() < 1e-4,
            "A {a}: sideways {most}, want {want}"
        );
    }
}

/// A port that added the input position inside the wave loop moves every point to N·p: points
/// must stay within Σ Qᵢ Aᵢ of where they started, with many waves and far from the origin.
#[test]
fn regression_position_added_once() {
    let ctx = Context::shared();
    let waves = Waves::new(sea(), 0.6).unwrap();
    let spacing = Vec2::splat(3.0);
    let (pos, _) = gpu_grid(
        &ctx,
        &waves,
        DVec2::ZERO,
        0.0,
        Vec2::splat(-48.0),
        spacing,
        [33, 33],
    );
    let reach: f32 = waves
        .waves()
        .iter()
        .map(|w| 0.6 * w.wavelength / (std::f32::consts::TAU * 3.0))
        .sum();
    for (i, p) in pos.iter().enumerate() {
        let start = Vec2::splat(-48.0) + Vec2::new((i % 33) as f32, (i / 33) as f32) * spacing;
        let moved = (Vec2::new(p.x, p.z) - start).length();
        assert!(moved <= reach + 1e-4, "point {i} moved {moved} > {reach}");
    }
}

/// Floating objects: the CPU query at a GPU point's displaced (x, z) gives the GPU's height and
/// normal there.
#[test]
fn cpu_query_agrees_with_the_gpu() {
    let ctx = Context::shared();
    let waves = Waves::new(sea(), 0.9).unwrap();
    let origin = DVec2::new(250.0, -80.0);
    let (pos, nrm) = gpu_grid(
        &ctx,
        &waves,
        origin,
        11.25,
        Vec2::splat(-20.0),
        Vec2::splat(1.7),
        [24, 24],
    );
    let (mut dh, mut dn) = (0f64, 0f64);
    for (p, n) in pos.iter().zip(&nrm) {
        let world = origin + DVec2::new(p.x as f64, p.z as f64);
        let s = waves.sample(world, 11.25);
        dh = dh.max((s.height - p.y as f64).abs());
        dn = dn.max((s.normal - n.truncate().as_dvec3()).length());
    }
    println!("query vs GPU: height {dh:.2e} m, normal {dn:.2e}");
    assert!(dh < 1e-4 && dn < 1e-3, "height {dh}, normal {dn}");
}

/// One thread keeps replacing the waves while another snapshots them: every snapshot is one
/// whole set.
#[test]
fn waves_update_safely_from_another_thread() {
    let calm = Waves::new(vec![wave(1.0, 0.0, 0.1, 40.0, 2.0)], 0.2).unwrap();
    let storm = Waves::new(sea(), 0.95).unwrap();
    let shared = SharedWaves::new(calm.clone());
    let writer = {
        let shared = shared.clone();
        let (calm, storm) = (calm.clone(), storm.clone());
        std::thread::spawn(move || {
            for k in 0..2000 {
                shared.set(if k % 2 == 0 {
                    storm.clone()
                } else {
                    calm.clone()
                });
            }
        })
    };
    let mut seen = [0usize; 2];
    for _ in 0..2000 {
        let s = shared.snapshot();
        if s == calm {
            seen[0] += 1;
        } else if s == storm {
            seen[1] += 1;
        } else {
            panic!("a snapshot mixed two sets: {s:?}");
        }
    }
    writer.join().unwrap();
    assert_eq!(seen[0] + seen[1], 2000);
}

#[test]
fn bad_input_gets_typed_errors() {
    let good = wave(1.0, 0.0, 1.0, 10.0, 1.0);
    let cases: Vec<(&str, Vec<Wave>, f32, &str)> = vec![
        ("no waves", vec![], 0.5, "number of waves"),
        (
            "too many",
            vec![good; MAX_WAVES + 1],
            0.5,
            "number of waves",
        ),
        (
            "NaN amplitude",
            vec![wave(1.0, 0.0, f32::NAN, 10.0, 1.0)],
            0.5,
            "amplitude",
        ),
        (
            "zero amplitude",
            vec![wave(1.0, 0.0, 0.0, 10.0, 1.0)],
            0.5,
            "amplitude",
        ),
        (
            "zero wavelength",
            vec![wave(1.0, 0.0, 1.0, 0.0, 1.0)],
            0.5,
            "wavelength",
        ),
        (
            "negative wavelength",
            vec![wave(1.0, 0.0, 1.0, -3.0, 1.0)],
            0.5,
            "wavelength",
        ),
        (
            "zero direction",
            vec![wave(0.0, 0.0, 1.0, 10.0, 1.0)],
            0.5,
            "direction",
        ),
        (
            "NaN direction",
            vec![wave(f32::NAN, 0.0, 1.0, 10.0, 1.0)],
            0.5,
            "direction",
        ),
        (
            "infinite speed",
            vec![wave(1.0, 0.0, 1.0, 10.0, f32::INFINITY)],
            0.5,
            "speed",
        ),
        ("NaN steepness", vec![good], f32::NAN, "steepness"),
        ("negative steepness", vec![good], -0.1, "steepness"),
        ("steepness past 1", vec![good], 1.5, "loops"),
    ];
    for (name, waves, q, needle) in cases {
        let err = Waves::new(waves, q).expect_err(name);
        assert!(err.to_string().contains(needle), "{name}: {err}");
        assert!(
            matches!(err, Error::Invalid { .. } | Error::Size { .. }),
            "{name}: {err:?}"
        );
    }
    // Grids: zero or oversized sides, non-finite placement.
    let ctx = Context::shared();
    let grid = WaveGrid::new(&ctx.device).unwrap();
    let set = Waves::new(vec![good], 0.5).unwrap().gpu(DVec2::ZERO, 0.0);
    for (name, start, size) in [
        ("zero side", Vec2::ZERO, [0, 4]),
        ("oversized side", Vec2::ZERO, [4, 5000]),
        ("NaN start", Vec2::new(f32::NAN, 0.0), [4, 4]),
    ] {
        let mut enc = ctx.encoder("bad");
        let err = grid
            .encode(&ctx.device, &mut enc, &set, start, Vec2::ONE, size)
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted"));
        assert!(
            matches!(err, Error::Invalid { .. } | Error::Size { .. }),
            "{name}: {err:?}"
        );
    }
}

#[test]
fn displaced_grid_snapshot() {
    let ctx = Context::shared();
    let waves = Waves::new(sea(), 0.75).unwrap();
    let size = [32, 24];
    let (pos, nrm) = gpu_grid(
        &ctx,
        &waves,
        DVec2::new(10.0, 5.0),
        4.0,
        Vec2::splat(-16.0),
        Vec2::ONE,
        size,
    );
    let shape = [24, 32];
    let heights: Vec<f32> = pos.iter().map(|p| p.y).collect();
    let sideways: Vec<f32> = pos
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let start = Vec2::splat(-16.0) + Vec2::new((i % 32) as f32, (i / 32) as f32);
            (Vec2::new(p.x, p.z) - start).length()
        })
        .collect();
    let up: Vec<f32> = nrm.iter().map(|n| n.y).collect();
    fieldkit::assert_summary!(
        "displaced_grid_snapshot",
        Summary::floats(&shape, &heights, 3)
            .and("sideways offset", Summary::floats(&shape, &sideways, 3))
            .and("normal y", Summary::floats(&shape, &up, 3))
            .to_string()
    );
}
