//! Metaball field stages against CPU references: the fixed-point splat, the iso-surface seeds,
//! and the signed distance of one blob against its analytic sphere.

use crate::common;

use common::metaball::run_stage;
use common::*;
use fieldkit::distance::Variant;
use fieldkit::distance::{Grid, Method};
use fieldkit::gpu::Context;
use fieldkit::gpu::{read_buffer, read_texture};
use fieldkit::metaball::{Metaballs, Settings, cpu, fixed_scale, packed_grid};
use glam::{Vec3, Vec4};

fn words(ctx: &fieldkit::gpu::Context, b: &wgpu::Buffer) -> Vec<u32> {
    bytemuck::cast_slice::<u8, u32>(&read_buffer(ctx, b).unwrap()).to_vec()
}

fn three_blobs() -> Vec<Vec4> {
    vec![
        Vec4::new(0.0, 0.0, 0.0, 1.0),
        Vec4::new(0.9, 0.2, -0.1, 0.7),
        Vec4::new(-0.3, 1.1, 0.4, 1.3),
    ]
}

/// Splat and seeds alone, on the fitted grid.
/// The three blobs, at 6 cells per edge.
fn three_blobs_at_6() -> (Vec<Vec4>, Settings) {
    let settings = Settings {
        cells_per_edge: 6.0,
        ..Settings::default()
    };
    (three_blobs(), settings)
}

fn seed_stages(
    ctx: &fieldkit::gpu::Context,
    voxels: &[Vec4],
    settings: &Settings,
) -> (Grid, fieldkit::metaball::SurfaceSeeds) {
    let grid = settings.fit_grid(voxels, 1.0).unwrap().unwrap();
    let seeds = run_stage(ctx, voxels, |balls, enc, inst| {
        balls.encode_seeds(&ctx.device, enc, inst, &grid, 1.0, settings)
    });
    (grid, seeds)
}

#[test]
fn splat_matches_the_cpu_sums() {
    let ctx = Context::shared();
    let (voxels, settings) = three_blobs_at_6();
    let (grid, seeds) = seed_stages(&ctx, &voxels, &settings);
    let gpu = words(&ctx, &seeds.density_fixed);
    let (cpu_sum, count) = cpu::splat_fixed(&voxels, 1.0, &settings, &grid, seeds.fixed_scale);
    let mut off = 0;
    let mut touched = 0;
    for i in 0..gpu.len() {
        // Each contribution is rounded from an f32 falloff on the GPU and an f64 one here: they
        // may fall on either side of a rounding boundary, one unit apart, never more.
        let diff = (gpu[i] as i64 - cpu_sum[i] as i64).unsigned_abs();
        assert!(
            diff <= count[i] as u64,
            "voxel {i}: GPU {} CPU {} with {} contributions",
            gpu[i],
            cpu_sum[i],
            count[i]
        );
        off += (diff > 0) as usize;
        touched += (count[i] > 0) as usize;
    }
    println!("splat: {touched} voxels touched, {off} one unit off");
    assert!(touched > 1000, "the blobs cover the grid's middle");
    // Zero where no instance reaches, exactly.
    assert!(gpu.iter().zip(&count).all(|(&g, &c)| c > 0 || g == 0));
}

#[test]
fn fixed_point_scale_keeps_sums_in_u32() {
    assert_eq!(fixed_scale(1), 10000.0);
    assert_eq!(fixed_scale(429_496), 10000.0);
    let s = fixed_scale(1_000_000);
    assert!(s < 10000.0 && s * 1.0e6 <= u32::MAX as f32, "{s}");
    // A huge scale covers the whole grid with density ≈ 1 per instance: the sum saturates at
    // count × scale, not wrapping.
    let ctx = Context::shared();
    let voxels = vec![Vec4::new(0.0, 0.0, 0.0, 1.0), Vec4::new(0.2, 0.0, 0.0, 1e4)];
    let settings = Settings::default();
    let grid = Grid {
        size: [8, 8, 8],
        voxel: 0.25,
        origin: glam::DVec3::splat(-1.0),
    };
    let seeds = run_stage(&ctx, &voxels, |balls, enc, inst| {
        balls.encode_seeds(&ctx.device, enc, inst, &grid, 1.0, &settings)
    });
    let gpu = words(&ctx, &seeds.density_fixed);
    let max = *gpu.iter().max().unwrap();
    assert!(
        max <= 20000,
        "two instances sum to at most 2 × scale, got {max}"
    );
    assert!(
        gpu.iter().all(|&g| g >= 9990),
        "the huge blob reaches every voxel at ≈ 1"
    );
}

