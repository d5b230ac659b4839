// Adds the frame's time to every value (a user of the shared `frame` group).

import package::shared::frame::frame;

@group(0) @binding(0) var<storage, read_write> values: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&values) {
        values[id.x] = values[id.x] + frame.time;
    }
}
