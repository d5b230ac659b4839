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

/// One voxel's attribute sums in the reference: colour in 8-bit levels, unit normals, and the
/// number of triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AttributeSum {
    /// Summed colour, 0–1 per channel.
    pub color: [f64; 4],
    /// Summed normal.
    pub normal: DVec3,
    /// Triangles touching the voxel.
    pub triangles: u32,
}

/// Reference for `voxelize/attributes`: for every voxel a triangle of `local` overlaps (the
/// 13-axis test), the triangle's vertex attributes from `mesh` interpolated at the voxel centre's
/// closest point on the triangle's plane (barycentrics clamped to the triangle),
/// summed. Keys are voxel indices ((z · ny + y) · nx + x).
pub fn attribute_sums(
    mesh: &super::Mesh,
    local: &GridMesh,
    size: [u32; 3],
) -> std::collections::BTreeMap<u64, AttributeSum> {
    let [nx, ny, nz] = size.map(|s| s as i64);
    let mut out = std::collections::BTreeMap::<u64, AttributeSum>::new();
    for (t, &source) in local.vertices.chunks(3).zip(&local.source) {
        let v = [t[0], t[1], t[2]].map(|p: Vec4| p.truncate().as_dvec3());
        let tri = mesh.triangles[source as usize];
        let face = (v[1] - v[0]).cross(v[2] - v[0]);
        let colour = tri.map(|i| {
            mesh.colors
                .get(i as usize)
                .map_or([255.0; 4], |c| c.map(f64::from))
        });
        let normal = tri.map(|i| {
            mesh.normals
                .get(i as usize)
                .copied()
                .unwrap_or(face.normalize())
        });
        let n = face.abs();
        let k = if n.x >= n.y && n.x >= n.z {
            0
        } else if n.y >= n.z {
            1
        } else {
            2
        };
        let (u, w) = ((k + 1) % 3, (k + 2) % 3);
        let flat = |p: DVec3| glam::DVec2::new(p[u], p[w]);
        let (a, e1, e2) = (flat(v[0]), flat(v[1]) - flat(v[0]), flat(v[2]) - flat(v[0]));
        let lo = v[0].min(v[1]).min(v[2]).ceil() - DVec3::ONE;
        let hi = v[0].max(v[1]).max(v[2]).floor();
        for z in (lo.z as i64).max(0)..=(hi.z as i64).min(nz - 1) {
            for y in (lo.y as i64).max(0)..=(hi.y as i64).min(ny - 1) {
                for x in (lo.x as i64).max(0)..=(hi.x as i64).min(nx - 1) {
                    let p = DVec3::new(x as f64, y as f64, z as f64);
                    if !overlaps(v[0], v[1], v[2], p) {
                        continue;
                    }
                    let centre = p + 0.5;
                    let r =
                        flat(centre - face * face.dot(centre - v[0]) / face.length_squared()) - a;
                    let area = e1.perp_dot(e2);
                    let mut b = glam::DVec2::new(r.perp_dot(e2), e1.perp_dot(r)) / area;
                    b = b.max(glam::DVec2::ZERO);
                    if b.x + b.y > 1.0 {
                        b /= b.x + b.y;
                    }
                    let mix = |q: [f64; 3]| q[0] + b.x * (q[1] - q[0]) + b.y * (q[2] - q[0]);
                    let sum = out.entry(((z * ny + y) * nx + x) as u64).or_default();
                    for (ch, total) in sum.color.iter_mut().enumerate() {
                        *total += mix(colour.map(|c| c[ch]));
                    }
                    let nrm =
                        normal[0] + b.x * (normal[1] - normal[0]) + b.y * (normal[2] - normal[0]);
                    sum.normal += if nrm == DVec3::ZERO { face } else { nrm }.normalize();
                    sum.triangles += 1;
                }
            }
        }
    }
    out
}
