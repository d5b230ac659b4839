// Min-max brick grid for empty-space skipping: per brick of `brick`³ voxels, the smallest and
// largest density of the voxels a trilinear sample inside the brick can touch (the brick dilated
// by one voxel on every side, clamped to the volume). The march skips a brick whose largest
// density the transfer function maps to zero opacity, so skipping cannot change the image.

struct BrickParams {
    dims: vec3<u32>,
    brick: u32,
    bricks: vec3<u32>,
}

@group(0) @binding(0) var<uniform> params: BrickParams;
@group(0) @binding(1) var density: texture_3d<f32>;
// (min, max) per brick, x fastest.
@group(0) @binding(2) var<storage, read_write> ranges: array<vec2<f32>>;

@compute @workgroup_size(4, 4, 4)
fn bricks(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.bricks) {
        return;
    }
    let top = vec3<i32>(params.dims) - 1;
    let lo = max(vec3<i32>(id * params.brick) - 1, vec3<i32>(0));
    let hi = min(vec3<i32>((id + 1u) * params.brick), top);
    var lo_d = 3.4e38;
    var hi_d = -3.4e38;
    for (var z = lo.z; z <= hi.z; z++) {
        for (var y = lo.y; y <= hi.y; y++) {
            for (var x = lo.x; x <= hi.x; x++) {
                let v = textureLoad(density, vec3<i32>(x, y, z), 0).r;
                lo_d = min(lo_d, v);
                hi_d = max(hi_d, v);
            }
        }
    }
    ranges[(id.z * params.bricks.y + id.y) * params.bricks.x + id.x] = vec2<f32>(lo_d, hi_d);
}
