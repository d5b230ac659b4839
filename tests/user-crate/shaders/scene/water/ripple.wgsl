// Writes each index's square: a stage two folders down (fieldkit-build's user-crate test:
// generated as `shaders::scene::water::ripple`).

@group(0) @binding(0) var<storage, read_write> heights: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&heights) {
        heights[id.x] = id.x * id.x;
    }
}
