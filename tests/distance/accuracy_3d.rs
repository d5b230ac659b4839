//! 3D distance fields against the exact CPU transform: the exact GPU transform must match it
//! everywhere, on both column paths (workgroup and global memory) and at WebGPU's default
//! workgroup-memory limit; the JFA variants' errors are measured, printed and asserted. Grids stay
//! ≤ 64³ (one case 96×200×37, columns to 1000 long) for lavapipe.

use crate::common;

use common::*;
use fieldkit::distance::{
    ColumnPasses, Distance3d, Method, Settings3d, tile_columns, unpack_seed3,
};
use fieldkit::distance::{FAR, Variant, cpu};
use fieldkit::gpu::Context;

struct Case {
    name: &'static str,
    size: [usize; 3],
    mask: Vec<bool>,
    /// Run the JFA variants too (the largest case runs the exact transform only).
    jfa: bool,
}

/// Seeds at (2,10,1), (0,9,10), (8,10,11) on 12³: plain JFA gives 12 voxels a wrong seed (found
/// by searching random 3-seed configurations with `cpu::jfa_3d`).
const JFA_TRAP: [[usize; 3]; 3] = [[2, 10, 1], [0, 9, 10], [8, 10, 11]];

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for (i, (density, size)) in [
        (1e-4, [64, 64, 64]),
        (1e-3, [48, 48, 48]),
        (1e-2, [32, 32, 32]),
        (0.1, [24, 24, 24]),
    ]
    .into_iter()
    .enumerate()
    {
        let name = [
            "random 1e-4 (64³)",
            "random 1e-3 (48³)",
            "random 1e-2 (32³)",
            "random 0.1 (24³)",
        ][i];
        v.push(Case {
            name,
            size,
            mask: random_mask_3d(size, density, 100 + i as u64),
            jfa: true,
        });
    }
    v.push(Case {
        name: "single seed",
        size: [33, 20, 17],
        mask: mask_3d([33, 20, 17], &[[5, 13, 9]]),
        jfa: true,
    });
    let s = [30, 22, 18];
    v.push(Case {
        name: "faces, edges, corners",
        size: s,
        mask: mask_3d(
            s,
            &[
                [0, 0, 0],
                [29, 21, 17],
                [15, 0, 0],
                [0, 21, 9],
                [29, 11, 8],
                [10, 5, 17],
            ],
        ),
        jfa: true,
    });
    // Dense seeds but for a hollow at the x = 0 edge: the global z pass's sweep
    // (`edt_columns.wgsl`'s SCAN) answers the workgroup of columns x ≥ 32 and, in the other,
    // finds voxels whose nearest seed is past its reach part-way along the columns (at z = 64,
    // the sweep's ninth step, having written the steps before). With the hollow x < 26,
    // 40 ≤ z < 90 about 4 voxels of that step are far (x < 2, z = 64 and 65), and the same
    // dispatch builds the workgroup's envelopes (`sweep_end`'s HERE); with x < 30, 40 ≤ z < 100
    // about 48 are (x < 6), and the pass after it does (LATER).
    for (name, x_end, z_end) in [
        ("dense, a hollow at an edge (a few voxels far)", 26, 90),
        (
            "dense, a larger hollow at an edge (many voxels far)",
            30,
            100,
        ),
    ] {
        let s = [64, 3, 110];
        v.push(Case {
            name,
            size: s,
            mask: hollow_at_edge(s, 11, x_end, 40..z_end),
            jfa: false,
        });
    }
    v.push(Case {
        name: "no seeds",
        size: [9, 7, 5],
        mask: vec![false; 9 * 7 * 5],
        jfa: true,
    });
    v.push(Case {
        name: "full grid",
        size: [10, 6, 4],
        mask: vec![true; 10 * 6 * 4],
        jfa: true,
    });
    v.push(Case {
        name: "anisotropic 61×7×29",
        size: [61, 7, 29],
        mask: random_mask_3d([61, 7, 29], 0.005, 7),
        jfa: true,
    });
    v.push(Case {
        name: "line along x",
        size: [50, 1, 1],
        mask: mask_3d([50, 1, 1], &[[3, 0, 0], [40, 0, 0]]),
        jfa: true,
    });
    v.push(Case {
        name: "line along y",
        size: [1, 40, 1],
        mask: mask_3d([1, 40, 1], &[[0, 21, 0]]),
        jfa: true,
    });
    v.push(Case {
        name: "line along z",
        size: [1, 1, 45],
        mask: mask_3d([1, 1, 45], &[[0, 0, 0], [0, 0, 44]]),
        jfa: true,
    });
    v.push(Case {
        name: "JFA trap 12³",
        size: [12, 12, 12],
        mask: mask_3d([12, 12, 12], &JFA_TRAP),
        jfa: true,
    });
    // The last pass's scan (`edt_tile.wgsl`): a tile whose every own cost is at most 24²
    // answers each voxel by looking along its column until the step's square reaches the best.
    // Seeds fill the column at x = 24 (own cost 576 at x = 0); voxel (0, 0, 34) is nearest to
    // (0, 0, 11), 23 steps away (529; (0, 1, 34) at 530). One column further out
    // (own cost 625) the tile takes the envelopes instead.
    for (name, far_x) in [
        ("scan reach 25×2×64", 24),
        ("past the scan reach 26×2×64", 25),
    ] {
        let size = [far_x + 1, 2, 64];
        let mut seeds: Vec<[usize; 3]> = (0..64)
            .flat_map(|z| [[far_x, 0, z], [far_x, 1, z]])
            .collect();
        seeds.push([0, 0, 11]);
        v.push(Case {
            name,
            size,
            mask: mask_3d(size, &seeds),
            jfa: false,
        });
    }
    v.push(Case {
        name: "non-pow2 96×200×37",
        size: [96, 200, 37],
        mask: random_mask_3d([96, 200, 37], 2e-3, 8),
        jfa: false,
    });
    v
}

