//! 3D distance fields beyond nearest seeds: signed distance, world units, the narrow band,
//! density thresholds, sub-voxel seeds on analytic shapes, and the exact 2D transform.

use crate::common;

use common::*;
use fieldkit::distance::{
    ColumnPasses, Distance3d, Grid, Inside, Method, Settings3d, upload_points,
    upload_points_with_homes, upload_volume,
};
use fieldkit::distance::{Variant, cpu, upload_mask};
use fieldkit::gpu::Context;
use fieldkit::gpu::{read_buffer, read_texture};
use glam::Vec3;

fn shape_mask(size: [usize; 3]) -> Vec<bool> {
    // A ball and a slab, off-grid, so inside and outside both have structure.
    let [w, h, d] = size;
    (0..w * h * d)
        .map(|i| {
            let p = Vec3::new((i % w) as f32, ((i / w) % h) as f32, (i / (w * h)) as f32);
            p.distance(Vec3::new(9.3, 8.7, 6.1)) < 5.6 || (p.x > 17.0 && p.x < 20.5 && p.y > 3.0)
        })
        .collect()
}

#[test]
fn signed_matches_cpu_for_exact_and_jfa_plus_2() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let size = [26, 19, 14];
    let m = shape_mask(size);
    let reference = cpu::signed_3d(&m, size);
    for method in [Method::Exact, Method::Jfa(Variant::JfaPlus2)] {
        let (_, outside, d) = run_3d(
            &ctx,
            &d3,
            &m,
            size,
            &Settings3d {
                method,
                signed: true,
                ..Settings3d::default()
            },
        );
        assert!(outside.is_some());
        for i in 0..d.len() {
            assert!(
                (d[i] as f64 - reference[i]).abs() <= 1e-5 * (1.0 + reference[i].abs()),
                "{}: voxel {i}: {} vs {}",
                method.name(),
                d[i],
                reference[i]
            );
            assert_eq!(d[i] < 0.0, m[i], "sign at voxel {i}");
        }
    }
}

/// The exact transform resolves in its last column pass: z, or y when the volume is one slice
/// thick, or a pass of its own when it is a single row. Each shape, unsigned and signed, against
/// the CPU transform.
#[test]
fn exact_resolves_in_whichever_pass_is_last() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    for size in [[23, 1, 1], [17, 11, 1], [9, 1, 13]] {
        let m = random_mask_3d(size, 0.15, 7);
        let unsigned = cpu::edt_3d_squared(&m, size);
        let signed = cpu::signed_3d(&m, size);
        for is_signed in [false, true] {
            let (_, _, d) = run_3d(
                &ctx,
                &d3,
                &m,
                size,
                &Settings3d {
                    signed: is_signed,
                    voxel_size: 0.5,
                    ..Settings3d::default()
                },
            );
            for i in 0..d.len() {
                let want = if is_signed {
                    signed[i] * 0.5
                } else {
                    (unsigned[i] as f64).sqrt() * 0.5
                };
                assert!(
                    (d[i] as f64 - want).abs() <= 1e-5 * (1.0 + want.abs()),
                    "{size:?} signed={is_signed} voxel {i}: {} vs {want}",
                    d[i]
                );
            }
        }
    }
}

#[test]
fn world_units_band_and_threshold() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let size = [20, 17, 12];
    let m = random_mask_3d(size, 0.004, 31);
    let exact = cpu::edt_3d_squared(&m, size);
    // Voxel size scales every distance.
    let (_, _, d) = run_3d(
        &ctx,
        &d3,
        &m,
        size,
        &Settings3d {
            voxel_size: 0.25,
            ..Settings3d::default()
        },
    );
    for i in 0..d.len() {
        let want = (exact[i] as f64).sqrt() * 0.25;
        assert!(
            (d[i] as f64 - want).abs() <= 1e-6 * (1.0 + want),
            "voxel {i}: {} vs {want}",
            d[i]
        );
    }
    // Narrow band of 3 voxels: JFA+2 starting at step 4 is exact inside the band, clamped beyond.
    for method in [Method::Exact, Method::Jfa(Variant::JfaPlus2)] {
        let (_, _, d) = run_3d(
            &ctx,
            &d3,
            &m,
            size,
            &Settings3d {
                method,
                band: Some(3.0),
                ..Settings3d::default()
            },
        );
        for i in 0..d.len() {
            let want = (exact[i] as f64).sqrt().min(3.0);
            assert!(
                (d[i] as f64 - want).abs() <= 1e-6 * (1.0 + want),
                "{} voxel {i}: {} vs {want}",
                method.name(),
                d[i]
            );
        }
    }
    assert_eq!(
        Settings3d {
            band: Some(3.0),
            ..Settings3d::default()
        }
        .steps(Variant::JfaPlus2, 20),
        vec![4, 2, 1, 2, 1]
    );
    assert_eq!(
        Settings3d {
            band: Some(3.0),
            ..Settings3d::default()
        }
        .steps(Variant::OnePlusJfa, 64),
        vec![1, 4, 2, 1]
    );
    // A density volume: marked where the value ≥ the threshold, not merely non-zero.
    let density: Vec<u8> = (0..m.len()).map(|i| if m[i] { 200 } else { 100 }).collect();
    let volume = upload_volume(&ctx.device, &ctx.queue, &density, size_u32(size)).unwrap();
    let mut enc = ctx.encoder("density");
    let field = d3
        .encode(
            &ctx.device,
            &mut enc,
            &volume,
            &Settings3d {
                inside: Inside::Threshold(0.5),
                ..Settings3d::default()
            },
        )
        .unwrap();
    ctx.submit_and_wait("density", enc).unwrap();
    let d: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
    for i in 0..d.len() {
        assert!(
            (d[i] as f64 - (exact[i] as f64).sqrt()).abs() <= 1e-5 * (1.0 + d[i] as f64),
            "threshold voxel {i}"
        );
    }
}

