//! Conservative surface voxelization (`voxelize/surface`) against the 13-axis SAT in f64
//! (`fieldkit::voxelize::cpu`), and the failure modes of the issue, each a test.

mod common;

use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::voxelize::{Grid, GridMesh, Mesh, Separation, Voxelizer, cpu};
use glam::{DVec3, Vec4};

/// GPU and CPU voxels: (misses, extras); every extra must overlap the triangle within `margin`
/// voxels (the GPU's rounding slack).
fn compare(ctx: &Context, mesh: &Mesh, grid: &Grid) -> (usize, usize, GridMesh) {
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, mesh, grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    check_against_sat(&gpu, mesh, grid)
}

/// [`compare`] for voxels the GPU already gave.
fn check_against_sat(gpu: &[bool], mesh: &Mesh, grid: &Grid) -> (usize, usize, GridMesh) {
    let local = mesh.to_grid(grid).unwrap();
    let want = cpu::conservative(&local, grid.size);
    let [nx, ny, _] = grid.size.map(|n| n as usize);
    let (mut misses, mut extras) = (0, 0);
    for (i, (&g, &w)) in gpu.iter().zip(&want).enumerate() {
        if w && !g {
            misses += 1;
        }
        if g && !w {
            extras += 1;
            let p = DVec3::new(
                (i % nx) as f64,
                ((i / nx) % ny) as f64,
                (i / (nx * ny)) as f64,
            );
            let near = local.vertices.chunks(3).any(|t| {
                let [a, b, c] = [t[0], t[1], t[2]].map(|q: Vec4| q.truncate().as_dvec3());
                cpu::overlaps_box(a, b, c, p + DVec3::splat(0.5), DVec3::splat(0.5 + 1e-3))
            });
            assert!(
                near,
                "extra voxel {p} is not within 1e-3 voxels of any triangle"
            );
        }
    }
    (misses, extras, local)
}

fn mesh(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        positions,
        triangles,
        ..Mesh::default()
    }
}

fn unit_grid(size: [u32; 3]) -> Grid {
    Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size,
    }
}

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

/// The failure modes, each in a small grid.
fn failure_cases() -> Vec<(&'static str, Mesh, Grid)> {
    let g = unit_grid([12, 12, 12]);
    let d = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    vec![
        // Lying exactly in the plane z = 5: both layers z = 4 and z = 5 touch it.
        (
            "on a voxel face",
            mesh(
                vec![d(1.2, 1.3, 5.0), d(9.7, 2.1, 5.0), d(4.4, 10.6, 5.0)],
                vec![[0, 1, 2]],
            ),
            g,
        ),
        (
            "vertices on voxel corners",
            mesh(
                vec![d(2.0, 2.0, 2.0), d(9.0, 3.0, 4.0), d(3.0, 8.0, 7.0)],
                vec![[0, 1, 2]],
            ),
            g,
        ),
        // Edge-on to z: its xy projection is a segment.
        (
            "edge-on",
            mesh(
                vec![d(1.5, 1.5, 1.2), d(9.5, 7.5, 1.2), d(1.5, 1.5, 10.7)],
                vec![[0, 1, 2]],
            ),
            g,
        ),
        (
            "sliver, aspect 1e4",
            mesh(
                vec![d(0.5, 6.1, 6.2), d(11.5, 6.1, 6.2), d(6.0, 6.1011, 6.2007)],
                vec![[0, 1, 2]],
            ),
            g,
        ),
        (
            "larger than the grid",
            mesh(
                vec![d(-30.0, -20.0, 5.5), d(40.0, -10.0, 6.5), d(5.0, 50.0, 7.5)],
                vec![[0, 1, 2]],
            ),
            g,
        ),
        (
            "non-cubic grid",
            Mesh::uv_sphere(d(20.2, 7.9, 11.3), 6.8, 24, 12),
            unit_grid([40, 17, 23]),
        ),
        (
            "more than 1024 voxels along x",
            mesh(
                vec![d(0.3, 0.4, 0.6), d(1099.6, 2.7, 1.1), d(550.0, 3.6, 3.9)],
                vec![[0, 1, 2]],
            ),
            unit_grid([1100, 4, 4]),
        ),
    ]
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

/// Voxels reached from the grid's boundary through empty voxels, with 6 or 26 neighbours.
fn flood(occupied: &[bool], size: [u32; 3], neighbours: usize) -> Vec<bool> {
    let [nx, ny, nz] = size.map(|n| n as i64);
    let index = |x: i64, y: i64, z: i64| ((z * ny + y) * nx + x) as usize;
    let mut seen = vec![false; occupied.len()];
    let mut stack = Vec::new();
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let edge = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
                if edge && !occupied[index(x, y, z)] {
                    seen[index(x, y, z)] = true;
                    stack.push((x, y, z));
                }
            }
        }
    }
    while let Some((x, y, z)) = stack.pop() {
        for dz in -1..=1i64 {
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let steps = dx.abs() + dy.abs() + dz.abs();
                    if steps == 0 || (neighbours == 6 && steps > 1) {
                        continue;
                    }
                    let (a, b, c) = (x + dx, y + dy, z + dz);
                    if a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz {
                        continue;
                    }
                    let i = index(a, b, c);
                    if !seen[i] && !occupied[i] {
                        seen[i] = true;
                        stack.push((a, b, c));
                    }
                }
            }
        }
    }
    seen
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

