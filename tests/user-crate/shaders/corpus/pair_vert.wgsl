// Golden corpus: a vertex entry alone in its file, drawn with another file's fragment entry.
// `pair_frag.wgsl` names it in a `// draw with:` line; this file's own pipeline is depth only.

struct Camera {
    offset: vec2<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) corner: vec2<f32>) -> VertexOut {
    var out: VertexOut;
    out.clip = vec4<f32>(corner + camera.offset, 0.0, 1.0);
    out.uv = corner;
    return out;
}
