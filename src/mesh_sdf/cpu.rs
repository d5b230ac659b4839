//! CPU reference, read side by side with `shaders/mesh_sdf/mesh_sdf.wgsl`: each point's
//! distance to its nearest triangle by brute force in f64, signed by the generalized winding
//! number (Jacobson, Kavan & Sorkine-Hornung, "Robust inside-outside segmentation using
//! generalized winding numbers", SIGGRAPH 2013): inside where it exceeds ½, which holds for
//! closed meshes exactly and degrades gracefully across holes. On the same f32 grid-local
//! vertices the GPU gets; distances in voxels.

use glam::DVec3;

use crate::voxelize::GridMesh;

/// The point of triangle (a, b, c) nearest `p` (Ericson, "Real-Time Collision Detection", §5.1.5).
pub fn nearest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let inv = 1.0 / (va + vb + vc);
    a + ab * (vb * inv) + ac * (vc * inv)
}

/// The triangles of `mesh` in f64.
pub fn triangles(mesh: &GridMesh) -> Vec<[DVec3; 3]> {
    mesh.vertices
        .chunks(3)
        .map(|t| [0, 1, 2].map(|k| t[k].truncate().as_dvec3()))
        .collect()
}

/// Distance from `p` to the nearest of `triangles`.
pub fn distance(p: DVec3, triangles: &[[DVec3; 3]]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| (nearest_on_triangle(p, a, b, c) - p).length_squared())
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

/// The generalized winding number of `triangles` (counter-clockwise seen from outside) at `p`:
/// the solid angles they subtend over 4π (Van Oosterom & Strackee's formula). 1 inside a closed
/// mesh, 0 outside, fractional near holes.
pub fn winding_number(p: DVec3, triangles: &[[DVec3; 3]]) -> f64 {
    let mut sum = 0.0;
    for &[a, b, c] in triangles {
        let (a, b, c) = (a - p, b - p, c - p);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c));
        let div = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        sum += 2.0 * det.atan2(div);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// Signed distance (negative inside, by the winding number) from `p` to `triangles`, voxels.
pub fn signed_distance(p: DVec3, triangles: &[[DVec3; 3]]) -> f64 {
    let d = distance(p, triangles);
    if winding_number(p, triangles) > 0.5 {
        -d
    } else {
        d
    }
}

/// The centre of voxel `v` in grid-local coordinates.
pub fn centre(v: [u32; 3]) -> DVec3 {
    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) + 0.5
}