/// Surface samples for an analytic SDF: for every voxel within one voxel of the surface, the
/// closest surface point (as a mesher or the metaball stage would emit them).
/// Returns (voxel, point) pairs.
fn surface_points(
    size: [usize; 3],
    sdf: &dyn Fn(Vec3) -> f32,
    closest: &dyn Fn(Vec3) -> Vec3,
) -> Vec<([u32; 3], Vec3)> {
    let [w, h, d] = size;
    (0..w * h * d)
        .map(|i| [(i % w) as u32, ((i / w) % h) as u32, (i / (w * h)) as u32])
        .filter(|v| sdf(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).abs() <= 1.0)
        .map(|v| (v, closest(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32))))
        .collect()
}

/// Runs sub-voxel seeds through JFA+2 with the sign from the analytic inside test; returns
/// (max, RMS) error in voxels over all voxels.
fn analytic_error(
    size: [usize; 3],
    sdf: &dyn Fn(Vec3) -> f32,
    closest: &dyn Fn(Vec3) -> Vec3,
    voxel_size: f32,
    with_homes: bool,
) -> (f64, f64) {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    // Grid placed in the world away from the origin, to exercise the world → voxel mapping.
    let grid = Grid {
        size: size_u32(size),
        voxel: voxel_size as f64,
        origin: glam::DVec3::new(-3.0, 10.0, 0.5),
    };
    let pts = surface_points(size, sdf, closest);
    let world: Vec<Vec3> = pts
        .iter()
        .map(|&(_, p)| grid.origin.as_vec3() + (p + 0.5) * voxel_size)
        .collect();
    let homes: Vec<[u32; 3]> = pts.iter().map(|&(v, _)| v).collect();
    let seeds = if with_homes {
        upload_points_with_homes(&ctx.device, &ctx.queue, &grid, &world, &homes)
    } else {
        upload_points(&ctx.device, &ctx.queue, &grid, &world)
    }
    .unwrap();
    let [w, h, d] = size;
    let inside: Vec<u8> = (0..w * h * d)
        .map(|i| {
            if sdf(Vec3::new(
                (i % w) as f32,
                ((i / w) % h) as f32,
                (i / (w * h)) as f32,
            )) < 0.0
            {
                255
            } else {
                0
            }
        })
        .collect();
    let volume = upload_volume(&ctx.device, &ctx.queue, &inside, grid.size).unwrap();
    let mut enc = ctx.encoder("points");
    let options = Settings3d {
        method: Method::Jfa(Variant::JfaPlus2),
        voxel_size,
        ..Settings3d::default()
    };
    let field = d3
        .encode_points(
            &ctx.device,
            &mut enc,
            &seeds,
            grid.size,
            Some(&volume),
            &options,
        )
        .unwrap();
    ctx.submit_and_wait("points", enc).unwrap();
    let got: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
    let (mut max, mut sum2) = (0f64, 0f64);
    for (i, &g) in got.iter().enumerate() {
        let p = Vec3::new((i % w) as f32, ((i / w) % h) as f32, (i / (w * h)) as f32);
        let err = (g / voxel_size - sdf(p)).abs() as f64;
        max = max.max(err);
        sum2 += err * err;
    }
    (max, (sum2 / got.len() as f64).sqrt())
}

