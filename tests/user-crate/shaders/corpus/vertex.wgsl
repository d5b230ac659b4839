// Golden corpus: a render pipeline whose vertex stage reads every 32-bit vertex format, in a
// mix that would pad a naive host struct (vec3 beside scalars), per vertex and per instance,
// with integer and float fragment outputs.

struct Camera {
    view_proj: mat4x4<f32>,
    eye: vec3<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) weight: f32,
    @location(2) uv: vec2<f32>,
    @location(3) color: vec4<f32>,
    @location(4) id: u32,
    @location(5) cell: vec2<u32>,
    @location(6) voxel: vec3<u32>,
    @location(7) mask: vec4<u32>,
    @location(8) delta: i32,
    @location(9) offset2: vec2<i32>,
    @location(10) offset3: vec3<i32>,
    @location(11) offset4: vec4<i32>,
    @location(12) instance_shift: vec3<f32>,
    @location(13) instance_tag: u32,
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
    let p = v.position * v.weight + v.instance_shift + vec3<f32>(v.offset3) + vec3<f32>(v.voxel);
    out.clip = camera.view_proj * vec4<f32>(p, 1.0);
    out.color = v.color + vec4<f32>(v.uv, f32(v.delta + v.offset2.x + v.offset4.w), f32(v.cell.x + v.mask.y));
    out.tag = v.id + v.instance_tag;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    var out: FragmentOut;
    out.color = in.color * vec4<f32>(camera.eye, 1.0);
    out.tag = in.tag;
    return out;
}
