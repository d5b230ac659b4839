// Golden corpus: an unsized binding array, its length given when the pipeline is made.
// Sums layer k of every texture, times k + 1, per texel: as many layers as the app binds.
// lint: allow(webgpu-limits): binding arrays are a native feature; the test asks for it.

enable wgpu_binding_array;

@group(0) @binding(0) var layers: binding_array<texture_2d<f32>>;
@group(0) @binding(1) var<storage, read_write> sums: array<f32>;
// wgpu refuses a uniform buffer in the group of a binding array: the count has its own.
@group(1) @binding(0) var<uniform> count: u32;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(layers[0]);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    var total = 0.0;
    for (var k = 0u; k < count; k++) {
        total += textureLoad(layers[k], id.xy, 0).x * f32(k + 1u);
    }
    sums[id.y * size.x + id.x] = total;
}