/// Several meshes placed by model matrices into one grid in one pass (issue 24, seed 004):
/// the surface is the union of each mesh voxelized alone, placed by hand (positions moved in
/// this test, not by `Mesh::transformed`); a mirroring matrix keeps the triangles facing out.
#[test]
fn placed_meshes_voxelize_into_one_grid() {
    use glam::DMat4;
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let torus = Mesh::torus(DVec3::ZERO, 1.0, 0.35, 24, 12);
    let ball = Mesh::uv_sphere(DVec3::ZERO, 0.6, 16, 8);
    let a = DMat4::from_translation(DVec3::new(-1.0, 0.2, 0.0)) * DMat4::from_rotation_x(0.9);
    let b = DMat4::from_translation(DVec3::new(1.4, -0.3, 0.4))
        * DMat4::from_scale(DVec3::new(1.5, 0.8, 1.0));
    let by_hand = |m: &Mesh, model: DMat4| Mesh {
        positions: m
            .positions
            .iter()
            .map(|&p| model.transform_point3(p))
            .collect(),
        ..m.clone()
    };
    let grid = Grid {
        origin: DVec3::new(-2.6, -1.6, -1.6),
        voxel: 0.1,
        size: [52, 32, 32],
    };
    let bits = |m: &Mesh| {
        let mut enc = ctx.encoder("placed");
        let s = v.encode_surface(&ctx.device, &mut enc, m, &grid).unwrap();
        ctx.submit_and_wait("placed", enc).unwrap();
        s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap()
    };
    let combined = Mesh::combined(&[(&torus, a), (&ball, b)]).unwrap();
    let both = bits(&combined);
    let (one, two) = (bits(&by_hand(&torus, a)), bits(&by_hand(&ball, b)));
    let union: Vec<bool> = one.iter().zip(&two).map(|(x, y)| *x || *y).collect();
    assert_eq!(both, union);
    let (n1, n2, n) = (
        one.iter().filter(|&&b| b).count(),
        two.iter().filter(|&&b| b).count(),
        both.iter().filter(|&&b| b).count(),
    );
    println!("placed: {n1} + {n2} voxels apart, {n} together");
    assert!(n1 > 500 && n2 > 300 && n >= n1.max(n2));
    // A mirror keeps the signed volume positive (the triangles still face out).
    let cube = Mesh::cuboid(DVec3::ZERO, DVec3::ONE);
    let mirrored = cube
        .transformed(DMat4::from_scale(DVec3::new(-2.0, 1.0, 1.0)))
        .unwrap();
    assert!(
        (mirrored.volume() - 2.0).abs() < 1e-12,
        "{}",
        mirrored.volume()
    );
    assert!(
        cube.transformed(DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0)))
            .is_err()
    );
    assert!(
        cube.transformed(DMat4::from_scale(DVec3::splat(f64::NAN)))
            .is_err()
    );
}

