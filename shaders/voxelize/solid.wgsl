// Solid voxelization of a watertight mesh by parity: for every row of voxel centres along x
// that a triangle's yz projection covers, the voxels whose centres lie beyond the point where
// the row meets the triangle flip. After every triangle, a centre is set when an odd number of
// triangles lie before it along its row, which for a closed mesh means inside. The host ORs the
// surface voxels in afterwards, so parts thinner than a voxel survive.
//
// Rows that pass exactly through an edge or a vertex are counted once (`shared::row_crossing`).

import package::shared::row_crossing::row_inside;

struct SolidParams {
    grid: vec3<u32>,
    first: u32,
    count: u32,
}

@group(0) @binding(0) var<uniform> params: SolidParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Same layout as the surface bitset: voxel (x, y, z) is bit i % 32 of word i / 32 with
// i = (z · ny + y) · nx + x.
@group(0) @binding(2) var<storage, read_write> occupancy: array<atomic<u32>>;

fn flip_from(x_start: i32, y: i32, z: i32) {
    let g = vec3<i32>(params.grid);
    if x_start >= g.x {
        return;
    }
    let row = u32((z * g.y + y) * g.x);
    let first = row + u32(max(x_start, 0));
    let last = row + u32(g.x) - 1u;
    var i = first;
    while i <= last {
        let word = i / 32u;
        let top = min(last, word * 32u + 31u);
        let lo_bit = i % 32u;
        let hi_bit = top % 32u;
        let width = hi_bit - lo_bit + 1u;
        let mask = select(((1u << width) - 1u) << lo_bit, 0xffffffffu, width == 32u);
        atomicXor(&occupancy[word], mask);
        i = top + 1u;
    }
}

@compute @workgroup_size(64)
fn solid(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let t = params.first + id.x;
    let v0 = triangles[3u * t].xyz;
    let v1 = triangles[3u * t + 1u].xyz;
    let v2 = triangles[3u * t + 2u].xyz;
    let n = cross(v1 - v0, v2 - v0);
    if n.x == 0.0 {
        // Parallel to the rows: no row crosses it (rows along its plane are counted by the
        // triangles around it).
        return;
    }
    // Orient the yz projection counter-clockwise.
    var a = v0;
    var b = v1;
    var c = v2;
    if n.x < 0.0 {
        b = v2;
        c = v1;
    }
    let g = vec3<i32>(params.grid);
    let lo = max(vec2<i32>(ceil(min(min(a.yz, b.yz), c.yz) - 0.5)), vec2<i32>(0));
    let hi = min(vec2<i32>(floor(max(max(a.yz, b.yz), c.yz) - 0.5)), g.yz - 1);
    for (var z = lo.y; z <= hi.y; z++) {
        for (var y = lo.x; y <= hi.x; y++) {
            let p = vec2<f32>(f32(y) + 0.5, f32(z) + 0.5);
            if row_inside(a.yz, b.yz, c.yz, p) {
                // Where the row meets the plane; centres beyond it flip.
                let xc = (dot(n, v0) - n.y * p.x - n.z * p.y) / n.x;
                flip_from(i32(ceil(xc - 0.5)), y, z);
            }
        }
    }
}