#[test]
fn seeds_are_the_boundary_voxels_moved_onto_the_surface() {
    let ctx = Context::shared();
    let (voxels, settings) = three_blobs_at_6();
    let (grid, seeds) = seed_stages(&ctx, &voxels, &settings);
    let fixed = words(&ctx, &seeds.density_fixed);
    let keys = words(&ctx, &seeds.keys);
    let points: Vec<[f32; 4]> =
        bytemuck::cast_slice(&read_buffer(&ctx, &seeds.points).unwrap()).to_vec();
    let dens: Vec<f32> = read_texture(&ctx, &seeds.density).unwrap();
    let [w, h, d] = grid.size.map(|s| s as i64);
    let rho = |x: i64, y: i64, z: i64| -> f64 {
        if x < 0 || y < 0 || z < 0 || x >= w || y >= h || z >= d {
            0.0
        } else {
            fixed[((z * h + y) * w + x) as usize] as f64 / seeds.fixed_scale as f64
        }
    };
    let t = settings.threshold as f64;
    let mut n_seeds = 0;
    let mut max_residual: f64 = 0.0;
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let i = ((z * h + y) * w + x) as usize;
                assert!(
                    (dens[i] as f64 - rho(x, y, z)).abs() < 1e-6,
                    "density texture at {i}"
                );
                let nb = [
                    rho(x - 1, y, z),
                    rho(x + 1, y, z),
                    rho(x, y - 1, z),
                    rho(x, y + 1, z),
                    rho(x, y, z - 1),
                    rho(x, y, z + 1),
                ];
                let seed = rho(x, y, z) >= t && nb.iter().any(|&n| n < t);
                // Integer decision from the same integers: compared exactly.
                assert_eq!(keys[i] != 0, seed, "voxel ({x},{y},{z})");
                if seed {
                    n_seeds += 1;
                    assert_eq!(fieldkit::distance::key_index(keys[i]), Some(i as u32));
                    let p = points[i];
                    let off = Vec3::new(p[0] - x as f32, p[1] - y as f32, p[2] - z as f32);
                    assert!(off.length() <= 0.8661, "offset {off} of voxel {i}");
                    // The point should sit near the analytic iso-surface.
                    let world = grid.origin
                        + (glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) + 0.5)
                            * grid.voxel;
                    let r = cpu::density_at(&voxels, 1.0, &settings, world) - t;
                    let g = cpu::gradient_at(&voxels, 1.0, &settings, world).length();
                    max_residual = max_residual.max((r / g).abs() / grid.voxel);
                }
            }
        }
    }
    println!("seeds: {n_seeds}, max distance to the analytic surface ≈ {max_residual:.3} cells");
    assert!(n_seeds > 100);
    // Measured 0.213 cells on llvmpipe at 6 cells per voxel edge (one Newton step on central
    // differences of a coarse grid).
    assert!(max_residual < 0.25, "{max_residual}");
}

#[test]
fn sdf_of_one_blob_is_its_sphere() {
    // Measured on llvmpipe: line passes max 0.613, RMS 0.129 cells; JFA+2 max 0.613, RMS 0.099.
    // The distance is to the nearest seed point, and the points lie about a cell apart on the
    // surface, so a voxel on the surface between two of them reads up to about half that
    // spacing; the seeds' own error adds to it, and the line passes keep a seed up to half a
    // cell farther than the nearest away from it (tests/distance/points_3d.rs).
    for (method, rms_bound) in [
        (Method::Lines, 0.14),
        (Method::Jfa(Variant::JfaPlus2), 0.11),
    ] {
        let settings = Settings {
            cells_per_edge: 16.0,
            method,
            ..Settings::default()
        };
        let (max_err, rms) = one_blob_error(&settings);
        println!("one blob, {method:?}: max SDF error {max_err:.3} cells, RMS {rms:.3}");
        assert!(
            max_err < 0.7 && rms < rms_bound,
            "{method:?}: max {max_err} rms {rms}"
        );
    }
}

