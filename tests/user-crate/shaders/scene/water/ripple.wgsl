// Writes each index's square plus the frame's scale: a stage two folders down that binds the
// shared `frame` group (fieldkit-build's user-crate test: generated as
// `shaders::scene::water::ripple`, its group reached at the generated file's root).

import package::shared::frame::frame;

@group(0) @binding(0) var<storage, read_write> heights: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&heights) {
        heights[id.x] = id.x * id.x + u32(frame.scale);
    }
}
