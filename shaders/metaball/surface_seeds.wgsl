// Iso-surface seeds: voxels at or above the threshold with a 6-neighbour below it become seeds,
// moved to the sub-voxel point where the density's linear model along its gradient reaches the
// threshold (one Newton step). Also converts the fixed-point density to f32 for the later stages.
//
// Each seed is its own voxel's point, so the seed table is indexed by voxel and the stage writes
// the JFA keys directly (see `point_key` in the distance stages).

import fieldkit::seed::{NO_SEED, point_key};

struct SurfaceParams {
    size: vec3<u32>,
    threshold: f32,
    // 1 / fixed-point scale of the splat.
    inv_fixed_scale: f32,
}

@group(0) @binding(0) var<uniform> params: SurfaceParams;
@group(0) @binding(1) var<storage, read> density: array<u32>;
@group(0) @binding(2) var density_out: texture_storage_3d<r32float, write>;
@group(0) @binding(3) var<storage, read_write> keys: array<u32>;
// Seed points in grid coordinates (voxel centres at integers); w = 1 for a seed.
@group(0) @binding(4) var<storage, read_write> points: array<vec4<f32>>;

// A home point may move at most this far (the key's quantisation covers √3/2).
const MAX_OFFSET: f32 = 0.8660254;

// Density at a voxel; zero outside the grid (the grid is fitted to the instances' support).
fn rho(p: vec3<i32>) -> f32 {
    if any(p < vec3<i32>(0)) || any(p >= vec3<i32>(params.size)) {
        return 0.0;
    }
    let i = (u32(p.z) * params.size.y + u32(p.y)) * params.size.x + u32(p.x);
    return f32(density[i]) * params.inv_fixed_scale;
}

@compute @workgroup_size(32, 4, 2)
fn surface_seeds(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let p = vec3<i32>(id);
    let i = (id.z * params.size.y + id.y) * params.size.x + id.x;
    let d = rho(p);
    textureStore(density_out, id, vec4<f32>(d, 0.0, 0.0, 0.0));
    let xm = rho(p - vec3<i32>(1, 0, 0));
    let xp = rho(p + vec3<i32>(1, 0, 0));
    let ym = rho(p - vec3<i32>(0, 1, 0));
    let yp = rho(p + vec3<i32>(0, 1, 0));
    let zm = rho(p - vec3<i32>(0, 0, 1));
    let zp = rho(p + vec3<i32>(0, 0, 1));
    let t = params.threshold;
    let edge = min(min(min(xm, xp), min(ym, yp)), min(zm, zp)) < t;
    if d < t || !edge {
        keys[i] = NO_SEED;
        points[i] = vec4<f32>(0.0);
        return;
    }
    let grad = 0.5 * vec3<f32>(xp - xm, yp - ym, zp - zm);
    let g2 = dot(grad, grad);
    var offset = vec3<f32>(0.0);
    if g2 > 1e-12 {
        // d ≥ t, so the step runs down the gradient, out of the surface.
        offset = grad * ((t - d) / g2);
        let len = length(offset);
        if len > MAX_OFFSET {
            offset *= MAX_OFFSET / len;
        }
    }
    keys[i] = point_key(i, length(offset));
    points[i] = vec4<f32>(vec3<f32>(p) + offset, 1.0);
}
