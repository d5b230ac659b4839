// Golden corpus: binding arrays of samplers, storage textures and storage buffers (no imports:
// the pinned WESL parser does not read `binding_array`).
// lint: allow(webgpu-limits): binding arrays are a native feature.
enable wgpu_binding_array;

struct Block {
    values: array<u32>,
}

@group(0) @binding(0) var images: binding_array<texture_2d<f32>, 2>;
@group(0) @binding(1) var samplers: binding_array<sampler, 2>;
@group(0) @binding(2) var targets: binding_array<texture_storage_2d<r32float, write>, 2>;
@group(0) @binding(3) var<storage, read_write> blocks: binding_array<Block, 4>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let uv = vec2<f32>(id.xy) / 8.0;
    let a = textureSampleLevel(images[0], samplers[0], uv, 0.0).x;
    let b = textureSampleLevel(images[1], samplers[1], uv, 0.0).x;
    textureStore(targets[0], id.xy, vec4<f32>(a));
    textureStore(targets[1], id.xy, vec4<f32>(b));
    blocks[3].values[id.x] = blocks[0].values[id.y] + 1u;
}
