//! Angle-weighted pseudo-normals (Bærentzen & Aanæs 2005): the normal that signs a point by the
//! feature of the mesh nearest it. A face's is its normal; an edge's the sum of the normals of
//! the faces that share it; a vertex's the sum of its faces' normals weighted by their angle
//! there. Vertices at one position are welded first, so a mesh split along its texture seams
//! signs across them as one surface.

use std::collections::HashMap;

use glam::{DVec3, Vec4};

use crate::voxelize::Mesh;

/// Seven unit pseudo-normals for each triangle named in `kept` (face; edges ab, bc, ca;
/// vertices a, b, c), in the order `shaders/mesh_sdf` reads them.
pub(super) fn pseudo_normals(mesh: &Mesh, kept: &[u32]) -> Vec<Vec4> {
    let weld = weld(&mesh.positions);
    let corners = |t: usize| mesh.triangles[t].map(|i| weld[i as usize]);
    let face = |t: usize| {
        let [a, b, c] = mesh.triangles[t].map(|i| mesh.positions[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let mut at_vertex = vec![DVec3::ZERO; mesh.positions.len()];
    let mut at_edge: HashMap<(u32, u32), DVec3> = HashMap::new();
    for t in 0..mesh.triangles.len() {
        // A face of no area adds nothing, but names its edges.
        let n = face(t);
        let v = corners(t);
        for k in 0..3 {
            let (here, next, prev) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
            let p = |i: u32| mesh.positions[i as usize];
            let angle = (p(next) - p(here)).angle_between(p(prev) - p(here));
            if angle.is_finite() {
                at_vertex[here as usize] += angle * n;
            }
            *at_edge.entry((here.min(next), here.max(next))).or_default() += n;
        }
    }
    let unit = |n: DVec3| n.normalize_or_zero().as_vec3().extend(0.0);
    let mut out = Vec::with_capacity(kept.len() * 7);
    for &t in kept {
        let t = t as usize;
        let v = corners(t);
        out.push(unit(face(t)));
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            out.push(unit(at_edge[&(a.min(b), a.max(b))]));
        }
        out.extend(v.map(|i| unit(at_vertex[i as usize])));
    }
    out
}

/// For each position, the first index holding the same point.
fn weld(positions: &[DVec3]) -> Vec<u32> {
    let mut first: HashMap<[u64; 3], u32> = HashMap::with_capacity(positions.len());
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // +0.0 and -0.0 are one point.
            let key = (*p + DVec3::ZERO).to_array().map(f64::to_bits);
            *first.entry(key).or_insert(i as u32)
        })
        .collect()
}
