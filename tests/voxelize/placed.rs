//! Placed and resident meshes (`Voxelizer::encode_surface_placed`, `_into`, `GpuMesh`): several
//! meshes into one grid, a surface refilled in place, resident meshes moved by matrices on the
//! GPU, each against the surface voxelizer and the SAT reference.

use crate::common;

use common::voxelize::*;
use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
use glam::DVec3;

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
