// Golden corpus: one slot, two variables — a storage and a uniform view of the same data, each
// used by its own entry point, so each pipeline binds only its own.

struct Scale {
    factor: vec4<f32>,
}

@group(0) @binding(0) var<storage, read> scale_storage: array<vec4<f32>>;
@group(0) @binding(0) var<uniform> scale_uniform: Scale;
@group(0) @binding(1) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(1)
fn from_storage() {
    out[0] = scale_storage[0].x * 2.0;
}

@compute @workgroup_size(1)
fn from_uniform() {
    out[1] = scale_uniform.factor.x * 3.0;
}
