//! 2D JFA against the exact Euclidean distance transform on the CPU, and against a CPU model of
//! the same passes. Sizes stay small for lavapipe.

use crate::common;

// The gallery example's scenes and test pictures (the example is the one place they live).
use crate::gallery;

use common::*;
use fieldkit::distance::{FAR, Jfa2d, JfaSettings2d, NO_SEED, Variant, cpu, unpack_seed};
use fieldkit::gpu::Context;

/// One test configuration.
struct Case {
    name: &'static str,
    w: usize,
    h: usize,
    mask: Vec<bool>,
}

fn points(w: usize, h: usize, pts: &[(usize, usize)]) -> Vec<bool> {
    let mut m = vec![false; w * h];
    for &(x, y) in pts {
        m[y * w + x] = true;
    }
    m
}

/// Seeds at (6,9), (12,6), (10,3) on 16×16: plain JFA sends one texel to the wrong seed (found by
/// searching with `cpu::jfa_2d`; the texel's true nearest seed's information is blocked by a
/// closer-looking seed at the step where it would have arrived).
pub const JFA_TRAP: [(usize, usize); 3] = [(6, 9), (12, 6), (10, 3)];

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for (i, density) in [1e-4, 1e-3, 1e-2, 0.1].into_iter().enumerate() {
        // 1e-4 on 128² is ~1.6 seeds: keep at least the grid big enough to hold some.
        let (w, h) = if density < 1e-3 {
            (200, 160)
        } else {
            (128, 128)
        };
        v.push(Case {
            name: ["random 1e-4", "random 1e-3", "random 1e-2", "random 0.1"][i],
            w,
            h,
            mask: random_mask(w, h, density, i as u64 + 1),
        });
    }
    v.push(Case {
        name: "single seed",
        w: 64,
        h: 48,
        mask: points(64, 48, &[(17, 30)]),
    });
    v.push(Case {
        name: "corners",
        w: 64,
        h: 64,
        mask: points(64, 64, &[(0, 0), (63, 0), (0, 63), (63, 63)]),
    });
    v.push(Case {
        name: "edges",
        w: 50,
        h: 40,
        mask: points(50, 40, &[(25, 0), (0, 20), (49, 13), (7, 39)]),
    });
    v.push(Case {
        name: "all seeds",
        w: 33,
        h: 17,
        mask: vec![true; 33 * 17],
    });
    v.push(Case {
        name: "non-pow2 97x200",
        w: 97,
        h: 200,
        mask: random_mask(97, 200, 0.003, 9),
    });
    v.push(Case {
        name: "non-square 200x3",
        w: 200,
        h: 3,
        mask: random_mask(200, 3, 0.02, 10),
    });
    v.push(Case {
        name: "1x1 seed",
        w: 1,
        h: 1,
        mask: vec![true],
    });
    v.push(Case {
        name: "JFA trap 16x16",
        w: 16,
        h: 16,
        mask: points(16, 16, &JFA_TRAP),
    });
    v
}

#[derive(Default, Clone, Copy)]
struct Errors {
    texels: usize,
    wrong: usize,
    max: f64,
    sum: f64,
}

/// Compare a GPU result with the exact transform. Every reported seed must be a real seed and the
/// reported distance must be the distance to it.
fn score(case: &Case, nearest: &[u32], dist: &[f32], exact: &[u64]) -> Errors {
    let mut e = Errors {
        texels: nearest.len(),
        ..Default::default()
    };
    for i in 0..nearest.len() {
        let (x, y) = ((i % case.w) as i64, (i / case.w) as i64);
        let Some((sx, sy)) = unpack_seed(nearest[i]) else {
            assert_eq!(
                exact[i],
                cpu::NONE,
                "{}: texel {i} has no seed but one exists",
                case.name
            );
            assert_eq!(dist[i], FAR);
            continue;
        };
        assert!(
            case.mask[sy as usize * case.w + sx as usize],
            "{}: texel {i} names ({sx},{sy}), not a seed",
            case.name
        );
        let d2 = ((sx as i64 - x).pow(2) + (sy as i64 - y).pow(2)) as u64;
        // Resolve writes exactly that seed's distance (f32 sqrt: relative 1e-6).
        assert!(
            ((dist[i] as f64) - (d2 as f64).sqrt()).abs() <= 1e-6 * (1.0 + (d2 as f64).sqrt()),
            "{}: distance {} for seed at d²={d2}",
            case.name,
            dist[i]
        );
        if d2 != exact[i] {
            e.wrong += 1;
            let err = (d2 as f64).sqrt() - (exact[i] as f64).sqrt();
            e.max = e.max.max(err);
            e.sum += err;
        }
    }
    e
}

