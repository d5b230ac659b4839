// 3D seed stage for sub-voxel seeds: each point of the seed table claims the voxel it lies in.
//
// Points are in voxel coordinates (voxel centres at integers). Several points in one voxel: the
// one nearest the centre wins, then the smaller index (see `point_key`), so the result does not
// depend on thread order. The field must be zeroed first.

import package::shared::seed::{point_key};

struct PointParams {
    size: vec3<u32>,
    count: u32,
}

@group(0) @binding(0) var<uniform> params: PointParams;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> nearest: array<atomic<u32>>;

@compute @workgroup_size(64)
fn seed_points(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let p = points[id.x].xyz;
    // The host rejects points outside the volume; the clamp only guards the edge voxels' rounding.
    let v = vec3<u32>(clamp(round(p), vec3<f32>(0.0), vec3<f32>(params.size - 1u)));
    let i = (v.z * params.size.y + v.y) * params.size.x + v.x;
    atomicMax(&nearest[i], point_key(id.x, length(p - vec3<f32>(v))));
}
