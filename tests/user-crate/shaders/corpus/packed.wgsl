// Golden corpus: vertex inputs in the packed formats real vertex buffers use.
// Declared on their lines: a position in `snorm16x2`, a colour in `unorm8x4`, a tag in one
// byte, and a per-instance scale in half floats (the step given by the declaration, not by an
// `instance_` name).

struct VertexIn {
    @location(0) position: vec2<f32>, // vertex: snorm16x2
    @location(1) color: vec4<f32>,    // vertex: unorm8x4
    @location(2) tag: u32,            // vertex: uint8
    @location(3) scale: vec2<f32>,    // vertex: float16x2, instance
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) color: vec4<f32>,
    @location(1) @interpolate(flat) tag: u32,
}

struct FragmentOut {
    @location(0) color: vec4<f32>,
    @location(1) tag: u32,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = vec4<f32>(v.position * v.scale - 1.0, 0.0, 1.0);
    out.color = v.color;
    out.tag = v.tag;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    out.color = in.color;
    out.tag = in.tag;
    return out;
}