#[test]
fn jfa_variants_against_exact_transform() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let cases = cases();
    let mut table = Vec::new();
    for variant in Variant::ALL {
        let mut total = Errors::default();
        let mut trap_wrong = 0;
        for case in &cases {
            let (nearest, dist) = run_jfa(
                &ctx,
                &jfa,
                &case.mask,
                case.w,
                case.h,
                variant_options(variant),
            );
            // Integer results compared exactly with the CPU model of the same passes.
            let model = cpu::jfa_2d(
                &case.mask,
                case.w,
                case.h,
                &variant.steps(case.w.max(case.h) as u32),
            );
            assert_eq!(
                nearest,
                model,
                "{} {}: GPU differs from the CPU model of the same passes",
                variant.name(),
                case.name
            );
            let exact = cpu::edt_2d_squared(&case.mask, case.w, case.h);
            let e = score(case, &nearest, &dist, &exact);
            if case.name.starts_with("JFA trap") {
                trap_wrong = e.wrong;
            }
            total.texels += e.texels;
            total.wrong += e.wrong;
            total.max = total.max.max(e.max);
            total.sum += e.sum;
        }
        table.push((variant, total, trap_wrong));
    }
    eprintln!("adapter: {}", ctx.adapter_name());
    eprintln!(
        "{:<6} {:>8} {:>7} {:>12} {:>10} {:>12}",
        "variant", "texels", "wrong", "wrong frac", "max err", "mean err"
    );
    for (v, e, _) in &table {
        eprintln!(
            "{:<7} {:>8} {:>7} {:>12.2e} {:>10.4} {:>12.2e}",
            v.name(),
            e.texels,
            e.wrong,
            e.wrong as f64 / e.texels as f64,
            e.max,
            e.sum / e.texels as f64
        );
    }
    let get = |v: Variant| table.iter().find(|t| t.0 == v).unwrap();
    // What the data shows: JFA+2 is exact on every case; plain JFA falls into the trap.
    assert_eq!(
        get(Variant::JfaPlus2).1.wrong,
        0,
        "JFA+2 must have no wrong texels"
    );
    assert!(
        get(Variant::Jfa).2 > 0,
        "plain JFA is expected to pick a wrong seed in the trap configuration"
    );
    assert_eq!(get(Variant::JfaPlus2).2, 0);
}

#[test]
fn no_seeds_gives_no_seed_and_far_everywhere() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let (nearest, dist) = run_jfa(
        &ctx,
        &jfa,
        &[false; 30 * 20],
        30,
        20,
        JfaSettings2d::default(),
    );
    assert!(nearest.iter().all(|&s| s == NO_SEED));
    assert!(dist.iter().all(|&d| d == FAR));
}

#[test]
fn signed_distance_matches_reference() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let (w, h) = (120, 72);
    let mask: Vec<bool> = gallery::shapes_mask(w as u32, h as u32)
        .iter()
        .map(|&m| m != 0)
        .collect();
    let options = JfaSettings2d {
        signed: true,
        texel_size: 0.25,
        ..JfaSettings2d::default()
    };
    let (_, dist) = run_jfa(&ctx, &jfa, &mask, w, h, options);
    let reference = cpu::signed_2d(&mask, w, h);
    let mut inside = 0;
    for i in 0..mask.len() {
        let want = reference[i] * 0.25;
        assert!(
            (dist[i] as f64 - want).abs() <= 1e-5 * (1.0 + want.abs()),
            "texel {i}: {} vs {want}",
            dist[i]
        );
        assert_eq!(dist[i] < 0.0, mask[i], "texel {i}: sign");
        inside += mask[i] as usize;
    }
    assert!(
        inside > 100 && inside < mask.len() - 100,
        "the mask has both sides"
    );
}

#[test]
fn full_mask_signed_is_minus_far() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let (_, dist) = run_jfa(&ctx, &jfa, &[true; 12 * 9], 12, 9, JfaSettings2d::signed());
    assert!(dist.iter().all(|&d| d == -FAR));
}

/// A field handed back with `Distance2d::recycle` is taken by the next call of its size (its
/// nearest-seed buffer is the one given), and the field made into it equals a new object's,
/// signed, bit for bit; a field of another size takes nothing.
#[test]
fn a_recycled_2d_field_is_taken_and_equals_a_new_one() {
    use fieldkit::distance::{Distance2d, Field2d, Nearest2d, Settings2d, upload_mask};
    let ctx = Context::shared();
    let (w, h) = (97usize, 61usize);
    let upload = |w: usize, h: usize, density, seed| {
        let m = random_mask(w, h, density, seed);
        upload_mask(&ctx.device, &ctx.queue, &to_bytes(&m), w as u32, h as u32).unwrap()
    };
    let (a, b, small) = (
        upload(w, h, 0.002, 41),
        upload(w, h, 0.05, 42),
        upload(40, 30, 0.05, 43),
    );
    let signed = Settings2d::signed();
    let (pooled, fresh) = (
        Distance2d::new(&ctx.device).unwrap(),
        Distance2d::new(&ctx.device).unwrap(),
    );
    let buffer = |n: &Nearest2d| match n {
        Nearest2d::Buffer(b) => b.clone(),
        Nearest2d::Texture(_) => panic!("the exact transform writes buffers"),
    };
    let bits = |f: &Field2d| {
        let n = f.read_nearest(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
        let d: Vec<u32> = fieldkit::gpu::read_texture(&ctx, &f.distance).unwrap();
        (n, d)
    };
    let mut enc = ctx.encoder("recycle 2d");
    let old = pooled.encode(&ctx.device, &mut enc, &a, &signed).unwrap();
    ctx.submit_and_wait("recycle 2d", enc).unwrap();
    let given = buffer(&old.nearest);
    pooled.recycle(old);
    let mut enc = ctx.encoder("recycle 2d");
    let other = pooled
        .encode(&ctx.device, &mut enc, &small, &signed)
        .unwrap();
    let got = pooled.encode(&ctx.device, &mut enc, &b, &signed).unwrap();
    let want = fresh.encode(&ctx.device, &mut enc, &b, &signed).unwrap();
    ctx.submit_and_wait("recycle 2d", enc).unwrap();
    let taken = [Some(&got.nearest), got.nearest_outside.as_ref()]
        .into_iter()
        .flatten()
        .any(|n| buffer(n) == given);
    assert!(taken, "the recycled buffer was not taken");
    assert!(
        buffer(&other.nearest) != given,
        "a field of another size took it"
    );
    assert!(bits(&got) == bits(&want), "the fields differ");
}
