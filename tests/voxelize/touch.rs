//! Meshes that touch voxels at a single point or lie on voxel planes, through every surface
//! path (`encode_surface`, `_with`, the raster path, resident meshes placed by a matrix, and
//! placed into a kept surface), near the origin and a million voxels from it: no path drops a
//! voxel the f64 13-axis reference (closed boxes, on the mesh moved into the grid in f64) says
//! the mesh touches. Extras are allowed only within 1e-3 voxels of a triangle.

use fieldkit::gpu::Context;
use fieldkit::voxelize::{GpuMesh, Grid, Mesh, Separation, Surface, Voxelizer, cpu};
use glam::{DMat4, DVec3};

/// The cases `far` voxels from the origin: spheres fitted with `Grid::fit` (one voxel of
/// margin, so their extreme vertices lie on the planes 1 and n − 1 and touch the voxels beyond
/// at single points; the placed path dropped 3 such voxels of the second sphere on llvmpipe
/// before its boxes grew with the rounding), and a box whose faces lie on voxel planes (the
/// layers on both sides of each face touch it) in a grid of eighths, exact in f64.
fn cases(far: f64) -> Vec<(String, Mesh, Grid)> {
    let mut out = Vec::new();
    for (k, (centre, radius)) in [
        (DVec3::new(0.31, 0.72, 0.15), 1.13),
        (DVec3::new(0.64, 0.09, 0.87), 0.92),
        (DVec3::new(0.27, 0.55, 0.48), 1.61),
    ]
    .into_iter()
    .enumerate()
    {
        for n in [17, 23] {
            let near = Mesh::uv_sphere(centre, radius, 12, 6);
            let voxel = Grid::fit(&near, n).unwrap().voxel;
            let shift = DVec3::splat(far * voxel);
            let mesh = Mesh {
                positions: near.positions.iter().map(|&p| p + shift).collect(),
                ..near
            };
            let grid = Grid::fit(&mesh, n).unwrap();
            out.push((format!("sphere {k} fitted to {n}"), mesh, grid));
        }
    }
    let grid = Grid {
        origin: DVec3::new(-0.375, -0.5, -0.25) + DVec3::splat(far * 0.125),
        voxel: 0.125,
        size: [14, 14, 14],
    };
    let at = |k: [f64; 3]| grid.origin + DVec3::from_array(k) * grid.voxel;
    let cuboid = Mesh::cuboid(at([2.0, 3.0, 4.0]), at([9.0, 11.0, 10.0]));
    out.push(("a box on voxel planes".into(), cuboid, grid));
    out
}

/// The reference: every voxel whose closed box a triangle of `mesh` (moved into `g` in f64)
/// overlaps.
fn reference(mesh: &Mesh, g: &Grid) -> Vec<bool> {
    let local: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|&p| (p - g.origin) / g.voxel)
        .collect();
    let [nx, ny, nz] = g.size.map(|n| n as usize);
    let mut out = vec![false; nx * ny * nz];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| local[i as usize]);
        // Closed boxes: only the voxels from ⌈min⌉ − 1 to ⌊max⌋ can touch (exact in f64).
        let lo = (a.min(b).min(c).ceil() - 1.0).max(DVec3::ZERO).as_uvec3();
        let hi = a.max(b).max(c).floor().as_uvec3();
        for z in lo.z..=hi.z.min(nz as u32 - 1) {
            for y in lo.y..=hi.y.min(ny as u32 - 1) {
                for x in lo.x..=hi.x.min(nx as u32 - 1) {
                    let p = DVec3::new(x as f64, y as f64, z as f64);
                    let i = (z as usize * ny + y as usize) * nx + x as usize;
                    out[i] |= cpu::overlaps(a, b, c, p);
                }
            }
        }
    }
    out
}

