// Voxel attributes as dense 3D textures the other techniques sample: the compact list of
// `voxelize/attributes` scattered into an RGBA8 colour volume and an RGBA8-snorm normal volume
// (zero where no voxel is; the normal's w is 1 exactly where one is), one thread per occupied
// voxel.

import fieldkit::octahedral::decode_octahedral;

struct AttributeVolumeParams {
    grid: vec3<u32>,
    // Entries the list has room for (the dispatch covers them).
    count: u32,
}

@group(0) @binding(0) var<uniform> params: AttributeVolumeParams;
// Per occupied voxel: (voxel index, RGBA8 colour, octahedral normal, triangles).
@group(0) @binding(1) var<storage, read> voxels: array<vec4<u32>>;
@group(0) @binding(2) var colour: texture_storage_3d<rgba8unorm, write>;
@group(0) @binding(3) var normal: texture_storage_3d<rgba8snorm, write>;
// Entries that hold an occupied voxel (a list sized by a bound has room for more).
@group(0) @binding(4) var<storage, read> occupied: u32;

// A 2D dispatch: rows of 65535 workgroups.
@compute @workgroup_size(64)
fn to_volumes(@builtin(global_invocation_id) id: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let j = id.y * groups.x * 64u + id.x;
    if j >= min(params.count, occupied) {
        return;
    }
    let v = voxels[j];
    let g = params.grid;
    let at = vec3<u32>(v.x % g.x, (v.x / g.x) % g.y, v.x / (g.x * g.y));
    textureStore(colour, at, unpack4x8unorm(v.y));
    textureStore(normal, at, vec4<f32>(decode_octahedral(v.z), 1.0));
}