/// Largest and RMS error (cells) of one blob's SDF against its sphere, within the band.
fn one_blob_error(settings: &Settings) -> (f64, f64) {
    let ctx = Context::shared();
    let voxels = vec![Vec4::new(0.013, -0.021, 0.034, 1.0)];
    let field = metaball_field(&ctx, &voxels, 1.0, settings);
    let sdf: Vec<f32> = read_texture(&ctx, &field.sdf).unwrap();
    let dens: Vec<f32> = read_texture(&ctx, &field.density).unwrap();
    let g = field.grid;
    let r_iso = cpu::blob_iso_radius(settings.radius(1.0, 1.0) as f64, 0.5);
    let centre = voxels[0].truncate().as_dvec3();
    let [w, h, d] = g.size;
    let (mut max_err, mut sum2, mut n) = (0.0f64, 0.0f64, 0usize);
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let i = ((z * h + y) * w + x) as usize;
                let c = g.voxel_centre([x, y, z]);
                let exact = (c - centre).length() - r_iso;
                assert_eq!(sdf[i] < 0.0, dens[i] >= 0.5, "sign at {i}");
                if exact.abs() < 0.75 * field.band as f64 {
                    let err = (sdf[i] as f64 - exact).abs() / g.voxel;
                    max_err = max_err.max(err);
                    sum2 += err * err;
                    n += 1;
                } else if exact > field.band as f64 * 1.5 {
                    // Beyond the band: clamped, a safe step for the raymarcher.
                    assert_eq!(sdf[i], field.band, "clamp at {i}");
                }
            }
        }
    }
    (max_err, (sum2 / n as f64).sqrt())
}

fn err<T>(r: Result<T, fieldkit::Error>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let ctx = Context::shared();
    let balls = Metaballs::new(&ctx.device).unwrap();
    let s = Settings::default();
    let nan = [Vec4::new(f32::NAN, 0.0, 0.0, 1.0)];
    assert!(err(balls.upload(&ctx.device, &ctx.queue, &nan)).contains("voxel 0"));
    let neg = [Vec4::new(0.0, 0.0, 0.0, -1.0)];
    assert!(err(balls.upload(&ctx.device, &ctx.queue, &neg)).contains("scale"));
    assert!(err(s.fit_grid(&three_blobs(), 0.0)).contains("edge"));
    let bad = Settings {
        threshold: f32::NAN,
        ..s
    };
    assert!(err(bad.fit_grid(&three_blobs(), 1.0)).contains("threshold"));
    let exact = Settings {
        method: Method::Exact,
        ..s
    };
    assert!(err(exact.fit_grid(&three_blobs(), 1.0)).contains("integer seeds"));
    // Past the 11/11/10-bit seed packing: a grid too large.
    let far = [
        Vec4::new(0.0, 0.0, 0.0, 1.0),
        Vec4::new(1000.0, 0.0, 0.0, 1.0),
    ];
    assert!(err(s.fit_grid(&far, 1.0)).contains("grid width"));
    // A caller-made grid past the seed table.
    let mut inst = balls
        .upload(&ctx.device, &ctx.queue, &three_blobs())
        .unwrap();
    let grid = Grid {
        size: [300, 300, 300],
        voxel: 0.1,
        origin: glam::DVec3::ZERO,
    };
    let mut enc = ctx.encoder("bad");
    assert!(err(balls.encode(&ctx.device, &mut enc, &inst, &grid, 1.0, &s)).contains("grid cells"));
    // Updating with another count.
    assert!(
        err(balls.update(&ctx.queue, &mut inst, &packed_grid([2, 2, 2], 1.0).unwrap()))
            .contains("voxels given")
    );
    // Empty and all-zero sets fit no grid: nothing to draw.
    assert!(s.fit_grid(&[], 1.0).unwrap().is_none());
    assert!(
        s.fit_grid(&[Vec4::new(0.0, 0.0, 0.0, 0.0)], 1.0)
            .unwrap()
            .is_none()
    );
}

