// Scales and offsets values by an immediate block (push constants): fieldkit-build's
// immediates, run by the user crate's test.
// lint: allow(webgpu-limits): immediates are a native feature (a WebGPU proposal); the test asks for it.

struct Push {
    scale: f32,
    offset: f32,
    count: u32,
}

var<immediate> push: Push;

@group(0) @binding(0) var<storage, read_write> values: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= push.count {
        return;
    }
    values[id.x] = values[id.x] * push.scale + push.offset;
}