#[derive(Default, Clone, Copy, Debug)]
struct Errors {
    voxels: usize,
    wrong: usize,
    max: f64,
    sum: f64,
}

/// Every reported seed must be a real seed, the resolved distance must be the distance to it,
/// and its squared distance is compared with the exact one.
fn score(case: &Case, nearest: &[u32], dist: &[f32], exact: &[u64]) -> Errors {
    let [w, h, _] = case.size;
    let mut e = Errors {
        voxels: nearest.len(),
        ..Default::default()
    };
    for i in 0..nearest.len() {
        let Some([sx, sy, sz]) = unpack_seed3(nearest[i]) else {
            assert_eq!(
                exact[i],
                cpu::NONE,
                "{}: voxel {i} has no seed but one exists",
                case.name
            );
            assert_eq!(dist[i], FAR);
            continue;
        };
        assert!(
            case.mask[(sz as usize * h + sy as usize) * w + sx as usize],
            "{}: voxel {i} names ({sx},{sy},{sz}), not a seed",
            case.name
        );
        let d2 = cpu::seed_d2_3(nearest[i], i, case.size).unwrap();
        assert!(
            ((dist[i] as f64) - (d2 as f64).sqrt()).abs() <= 1e-6 * (1.0 + (d2 as f64).sqrt()),
            "{}: distance {} for d²={d2}",
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

/// A signed field against the CPU's signed transform. The distance is an f32 square root of an
/// exact integer, less half a voxel: a few ulps (Vulkan lets sqrt be that loose on any GPU), far
/// inside 1e-5. No seed on the other side is ±FAR, sign included.
fn check_signed(what: &str, dist: &[f32], signed: &[f64]) {
    for (i, (&got, &want)) in dist.iter().zip(signed).enumerate() {
        let far = want.abs() > 1e30;
        assert!(
            (!far && (got as f64 - want).abs() <= 1e-5 * (1.0 + want.abs()))
                || (far && got.abs() > 1e30 && (got < 0.0) == (want < 0.0)),
            "{what}: voxel {i}: {got} vs {want}"
        );
    }
}

fn methods() -> Vec<Method> {
    std::iter::once(Method::Exact)
        .chain(Variant::ALL.into_iter().map(Method::Jfa))
        .collect()
}

#[test]
fn exact_and_jfa_against_the_cpu_transform() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let mut totals: Vec<(Method, Errors)> = methods()
        .into_iter()
        .map(|m| (m, Errors::default()))
        .collect();
    let mut trap_wrong = 0;
    for case in cases() {
        let exact = cpu::edt_3d_squared(&case.mask, case.size);
        for (method, total) in totals.iter_mut() {
            if !case.jfa && *method != Method::Exact {
                continue;
            }
            let (nearest, _, dist) = run_3d(
                &ctx,
                &d3,
                &case.mask,
                case.size,
                &Settings3d {
                    method: *method,
                    ..Settings3d::default()
                },
            );
            let e = score(&case, &nearest, &dist, &exact);
            if let Method::Jfa(v) = method
                && e.voxels <= 20_000
            {
                // The shader and its CPU model take the same decisions, tie-breaks included.
                let model = cpu::jfa_3d(
                    &case.mask,
                    case.size,
                    &v.steps(*case.size.iter().max().unwrap() as u32),
                );
                assert_eq!(
                    nearest,
                    model,
                    "{}: {} differs from cpu::jfa_3d",
                    case.name,
                    v.name()
                );
            }
            if case.name.starts_with("JFA trap") && *method == Method::Jfa(Variant::Jfa) {
                trap_wrong = e.wrong;
            }
            if *method == Method::Exact {
                assert_eq!(
                    e.wrong, 0,
                    "{}: the exact transform has {} wrong voxels",
                    case.name, e.wrong
                );
            }
            total.voxels += e.voxels;
            total.wrong += e.wrong;
            total.max = total.max.max(e.max);
            total.sum += e.sum;
        }
    }
    println!("| method | voxels | wrong | fraction | max err (voxels) | mean err |");
    println!("|---|---|---|---|---|---|");
    for (m, e) in &totals {
        println!(
            "| {} | {} | {} | {:.2e} | {:.3} | {:.2e} |",
            m.name(),
            e.voxels,
            e.wrong,
            e.wrong as f64 / e.voxels as f64,
            e.max,
            e.sum / e.voxels as f64
        );
    }
    let get = |m: Method| totals.iter().find(|t| t.0 == m).unwrap().1;
    assert!(
        trap_wrong > 0,
        "plain JFA is expected to pick a wrong seed in the trap configuration"
    );
    assert_eq!(
        get(Method::Jfa(Variant::JfaPlus2)).wrong,
        0,
        "JFA+2 must have no wrong voxels on these cases"
    );
    assert_eq!(
        get(Method::Jfa(Variant::OnePlusJfaPlus2)).wrong,
        0,
        "1+JFA+2 must have no wrong voxels on these cases"
    );
}

/// The column passes split each column into 1 to 32 bands, each building its own envelope and
/// searching the others'. Test grids are small, so the automatic choice is always 32 bands; every
/// other count must be exact too.
#[test]
fn every_column_band_count_is_exact() {
    let ctx = Context::shared();
    let mut d3 = Distance3d::new(&ctx.device).unwrap();
    // The bands are the global-memory passes' (the workgroup-memory passes pick their own).
    d3.set_column_passes(ColumnPasses::Global);
    for bands in [1, 2, 4, 8, 16, 32] {
        d3.set_column_bands(Some(bands)).unwrap();
        for case in cases() {
            let exact = cpu::edt_3d_squared(&case.mask, case.size);
            let (nearest, _, dist) =
                run_3d(&ctx, &d3, &case.mask, case.size, &Settings3d::default());
            let e = score(&case, &nearest, &dist, &exact);
            assert_eq!(
                e.wrong, 0,
                "{} with {bands} bands: {} wrong voxels",
                case.name, e.wrong
            );
            // At 8 bands the resolving z pass sweeps where every voxel is near a site
            // (`edt_columns.wgsl`'s SCAN), in the signed entry too.
            if bands == 8 {
                let options = Settings3d::signed();
                let (_, _, dist) = run_3d(&ctx, &d3, &case.mask, case.size, &options);
                let signed = cpu::signed_3d(&case.mask, case.size);
                check_signed(&format!("{} signed, 8 bands", case.name), &dist, &signed);
            }
        }
    }
    // The sweep's ring and the band sizes (9 KiB) fit WebGPU's default 16 KiB.
    let defaults = default_limits(&ctx);
    let mut d3_defaults = Distance3d::new(&defaults.device).unwrap();
    d3_defaults.set_column_passes(ColumnPasses::Global);
    d3_defaults.set_column_bands(Some(8)).unwrap();
    for case in cases() {
        let exact = cpu::edt_3d_squared(&case.mask, case.size);
        let (nearest, _, dist) = run_3d(
            &defaults,
            &d3_defaults,
            &case.mask,
            case.size,
            &Settings3d::default(),
        );
        let e = score(&case, &nearest, &dist, &exact);
        assert_eq!(
            e.wrong, 0,
            "{} (default limits): {} wrong",
            case.name, e.wrong
        );
    }
    assert!(defaults.take_uncaptured().is_empty());
    for bad in [0, 3, 64] {
        let err = d3.set_column_bands(Some(bad)).unwrap_err().to_string();
        assert!(err.contains("column bands"), "{err}");
    }
}

/// 20% random seeds (`seed`) in a field of `size` but for a hollow at its x = 0 edge: x <
/// `x_end` and z in `z`, every y.
fn hollow_at_edge(
    size: [usize; 3],
    seed: u64,
    x_end: usize,
    z: std::ops::Range<usize>,
) -> Vec<bool> {
    hollow_along(size, seed, x_end, 2, z)
}

/// As `hollow_at_edge`, with the range along `axis` (1: y, every z; 2: z, every y).
fn hollow_along(
    size: [usize; 3],
    seed: u64,
    x_end: usize,
    axis: usize,
    range: std::ops::Range<usize>,
) -> Vec<bool> {
    let mut mask = random_mask_3d(size, 0.2, seed);
    for z in 0..size[2] {
        for y in 0..size[1] {
            if range.contains(&[y, z][axis - 1]) {
                for x in 0..x_end {
                    mask[(z * size[1] + y) * size[0] + x] = false;
                }
            }
        }
    }
    mask
}

/// The z pass's sweep after a y pass in workgroup memory (Auto at 8 bands: y of 3 in a tile,
/// which then writes the kept stack the sweep reads its sites from; z of 300 in global memory),
/// unsigned and signed, with a hollow at the x = 0 edge that stops the sweep part-way (a few far
/// voxels: the envelopes in the same dispatch; many: in the pass after).
#[test]
fn the_sweep_after_a_workgroup_y_pass_is_exact() {
    let ctx = Context::shared();
    let mut d3 = Distance3d::new(&ctx.device).unwrap();
    d3.set_column_bands(Some(8)).unwrap();
    let storage = ctx.device.limits().max_compute_workgroup_storage_size;
    assert!(tile_columns(storage, 3, 3).is_some());
    assert_eq!(tile_columns(storage, 300, 3), None);
    let s = [64, 3, 300];
    for (x_end, z_end) in [(26, 190), (30, 200)] {
        let case = Case {
            name: "dense, a hollow at an edge",
            size: s,
            mask: hollow_at_edge(s, 17, x_end, 140..z_end),
            jfa: false,
        };
        let exact = cpu::edt_3d_squared(&case.mask, s);
        let (nearest, _, dist) = run_3d(&ctx, &d3, &case.mask, s, &Settings3d::default());
        let e = score(&case, &nearest, &dist, &exact);
        assert_eq!(e.wrong, 0, "hollow x < {x_end}: {} wrong voxels", e.wrong);
        let options = Settings3d::signed();
        let (_, _, dist) = run_3d(&ctx, &d3, &case.mask, s, &options);
        check_signed(
            &format!("hollow x < {x_end}, signed"),
            &dist,
            &cpu::signed_3d(&case.mask, s),
        );
    }
}

/// A field split across bindings runs the y pass last, from its parts into its slabs; in
/// global memory that pass sweeps as the z pass of a whole field does, reading its sites from
/// the part, at 8 bands whether set so or chosen (the automatic count would be 32 here).
/// Dense seeds (the sweep answers every voxel, some from far along y), and hollows at the
/// x = 0 edge part-way along y that stop it (a few far voxels: the envelopes in the same
/// dispatch; many: in the pass after), unsigned and signed, against the CPU transform.
#[test]
fn the_y_pass_of_a_split_field_sweeps_exactly() {
    let ctx = Context::shared();
    let mut d3 = Distance3d::new(&ctx.device).unwrap();
    d3.set_column_passes(ColumnPasses::Global);
    let s = [70, 300, 3];
    // Three parts (32, 32 and 6 columns) and three slabs of one plane.
    d3.set_split_bytes(Some((32 * 300 * 3 * 4) as u64));
    let masks = [
        ("dense", random_mask_3d(s, 0.2, 31)),
        // No voxel far (every row's own site within 22), but those at x = 0 take their
        // answer from 20 rows away or more: a sweep that looked less far would be wrong.
        (
            "a hollow narrower than the reach",
            hollow_along(s, 34, 22, 1, 100..160),
        ),
        (
            "a hollow (a few voxels far)",
            hollow_along(s, 32, 26, 1, 140..190),
        ),
        (
            "a larger hollow (many far)",
            hollow_along(s, 33, 30, 1, 140..200),
        ),
    ];
    for bands in [None, Some(8)] {
        d3.set_column_bands(bands).unwrap();
        for (name, mask) in &masks {
            let case = Case {
                name,
                size: s,
                mask: mask.clone(),
                jfa: false,
            };
            let exact = cpu::edt_3d_squared(mask, s);
            let (nearest, _, dist) = run_3d(&ctx, &d3, mask, s, &Settings3d::default());
            let e = score(&case, &nearest, &dist, &exact);
            assert_eq!(
                e.wrong, 0,
                "{name}, split, bands {bands:?}: {} wrong voxels",
                e.wrong
            );
            let options = Settings3d::signed();
            let (_, _, dist) = run_3d(&ctx, &d3, mask, s, &options);
            check_signed(
                &format!("{name}, split, bands {bands:?}, signed"),
                &dist,
                &cpu::signed_3d(mask, s),
            );
        }
    }
}

/// The column passes in workgroup memory (`edt_tile.wgsl`) and in global memory
/// (`edt_columns.wgsl`), chosen automatically or forced, at the adapter's limits and at WebGPU's
/// defaults, unsigned and signed, against the CPU transform: exact everywhere. The extra shapes
/// reach the tile's edge cases: one voxel, one column 300 long (forced into workgroup memory at
/// 16 KiB: 8 columns per tile, 7 of them past the grid), and columns 600 and 1000 long (4 and 2
/// per tile when forced).
#[test]
fn every_column_path_is_exact() {
    let shared = Context::shared();
    let defaults = default_limits(&shared);
    assert_eq!(
        defaults.device.limits().max_compute_workgroup_storage_size,
        16384
    );
    // What Auto takes along z at these lengths (forced to workgroup memory at 16 KiB, 300, 600
    // and 1000 take 4, 2 and 2 columns per tile, bands of 8): the test covers each of them.
    // Along y Auto holds columns up to 128 in workgroup memory.
    assert_eq!(tile_columns(16384, 37, 3), Some(16));
    assert_eq!(tile_columns(16384, 200, 3), Some(8));
    assert_eq!(tile_columns(16384, 256, 3), Some(8));
    assert_eq!(tile_columns(16384, 257, 3), None);
    assert_eq!(tile_columns(16384, 300, 3), None);
    assert_eq!(tile_columns(16384, 300, 2), None);
    assert_eq!(tile_columns(16384, 512, 3), None);
    assert_eq!(tile_columns(16384, 600, 3), None);
    assert_eq!(tile_columns(16384, 1000, 3), None);
    let mut extra = vec![
        ("one voxel, seeded", [1, 1, 1], vec![true]),
        ("one voxel, empty", [1, 1, 1], vec![false]),
        (
            "1×300×2",
            [1, 300, 2],
            mask_3d([1, 300, 2], &[[0, 7, 0], [0, 290, 1]]),
        ),
        (
            "3×1000×2",
            [3, 1000, 2],
            random_mask_3d([3, 1000, 2], 3e-3, 12),
        ),
        (
            "5×2×600",
            [5, 2, 600],
            random_mask_3d([5, 2, 600], 4e-3, 13),
        ),
        // Rows of 2000 voxels: 63 row words, one row per workgroup of the word pass.
        (
            "2000×5×2",
            [2000, 5, 2],
            random_mask_3d([2000, 5, 2], 2e-3, 15),
        ),
        // Auto: y in workgroup memory, z (400) in global memory.
        (
            "6×3×400",
            [6, 3, 400],
            random_mask_3d([6, 3, 400], 5e-3, 14),
        ),
        // Auto: y (200) in global memory, z in workgroup memory.
        (
            "6×200×40",
            [6, 200, 40],
            random_mask_3d([6, 200, 40], 5e-3, 16),
        ),
    ];
    let mut all: Vec<(String, [usize; 3], Vec<bool>)> = cases()
        .into_iter()
        .map(|c| (c.name.to_string(), c.size, c.mask))
        .collect();
    all.extend(extra.drain(..).map(|(n, s, m)| (n.to_string(), s, m)));
    let references: Vec<(Vec<u64>, Vec<f64>)> = all
        .iter()
        .map(|(_, size, mask)| {
            (
                cpu::edt_3d_squared(mask, *size),
                cpu::signed_3d(mask, *size),
            )
        })
        .collect();
    for (device_name, ctx) in [("adapter limits", &shared), ("default limits", &defaults)] {
        let mut d3 = Distance3d::new(&ctx.device).unwrap();
        for passes in [
            ColumnPasses::Auto,
            ColumnPasses::Workgroup,
            ColumnPasses::Global,
        ] {
            d3.set_column_passes(passes);
            for ((name, size, mask), (exact, signed)) in all.iter().zip(&references) {
                for is_signed in [false, true] {
                    let options = Settings3d {
                        signed: is_signed,
                        ..Settings3d::default()
                    };
                    let (nearest, _, dist) = run_3d(ctx, &d3, mask, *size, &options);
                    let case = Case {
                        name: Box::leak(name.clone().into_boxed_str()),
                        size: *size,
                        mask: mask.clone(),
                        jfa: false,
                    };
                    let what = format!("{name} ({device_name}, {passes:?}, signed {is_signed})");
                    if is_signed {
                        check_signed(&what, &dist, signed);
                    } else {
                        let e = score(&case, &nearest, &dist, exact);
                        assert_eq!(e.wrong, 0, "{what}: {} wrong voxels", e.wrong);
                    }
                }
            }
        }
    }
    // Forced into workgroup memory, a column longer than one tile holds is a typed error naming
    // the longest that fits (3613 at 16 KiB), not a pipeline the device refuses.
    let mut d3 = Distance3d::new(&defaults.device).unwrap();
    d3.set_column_passes(ColumnPasses::Workgroup);
    let tall = fieldkit::distance::upload_mask(
        &defaults.device,
        &defaults.queue,
        &vec![0u8; 4000],
        1,
        4000,
    )
    .unwrap();
    let mut enc = defaults.encoder("too long");
    match d3
        .exact()
        .encode_exact_2d(&defaults.device, &mut enc, &tall, &Settings3d::default())
    {
        Err(fieldkit::Error::Size { got, max, .. }) => assert_eq!((got, max), (4000, 3613)),
        other => panic!("expected Error::Size, got {other:?}"),
    }
    assert!(shared.take_uncaptured().is_empty());
    assert!(defaults.take_uncaptured().is_empty());
}

/// A field larger than one storage binding (1024³ is 4 GiB where wgpu binds 2 GiB − 1) is split:
/// the z pass into parts of whole columns held apart, the y pass into the field's slabs of
/// planes, one buffer each. Here the split is forced at small sizes (`set_split_bytes`) so that
/// every part and slab boundary runs on lavapipe (parts that do not divide the width, two
/// slabs or more), unsigned and signed, at the adapter's limits and at WebGPU's defaults,
/// against the CPU transform.
#[test]
fn fields_split_across_bindings_are_exact() {
    let shared = Context::shared();
    let defaults = default_limits(&shared);
    // (name, size, mask, bytes per binding): three parts or more, and two slabs or more.
    let cases = [
        (
            "96×200×37",
            [96, 200, 37],
            random_mask_3d([96, 200, 37], 2e-3, 21),
            96 * 200 * 37 * 4 / 3,
        ),
        (
            "70×33×90",
            [70, 33, 90],
            random_mask_3d([70, 33, 90], 5e-3, 22),
            300_000,
        ),
        (
            "single seed 40×9×30",
            [40, 9, 30],
            mask_3d([40, 9, 30], &[[39, 0, 29]]),
            40 * 9 * 30 * 4 / 2,
        ),
        // Columns of z past 256: Auto runs the z pass in global memory, the y pass in tiles.
        (
            "40×12×300",
            [40, 12, 300],
            random_mask_3d([40, 12, 300], 3e-3, 23),
            40 * 12 * 300 * 4 / 2,
        ),
    ];
    for (name, size, mask, split) in &cases {
        let exact = cpu::edt_3d_squared(mask, *size);
        let signed = cpu::signed_3d(mask, *size);
        for (device_name, ctx) in [("adapter limits", &shared), ("default limits", &defaults)] {
            let mut d3 = Distance3d::new(&ctx.device).unwrap();
            d3.set_split_bytes(Some(*split));
            let volume = fieldkit::distance::upload_volume(
                &ctx.device,
                &ctx.queue,
                &to_bytes(mask),
                size_u32(*size),
            )
            .unwrap();
            let mut enc = ctx.encoder("split");
            let field = d3
                .encode(&ctx.device, &mut enc, &volume, &Settings3d::default())
                .unwrap();
            assert!(
                field.nearest.buffers.len() >= 2 && field.nearest.whole().is_none(),
                "{name}: {} slabs",
                field.nearest.buffers.len()
            );
            // Slab k holds planes k · depth onwards; `plane` finds each one's buffer.
            let depth = field.nearest.depth as usize;
            let plane_bytes = (size[0] * size[1] * 4) as u64;
            for (k, b) in field.nearest.buffers.iter().enumerate() {
                let planes = depth.min(size[2] - k * depth);
                assert_eq!(b.size(), planes as u64 * plane_bytes, "{name}: slab {k}");
            }
            for z in 0..size[2] as u32 {
                let (b, local) = field.nearest.plane(z).unwrap();
                let k = z as usize / depth;
                assert_eq!(b, &field.nearest.buffers[k], "{name}: plane {z}");
                assert_eq!(local as usize, z as usize - k * depth, "{name}: plane {z}");
            }
            assert!(field.nearest.plane(size[2] as u32).is_none());
            drop(enc);
            // Each pass in workgroup or global memory, and as Auto mixes them (y past 128 and
            // z past 256 in global memory).
            for passes in [
                ColumnPasses::Auto,
                ColumnPasses::Workgroup,
                ColumnPasses::Global,
            ] {
                d3.set_column_passes(passes);
                for is_signed in [false, true] {
                    let options = Settings3d {
                        signed: is_signed,
                        ..Settings3d::default()
                    };
                    let what =
                        format!("{name} ({device_name}, split, {passes:?}, signed {is_signed})");
                    let (nearest, _, dist) = run_3d(ctx, &d3, mask, *size, &options);
                    if is_signed {
                        for i in 0..dist.len() {
                            let want = signed[i];
                            // As in every_column_path_is_exact: a few ulps of sqrt (lavapipe).
                            let ok = if want.abs() > 1e30 {
                                dist[i].abs() > 1e30 && (dist[i] < 0.0) == (want < 0.0)
                            } else {
                                (dist[i] as f64 - want).abs() <= 1e-5 * (1.0 + want.abs())
                            };
                            assert!(ok, "{what}: voxel {i}: {} vs {want}", dist[i]);
                        }
                    } else {
                        let case = Case {
                            name: Box::leak(what.clone().into_boxed_str()),
                            size: *size,
                            mask: mask.clone(),
                            jfa: false,
                        };
                        let e = score(&case, &nearest, &dist, &exact);
                        assert_eq!(e.wrong, 0, "{what}: {} wrong voxels", e.wrong);
                    }
                }
            }
            // A binding too small for even one tile of whole columns: a typed error naming it.
            d3.set_column_passes(ColumnPasses::Auto);
            d3.set_split_bytes(Some(64));
            let mut enc = ctx.encoder("split, too fine");
            match d3.encode(&ctx.device, &mut enc, &volume, &Settings3d::default()) {
                Err(fieldkit::Error::Size { what, got, max, .. }) => {
                    assert!(what.contains("tile of columns"), "{what}");
                    assert!(got > max && max == 64, "{got} vs {max}");
                }
                other => panic!("{name}: expected Error::Size, got {other:?}"),
            }
            assert!(ctx.take_uncaptured().is_empty());
        }
    }
    // The bench's knob takes powers of two up to 16 columns, and says so otherwise.
    let mut d3 = Distance3d::new(&shared.device).unwrap();
    for bad in [0, 3, 32] {
        let e = d3.set_split_columns(Some(bad)).unwrap_err().to_string();
        assert!(e.contains("split columns"), "{e}");
    }
    d3.set_split_columns(None).unwrap();
}

/// Grids past the standard packing's 2048 × 2048 × 1024 (a side of 2048 along z): the exact
/// transform packs their seeds with the bits each side needs (`SeedPacking::for_size`), on every
/// column path, whole and split across bindings, unsigned and signed, at WebGPU's default
/// limits too; every voxel's seed is a seed at the CPU transform's squared distance. The JFA
/// passes, which keep the standard packing, refuse such a grid with a typed error.
#[test]
fn tall_grids_pack_seeds_with_the_bits_they_need() {
    use fieldkit::distance::SeedPacking;
    let shared = Context::shared();
    let defaults = default_limits(&shared);
    let cases: Vec<([usize; 3], Vec<bool>)> = vec![
        ([3, 2, 2048], random_mask_3d([3, 2, 2048], 2e-3, 21)),
        (
            [1, 1, 1500],
            mask_3d([1, 1, 1500], &[[0, 0, 3], [0, 0, 1400]]),
        ),
        ([80, 2, 1100], random_mask_3d([80, 2, 1100], 1e-3, 22)),
    ];
    let packing = |size: [usize; 3]| {
        SeedPacking::for_size([size[0] as u32, size[1] as u32, size[2] as u32]).unwrap()
    };
    assert_eq!(
        packing([3, 2, 2048]),
        SeedPacking {
            x_bits: 2,
            y_bits: 1
        }
    );
    assert_eq!(
        packing([80, 2, 1100]),
        SeedPacking {
            x_bits: 7,
            y_bits: 1
        }
    );
    for (size, mask) in &cases {
        let p = packing(*size);
        let exact = cpu::edt_3d_squared(mask, *size);
        let signed = cpu::signed_3d(mask, *size);
        let [w, h, _] = *size;
        for (device_name, ctx) in [("adapter limits", &shared), ("default limits", &defaults)] {
            let mut d3 = Distance3d::new(&ctx.device).unwrap();
            let mut runs = vec![
                (ColumnPasses::Auto, None),
                (ColumnPasses::Workgroup, None),
                (ColumnPasses::Global, None),
            ];
            // Split across bindings where the field is wide enough for parts of whole tiles.
            if w >= 64 {
                runs.push((ColumnPasses::Auto, Some((w * h * size[2] * 4 / 3) as u64)));
            }
            for (passes, split) in runs {
                d3.set_column_passes(passes);
                d3.set_split_bytes(split);
                for is_signed in [false, true] {
                    let what = format!(
                        "{size:?} ({device_name}, {passes:?}, split {split:?}, signed {is_signed})"
                    );
                    let volume = fieldkit::distance::upload_volume(
                        &ctx.device,
                        &ctx.queue,
                        &to_bytes(mask),
                        [w as u32, h as u32, size[2] as u32],
                    )
                    .unwrap();
                    let options = Settings3d {
                        signed: is_signed,
                        ..Settings3d::default()
                    };
                    let mut enc = ctx.encoder("tall");
                    let field = d3
                        .encode(&ctx.device, &mut enc, &volume, &options)
                        .unwrap_or_else(|e| panic!("{what}: {e}"));
                    ctx.submit_and_wait("tall", enc).unwrap();
                    assert_eq!(field.packing, p, "{what}");
                    let nearest = field
                        .nearest
                        .read(&ctx.device, &ctx.queue)
                        .wait(ctx)
                        .unwrap();
                    let dist: Vec<f32> = fieldkit::gpu::read_texture(ctx, &field.distance).unwrap();
                    if is_signed {
                        check_signed(&what, &dist, &signed);
                        continue;
                    }
                    for i in 0..nearest.len() {
                        let (x, y, z) = (i % w, i / w % h, i / (w * h));
                        let Some([sx, sy, sz]) = field.packing.unpack(nearest[i]) else {
                            assert_eq!(exact[i], cpu::NONE, "{what}: voxel {i} has no seed");
                            continue;
                        };
                        let [sx, sy, sz] = [sx as usize, sy as usize, sz as usize];
                        assert!(
                            sx < w && sy < h && sz < size[2] && mask[(sz * h + sy) * w + sx],
                            "{what}: voxel {i} names ({sx},{sy},{sz}), not a seed"
                        );
                        let d2 = [(sx, x), (sy, y), (sz, z)]
                            .iter()
                            .map(|&(a, b)| (a as i64 - b as i64).pow(2) as u64)
                            .sum::<u64>();
                        assert_eq!(d2, exact[i], "{what}: voxel {i}");
                        assert!(
                            (dist[i] as f64 - (d2 as f64).sqrt()).abs()
                                <= 1e-6 * (1.0 + (d2 as f64).sqrt()),
                            "{what}: voxel {i}: distance {}",
                            dist[i]
                        );
                    }
                }
            }
        }
    }
    // The JFA passes keep the standard packing: z past 1024 is refused.
    let (size, mask) = &cases[0];
    let volume = fieldkit::distance::upload_volume(
        &shared.device,
        &shared.queue,
        &to_bytes(mask),
        [size[0] as u32, size[1] as u32, size[2] as u32],
    )
    .unwrap();
    let d3 = Distance3d::new(&shared.device).unwrap();
    let mut enc = shared.encoder("tall jfa");
    let jfa = Settings3d {
        method: Method::Jfa(Variant::JfaPlus2),
        ..Settings3d::default()
    };
    match d3.encode(&shared.device, &mut enc, &volume, &jfa) {
        Err(fieldkit::Error::Size { got, max, .. }) => assert_eq!((got, max), (2048, 1024)),
        other => panic!("expected Error::Size, got {:?}", other.err()),
    }
    assert!(shared.take_uncaptured().is_empty());
    assert!(defaults.take_uncaptured().is_empty());
}