/// A surface refilled in place (`encode_surface_placed_into`, for loops that voxelize every
/// frame): each frame's bits equal a new surface's for the same placement exactly. The frames
/// are chosen so that each thing the refill must do fails the test when left out: the meshes
/// move apart (a missing clear leaves stale voxels), a bar grows past the kept list (a list
/// not made again for it drops chunks), and a ball of heavy triangles follows the large bar (a
/// work list whose count is not reset puts the ball's chunks past the ball's own capacity,
/// where they are dropped: 1 657 voxels missing on llvmpipe); `degenerate` follows the parts.
/// A surface
/// of another size, a buffer too small or without `COPY_DST` are refused with a typed error
/// before anything is recorded, and the surface keeps its bits.
#[test]
fn a_surface_refilled_in_place_equals_a_new_one() {
    use fieldkit::voxelize::{GpuMesh, Surface};
    use glam::DMat4;
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut flat = Mesh::uv_sphere(DVec3::ZERO, 0.6, 16, 8);
    flat.triangles.push([0, 0, 1]);
    let ball = GpuMesh::upload(&ctx.device, &flat).unwrap();
    // Long thin boxes cross the grid, so their triangles go through the heavy work list.
    let bar = GpuMesh::upload(
        &ctx.device,
        &Mesh::cuboid(DVec3::new(-2.0, -0.1, -0.1), DVec3::new(2.0, 0.1, 0.1)),
    )
    .unwrap();
    let grid = Grid {
        origin: DVec3::splat(-2.4),
        voxel: 0.1,
        size: [48, 40, 36],
    };
    let read = |s: &Surface| s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let low = DMat4::from_translation(DVec3::new(0.0, -1.5, -1.0));
    // Stretched across the grid: a list more than four times the thin bar's.
    let thick = DMat4::from_scale(DVec3::new(1.0, 15.0, 15.0));
    let frames: [Vec<(&GpuMesh, DMat4)>; 9] = [
        vec![
            (&ball, DMat4::from_translation(DVec3::new(-1.2, 0.0, 0.0))),
            (&bar, DMat4::from_translation(DVec3::new(0.0, 1.0, 0.5))),
        ],
        vec![
            (&ball, DMat4::from_translation(DVec3::new(1.2, 0.5, -0.3))),
            (&bar, DMat4::from_rotation_z(1.2)),
        ],
        vec![],
        vec![(&bar, low)],
        vec![(&bar, low)],
        vec![(&bar, low)],
        vec![(&bar, thick)],
        vec![(&bar, thick)],
        vec![(&ball, DMat4::from_scale(DVec3::splat(2.5)))],
    ];
    let mut enc = ctx.encoder("refill");
    let mut kept = v
        .encode_surface_placed(
            &ctx.device,
            &mut enc,
            &frames[0],
            &grid,
            Separation::Conservative,
        )
        .unwrap();
    ctx.submit_and_wait("refill", enc).unwrap();
    let mut before = read(&kept);
    assert_eq!(kept.degenerate, 1);
    for (f, parts) in frames.iter().enumerate().skip(1) {
        let mut enc = ctx.encoder("refill");
        v.encode_surface_placed_into(
            &ctx.device,
            &mut enc,
            parts,
            &grid,
            Separation::Conservative,
            &mut kept,
        )
        .unwrap();
        let new = v
            .encode_surface_placed(
                &ctx.device,
                &mut enc,
                parts,
                &grid,
                Separation::Conservative,
            )
            .unwrap();
        ctx.submit_and_wait("refill", enc).unwrap();
        let (refilled, want) = (read(&kept), read(&new));
        let voxels = want.iter().filter(|&&b| b).count();
        let stale = before.iter().zip(&want).filter(|&(&b, &w)| b && !w).count();
        let missing = want
            .iter()
            .zip(&refilled)
            .filter(|&(&w, &r)| w && !r)
            .count();
        println!(
            "frame {f}: {voxels} voxels, {stale} of the frame before not in it, {missing} missing"
        );
        // The frames the clear is tested on must differ from the one before.
        assert!(!matches!(f, 1 | 2 | 6) || stale > 100, "frame {f}: {stale}");
        assert!(f == 2 || voxels > 500, "frame {f}: {voxels}");
        assert!(
            refilled == want,
            "frame {f}: the refilled surface differs from a new one"
        );
        assert_eq!(kept.degenerate, new.degenerate, "frame {f}");
        let has_ball = parts.iter().any(|p| std::ptr::eq(p.0, &ball));
        assert_eq!(kept.degenerate, usize::from(has_ball), "frame {f}");
        before = refilled;
    }
    // Refusals leave the surface as it was (the last frame's bar).
    let bad = |s: &mut Surface, g: &Grid, want: &str| {
        let mut enc = ctx.encoder("refill errors");
        let e = v
            .encode_surface_placed_into(
                &ctx.device,
                &mut enc,
                &frames[0],
                g,
                Separation::Conservative,
                s,
            )
            .expect_err("refused");
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains(want)),
            "{e}"
        );
        ctx.submit_and_wait("refill errors", enc).unwrap();
    };
    let other = Grid {
        size: [48, 40, 35],
        ..grid
    };
    bad(
        &mut kept,
        &other,
        "the surface to refill is [48, 40, 36] voxels, the grid [48, 40, 35]",
    );
    assert!(read(&kept) == before, "a refusal changed the surface");
    let buffer = |size, usage| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::STORAGE | usage,
            mapped_at_creation: false,
        })
    };
    let words = (48 * 40 * 36u64).div_ceil(32);
    kept.occupancy = buffer(4 * words - 4, wgpu::BufferUsages::COPY_DST);
    bad(
        &mut kept,
        &grid,
        &format!("buffer is {} bytes", 4 * words - 4),
    );
    kept.occupancy = buffer(4 * words, wgpu::BufferUsages::COPY_SRC);
    kept.degenerate = 7;
    bad(&mut kept, &grid, "refilling it needs");
    assert_eq!(kept.degenerate, 7);
}

