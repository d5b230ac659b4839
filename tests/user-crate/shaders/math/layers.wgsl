// Weighs the layers of a binding array of textures per texel (layer k by k + 1): fieldkit-build's
// binding arrays, in a file that imports a helper, run by the user crate's test.
// lint: allow(webgpu-limits): binding arrays are a native feature; the test asks for it.

import package::shared::scale::scaled;

enable wgpu_binding_array;

@group(0) @binding(0) var layers: binding_array<texture_2d<f32>, 3>;
@group(0) @binding(1) var<storage, read_write> sums: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(layers[0]);
    if id.x >= size.x || id.y >= size.y {
        return;
    }
    var total = 0.0;
    for (var k = 0u; k < 3u; k++) {
        total += scaled(textureLoad(layers[k], id.xy, 0).x, f32(k + 1u));
    }
    sums[id.y * size.x + id.x] = total;
}
