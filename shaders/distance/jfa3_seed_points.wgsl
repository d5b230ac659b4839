// 3D seed stage for sub-voxel seeds: each point of the seed table claims its home voxel.
//
// Points are in voxel coordinates (voxel centres at integers). A point's home is the voxel named
// in `homes` (packed, as surface extraction emits one point per voxel), or with `use_homes` off
// the voxel it lies in. Several points for one voxel: the one nearest the centre wins, then the
// smaller index (see `point_key`), so the result does not depend on thread order. Points that
// lose are not seen by JFA; homes avoid that. The field must be zeroed first.

import fieldkit::seed::{point_key, unpack_seed3};

struct PointParams {
    size: vec3<u32>,
    count: u32,
    // 1: `homes` names each point's voxel.
    use_homes: u32,
}

@group(0) @binding(0) var<uniform> params: PointParams;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> nearest: array<atomic<u32>>;
@group(0) @binding(3) var<storage, read> homes: array<u32>;

@compute @workgroup_size(64)
fn seed_points(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let p = points[id.x].xyz;
    // The host rejects points and homes outside the volume; the clamp only guards rounding.
    var v = vec3<u32>(clamp(round(p), vec3<f32>(0.0), vec3<f32>(params.size - 1u)));
    if params.use_homes != 0u {
        v = min(vec3<u32>(unpack_seed3(homes[id.x])), params.size - 1u);
    }
    let i = (v.z * params.size.y + v.y) * params.size.x + v.x;
    atomicMax(&nearest[i], point_key(id.x, length(p - vec3<f32>(v))));
}
