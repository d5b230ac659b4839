//! CPU reference: the Akenine-Möller triangle/box overlap test (13 separating axes) in f64, on
//! the same f32 grid-local vertices the GPU gets.

use glam::{DVec3, Vec4};

use super::GridMesh;

/// Whether triangle (a, b, c) and the closed box [lo, lo + 1]³ overlap: no separating axis among
/// the box's 3 normals, the triangle's normal and the 9 edge × axis cross products.
pub fn overlaps(a: DVec3, b: DVec3, c: DVec3, lo: DVec3) -> bool {
    overlaps_box(a, b, c, lo + DVec3::splat(0.5), DVec3::splat(0.5))
}

/// [`overlaps`] for a box with centre `centre` and half extents `half`.
pub fn overlaps_box(a: DVec3, b: DVec3, c: DVec3, centre: DVec3, half: DVec3) -> bool {
    let v = [a - centre, b - centre, c - centre];
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let separated = |axis: DVec3| {
        if axis.length_squared() == 0.0 {
            return false;
        }
        let p = v.map(|q| q.dot(axis));
        let r = half.x * axis.x.abs() + half.y * axis.y.abs() + half.z * axis.z.abs();
        p.iter().cloned().fold(f64::INFINITY, f64::min) > r
            || p.iter().cloned().fold(f64::NEG_INFINITY, f64::max) < -r
    };
    for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
        if separated(axis) {
            return false;
        }
    }
    if separated(e[0].cross(e[1])) {
        return false;
    }
    for edge in e {
        for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
            if separated(edge.cross(axis)) {
                return false;
            }
        }
    }
    true
}

/// Conservative surface voxels of a grid-local mesh: every voxel of `size` whose closed box a
/// triangle overlaps, one bool per voxel, x fastest.
pub fn conservative(mesh: &GridMesh, size: [u32; 3]) -> Vec<bool> {
    let [nx, ny, nz] = size.map(|s| s as i64);
    let mut out = vec![false; (nx * ny * nz) as usize];
    for t in mesh.vertices.chunks(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|p: Vec4| p.truncate().as_dvec3());
        // Closed boxes: a triangle reaching x = k touches the voxel that ends there too.
        let lo = a.min(b).min(c).ceil() - DVec3::ONE;
        let hi = a.max(b).max(c).floor();
        for z in (lo.z as i64).max(0)..=(hi.z as i64).min(nz - 1) {
            for y in (lo.y as i64).max(0)..=(hi.y as i64).min(ny - 1) {
                for x in (lo.x as i64).max(0)..=(hi.x as i64).min(nx - 1) {
                    if overlaps(a, b, c, DVec3::new(x as f64, y as f64, z as f64)) {
                        out[((z * ny + y) * nx + x) as usize] = true;
                    }
                }
            }
        }
    }
    out
}
