// Adds one to every value: a stage directly in the shader folder, as most wgpu projects keep
// theirs (fieldkit-build's user-crate test: generated as `shaders::flat`).

@group(0) @binding(0) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&values) {
        values[id.x] += 1u;
    }
}