#[test]
fn packed_grid_is_centred() {
    let v = packed_grid([3, 2, 1], 2.0).unwrap();
    assert_eq!(v.len(), 6);
    let mean = v.iter().map(|p| p.truncate()).sum::<Vec3>() / 6.0;
    assert!(mean.length() < 1e-6);
    assert_eq!(v[0], Vec4::new(-2.0, -1.0, 0.0, 1.0));
    assert_eq!(v[5], Vec4::new(2.0, 1.0, 0.0, 1.0));
}

/// The blob bins of direct tracing: starts are an exclusive scan of the lists, every blob whose
/// support reaches a bin is in that bin's list (what the tracers rely on), no list holds a blob
/// whose support box misses the bin, and the global bound is the largest bin sum of 1.717/R.
#[test]
fn blob_bins_hold_every_blob_that_reaches_them() {
    let ctx = Context::shared();
    let s = Settings::default();
    // Scales from 0 (skipped) to 1.3, centres off the lattice.
    let voxels: Vec<Vec4> = packed_grid([4, 3, 3], 1.0)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let k = i as f32;
            Vec4::new(
                v.x + 0.31 * (k * 1.7).sin(),
                v.y + 0.27 * (k * 2.3).cos(),
                v.z + 0.19 * (k * 0.9).sin(),
                if i % 7 == 3 {
                    0.0
                } else {
                    0.4 + 0.9 * ((k * 0.61).sin() * 0.5 + 0.5)
                },
            )
        })
        .collect();
    let grid = s.fit_grid(&voxels, 1.0).unwrap().unwrap();
    let bins = run_stage(&ctx, &voxels, |balls, enc, inst| {
        balls.encode_bins(&ctx.device, enc, inst, &grid, 1.0, &s)
    });
    let max_r = s.radius(1.0, voxels.iter().map(|v| v.w).fold(0.0, f32::max));
    assert_eq!(bins.bin_size, max_r, "bins are one largest radius wide");
    let starts = words(&ctx, &bins.starts);
    let items: Vec<Vec4> = bytemuck::cast_slice(&read_buffer(&ctx, &bins.items).unwrap()).to_vec();
    let stats = words(&ctx, &bins.stats);
    let [nx, ny, nz] = bins.bins;
    let n = (nx * ny * nz) as usize;
    assert_eq!(starts.len(), n + 1);
    assert!(starts.windows(2).all(|w| w[0] <= w[1]), "starts are a scan");
    let mut most_slope = 0.0f64;
    let mut most_count = 0;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let b = ((z * ny + y) * nx + x) as usize;
                let list = &items[starts[b] as usize..starts[b + 1] as usize];
                let lo = bins.origin + Vec3::new(x as f32, y as f32, z as f32) * bins.bin_size;
                let hi = lo + Vec3::splat(bins.bin_size);
                for v in voxels.iter().filter(|v| v.w > 0.0) {
                    let r = s.radius(1.0, v.w);
                    let c = v.truncate();
                    // Sphere against box, with a margin either way for f32 rounding.
                    let gap = (c.clamp(lo, hi) - c).length();
                    let listed = list.iter().any(|e| e.truncate() == c && e.w == r);
                    if gap < r - 1e-4 {
                        assert!(listed, "bin {x},{y},{z} misses the blob at {c} (r {r})");
                    }
                    let box_gap = (c - r - hi).max(lo - (c + r)).max_element();
                    if box_gap > 1e-4 {
                        assert!(
                            !listed,
                            "bin {x},{y},{z} lists the blob at {c} it cannot reach"
                        );
                    }
                }
                most_count = most_count.max(list.len() as u32);
                most_slope = most_slope.max(list.iter().map(|e| 1.7173148 / e.w as f64).sum());
            }
        }
    }
    assert_eq!(stats[0], most_count);
    let bound = f32::from_bits(stats[1]) as f64;
    assert!(
        (bound - most_slope).abs() < 1e-5 * most_slope,
        "{bound} vs {most_slope}"
    );
}

