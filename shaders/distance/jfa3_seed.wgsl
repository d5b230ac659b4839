// 3D seed stage: each marked voxel of a mask or density volume becomes its own nearest seed.
//
// A voxel is marked where the volume's red channel is ≥ `threshold` (a mask uses the smallest
// positive f32, so any positive value marks); `invert` seeds the unmarked voxels instead, for the
// inside half of a signed distance. The field is a buffer, x fastest, so every JFA neighbour read
// of a warp is one contiguous run.

import fieldkit::seed::{NO_SEED, pack_seed3};

struct SeedParams {
    size: vec3<u32>,
    threshold: f32,
    // 1: seeds are the unmarked voxels.
    invert: u32,
}

@group(0) @binding(0) var<uniform> params: SeedParams;
@group(0) @binding(1) var volume: texture_3d<f32>;
@group(0) @binding(2) var<storage, read_write> nearest: array<u32>;

@compute @workgroup_size(32, 4, 2)
fn seed(@builtin(global_invocation_id) id: vec3<u32>) {
    // The dispatch is rounded up to whole workgroups.
    if any(id >= params.size) {
        return;
    }
    let marked = textureLoad(volume, id, 0).r >= params.threshold;
    let is_seed = marked != (params.invert != 0u);
    let i = (id.z * params.size.y + id.y) * params.size.x + id.x;
    nearest[i] = select(NO_SEED, pack_seed3(id), is_seed);
}