/// Resident meshes moved by matrices on the GPU (issue 24, seed 004: "a per-mesh model matrix
/// so several meshes voxelize into one grid without re-uploading each"). Each mesh is uploaded
/// once; three frames move them (rotation, non-uniform scale, a mirror, and a cube stretched
/// across the grid whose triangles go through the heavy work list). Every frame's voxels miss
/// nothing against the f64 SAT reference of the meshes moved on the CPU (`Mesh::combined`),
/// and every extra voxel lies within 10⁻³ voxels of a triangle.
#[test]
fn resident_meshes_move_by_matrices_on_the_gpu() {
    use fieldkit::voxelize::GpuMesh;
    use glam::DMat4;
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let torus = Mesh::torus(DVec3::new(30.0, -20.0, 5.0), 1.0, 0.35, 24, 12);
    let ball = Mesh::uv_sphere(DVec3::ZERO, 0.6, 16, 8);
    let cube = Mesh::cuboid(DVec3::splat(-0.5), DVec3::splat(0.5));
    let gpu = [&torus, &ball, &cube].map(|m| GpuMesh::upload(&ctx.device, m).unwrap());
    assert_eq!(gpu[0].triangles() as usize, torus.triangles.len());
    let (centre, radius) = gpu[0].bounding_sphere();
    assert!(
        (centre - DVec3::new(30.0, -20.0, 5.0)).length() < 1e-9,
        "{centre}"
    );
    assert!((radius - 1.35).abs() < 1e-6, "{radius}");
    let grid = Grid {
        origin: DVec3::new(-2.6, -1.6, -1.6),
        voxel: 0.1,
        size: [52, 32, 32],
    };
    for frame in 0..3 {
        let t = frame as f64 * 0.7;
        let models = [
            DMat4::from_translation(DVec3::new(-1.0, 0.2 + 0.1 * t, 0.0))
                * DMat4::from_rotation_x(0.9 + t)
                * DMat4::from_translation(DVec3::new(-30.0, 20.0, -5.0)),
            DMat4::from_translation(DVec3::new(1.4, -0.3, 0.4 - 0.2 * t))
                * DMat4::from_scale(DVec3::new(-1.5, 0.8, 1.0 + 0.3 * t)),
            DMat4::from_translation(DVec3::new(0.1, 0.0, 0.0))
                * DMat4::from_rotation_z(0.3 * t + 0.2)
                * DMat4::from_scale(DVec3::new(4.4, 2.2, 0.4)),
        ];
        let parts: Vec<(&GpuMesh, DMat4)> = gpu.iter().zip(models).collect();
        let mut enc = ctx.encoder("placed");
        let s = v
            .encode_surface_placed(
                &ctx.device,
                &mut enc,
                &parts,
                &grid,
                Separation::Conservative,
            )
            .unwrap();
        ctx.submit_and_wait("placed", enc).unwrap();
        let bits = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
        let moved =
            Mesh::combined(&[(&torus, models[0]), (&ball, models[1]), (&cube, models[2])]).unwrap();
        let (misses, extras, _) = check_against_sat(&bits, &moved, &grid);
        let n = bits.iter().filter(|&&b| b).count();
        println!("frame {frame}: {n} voxels, {misses} missed, {extras} extra");
        assert_eq!(misses, 0, "frame {frame}");
        assert!(n > 2000, "frame {frame}: {n} voxels");
    }
    // Nothing placed: an empty surface. A singular or non-finite matrix: a typed error that
    // names the part.
    let mut enc = ctx.encoder("placed errors");
    let empty = v
        .encode_surface_placed(&ctx.device, &mut enc, &[], &grid, Separation::Six)
        .unwrap();
    ctx.submit_and_wait("placed errors", enc).unwrap();
    assert!(
        !empty
            .read(&ctx.device, &ctx.queue)
            .wait(&ctx)
            .unwrap()
            .contains(&true)
    );
    for bad in [
        DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0)),
        DMat4::from_translation(DVec3::splat(f64::NAN)),
        DMat4::from_translation(DVec3::splat(1e300)),
    ] {
        let mut enc = ctx.encoder("placed errors");
        let e = v
            .encode_surface_placed(
                &ctx.device,
                &mut enc,
                &[(&gpu[1], DMat4::IDENTITY), (&gpu[1], bad)],
                &grid,
                Separation::Conservative,
            )
            .err()
            .expect("a bad matrix is refused");
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.starts_with("part 1")),
            "{e}"
        );
    }
    // Upload refuses what `encode_surface` refuses, and counts zero-area triangles.
    assert!(GpuMesh::upload(&ctx.device, &Mesh::default()).is_err());
    let mut flat = ball.clone();
    flat.triangles.push([0, 0, 1]);
    assert_eq!(GpuMesh::upload(&ctx.device, &flat).unwrap().degenerate(), 1);
    flat.positions[0].x = f64::INFINITY;
    assert!(GpuMesh::upload(&ctx.device, &flat).is_err());
}

