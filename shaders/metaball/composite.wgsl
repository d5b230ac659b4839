// Writes a marched image (colour and NDC depth from `raymarch/sdf_raymarch`) into the caller's
// colour and depth targets through their depth test, so the surface composites with their scene.
// A full-screen triangle, scissored by the host to the marched rectangle; pixels the march left
// as a miss (depth −1) are discarded. Hit depths are clamped to [0, 1] as a rasterised depth would
// be: a hit on the near plane can come out a rounding error below 0.

struct FragmentOut {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@group(0) @binding(0) var marched_colour: texture_2d<f32>;
@group(0) @binding(1) var marched_depth: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let xy = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> FragmentOut {
    let xy = vec2<u32>(position.xy);
    let depth = textureLoad(marched_depth, xy, 0).r;
    if !(depth >= -0.5) {
        discard;
    }
    var out: FragmentOut;
    out.colour = textureLoad(marched_colour, xy, 0);
    out.depth = clamp(depth, 0.0, 1.0);
    return out;
}
