//! What the voxelize tests share.
#![allow(unused_imports)]

use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::voxelize::{Grid, GridMesh, Mesh, Separation, Voxelizer, cpu};
use glam::{DVec3, Vec4};

/// GPU and CPU voxels: (misses, extras); every extra must overlap the triangle within `margin`
/// voxels (the GPU's rounding slack).
pub fn compare(ctx: &Context, mesh: &Mesh, grid: &Grid) -> (usize, usize, GridMesh) {
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, mesh, grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    check_against_sat(&gpu, mesh, grid)
}

/// [`compare`] for voxels the GPU already gave.
pub fn check_against_sat(gpu: &[bool], mesh: &Mesh, grid: &Grid) -> (usize, usize, GridMesh) {
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

pub fn mesh(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Mesh {
    Mesh {
        positions,
        triangles,
        ..Mesh::default()
    }
}

pub fn unit_grid(size: [u32; 3]) -> Grid {
    Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size,
    }
}

/// The failure modes, each in a small grid.
pub fn failure_cases() -> Vec<(&'static str, Mesh, Grid)> {
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

/// Voxels reached from the grid's boundary through empty voxels, with 6 or 26 neighbours.
pub fn flood(occupied: &[bool], size: [u32; 3], neighbours: usize) -> Vec<bool> {
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

/// Two triangles covering the square [0, 4096]² at z = 1.5, inside voxel layer 1.
pub fn square_on_layer_one() -> (Vec<DVec3>, Vec<[u32; 3]>) {
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
pub fn check_layer_one(ctx: &Context, s: &fieldkit::voxelize::Surface) {
    let gpu = s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    let layer = 4096 * 4096;
    let missing = gpu[layer..].iter().filter(|&&o| !o).count();
    let stray = gpu[..layer].iter().filter(|&&o| o).count();
    assert_eq!((missing, stray), (0, 0), "layer 1 missing, layer 0 set");
}

/// `mesh` resident and placed by the identity: its surface voxels.
pub fn resident_voxels(ctx: &Context, mesh: &Mesh, grid: &Grid) -> Vec<bool> {
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
pub fn right_triangles_on_layers(legs: &[u32], side: u32) -> (Mesh, Vec<bool>) {
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