/// Two triangles covering the square [0, 4096]² at z = 1.5, inside voxel layer 1.
fn square_on_layer_one() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let n = 4096.0;
    let positions = vec![
        DVec3::new(0.0, 0.0, 1.5),
        DVec3::new(n, 0.0, 1.5),
        DVec3::new(n, n, 1.5),
        DVec3::new(0.0, n, 1.5),
    ];
    (positions, vec![[0, 1, 2], [0, 2, 3]])
}

/// Every voxel of layer 1 of a 4096 × 4096 × 2 grid set, none of layer 0.
fn check_layer_one(ctx: &Context, s: &fieldkit::voxelize::Surface) {
    let gpu = s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    let layer = 4096 * 4096;
    let missing = gpu[layer..].iter().filter(|&&o| !o).count();
    let stray = gpu[..layer].iter().filter(|&&o| o).count();
    assert_eq!((missing, stray), (0, 0), "layer 1 missing, layer 0 set");
}

/// More threads than one dispatch row holds (65 535 workgroups of 64): 257 copies of a right
/// triangle whose box face holds 256² columns list 257 × 16 384 = 4.21 M chunks of 4 columns
/// (a box face of at most 65 536 columns keeps chunks of 4), so `surface_listed` runs in two
/// rows of workgroups. The copies set the voxels of one: every one against the SAT.
#[test]
fn more_chunks_than_one_dispatch_row_holds() {
    let ctx = Context::shared();
    let one = common::right_triangle(255.0);
    let copies = 257u32;
    let m = common::repeated(&one, copies);
    let grid = unit_grid([256, 256, 2]);
    let chunks = fieldkit::voxelize::heavy_chunk_bound(&m.to_grid(&grid).unwrap(), grid.size);
    assert_eq!(chunks as u64, copies as u64 * 256 * 256 / 4);
    assert!(chunks > 65_535 * 64, "{chunks} chunks fit one row");
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let (misses, extras, _) = check_against_sat(&gpu, &one, &grid);
    println!("{misses} missed, {extras} extra (each within 1e-3 voxels of the triangle)");
    assert_eq!(misses, 0, "missed voxels");
    assert!(gpu.iter().filter(|&&o| o).count() > 30_000);
}

