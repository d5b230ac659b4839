// Golden corpus: overrides of every scalar type, one with an @id, one without a default, one
// the shader computes from another, sizing a workgroup array and the workgroup.

@id(7) override GAIN: f32 = 1.5;
override ENABLED: bool = true;
override BIAS: i32 = -2;
override LANES: u32;
override HALF: u32 = LANES / 2u;

@group(0) @binding(0) var<storage, read_write> out: array<f32>;

var<workgroup> scratch: array<f32, 64>;

@compute @workgroup_size(64)
fn main(@builtin(local_invocation_index) li: u32) {
    scratch[li] = f32(li) * GAIN + f32(BIAS);
    workgroupBarrier();
    if ENABLED && li < HALF {
        out[li] = scratch[li] + scratch[li + HALF] + f32(LANES);
    }
}