/// (missed, extras) of `got` against the reference; panics on an extra farther than 1e-3
/// voxels from every triangle.
fn check(what: &str, got: &[bool], mesh: &Mesh, g: &Grid) -> (usize, usize) {
    let want = reference(mesh, g);
    let [nx, ny, _] = g.size.map(|n| n as usize);
    let local: Vec<DVec3> = mesh
        .positions
        .iter()
        .map(|&p| (p - g.origin) / g.voxel)
        .collect();
    let (mut missed, mut extras) = (0, 0);
    for (i, (&g, &w)) in got.iter().zip(&want).enumerate() {
        let p = DVec3::new(
            (i % nx) as f64,
            ((i / nx) % ny) as f64,
            (i / (nx * ny)) as f64,
        );
        if w && !g {
            missed += 1;
            eprintln!("{what}: missed voxel {p}");
        }
        if g && !w {
            extras += 1;
            let near = mesh.triangles.iter().any(|t| {
                let [a, b, c] = t.map(|i| local[i as usize]);
                cpu::overlaps_box(a, b, c, p + 0.5, DVec3::splat(0.5 + 1e-3))
            });
            assert!(
                near,
                "{what}: extra voxel {p} is not within 1e-3 voxels of the mesh"
            );
        }
    }
    assert!(want.iter().any(|&w| w), "{what}: the reference is empty");
    (missed, extras)
}

#[test]
fn no_path_drops_a_voxel_touched_at_a_point_or_on_a_plane() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let read = |s: &Surface| s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let conservative = Separation::Conservative;
    let mut failures = Vec::new();
    for far in [0.0, 1e6] {
        for (name, mesh, g) in cases(far) {
            let mut enc = ctx.encoder("touch");
            let surface = v.encode_surface(&ctx.device, &mut enc, &mesh, &g).unwrap();
            let with = v
                .encode_surface_with(&ctx.device, &mut enc, &mesh, &g, conservative)
                .unwrap();
            let raster = v
                .encode_surface_raster(&ctx.device, &mut enc, &mesh, &g)
                .unwrap();
            let resident = GpuMesh::upload(&ctx.device, &mesh).unwrap();
            let parts = [(&resident, DMat4::IDENTITY)];
            let placed = v
                .encode_surface_placed(&ctx.device, &mut enc, &parts, &g, conservative)
                .unwrap();
            // The same mesh resident near the world's origin, moved out by its matrix, into a
            // surface kept from a first fill.
            let home = Mesh {
                positions: mesh.positions.iter().map(|&p| p - g.origin).collect(),
                ..mesh.clone()
            };
            let home = GpuMesh::upload(&ctx.device, &home).unwrap();
            let moved = [(&home, DMat4::from_translation(g.origin))];
            let mut into = v
                .encode_surface_placed(&ctx.device, &mut enc, &moved, &g, conservative)
                .unwrap();
            ctx.submit_and_wait("touch", enc).unwrap();
            let mut enc = ctx.encoder("touch into");
            v.encode_surface_placed_into(
                &ctx.device,
                &mut enc,
                &moved,
                &g,
                conservative,
                &mut into,
            )
            .unwrap();
            ctx.submit_and_wait("touch into", enc).unwrap();
            for (path, s) in [
                ("encode_surface", &surface),
                ("encode_surface_with", &with),
                ("raster", &raster),
                ("placed", &placed),
                ("placed by a translation, into", &into),
            ] {
                let what = format!("{name}, {path}, {far} voxels out");
                let (missed, extras) = check(&what, &read(s), &mesh, &g);
                println!("{what}: {missed} missed, {extras} extra");
                if missed > 0 {
                    failures.push(what);
                }
            }
        }
    }
    assert!(failures.is_empty(), "voxels dropped: {failures:?}");
}

/// A resident mesh placed so far from the grid's origin that f32 holds its vertices only to
/// more than half a voxel is refused with a typed error naming the way out, not voxelized with
/// voxels the rounding could drop.
#[test]
fn a_placement_past_f32s_reach_is_refused() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let ball = GpuMesh::upload(&ctx.device, &Mesh::uv_sphere(DVec3::ZERO, 1.0, 8, 4)).unwrap();
    let grid = Grid {
        origin: DVec3::splat(-2.0),
        voxel: 0.125,
        size: [32, 32, 32],
    };
    let mut enc = ctx.encoder("far");
    let near = [(&ball, DMat4::from_translation(DVec3::splat(1e3)))];
    assert!(
        v.encode_surface_placed(
            &ctx.device,
            &mut enc,
            &near,
            &grid,
            Separation::Conservative
        )
        .is_ok()
    );
    let far = [(&ball, DMat4::from_translation(DVec3::new(1e5, 0.0, 0.0)))];
    let e = v
        .encode_surface_placed(&ctx.device, &mut enc, &far, &grid, Separation::Conservative)
        .err()
        .expect("800 000 voxels out");
    assert!(matches!(e, fieldkit::Error::Invalid { .. }), "{e}");
    assert!(e.to_string().contains("encode_surface"), "{e}");
}