/// Giant triangles are listed in at most `MAX_CHUNKS` chunks each (longer ones past that) on
/// the GPU (`encode_surface_placed` with a resident mesh), and the host's list
/// (`encode_surface`) is shorter still, so the list for 500 triangles each spanning a 4096²
/// grid holds at most 500 × 16 384 entries (66 MB),
/// which a storage binding of WebGPU's default 128 MiB holds. Before, each counted 4.2 M chunks
/// of 4 (16.8 GB in all) and the mesh was refused by both. The 500 lie past the grid's last
/// layer: the host lists them as light triangles (their box misses the grid), the resident
/// mesh's bound cannot know that (the GPU lists nothing for them); a square of two more, on
/// layer 1, is walked in chunks of 32 (host, 2^20 chunks between the two) or 512 (GPU) columns,
/// and every voxel of that layer is set and none of layer 0.
#[test]
fn giant_triangles_get_a_short_work_list() {
    use fieldkit::voxelize::GpuMesh;
    use glam::DMat4;
    let ctx = Context::shared();
    let n = 4096.0;
    let (mut positions, mut triangles) = square_on_layer_one();
    for k in 0..500u32 {
        let z = 2.5 + k as f64 * 0.001;
        let at = positions.len() as u32;
        positions.extend([
            DVec3::new(0.0, 0.0, z),
            DVec3::new(n, 0.0, z),
            DVec3::new(0.0, n, z),
        ]);
        triangles.push([at, at + 1, at + 2]);
    }
    let m = mesh(positions, triangles);
    let grid = unit_grid([4096, 4096, 2]);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("giant triangles, host-listed");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("giant triangles, host-listed", enc)
        .unwrap();
    check_layer_one(&ctx, &s);
    let resident = GpuMesh::upload(&ctx.device, &m).unwrap();
    let mut enc = ctx.encoder("giant triangles, resident");
    let s = v
        .encode_surface_placed(
            &ctx.device,
            &mut enc,
            &[(&resident, DMat4::IDENTITY)],
            &grid,
            Separation::Conservative,
        )
        .unwrap();
    ctx.submit_and_wait("giant triangles, resident", enc)
        .unwrap();
    check_layer_one(&ctx, &s);
}

/// A triangle whose box face holds 2101² columns (1.1 M chunks of 4, past the host's list
/// budget of 2^20 entries) is listed in chunks of 5 columns, which `surface_listed` walks in
/// full: exactly the voxels whose box meets it.
#[test]
fn a_triangle_past_the_list_budget_is_walked_in_longer_chunks() {
    let ctx = Context::shared();
    let m = common::right_triangle(2100.0);
    let grid = unit_grid([2104, 2104, 2]);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let want = common::right_triangle_voxels(2100, [2104, 2104, 2]);
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "{wrong} voxels wrong");
}

