// 2D JFA resolve: nearest-seed texture(s) to distance, unsigned or signed (inside negative).
//
// Signed distance comes from two floods: one seeded by the inside texels (distance for outside
// texels) and one by the outside texels (distance for inside ones). A texel is inside when it is
// its own nearest inside seed. Half a texel is taken off so the zero crossing lies on the boundary
// between texel centres, as in the source tool's mask mode.

import fieldkit::seed::{FAR, NO_SEED, pack_seed2, unpack_seed2};

struct ResolveParams {
    size: vec2<u32>,
    // World units per texel.
    texel_size: f32,
}

@group(0) @binding(0) var<uniform> params: ResolveParams;
@group(0) @binding(1) var nearest: texture_2d<u32>;
@group(0) @binding(2) var nearest_outside: texture_2d<u32>;
@group(0) @binding(3) var distance: texture_storage_2d<r32float, write>;

fn seed_distance(s: u32, p: vec2<i32>) -> f32 {
    if s == NO_SEED {
        return FAR;
    }
    return length(vec2<f32>(unpack_seed2(s) - p)) * params.texel_size;
}

@compute @workgroup_size(8, 8)
fn resolve_unsigned(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let d = seed_distance(textureLoad(nearest, p, 0).r, p);
    textureStore(distance, p, vec4<f32>(d, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8)
fn resolve_signed(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let inside_seed = textureLoad(nearest, p, 0).r;
    let half = 0.5 * params.texel_size;
    var d: f32;
    if inside_seed == pack_seed2(id.xy) {
        let out = textureLoad(nearest_outside, p, 0).r;
        d = select(-(seed_distance(out, p) - half), -FAR, out == NO_SEED);
    } else {
        d = select(seed_distance(inside_seed, p) - half, FAR, inside_seed == NO_SEED);
    }
    textureStore(distance, p, vec4<f32>(d, 0.0, 0.0, 0.0));
}
