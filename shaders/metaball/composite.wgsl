// Writes a marched image (colour and NDC depth from `metaball/sdf_raymarch`) into the caller's
// colour and depth targets through their depth test, so the surface composites with their scene.
// A full-screen triangle, scissored by the host to the marched rectangle; pixels the march left
// as a miss (depth −1) are discarded. Hit depths are clamped to [0, 1] as a rasterised depth would
// be: a hit on the near plane can come out a rounding error below 0.
//
// `fs_gbuffer` writes a G-buffer march (world normal in rgb, base colour packed in a) into four
// targets in the ocean's order: scene colour (emissive: none), world normal (× ½ + ½), material
// (metallic, specular, roughness, shading model / 255), base colour.

import package::shared::shading::unpack_rgb8;

struct Material {
    metallic: f32,
    specular: f32,
    roughness: f32,
    // Written as shading_model / 255.
    shading_model: u32,
}

struct GBufferOut {
    @location(0) scene_colour: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) material: vec4<f32>,
    @location(3) base_colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

struct FragmentOut {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@group(0) @binding(0) var marched_colour: texture_2d<f32>;
@group(0) @binding(1) var marched_depth: texture_2d<f32>;
@group(0) @binding(2) var<uniform> material: Material;

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

@fragment
fn fs_gbuffer(@builtin(position) position: vec4<f32>) -> GBufferOut {
    let xy = vec2<u32>(position.xy);
    let depth = textureLoad(marched_depth, xy, 0).r;
    if !(depth >= -0.5) {
        discard;
    }
    let texel = textureLoad(marched_colour, xy, 0);
    var out: GBufferOut;
    out.scene_colour = vec4<f32>(0.0, 0.0, 0.0, 1.0);
    out.normal = vec4<f32>(texel.rgb * 0.5 + 0.5, 1.0);
    out.material = vec4<f32>(material.metallic, material.specular, material.roughness, f32(material.shading_model) / 255.0);
    out.base_colour = vec4<f32>(unpack_rgb8(texel.a), 1.0);
    out.depth = clamp(depth, 0.0, 1.0);
    return out;
}