/// `mesh` resident and placed by the identity: its surface voxels.
fn resident_voxels(ctx: &Context, mesh: &Mesh, grid: &Grid) -> Vec<bool> {
    use fieldkit::voxelize::GpuMesh;
    let v = Voxelizer::new(&ctx.device).unwrap();
    let resident = GpuMesh::upload(&ctx.device, mesh).unwrap();
    let mut enc = ctx.encoder("resident");
    let s = v
        .encode_surface_placed(
            &ctx.device,
            &mut enc,
            &[(&resident, glam::DMat4::IDENTITY)],
            grid,
            Separation::Conservative,
        )
        .unwrap();
    ctx.submit_and_wait("resident", enc).unwrap();
    s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()
}

/// Right triangles with legs `legs[k]` on layer `k`, as `common::right_triangle` puts one on
/// layer 1: voxel (x, y, k) is set exactly when x + y ≤ legs[k].
fn right_triangles_on_layers(legs: &[u32], side: u32) -> (Mesh, Vec<bool>) {
    let mut positions = Vec::new();
    for (k, &leg) in legs.iter().enumerate() {
        let (z, leg) = (k as f64 + 0.5, leg as f64);
        positions.extend([
            DVec3::new(0.5, 0.5, z),
            DVec3::new(leg, 0.5, z),
            DVec3::new(0.5, leg, z),
        ]);
    }
    let triangles = (0..legs.len() as u32)
        .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
        .collect();
    let n = side as usize;
    let want = (0..n * n * legs.len())
        .map(|i| (i % n) + (i / n % n) <= legs[i / (n * n)] as usize)
        .collect();
    (mesh(positions, triangles), want)
}

/// A resident giant triangle (2101² columns, past `GIANT_MIN_COLUMNS`) gets a record instead
/// of work-list entries, and `surface_giant` walks it a workgroup per block of 64 chunks of 5
/// columns (its 4.4 M columns over the 2^20 chunks a giant may have): exactly the voxels whose
/// box meets it. Fails when the giant pass walks 4 columns per chunk, or is not recorded.
#[test]
fn a_resident_giant_triangle_is_walked_in_blocks() {
    let ctx = Context::shared();
    let m = common::right_triangle(2100.0);
    let grid = unit_grid([2104, 2104, 2]);
    let gpu = resident_voxels(&ctx, &m, &grid);
    let want = common::right_triangle_voxels(2100, [2104, 2104, 2]);
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "{wrong} voxels wrong");
}

/// More giant blocks than one dispatch row holds: five giant triangles of 2048² columns, 2^20
/// chunks of 4 each, are 81 920 blocks of 64 chunks, walked in two rows of workgroups; and
/// 64 giants (201² columns) beside 10 smaller triangles (101²) that the resident mesh's bound
/// cannot tell from them, so those are listed in chunks: both exactly the triangles' voxels.
#[test]
fn giant_triangles_fill_two_dispatch_rows_beside_listed_ones() {
    let ctx = Context::shared();
    let (m, want) = right_triangles_on_layers(&[2047; 5], 2048);
    let gpu = resident_voxels(&ctx, &m, &unit_grid([2048, 2048, 5]));
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "five giants: {wrong} voxels wrong");

    let mut legs = vec![200; 64];
    legs.extend([100; 10]);
    let (m, want) = right_triangles_on_layers(&legs, 208);
    let gpu = resident_voxels(&ctx, &m, &unit_grid([208, 208, legs.len() as u32]));
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "64 giants and 10 listed: {wrong} voxels wrong");
}

