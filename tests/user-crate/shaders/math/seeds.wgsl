// Packs each voxel's coordinates as fieldkit's distance stages store seeds, with fieldkit's own
// helper imported from the `fieldkit` WESL package (fieldkit-build's user-crate test).

import fieldkit::seed::{NO_SEED, pack_seed3, unpack_seed3};

struct Grid {
    size: vec3<u32>,
    // Voxels whose index is a multiple of this hold a seed; the others hold NO_SEED.
    every: u32,
}

@group(0) @binding(0) var<uniform> grid: Grid;
@group(0) @binding(1) var<storage, read_write> packed: array<u32>;
// Each packed seed unpacked again (x, y, z, 0), or -1s for none.
@group(0) @binding(2) var<storage, read_write> unpacked: array<vec4<i32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let count = grid.size.x * grid.size.y * grid.size.z;
    let i = id.x;
    if i >= count {
        return;
    }
    let p = vec3<u32>(i % grid.size.x, (i / grid.size.x) % grid.size.y, i / (grid.size.x * grid.size.y));
    let s = select(NO_SEED, pack_seed3(p), i % grid.every == 0u);
    packed[i] = s;
    unpacked[i] = select(vec4<i32>(-1), vec4<i32>(unpack_seed3(s), 0), s != NO_SEED);
}
