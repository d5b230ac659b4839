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

/// A `vec4<f32>` beside a `vec2<f32>` (and a `vec3`, a scalar, integer vectors): glam's
/// 16-byte-aligned `Vec4` made such a struct 32 bytes against a stride of 24, which neither
/// `bytemuck::Pod` nor the stride assertion accepts. Fields are arrays of 4-byte scalars,
/// so the struct is exactly the stride.
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
