// 2D JFA seed stage: each seed texel becomes its own nearest seed (Rong & Tan 2006, "Jump Flooding in GPU").
//
// A texel is a seed where its value (the largest of its channels weighted by `channels`: red by
// default, red/green/blue for "any non-black texel") is ≥ threshold, or below it when `invert`
// is set (the outside of a mask, for the inside half of a signed distance).

import fieldkit::seed::{NO_SEED, pack_seed2, seed_value};

struct SeedParams {
    size: vec2<u32>,
    // 1: seeds are the texels below the threshold.
    invert: u32,
    // A texel is marked where its value is ≥ threshold.
    threshold: f32,
    // Channel weights (0 or 1) of the value.
    channels: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: SeedParams;
@group(0) @binding(1) var seeds: texture_2d<f32>;
@group(0) @binding(2) var nearest: texture_storage_2d<r32uint, write>;

@compute @workgroup_size(8, 8)
fn seed(@builtin(global_invocation_id) id: vec3<u32>) {
    // The dispatch is rounded up to whole workgroups.
    if any(id.xy >= params.size) {
        return;
    }
    let marked = seed_value(textureLoad(seeds, id.xy, 0), params.channels) >= params.threshold;
    let is_seed = marked != (params.invert != 0u);
    textureStore(nearest, id.xy, vec4<u32>(select(NO_SEED, pack_seed2(id.xy), is_seed), 0u, 0u, 0u));
}