// llvmpipe measured max 0.166 / RMS 0.0195 (sphere) and 0.164 / 0.0243 (torus). The max is the
// sampling limit one voxel off the surface, where the nearest sample point sits up to half a
// voxel to the side of the true closest point; integer seeds cannot get below half a voxel.
const MAX_WITH_HOMES: f64 = 0.2;
const RMS_WITH_HOMES: f64 = 0.03;

#[test]
fn sub_voxel_seeds_on_a_sphere() {
    let (c, r) = (Vec3::new(19.3, 17.6, 15.2), 9.37);
    let sdf = move |p: Vec3| p.distance(c) - r;
    let closest = move |p: Vec3| c + (p - c).normalize() * r;
    let (max, rms) = analytic_error([40, 36, 32], &sdf, &closest, 0.5, true);
    let (max_c, rms_c) = analytic_error([40, 36, 32], &sdf, &closest, 0.5, false);
    println!(
        "sphere: homes max {max:.4} rms {rms:.4}; containing voxel max {max_c:.4} rms {rms_c:.4} (voxels)"
    );
    // Bounds from llvmpipe's measurement with a margin (see the note on issue 3).
    assert!(
        max < MAX_WITH_HOMES && rms < RMS_WITH_HOMES,
        "sphere: max {max} rms {rms}"
    );
    // Without homes, points that share a voxel are dropped: worse, and this shows by how much.
    assert!(
        max_c > max && max_c < 0.4 && rms_c < 0.05,
        "sphere without homes: max {max_c} rms {rms_c}"
    );
}

#[test]
fn sub_voxel_seeds_on_a_torus() {
    let (c, big, small) = (Vec3::new(21.4, 20.7, 9.6), 11.2f32, 4.3f32);
    let ring = move |p: Vec3| {
        let q = p - c;
        c + Vec3::new(q.x, q.y, 0.0).normalize() * big
    };
    let sdf = move |p: Vec3| p.distance(ring(p)) - small;
    let closest = move |p: Vec3| ring(p) + (p - ring(p)).normalize() * small;
    let (max, rms) = analytic_error([44, 42, 20], &sdf, &closest, 1.0, true);
    println!("torus: max {max:.4} rms {rms:.4} voxels");
    assert!(
        max < MAX_WITH_HOMES && rms < RMS_WITH_HOMES,
        "torus: max {max} rms {rms}"
    );
}

#[test]
fn exact_2d_matches_cpu() {
    let ctx = Context::shared();
    // Both column paths resolve as they answer (a single row, 50×1, has no column pass and is
    // resolved on its own).
    let mut d3 = Distance3d::new(&ctx.device).unwrap();
    for (w, h, density, seed, passes) in [
        (97usize, 61usize, 0.01, 1u64, ColumnPasses::Workgroup),
        (97, 61, 0.01, 1, ColumnPasses::Global),
        (300, 2, 0.02, 2, ColumnPasses::Auto),
        (1, 80, 0.05, 3, ColumnPasses::Global),
        (513, 40, 0.001, 4, ColumnPasses::Auto),
        (50, 1, 0.05, 5, ColumnPasses::Auto),
        // Rows across word and thread boundaries of the row pass's bitmask (32 texels a word,
        // 64 a thread), and the longest row the exact transform takes.
        (33, 4, 0.1, 6, ColumnPasses::Auto),
        (200, 3, 0.004, 7, ColumnPasses::Auto),
        (16384, 2, 2e-4, 8, ColumnPasses::Global),
        // Columns whose separators' numerators pass 2^24 (sites more than 4096 texels off the
        // column), where the f32 quotient may round: the answers must still be exact. (Removing
        // the separator's correction did not fail this case: a CPU model of the passes found no
        // seed set in 200 000 where an off-by-one separator changed an answer, as each position
        // is answered by walking costs, not separators.)
        (5000, 40, 3e-4, 9, ColumnPasses::Global),
        (5000, 40, 3e-4, 9, ColumnPasses::Workgroup),
    ] {
        d3.set_column_passes(passes);
        let m = random_mask(w, h, density, seed);
        let exact = cpu::edt_2d_squared(&m, w, h);
        let signed = cpu::signed_2d(&m, w, h);
        let tex = upload_mask(&ctx.device, &ctx.queue, &to_bytes(&m), w as u32, h as u32).unwrap();
        for is_signed in [false, true] {
            let mut enc = ctx.encoder("exact 2d");
            let field = d3
                .exact()
                .encode_exact_2d(
                    &ctx.device,
                    &mut enc,
                    &tex,
                    &Settings3d {
                        signed: is_signed,
                        ..Settings3d::default()
                    },
                )
                .unwrap();
            ctx.submit_and_wait("exact 2d", enc).unwrap();
            let nearest: Vec<u32> =
                bytemuck::cast_slice(&read_buffer(&ctx, &field.nearest).unwrap()).to_vec();
            let d: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
            for i in 0..m.len() {
                let want = if is_signed {
                    signed[i]
                } else if exact[i] == cpu::NONE {
                    f32::MAX as f64
                } else {
                    (exact[i] as f64).sqrt()
                };
                assert!(
                    (d[i] as f64 - want).abs() <= 1e-5 * (1.0 + want.abs()),
                    "{w}x{h} {passes:?} signed={is_signed} texel {i}: {} vs {want}",
                    d[i]
                );
                if !is_signed {
                    let got = fieldkit::distance::unpack_seed(nearest[i]).map(|(sx, sy)| {
                        ((sx as i64 - (i % w) as i64).pow(2) + (sy as i64 - (i / w) as i64).pow(2))
                            as u64
                    });
                    assert_eq!(got.unwrap_or(cpu::NONE), exact[i], "{w}x{h} texel {i}");
                }
            }
        }
    }
}

