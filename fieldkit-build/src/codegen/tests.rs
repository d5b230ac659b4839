//! The generated host code against hand-checked expectations.

use super::*;
use crate::lint::test_util::stage;

const RENDER: &str = "// Test render stage.
struct Camera { view_proj: mat4x4<f32>, eye: vec3<f32>, exposure: f32 }
struct VsOut { @builtin(position) clip: vec4<f32>, @location(0) normal: vec3<f32> }
struct FsOut { @location(0) colour: vec4<f32>, @location(1) id: u32 }
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var tint: texture_2d<f32>;
@group(0) @binding(2) var tint_sampler: sampler;
@vertex fn vs(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) instance_offset: vec4<f32>) -> VsOut {
var o: VsOut;
o.clip = camera.view_proj * vec4<f32>(position + instance_offset.xyz, 1.0);
o.normal = normal;
return o;
}
@fragment fn fs(in: VsOut) -> FsOut {
var o: FsOut;
o.colour = textureSample(tint, tint_sampler, in.normal.xy) * camera.exposure;
o.id = 1u;
return o;
}
";

/// Every kind of override: literal defaults of each scalar type, an `@id`, a default the
/// shader computes, none at all, and a name that is a Rust keyword.
#[test]
fn overrides_are_typed_with_their_defaults() {
    let src = "// Test overrides.
override ROWS: u32 = 4u;
override GAIN: f32 = 0.5;
override BIAS: i32 = -3;
override SIGNED: bool = true;
@id(7) override SEED: u32 = 9u;
override dyn: u32 = 1u;
@group(0) @binding(0) var<storage, read_write> out: array<f32>;
@compute @workgroup_size(1) fn main() {
out[0] = f32(ROWS) * GAIN + f32(BIAS) + f32(SIGNED) + f32(SEED) + f32(dyn);
}
";
    let code = format(&stage_module(&stage(src)));
    let flat: String = code.split_whitespace().collect();
    for want in [
        "pubrows:u32,",
        "pubgain:f32,",
        "pubbias:i32,",
        "pubsigned:bool,",
        "pubseed:u32,",
        "pubr#dyn:u32,",
        "rows:4u32,gain:0.5f32,bias:-3i32,signed:true,seed:9u32,r#dyn:1u32",
        // An `@id` override is set by its id.
        "Some((\"7\",vasf64))",
        "Some((\"SIGNED\",vasu32asf64))",
        "overrides:&[\"ROWS\",\"GAIN\",\"BIAS\",\"SIGNED\",\"7\",\"dyn\"]",
    ] {
        assert!(flat.contains(want), "{want} in {code}");
    }
    let computed = "// Test computed and required overrides.
override BASE: u32;
override TWICE: u32 = BASE * 2u;
@group(0) @binding(0) var<storage, read_write> out: array<u32>;
@compute @workgroup_size(1) fn main() {
out[0] = TWICE;
}
";
    let code = format(&stage_module(&stage(computed)));
    let flat: String = code.split_whitespace().collect();
    assert!(flat.contains("pubbase:u32,"), "{code}");
    assert!(flat.contains("pubtwice:Option<u32>,"), "{code}");
    assert!(
        flat.contains("self.twice.map(|v|(\"TWICE\",vasf64))"),
        "{code}"
    );
    // BASE has no default, so there is no `Default` to fill it with.
    assert!(!code.contains("impl Default for Overrides"), "{code}");
}

