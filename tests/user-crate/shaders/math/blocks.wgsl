// Writes each invocation's workgroup and place in it: a workgroup sized by an override
// (fieldkit-build's user-crate test: `workgroup_size(&Overrides)` and the pipeline's groups).

override BLOCK: u32 = 64u;

@group(0) @binding(0) var<storage, read_write> values: array<u32>;

@compute @workgroup_size(BLOCK)
fn main(@builtin(global_invocation_id) id: vec3<u32>,
        @builtin(workgroup_id) group: vec3<u32>,
        @builtin(local_invocation_index) local: u32) {
    if id.x < arrayLength(&values) {
        values[id.x] = group.x * 1000u + local;
    }
}