/// More giant triangles than the device's storage binding holds chunks for (each lists
/// `MAX_CHUNKS` of 8 bytes): the host sums the chunks before it allocates them and gives a
/// typed error instead, for its own list and for the GPU's list of a resident mesh (the same
/// size: triangles of equal size, none of which the GPU's list makes giant).
#[test]
fn a_chunk_list_too_large_is_refused_before_it_is_made() {
    use fieldkit::voxelize::MAX_CHUNKS;
    let ctx = Context::shared();
    let limit = ctx.device.limits().max_storage_buffer_binding_size;
    let count = (limit / (8 * MAX_CHUNKS as u64) + 1) as u32;
    let n = 4096.0;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..count {
        let z = 0.25 + k as f64 * (1.0 / count as f64);
        positions.extend([
            DVec3::new(0.0, 0.0, z),
            DVec3::new(n, 0.0, z),
            DVec3::new(0.0, n, z),
        ]);
        triangles.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let m = mesh(positions, triangles);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    match v.encode_surface(&ctx.device, &mut enc, &m, &unit_grid([4096, 4096, 2])) {
        Err(Error::Size { what, got, max, .. }) => {
            assert_eq!(what, "heavy-triangle chunk list bytes");
            assert_eq!((got, max), (count as u64 * 8 * MAX_CHUNKS as u64, limit));
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a chunk list past the binding's {limit} bytes was accepted"),
    }
    let resident = fieldkit::voxelize::GpuMesh::upload(&ctx.device, &m).unwrap();
    match v.encode_surface_placed(
        &ctx.device,
        &mut enc,
        &[(&resident, glam::DMat4::IDENTITY)],
        &unit_grid([4096, 4096, 2]),
        Separation::Conservative,
    ) {
        Err(Error::Size { what, got, max, .. }) => {
            assert_eq!(what, "heavy-triangle work list bytes");
            assert_eq!((got, max), (count as u64 * 8 * MAX_CHUNKS as u64, limit));
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a resident list past the binding's {limit} bytes was accepted"),
    }
}

/// However the triangles are cut into threads (light or in chunks, sorted or not, any
/// workgroup size; `Listing::auto` picks per mesh), the voxels are the same, and they are the
/// SAT's: a sphere of small triangles and a few triangles of many columns each.
#[test]
fn every_way_of_cutting_triangles_gives_the_same_voxels() {
    use fieldkit::voxelize::Listing;
    let ctx = Context::shared();
    let mut m = Mesh::uv_sphere(DVec3::new(21.3, 19.8, 17.1), 12.7, 40, 20);
    let base = m.positions.len() as u32;
    m.positions.extend([
        DVec3::new(1.2, 2.3, 3.1),
        DVec3::new(44.7, 6.1, 30.2),
        DVec3::new(9.4, 38.8, 12.6),
        DVec3::new(40.2, 37.9, 2.2),
    ]);
    m.triangles
        .extend([[base, base + 1, base + 2], [base + 1, base + 3, base + 2]]);
    let grid = unit_grid([46, 40, 33]);
    let listings = [
        None,
        Some(Listing::default()),
        Some(Listing::auto(1 << 20)),
        Some(Listing {
            light: 4,
            chunk: 2,
            sort: true,
            workgroup: 32,
        }),
        Some(Listing {
            light: 1,
            chunk: 1,
            sort: false,
            workgroup: 256,
        }),
        Some(Listing {
            light: 64,
            chunk: 16,
            sort: true,
            workgroup: 128,
        }),
    ];
    let mut v = Voxelizer::new(&ctx.device).unwrap();
    for separation in [Separation::Conservative, Separation::Six] {
        let mut first: Option<Vec<bool>> = None;
        for listing in listings {
            v.set_listing(&ctx.device, listing).unwrap();
            let mut enc = ctx.encoder("voxelize");
            let s = v
                .encode_surface_with(&ctx.device, &mut enc, &m, &grid, separation)
                .unwrap();
            ctx.submit_and_wait("voxelize", enc).unwrap();
            let got = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
            match &first {
                None => {
                    if separation == Separation::Conservative {
                        let (misses, _, _) = check_against_sat(&got, &m, &grid);
                        assert_eq!(misses, 0, "voxels the SAT has and the GPU missed");
                    }
                    first = Some(got);
                }
                Some(want) => {
                    let differ = got.iter().zip(want).filter(|(a, b)| a != b).count();
                    assert_eq!(differ, 0, "{separation:?}, {listing:?}: voxels differ");
                }
            }
        }
    }
    let bad = Listing {
        chunk: 0,
        ..Listing::default()
    };
    assert!(matches!(
        v.set_listing(&ctx.device, Some(bad)),
        Err(Error::Invalid { .. })
    ));
}