/// A `vec4<f32>` beside a `vec2<f32>` (and a `vec3`, a scalar, integer vectors): glam's
/// 16-byte-aligned `Vec4` made such a struct 32 bytes against a stride of 24, which neither
/// `bytemuck::Pod` nor the stride assertion accepts. Fields are arrays of 4-byte scalars,
/// so the struct is exactly the stride.
#[test]
fn vertex_structs_have_no_padding() {
    let src = "// Test vertex mix.
struct VsOut { @builtin(position) clip: vec4<f32>, @location(0) uv: vec2<f32> }
@vertex fn vs(@location(0) position: vec4<f32>, @location(1) uv: vec2<f32>, @location(2) normal: vec3<f32>, @location(3) weight: f32, @location(4) joints: vec4<u32>, @location(5) id: i32) -> VsOut {
var o: VsOut;
o.clip = position + vec4<f32>(normal * weight, f32(joints.x) + f32(id));
o.uv = uv;
return o;
}
@fragment fn fs(in: VsOut) -> @location(0) vec4<f32> {
return vec4<f32>(in.uv, 0.0, 1.0);
}
";
    let code = format(&stage_module(&stage(src)));
    let flat: String = code.split_whitespace().collect();
    for field in [
        "pubposition:[f32;4],",
        "pubuv:[f32;2],",
        "pubnormal:[f32;3],",
        "pubweight:f32,",
        "pubjoints:[u32;4],",
        "pubid:i32,",
    ] {
        assert!(flat.contains(field), "{field} in {code}");
    }
    assert!(!code.contains("glam::Vec4"), "{code}");
    // 16 + 8 + 12 + 4 + 16 + 4, asserted against the struct's size in the generated code.
    assert!(flat.contains("array_stride:60"), "{code}");
    assert!(flat.contains("size_of::<Vertex>()==60"), "{code}");
    for (format, offset) in [
        ("Float32x4", 0),
        ("Float32x2", 16),
        ("Float32x3", 24),
        ("Float32", 36),
        ("Uint32x4", 40),
        ("Sint32", 56),
    ] {
        assert!(
            flat.contains(&format!(
                "format:wgpu::VertexFormat::{format},offset:{offset},"
            )),
            "{format} at {offset} in {code}"
        );
    }
}

#[test]
fn render_stage_generates_vertex_structs_layouts_and_targets() {
    let code = format(&stage_module(&stage(RENDER)));
    // Per-vertex inputs in buffer 0, `instance_*` inputs in a per-instance buffer 1.
    assert!(code.contains("pub struct Vertex {"), "{code}");
    assert!(code.contains("pub position: [f32; 3]"));
    assert!(code.contains("pub struct Instance {"));
    assert!(code.contains("pub instance_offset: [f32; 4]"));
    assert!(code.contains("array_stride: 24"));
    assert!(code.contains("step_mode: wgpu::VertexStepMode::Instance"));
    assert!(code.contains("format: wgpu::VertexFormat::Float32x3"));
    assert!(code.contains("offset: 12"));
    // Visibility from real use: the camera is read by both stages, the texture by the fragment only.
    let flat: String = code.split_whitespace().collect();
    assert!(
        flat.contains("visibility:wgpu::ShaderStages::FRAGMENT.union(wgpu::ShaderStages::VERTEX)"),
        "{code}"
    );
    assert!(
        code.contains("filterable: true"),
        "sampled through a sampler: filterable"
    );
    assert!(code.contains("SamplerBindingType::Filtering"));
    // Fragment targets: a float and a uint output.
    assert!(code.contains("scalar: crate::bind::ScalarClass::Float"));
    assert!(code.contains("scalar: crate::bind::ScalarClass::Uint"));
    // vec3 followed by f32 packs into its padding: offsets 64 and 76, size 80.
    assert!(
        code.contains(".offset(1) == 64")
            && code.contains(".offset(2) == 76")
            && code.contains("min_size().get() == 80"),
        "{code}"
    );
}

#[test]
fn generated_code_is_deterministic() {
    let a = stage_module(&stage(RENDER));
    let b = stage_module(&stage(RENDER));
    assert_eq!(a, b);
}

