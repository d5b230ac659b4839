//! Conservative surface voxelization (`voxelize/surface`) against the 13-axis SAT in f64
//! (`fieldkit::voxelize::cpu`), and the failure modes of the issue, each a test.

use crate::common;

use common::voxelize::*;
use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer, cpu};
use glam::DVec3;

#[test]
fn sphere_matches_the_sat_reference() {
    let ctx = Context::shared();
    let sphere = Mesh::uv_sphere(DVec3::new(16.3, 15.7, 16.1), 11.37, 48, 24);
    let (misses, extras, local) = compare(&ctx, &sphere, &unit_grid([32, 32, 32]));
    println!(
        "{} triangles: {misses} missed, {extras} extra",
        local.vertices.len() / 3
    );
    assert_eq!(misses, 0);
}

/// Failure modes: no voxel the SAT finds may be missed.
#[test]
fn failure_modes_miss_nothing() {
    let ctx = Context::shared();
    for (name, m, grid) in failure_cases() {
        let (misses, extras, local) = compare(&ctx, &m, &grid);
        println!("{name}: {misses} missed, {extras} extra");
        assert_eq!(misses, 0, "{name}");
        if name == "larger than the grid" || name == "more than 1024 voxels along x" {
            // These have heavy triangles: chunks listed by the host (`surface_listed`).
            assert!(
                fieldkit::voxelize::heavy_chunk_bound(&local, grid.size) > 0,
                "{name}"
            );
        }
        if name == "on a voxel face" {
            // The reference itself: closed boxes on both sides of the plane z = 5.
            let want = cpu::conservative(&local, grid.size);
            let layer = |z: usize| want[z * 144..(z + 1) * 144].iter().filter(|&&o| o).count();
            assert!(
                layer(4) > 10 && layer(4) == layer(5),
                "layers {} and {}",
                layer(4),
                layer(5)
            );
            assert_eq!(layer(3) + layer(6), 0);
        }
    }
}

/// 100 km from the origin (cuda_voxelizer's issues #7 and #61 come from voxelizing in world f32):
/// the mesh moves into grid-local coordinates in f64 first, so it voxelizes exactly as at the
/// origin.
#[test]
fn far_from_the_origin_is_the_same_as_at_it() {
    let ctx = Context::shared();
    let far = DVec3::new(1.0e5, -3.0e4, 7.0e4);
    let near = Mesh::uv_sphere(DVec3::new(8.3, 7.9, 8.2), 5.4, 24, 12);
    let moved = Mesh {
        positions: near.positions.iter().map(|p| *p * 0.25 + far).collect(),
        triangles: near.triangles.clone(),
        ..Mesh::default()
    };
    let v = Voxelizer::new(&ctx.device).unwrap();
    let run = |m: &Mesh, grid: &Grid| {
        let mut enc = ctx.encoder("voxelize");
        let s = v.encode_surface(&ctx.device, &mut enc, m, grid).unwrap();
        ctx.submit_and_wait("voxelize", enc).unwrap();
        s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap()
    };
    let a = run(&near, &unit_grid([16, 16, 16]));
    let b = run(
        &moved,
        &Grid {
            origin: far,
            voxel: 0.25,
            size: [16, 16, 16],
        },
    );
    assert!(a.iter().filter(|&&o| o).count() > 100);
    assert_eq!(a, b);
}

#[test]
fn zero_area_triangles_are_left_out_and_counted() {
    let ctx = Context::shared();
    let d = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let m = mesh(
        vec![
            d(1.0, 1.0, 1.0),
            d(5.0, 5.0, 5.0),
            d(9.0, 9.0, 9.0),
            d(2.0, 7.0, 3.0),
        ],
        vec![[0, 1, 2], [0, 0, 3], [0, 1, 3]],
    );
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v
        .encode_surface(&ctx.device, &mut enc, &m, &unit_grid([12, 12, 12]))
        .unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    assert_eq!(s.degenerate, 2);
    assert!(
        s.read(&ctx.device, &ctx.queue)
            .wait(&ctx)
            .unwrap()
            .iter()
            .any(|&o| o)
    );
}

