// 2D JFA pass: each texel keeps the nearest seed among itself and its 8 neighbours at ±step (Rong & Tan 2006).
//
// Out-of-range neighbours are skipped, never wrapped or clamped: a clamped read would offer the
// edge texel's seed again and hide nothing, but a wrapped one would offer seeds from the far side.
// Equal distances keep the smaller packed seed so the result is the same on every adapter.

import fieldkit::seed::{FAR2, NO_SEED, dist2, unpack_seed2};

struct JumpParams {
    size: vec2<u32>,
    step: u32,
}

@group(0) @binding(0) var<uniform> params: JumpParams;
@group(0) @binding(1) var src: texture_2d<u32>;
@group(0) @binding(2) var dst: texture_storage_2d<r32uint, write>;

@compute @workgroup_size(8, 8)
fn jump(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let size = vec2<i32>(params.size);
    let step = i32(params.step);
    var best = textureLoad(src, p, 0).r;
    var best_d = select(FAR2, dist2(unpack_seed2(best), p), best != NO_SEED);
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = p + vec2<i32>(dx, dy) * step;
            if (dx == 0 && dy == 0) || any(q < vec2<i32>(0)) || any(q >= size) {
                continue;
            }
            let s = textureLoad(src, q, 0).r;
            if s == NO_SEED {
                continue;
            }
            let d = dist2(unpack_seed2(s), p);
            if d < best_d || (d == best_d && s < best) {
                best = s;
                best_d = d;
            }
        }
    }
    textureStore(dst, p, vec4<u32>(best, 0u, 0u, 0u));
}