/// Formats and steps declared on the inputs' lines: each attribute at the next offset its
/// format allows, explicit padding, the step overriding the `instance_` name.
#[test]
fn declared_vertex_formats_are_packed_as_the_buffer_holds_them() {
    let src = "// Test declared vertex formats.
struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) flag: u32,            // vertex: uint8
    @location(2) color: vec4<f32>,     // vertex: unorm8x4
    @location(3) normal: vec2<f32>,    // vertex: snorm16x2
    @location(4) tag: u32,             // vertex: uint16
    @location(5) weight: f32,          // vertex: unorm8
    @location(6) offset: vec2<f32>,    // vertex: float16x2, instance
    @location(7) instance_scale: f32,  // vertex: vertex
}
struct VsOut { @builtin(position) clip: vec4<f32>, @location(0) color: vec4<f32> }
@vertex fn vs(v: VsIn) -> VsOut {
var o: VsOut;
o.clip = vec4<f32>(v.position * v.weight * v.instance_scale, 1.0) + vec4<f32>(v.normal, v.offset);
o.color = v.color * f32(v.flag + v.tag);
return o;
}
@fragment fn fs(in: VsOut) -> @location(0) vec4<f32> {
return in.color;
}
";
    let code = format(&stage_module(&stage(src)));
    let flat: String = code.split_whitespace().collect();
    for want in [
        "pubposition:[f32;3],",
        "pubflag:u8,",
        "pub_pad13:[u8;3],",
        "pubcolor:[u8;4],",
        "pubnormal:[i16;2],",
        "pubtag:u16,",
        "pubweight:u8,",
        "pub_pad27:[u8;1],",
        "pubinstance_scale:f32,",
        "pubstructInstance{",
        "puboffset:[u16;2],",
        "size_of::<Vertex>()==32",
        "offset_of!(Vertex,color)==16",
        "offset_of!(Vertex,instance_scale)==28",
        "size_of::<Instance>()==4",
        "format:wgpu::VertexFormat::Uint8,offset:12,shader_location:1",
        "format:wgpu::VertexFormat::Unorm8x4,offset:16,shader_location:2",
        "format:wgpu::VertexFormat::Snorm16x2,offset:20,shader_location:3",
        "format:wgpu::VertexFormat::Uint16,offset:24,shader_location:4",
        "format:wgpu::VertexFormat::Unorm8,offset:26,shader_location:5",
        "format:wgpu::VertexFormat::Float32,offset:28,shader_location:7",
        "array_stride:32,step_mode:wgpu::VertexStepMode::Vertex",
        "array_stride:4,step_mode:wgpu::VertexStepMode::Instance,attributes:&[wgpu::VertexAttribute{format:wgpu::VertexFormat::Float16x2,offset:0,shader_location:6",
    ] {
        assert!(flat.contains(want), "{want} in {code}");
    }
}

/// What a declaration cannot be, each an error at its line: an unknown word, a format of
/// another scalar kind, a comment on a line that declares no input, and a 16-bit input with no
/// declared format.
#[test]
fn bad_vertex_declarations_are_errors_at_their_lines() {
    let problems = |src: &str| {
        let st = stage(src);
        let ep = &st.module.entry_points[0];
        crate::reflect::vertex::inputs(&st.original, &st.module, ep).unwrap_err()
    };
    let src = "// Test.
@vertex fn vs(
    @location(0) a: vec4<f32>, // vertex: unorm8x3
    @location(1) b: vec2<u32>, // vertex: unorm16x2
    // vertex: instance
    @location(2) c: f32,
) -> @builtin(position) vec4<f32> {
return a + vec4<f32>(vec2<f32>(b), c, 0.0);
}
";
    let found = problems(src);
    let at: Vec<usize> = found.iter().map(|p| p.0).collect();
    assert_eq!(at, [3, 4, 5], "{found:?}");
    assert!(
        found[0].2.contains("`unorm8x3` is not a vertex format"),
        "{found:?}"
    );
    assert!(
        found[1].2.contains("`unorm16x2` feeds `f32`/`f16` inputs"),
        "{found:?}"
    );
    assert!(found[2].2.contains("declares no vertex input"), "{found:?}");

    let half = "// Test.
enable f16;
@vertex fn vs(@location(0) a: vec2<f16>) -> @builtin(position) vec4<f32> {
return vec4<f32>(vec2<f32>(a), 0.0, 1.0);
}
";
    let found = problems(half);
    assert!(found[0].2.contains("`// vertex: float16x2`"), "{found:?}");
    let declared = half.replace("vec2<f16>)", "vec2<f16>, // vertex: float16x2\n)");
    let st = stage(&declared);
    let inputs =
        crate::reflect::vertex::inputs(&st.original, &st.module, &st.module.entry_points[0])
            .unwrap();
    assert_eq!(
        (inputs[0].format.as_str(), inputs[0].size),
        ("Float16x2", 4)
    );
}
