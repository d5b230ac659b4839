// Golden corpus: a fragment entry alone in its file, drawing with another file's vertex entry.
// draw with: corpus::pair_vert::vs_main

struct Tint {
    color: vec4<f32>,
}

@group(0) @binding(1) var<uniform> tint: Tint;

@fragment
fn fs_main(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {
    return tint.color + vec4<f32>(0.0 * uv, 0.0, 0.0);
}
