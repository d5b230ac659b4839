// 3D JFA pass: each voxel keeps the nearest seed among itself and its 26 neighbours at ±step
// (Rong & Tan 2006, extended to 3D as in the sources' metaball SDF).
//
// `jump` reads packed integer seeds; `jump_points` reads keys into the sub-voxel seed table.
// Out-of-range neighbours are skipped. Equal distances keep the smaller packed seed (smaller
// table index), so the result is the same on every adapter.

import fieldkit::seed::{NO_SEED, dist2_3, key_index, unpack_seed3};

struct JumpParams {
    size: vec3<u32>,
    step: u32,
}

@group(0) @binding(0) var<uniform> params: JumpParams;
@group(0) @binding(1) var<storage, read> src: array<u32>;
@group(0) @binding(2) var<storage, read_write> dst: array<u32>;
@group(0) @binding(3) var<storage, read> points: array<vec4<f32>>;

fn index_of(p: vec3<i32>) -> u32 {
    let q = vec3<u32>(p);
    return (q.z * params.size.y + q.y) * params.size.x + q.x;
}

fn outside(q: vec3<i32>) -> bool {
    return any(q < vec3<i32>(0)) || any(q >= vec3<i32>(params.size));
}

@compute @workgroup_size(32, 4, 2)
fn jump(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let p = vec3<i32>(id);
    let step = i32(params.step);
    var best = src[index_of(p)];
    var best_d = select(0x7fffffff, dist2_3(unpack_seed3(best), p), best != NO_SEED);
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = p + vec3<i32>(dx, dy, dz) * step;
                if (dx == 0 && dy == 0 && dz == 0) || outside(q) {
                    continue;
                }
                let s = src[index_of(q)];
                if s == NO_SEED {
                    continue;
                }
                let d = dist2_3(unpack_seed3(s), p);
                if d < best_d || (d == best_d && s < best) {
                    best = s;
                    best_d = d;
                }
            }
        }
    }
    dst[index_of(p)] = best;
}

fn point_d2(key: u32, p: vec3<f32>) -> f32 {
    let d = points[key_index(key)].xyz - p;
    return dot(d, d);
}

@compute @workgroup_size(32, 4, 2)
fn jump_points(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let p = vec3<i32>(id);
    let pf = vec3<f32>(p);
    let step = i32(params.step);
    var best = src[index_of(p)];
    var best_d = select(3.4e38, point_d2(best, pf), best != NO_SEED);
    for (var dz = -1; dz <= 1; dz++) {
        for (var dy = -1; dy <= 1; dy++) {
            for (var dx = -1; dx <= 1; dx++) {
                let q = p + vec3<i32>(dx, dy, dz) * step;
                if (dx == 0 && dy == 0 && dz == 0) || outside(q) {
                    continue;
                }
                let s = src[index_of(q)];
                if s == NO_SEED || s == best {
                    continue;
                }
                let d = point_d2(s, pf);
                if d < best_d || (d == best_d && key_index(s) < key_index(best)) {
                    best = s;
                    best_d = d;
                }
            }
        }
    }
    dst[index_of(p)] = best;
}
