// Scales every value of a buffer by a uniform factor (fieldkit-build's user-crate test).

import package::shared::scale::scaled;

struct Params {
    factor: f32,
    count: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read_write> values: array<f32>;

override OFFSET: f32 = 0.0;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < params.count {
        values[id.x] = scaled(values[id.x], params.factor) + OFFSET;
    }
}