/// Fields handed back with `Distance3d::recycle` are taken by the next calls and written whole:
/// after a field of one seed set is recycled, the next field (another seed set, dense where
/// the first was sparse, so a value left over would show) is made on the recycled buffers and
/// texture and equals, bit for bit, the field a `Distance3d` with nothing recycled makes of the
/// same volume: the exact transform unsigned, signed and split across bindings, JFA, and the
/// exact 2D transform (`recycle_2d`). Recycling the field of another size takes nothing.
#[test]
fn recycled_fields_are_taken_again_and_written_whole() {
    let ctx = Context::shared();
    let size = [40, 33, 21];
    let sparse = random_mask_3d(size, 2e-3, 31);
    let dense = random_mask_3d(size, 0.08, 32);
    let upload = |m: &[bool], s: [usize; 3]| {
        upload_volume(&ctx.device, &ctx.queue, &to_bytes(m), size_u32(s)).unwrap()
    };
    let (first, second) = (upload(&sparse, size), upload(&dense, size));
    let jfa = Method::Jfa(fieldkit::distance::Variant::JfaPlus2);
    // (case, bytes per binding, options)
    let cases = [
        ("exact", None, Settings3d::default()),
        ("exact signed", None, Settings3d::signed()),
        (
            "exact split",
            Some(40 * 33 * 21 * 4 / 2),
            Settings3d::default(),
        ),
        (
            "jfa signed",
            None,
            Settings3d {
                method: jfa,
                signed: true,
                ..Settings3d::default()
            },
        ),
    ];
    let bits = |f: &fieldkit::distance::Field3d| {
        let mut words = f.nearest.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
        if let Some(o) = &f.nearest_outside {
            words.extend(o.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap());
        }
        let d: Vec<f32> = read_texture(&ctx, &f.distance).unwrap();
        (words, d.iter().map(|v| v.to_bits()).collect::<Vec<u32>>())
    };
    for (case, split, options) in &cases {
        let mut pooled = Distance3d::new(&ctx.device).unwrap();
        let mut fresh = Distance3d::new(&ctx.device).unwrap();
        pooled.set_split_bytes(*split);
        fresh.set_split_bytes(*split);
        let mut enc = ctx.encoder("recycle");
        let old = pooled
            .encode(&ctx.device, &mut enc, &first, options)
            .unwrap();
        ctx.submit_and_wait("recycle", enc).unwrap();
        let old_bits = bits(&old);
        let mut given: Vec<wgpu::Buffer> = old.nearest.buffers.clone();
        given.extend(old.nearest_outside.iter().flat_map(|s| s.buffers.clone()));
        let old_texture = old.distance.clone();
        if split.is_some() {
            assert!(given.len() > 1, "{case}: not split");
        }
        pooled.recycle(old);
        let mut enc = ctx.encoder("recycle");
        let got = pooled
            .encode(&ctx.device, &mut enc, &second, options)
            .unwrap();
        let want = fresh
            .encode(&ctx.device, &mut enc, &second, options)
            .unwrap();
        ctx.submit_and_wait("recycle", enc).unwrap();
        let mut taken: Vec<wgpu::Buffer> = got.nearest.buffers.clone();
        taken.extend(got.nearest_outside.iter().flat_map(|s| s.buffers.clone()));
        // JFA also takes them for its seeds and ping-pong buffers, so its field holds some.
        let all = taken.iter().all(|b| given.contains(b)) && taken.len() == given.len();
        let some = taken.iter().any(|b| given.contains(b));
        assert!(
            if options.method == jfa { some } else { all },
            "{case}: the recycled buffers were not taken"
        );
        assert!(
            got.distance == old_texture,
            "{case}: the texture was not taken"
        );
        let (got_bits, want_bits) = (bits(&got), bits(&want));
        assert!(
            got_bits != old_bits,
            "{case}: the two seed sets give the same field"
        );
        assert!(got_bits.0 == want_bits.0, "{case}: nearest seeds differ");
        assert!(got_bits.1 == want_bits.1, "{case}: distances differ");
        // A field of another size takes nothing: new buffers, the same answers.
        let other = [size[0] - 1, size[1], size[2]];
        let third = upload(&random_mask_3d(other, 0.08, 33), other);
        pooled.recycle(got);
        let mut enc = ctx.encoder("recycle");
        let a = pooled
            .encode(&ctx.device, &mut enc, &third, options)
            .unwrap();
        let b = fresh
            .encode(&ctx.device, &mut enc, &third, options)
            .unwrap();
        ctx.submit_and_wait("recycle", enc).unwrap();
        assert!(
            !taken.iter().any(|t| a.nearest.buffers.contains(t)),
            "{case}"
        );
        assert!(bits(&a) == bits(&b), "{case}: another size");
    }
    // Sub-voxel seeds: the seed buffer taken from a field of many points must be cleared, or
    // those points would seed the next field of few.
    let grid = Grid::new(size_u32(size));
    let points = |n: usize, salt: u64| {
        let mut x = salt;
        let mut next = move || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let world: Vec<Vec3> = (0..n)
            .map(|_| Vec3::new(next() * 40.0, next() * 33.0, next() * 21.0))
            .collect();
        upload_points(&ctx.device, &ctx.queue, &grid, &world).unwrap()
    };
    let (many, few) = (points(300, 1), points(4, 2));
    let options = Settings3d {
        method: jfa,
        ..Settings3d::default()
    };
    let pooled = Distance3d::new(&ctx.device).unwrap();
    let fresh = Distance3d::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("recycle points");
    let old = pooled
        .encode_points(&ctx.device, &mut enc, &many, grid.size, None, &options)
        .unwrap();
    ctx.submit_and_wait("recycle points", enc).unwrap();
    pooled.recycle(old);
    let mut enc = ctx.encoder("recycle points");
    let got = pooled
        .encode_points(&ctx.device, &mut enc, &few, grid.size, None, &options)
        .unwrap();
    let want = fresh
        .encode_points(&ctx.device, &mut enc, &few, grid.size, None, &options)
        .unwrap();
    ctx.submit_and_wait("recycle points", enc).unwrap();
    assert!(bits(&got) == bits(&want), "points: the fields differ");

    // 2D: the exact transform's field, recycled with `recycle_2d`.
    let (w, h) = (97usize, 61usize);
    let textures = [(0.002, 41), (0.05, 42)].map(|(density, seed)| {
        let m = random_mask(w, h, density, seed);
        upload_mask(&ctx.device, &ctx.queue, &to_bytes(&m), w as u32, h as u32).unwrap()
    });
    let pooled = Distance3d::new(&ctx.device).unwrap();
    let fresh = Distance3d::new(&ctx.device).unwrap();
    let signed = Settings3d::signed();
    let bits_2d = |f: &fieldkit::distance::FieldBuf2d| {
        let mut words = read_buffer(&ctx, &f.nearest).unwrap();
        words.extend(read_buffer(&ctx, f.nearest_outside.as_ref().unwrap()).unwrap());
        (words, read_texture::<u32>(&ctx, &f.distance).unwrap())
    };
    let mut enc = ctx.encoder("recycle 2d");
    let old = pooled
        .exact()
        .encode_exact_2d(&ctx.device, &mut enc, &textures[0], &signed)
        .unwrap();
    ctx.submit_and_wait("recycle 2d", enc).unwrap();
    let given = old.nearest.clone();
    pooled.recycle_2d(old);
    let mut enc = ctx.encoder("recycle 2d");
    let got = pooled
        .exact()
        .encode_exact_2d(&ctx.device, &mut enc, &textures[1], &signed)
        .unwrap();
    let want = fresh
        .exact()
        .encode_exact_2d(&ctx.device, &mut enc, &textures[1], &signed)
        .unwrap();
    ctx.submit_and_wait("recycle 2d", enc).unwrap();
    assert!(
        got.nearest == given || got.nearest_outside.as_ref() == Some(&given),
        "2D: the recycled buffer was not taken"
    );
    assert!(bits_2d(&got) == bits_2d(&want), "2D: the fields differ");
}