#[test]
fn bad_input_gets_typed_errors() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let tri = |p: Vec<DVec3>| mesh(p, vec![[0, 1, 2]]);
    let ok = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let g = unit_grid([8, 8, 8]);
    let cases: Vec<(&str, Mesh, Grid)> = vec![
        ("empty mesh", Mesh::default(), g),
        (
            "NaN vertex",
            tri(vec![DVec3::ZERO, DVec3::NAN, DVec3::Y]),
            g,
        ),
        ("index out of range", mesh(ok.clone(), vec![[0, 1, 3]]), g),
        ("zero grid side", tri(ok.clone()), unit_grid([8, 0, 8])),
        (
            "grid past the limit",
            tri(ok.clone()),
            unit_grid([8, 8, 5000]),
        ),
        ("zero voxel", tri(ok.clone()), Grid { voxel: 0.0, ..g }),
        (
            "NaN origin",
            tri(ok.clone()),
            Grid {
                origin: DVec3::NAN,
                ..g
            },
        ),
        (
            "bitset past the binding limit",
            tri(ok.clone()),
            unit_grid([4096, 4096, 512]),
        ),
    ];
    for (name, m, grid) in cases {
        let mut enc = ctx.encoder("bad");
        let err = v
            .encode_surface(&ctx.device, &mut enc, &m, &grid)
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted"));
        assert!(
            matches!(err, Error::Invalid { .. } | Error::Size { .. }),
            "{name}: {err:?}"
        );
    }
}

/// Signed distance to an analytic shape (negative inside).
type SignedDistance = Box<dyn Fn(DVec3) -> f64>;

/// The two thicknesses against flood fills from outside a closed sphere and torus: the
/// conservative voxels stop 26-connected floods, the six-separating ones stop 6-connected
/// floods, are a subset of the conservative ones, and let a 26-connected flood through (what
/// they are not made for).
#[test]
fn separation_holds_against_flood_fills() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let g = unit_grid([32, 32, 32]);
    let sphere_c = DVec3::new(16.3, 15.7, 16.1);
    let torus_c = DVec3::new(16.2, 15.9, 16.4);
    let shapes: Vec<(&str, Mesh, SignedDistance)> = vec![
        (
            "sphere",
            Mesh::uv_sphere(sphere_c, 11.37, 48, 24),
            Box::new(move |p: DVec3| (p - sphere_c).length() - 11.37),
        ),
        (
            "torus",
            Mesh::torus(torus_c, 10.2, 3.7, 64, 24),
            Box::new(move |p: DVec3| {
                let q = p - torus_c;
                let ring = (q.x * q.x + q.z * q.z).sqrt() - 10.2;
                (ring * ring + q.y * q.y).sqrt() - 3.7
            }),
        ),
    ];
    for (name, mesh, signed) in shapes {
        let run = |sep| {
            let mut enc = ctx.encoder("voxelize");
            let s = v
                .encode_surface_with(&ctx.device, &mut enc, &mesh, &g, sep)
                .unwrap();
            ctx.submit_and_wait("voxelize", enc).unwrap();
            s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap()
        };
        let thick = run(Separation::Conservative);
        let thin = run(Separation::Six);
        assert!(
            thin.iter().zip(&thick).all(|(&t, &k)| !t || k),
            "{name}: six-separating outside the conservative set"
        );
        let deep: Vec<usize> = (0..thick.len())
            .filter(|&i| {
                let p =
                    DVec3::new((i % 32) as f64, ((i / 32) % 32) as f64, (i / 1024) as f64) + 0.5;
                signed(p) < -1.5
            })
            .collect();
        let leaks = |occ: &[bool], k| {
            let reached = flood(occ, g.size, k);
            deep.iter().filter(|&&i| reached[i]).count()
        };
        let (n_thick, n_thin) = (
            thick.iter().filter(|&&o| o).count(),
            thin.iter().filter(|&&o| o).count(),
        );
        let (l26_thick, l6_thin, l26_thin) = (leaks(&thick, 26), leaks(&thin, 6), leaks(&thin, 26));
        println!(
            "{name}: conservative {n_thick} voxels, 26-flood reaches {l26_thick} of {} deep voxels; \
             six-separating {n_thin} voxels, 6-flood reaches {l6_thin}, 26-flood reaches {l26_thin}",
            deep.len()
        );
        assert!(!deep.is_empty());
        assert_eq!(
            l26_thick, 0,
            "{name}: a 26-connected flood got through the conservative surface"
        );
        assert_eq!(
            l6_thin, 0,
            "{name}: a 6-connected flood got through the six-separating surface"
        );
        assert!(n_thin < n_thick, "{name}: six-separating is not thinner");
        assert!(
            l26_thin > 0,
            "{name}: expected a 26-connected flood to leak through the thin surface"
        );
    }
}

