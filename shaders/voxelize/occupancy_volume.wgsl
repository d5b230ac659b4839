// An occupancy bitset as a 3D texture the other stages read (1 occupied, 0 empty): a mesh's
// distance field is its solid voxels through `distance/edt_*` with `Inside::Mask`.

struct VolumeParams {
    grid: vec3<u32>,
}

@group(0) @binding(0) var<uniform> params: VolumeParams;
// Voxel (x, y, z) is bit i % 32 of word i / 32 with i = (z · ny + y) · nx + x.
@group(0) @binding(1) var<storage, read> occupancy: array<u32>;
@group(0) @binding(2) var volume: texture_storage_3d<r32float, write>;

@compute @workgroup_size(32, 4, 2)
fn to_volume(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.grid) {
        return;
    }
    let i = (id.z * params.grid.y + id.y) * params.grid.x + id.x;
    let bit = (occupancy[i / 32u] >> (i % 32u)) & 1u;
    textureStore(volume, id, vec4<f32>(f32(bit), 0.0, 0.0, 0.0));
}
