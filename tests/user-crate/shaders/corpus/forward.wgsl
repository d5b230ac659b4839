// Golden corpus: a forward renderer's file — a shadow pass's vertex entry with no fragment, the
// main vertex entry, and two fragment entries that draw with it (each entry gets a pipeline:
// `shadow_vs` depth-only, `main_vs_fs_lit` and `main_vs_fs_flat`).

struct Camera {
    depth: f32,
    tint: vec3<f32>,
}

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) shade: f32,
}

@group(0) @binding(0) var<uniform> camera: Camera;

// A triangle that covers the target: vertex i of (-1, -1), (3, -1), (-1, 3).
fn corner(i: u32) -> vec2<f32> {
    return vec2<f32>(f32(i & 1u) * 4.0 - 1.0, f32(i >> 1u) * 4.0 - 1.0);
}

@vertex
fn shadow_vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    return vec4<f32>(corner(i), camera.depth, 1.0);
}

@vertex
fn main_vs(@builtin(vertex_index) i: u32) -> Varyings {
    let p = corner(i);
    return Varyings(vec4<f32>(p, 0.5, 1.0), p * 0.5 + 0.5, 0.25);
}

@fragment
fn fs_lit(v: Varyings) -> @location(0) vec4<f32> {
    return vec4<f32>(camera.tint * v.shade, 1.0);
}

@fragment
fn fs_flat(@location(0) uv: vec2<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(uv, 0.0, 1.0);
}