/// The write-up's raster path (`voxelize/raster`) finds columns with enlarged triangles
/// instead of walking boxes; its fragments run the same exact tests, so it must give the
/// compute path's voxels bit for bit. A missed column (too little enlargement) shows as a
/// missing voxel.
#[test]
fn raster_path_gives_the_compute_voxels() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut cases = failure_cases();
    cases.push((
        "sphere",
        Mesh::uv_sphere(DVec3::new(16.3, 15.7, 16.1), 11.37, 48, 24),
        unit_grid([32, 32, 32]),
    ));
    cases.push((
        "torus",
        Mesh::torus(DVec3::new(12.1, 6.2, 11.9), 8.3, 3.1, 40, 16),
        unit_grid([25, 13, 24]),
    ));
    for (name, m, grid) in cases {
        let run = |raster: bool| {
            let mut enc = ctx.encoder("voxelize");
            let s = if raster {
                v.encode_surface_raster(&ctx.device, &mut enc, &m, &grid)
            } else {
                v.encode_surface(&ctx.device, &mut enc, &m, &grid)
            }
            .unwrap();
            ctx.submit_and_wait("voxelize", enc).unwrap();
            s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap()
        };
        let (compute, raster) = (run(false), run(true));
        let count = |v: &[bool]| v.iter().filter(|&&o| o).count();
        println!(
            "{name}: compute {} voxels, raster {}",
            count(&compute),
            count(&raster)
        );
        assert!(count(&compute) > 0, "{name}");
        assert!(
            compute == raster,
            "{name}: raster and compute voxels differ"
        );
    }
}

/// A bitset written by the caller becomes a `Surface`: it reads back voxel for voxel (bit
/// i % 32 of word i / 32, x fastest) and `encode_volume` turns it into the same mask; a
/// bitset too small for its size, or a side of 0, is a typed error.
#[test]
fn a_callers_bitset_is_a_surface() {
    use fieldkit::voxelize::Surface;
    use wgpu::util::DeviceExt;
    let ctx = Context::shared();
    let size = [5u32, 3, 4];
    let voxels = 5usize * 3 * 4;
    let want: Vec<bool> = (0..voxels).map(|i| i % 7 == 2 || i == voxels - 1).collect();
    let mut words = vec![0u32; voxels.div_ceil(32)];
    for (i, _) in want.iter().enumerate().filter(|(_, b)| **b) {
        words[i / 32] |= 1 << (i % 32);
    }
    let bits = |words: &[u32]| {
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("caller's bits"),
                contents: bytemuck::cast_slice(words),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            })
    };
    let surface = Surface::from_bits(size, bits(&words)).unwrap();
    let read = surface.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    assert_eq!(read, want);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("volume");
    let volume = v.encode_volume(&ctx.device, &mut enc, &surface).unwrap();
    ctx.submit_and_wait("volume", enc).unwrap();
    let mask: Vec<f32> = fieldkit::gpu::read_texture(&ctx, &volume).unwrap();
    assert_eq!(
        mask,
        want.iter().map(|&b| b as u8 as f32).collect::<Vec<_>>()
    );
    let short = Surface::from_bits([8, 8, 8], bits(&words)).err();
    assert!(
        matches!(&short, Some(Error::Invalid { what, .. }) if what.contains("need 64")),
        "{short:?}"
    );
    assert!(matches!(
        Surface::from_bits([0, 3, 4], bits(&words)),
        Err(Error::Invalid { .. })
    ));
}
