// Blends a volume march (`volume/volume_march`, premultiplied colour and coverage) over the
// caller's colour target: a full-screen triangle scissored by the host to the marched rectangle,
// with blending One / OneMinusSrcAlpha. The march already stopped each ray at the scene's depth,
// so no depth test is needed and none is written: the volume is not an opaque surface.

@group(0) @binding(0) var marched: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let xy = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(marched, vec2<u32>(position.xy), 0);
}
