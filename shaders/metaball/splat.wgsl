// Metaball density splat: each instance adds the smooth falloff (1 − d²/R²)³ (Wyvill & Blinn
// style) to the voxels inside its support, as fixed-point integers with atomicAdd, one thread per
// instance as in the source's Unreal pass.
//
// Fixed point: a contribution w ∈ [0, 1] adds round(w · scale). The host picks
// scale = min(10000, ⌊(2³² − 1) / instances⌋): no voxel can receive more than one contribution per
// instance, so the sum never wraps. Each contribution is off by at most 0.5 / scale (5e-5 at the
// default scale).

struct SplatParams {
    size: vec3<u32>,
    count: u32,
    // Local-space corner of the grid; voxel centres at origin + (i + ½)·cell.
    origin: vec3<f32>,
    cell: f32,
    // Support radius per unit of instance scale: edge × ½ × overlap.
    radius_per_scale: f32,
    // Fixed-point units per unit density.
    fixed_scale: f32,
}

@group(0) @binding(0) var<uniform> params: SplatParams;
// xyz: centre (local space); w: scale.
@group(0) @binding(1) var<storage, read> instances: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> density: array<atomic<u32>>;

@compute @workgroup_size(64)
fn splat(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let inst = instances[id.x];
    let r = params.radius_per_scale * inst.w;
    if !(r > 0.0) {
        return;
    }
    // Search box in grid coordinates (voxel centres at integers), clamped to the grid.
    let g = (inst.xyz - params.origin) / params.cell - 0.5;
    let reach = r / params.cell;
    let lo = vec3<i32>(max(ceil(g - reach), vec3<f32>(0.0)));
    let hi = vec3<i32>(min(floor(g + reach), vec3<f32>(params.size) - 1.0));
    let inv_r2 = 1.0 / (r * r);
    // Only voxels inside the support sphere add anything, about half of its box: each row
    // visits the sphere's chord, widened by a voxel on each side, and rows that miss the
    // sphere are skipped. The widening covers rounding, so no voxel with a nonzero
    // contribution is left out; the weights are computed as for the whole box.
    for (var z = lo.z; z <= hi.z; z++) {
        let pz = (f32(z) - g.z) * params.cell;
        for (var y = lo.y; y <= hi.y; y++) {
            let py = (f32(y) - g.y) * params.cell;
            let chord2 = r * r - pz * pz - py * py;
            if chord2 <= 0.0 {
                continue;
            }
            let half = sqrt(chord2) / params.cell + 1.0;
            let x0 = max(lo.x, i32(ceil(g.x - half)));
            let x1 = min(hi.x, i32(floor(g.x + half)));
            let row = (u32(z) * params.size.y + u32(y)) * params.size.x;
            for (var x = x0; x <= x1; x++) {
                let p = (vec3<f32>(f32(x), f32(y), f32(z)) - g) * params.cell;
                let q = 1.0 - dot(p, p) * inv_r2;
                if q > 0.0 {
                    let w = u32(round(q * q * q * params.fixed_scale));
                    if w > 0u {
                        atomicAdd(&density[row + u32(x)], w);
                    }
                }
            }
        }
    }
}