/// A `Metaballs` rebuilding its field every frame on one grid keeps what it builds with: a
/// field dropped before the next `encode` gives its textures and buffers back, one still held
/// is never written again (the next field gets its own), and a field built into kept
/// resources equals, bit for bit, the one a new `Metaballs` builds.
#[test]
fn an_animated_field_on_one_grid_reuses_what_was_dropped() {
    use fieldkit::metaball::Animation;
    let ctx = Context::shared();
    let settings = Settings::default();
    let base = three_blobs();
    let animation = Animation::default();
    let grid = settings
        .fit_grid(&animation.envelope(&base, 1.0), 1.0)
        .unwrap()
        .unwrap();
    let balls = Metaballs::new(&ctx.device).unwrap();
    let frame = |t: f32| animation.apply(&base, 1.0, t).unwrap();
    let mut inst = balls.upload(&ctx.device, &ctx.queue, &frame(0.0)).unwrap();
    let build = |balls: &Metaballs, inst: &fieldkit::metaball::Instances| {
        let mut enc = ctx.encoder("field");
        let f = balls
            .encode(&ctx.device, &mut enc, inst, &grid, 1.0, &settings)
            .unwrap();
        ctx.submit_and_wait("field", enc).unwrap();
        f
    };
    let first = build(&balls, &inst);
    let held = build(&balls, &inst);
    assert!(
        held.sdf != first.sdf && held.march != first.march,
        "a held field was written"
    );
    let textures = (
        first.sdf.clone(),
        first.march.clone(),
        first.nearest.clone(),
    );
    drop((first, held));
    balls.update(&ctx.queue, &mut inst, &frame(0.7)).unwrap();
    let again = build(&balls, &inst);
    assert!(
        [again.sdf.clone(), again.march.clone()]
            .iter()
            .any(|t| *t == textures.0 || *t == textures.1)
            || again.nearest == textures.2,
        "a dropped field's resources were not taken back"
    );
    // A new Metaballs, new resources: the same field.
    let fresh_balls = Metaballs::new(&ctx.device).unwrap();
    let fresh_inst = fresh_balls
        .upload(&ctx.device, &ctx.queue, &frame(0.7))
        .unwrap();
    let fresh = build(&fresh_balls, &fresh_inst);
    let sdf = |f: &fieldkit::metaball::MetaballField| read_texture::<f32>(&ctx, &f.sdf).unwrap();
    let march =
        |f: &fieldkit::metaball::MetaballField| read_texture::<[u16; 4]>(&ctx, &f.march).unwrap();
    assert!(
        sdf(&again) == sdf(&fresh),
        "the kept field's distances differ"
    );
    assert!(
        march(&again) == march(&fresh),
        "the kept field's march volume differs"
    );
    assert_eq!(words(&ctx, &again.nearest), words(&ctx, &fresh.nearest));
}

/// `Animation::envelope` bounds every frame: on the grid fitted to it, every frame's blobs
/// reach no farther than their supports, with the cell of margin `fit_grid` leaves.
#[test]
fn the_animation_envelope_holds_every_frame() {
    use fieldkit::metaball::Animation;
    use glam::DVec3;
    let settings = Settings::default();
    let base = packed_grid([4, 3, 2], 1.0).unwrap();
    for animation in [Animation::default(), Animation::seed()] {
        let outer = settings
            .fit_grid(&animation.envelope(&base, 1.0), 1.0)
            .unwrap()
            .unwrap();
        let top = outer.origin + DVec3::from_array(outer.size.map(f64::from)) * outer.voxel;
        for k in 0..50 {
            let t = k as f32 * 0.173;
            for v in animation.apply(&base, 1.0, t).unwrap() {
                let r = settings.radius(1.0, v.w) as f64 + outer.voxel;
                let c = v.truncate().as_dvec3();
                assert!(
                    (c - r).cmpge(outer.origin - 1e-5).all() && (c + r).cmple(top + 1e-5).all(),
                    "{animation:?} at t = {t}: a blob at {c} reaching {r} leaves {outer:?}"
                );
            }
        }
    }
}
