//! Where JFA+2 fails: sparse seeds on non-square grids. The seed sets were found by searching
//! the seed space on the CPU model of the passes (`cpu::jfa_2d`, which follows the shader pass
//! for pass): random sets of 3–6 seeds on six non-square sizes, each hill-climbed one seed at a
//! time towards more wrong texels. JFA+2 leaves dozens of texels at a seed several texels
//! farther than the nearest; the exact transform, the 2D default, has none. The GPU's JFA+2 must
//! pick exactly the seeds the CPU model picks (integer results, compared exactly).

use crate::common;

use common::*;
use fieldkit::distance::{Distance2d, Method2d, Settings2d, Variant, cpu, upload_mask};
use fieldkit::gpu::Context;
use fieldkit::gpu::read_texture;

struct Trap {
    w: usize,
    h: usize,
    seeds: &'static [(usize, usize)],
    /// Texels JFA+2 leaves at a farther seed (the CPU model's count).
    wrong: usize,
}

const TRAPS: &[Trap] = &[
    Trap {
        w: 37,
        h: 101,
        seeds: &[(15, 29), (31, 13), (2, 62), (32, 99)],
        wrong: 77,
    },
    Trap {
        w: 64,
        h: 23,
        seeds: &[(34, 6), (50, 22), (5, 6)],
        wrong: 34,
    },
];

/// Texels whose seed is farther than the nearest, and the largest excess (texels).
fn wrong(nearest: &[u32], exact: &[u64], w: usize) -> (usize, f64) {
    let mut n = 0;
    let mut worst = 0f64;
    for (i, (&s, &e)) in nearest.iter().zip(exact).enumerate() {
        let (sx, sy) = ((s & 0xffff) as i64 - 1, (s >> 16) as i64 - 1);
        let (x, y) = ((i % w) as i64, (i / w) as i64);
        let d = ((sx - x).pow(2) + (sy - y).pow(2)) as u64;
        if d != e {
            n += 1;
            worst = worst.max((d as f64).sqrt() - (e as f64).sqrt());
        }
    }
    (n, worst)
}

#[test]
fn jfa_plus_2_fails_on_sparse_non_square_sets_and_exact_does_not() {
    let ctx = Context::shared();
    let distance = Distance2d::new(&ctx.device).unwrap();
    for trap in TRAPS {
        let (w, h) = (trap.w, trap.h);
        let mut mask = vec![false; w * h];
        for &(x, y) in trap.seeds {
            mask[y * w + x] = true;
        }
        let exact = cpu::edt_2d_squared(&mask, w, h);
        let model = cpu::jfa_2d(&mask, w, h, &Variant::JfaPlus2.steps(w.max(h) as u32));
        assert_eq!(
            wrong(&model, &exact, w).0,
            trap.wrong,
            "the CPU model on {w}×{h}"
        );
        let seeds = upload_mask(
            &ctx.device,
            &ctx.queue,
            &to_bytes(&mask),
            w as u32,
            h as u32,
        )
        .unwrap();
        for method in [Method2d::Jfa(Variant::JfaPlus2), Method2d::Exact] {
            let mut enc = ctx.encoder("trap");
            let field = distance
                .encode(
                    &ctx.device,
                    &mut enc,
                    &seeds,
                    &Settings2d {
                        method,
                        ..Settings2d::default()
                    },
                )
                .unwrap();
            ctx.submit_and_wait("trap", enc).unwrap();
            let nearest = field
                .read_nearest(&ctx.device, &ctx.queue)
                .wait(&ctx)
                .unwrap();
            let (n, worst) = wrong(&nearest, &exact, w);
            eprintln!(
                "{w}×{h}, {} seeds, {method:?}: {n} wrong, up to {worst:.2} texels",
                trap.seeds.len()
            );
            match method {
                Method2d::Exact => assert_eq!(n, 0, "the exact transform on {w}×{h}"),
                Method2d::Jfa(_) => {
                    assert_eq!(
                        nearest, model,
                        "GPU JFA+2 picks the CPU model's seeds on {w}×{h}"
                    );
                    assert_eq!(n, trap.wrong);
                    assert!(worst > 2.0, "JFA+2 is off by {worst} texels on {w}×{h}");
                }
            }
            let distances: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
            assert_eq!(distances.len(), w * h);
        }
    }
}
