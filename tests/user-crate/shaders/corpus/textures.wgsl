// Golden corpus: every kind of sampled texture, both samplers, and storage textures of each
// dimension and access, read and written by one compute entry point.

@group(0) @binding(0) var t1d: texture_1d<f32>;
@group(0) @binding(1) var t2d_uint: texture_2d<u32>;
@group(0) @binding(2) var t2d_array_sint: texture_2d_array<i32>;
@group(0) @binding(3) var t_cube: texture_cube<f32>;
@group(0) @binding(4) var t_cube_array: texture_cube_array<f32>;
@group(0) @binding(5) var t3d: texture_3d<f32>;
@group(0) @binding(6) var t_ms: texture_multisampled_2d<f32>;
@group(0) @binding(7) var t_depth: texture_depth_2d;
@group(0) @binding(8) var t_depth_array: texture_depth_2d_array;
@group(0) @binding(9) var t_depth_cube: texture_depth_cube;
@group(0) @binding(10) var t_depth_ms: texture_depth_multisampled_2d;
@group(0) @binding(11) var linear: sampler;
@group(0) @binding(12) var shadow: sampler_comparison;
@group(1) @binding(0) var s1d: texture_storage_1d<rgba8unorm, write>;
@group(1) @binding(1) var s2d_array: texture_storage_2d_array<r32uint, read_write>;
@group(1) @binding(2) var s3d: texture_storage_3d<rgba16float, write>;
@group(1) @binding(3) var s2d_read: texture_storage_2d<r32float, read>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let uv = vec2<f32>(id.xy) / 8.0;
    let dir = normalize(vec3<f32>(uv, 1.0));
    var v = textureLoad(t1d, i32(id.x), 0);
    v += vec4<f32>(textureLoad(t2d_uint, id.xy, 0));
    v += vec4<f32>(textureLoad(t2d_array_sint, id.xy, 0, 0));
    v += textureSampleLevel(t_cube, linear, dir, 0.0);
    v += textureSampleLevel(t_cube_array, linear, dir, 1, 0.0);
    v += textureSampleLevel(t3d, linear, vec3<f32>(uv, 0.5), 0.0);
    v += textureLoad(t_ms, id.xy, 0);
    var d = textureSampleCompareLevel(t_depth, shadow, uv, 0.5);
    d += textureLoad(t_depth_array, id.xy, 0, 0);
    d += textureSampleCompareLevel(t_depth_cube, shadow, dir, 0.5);
    d += textureLoad(t_depth_ms, id.xy, 0);
    d += textureLoad(s2d_read, id.xy).x;
    textureStore(s1d, id.x, v * d);
    let old = textureLoad(s2d_array, id.xy, 1);
    textureStore(s2d_array, id.xy, 1, old + vec4<u32>(1u));
    textureStore(s3d, vec3<u32>(id.xy, 0u), v);
}
