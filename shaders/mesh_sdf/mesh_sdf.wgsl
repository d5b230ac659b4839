// A triangle mesh's signed distance field, exact inside a band around the surface. In
// `per_triangle` every triangle offers itself to each voxel whose centre lies within the band
// of it, as one key (its distance, coarsely, above its index) of which the voxel keeps the
// least; there or in `cross_triangles` (a thread a small triangle) it counts, along rows of
// voxel centres in x, y and z, the triangles each row crosses before every voxel and in all
// (parity, as `voxelize/solid` does along x); `resolve` measures each voxel's distance to the
// triangle its key names and signs it by the rows' vote: a row crossed an even number of times
// in all votes inside where an odd number of crossings lie before the voxel, a row crossed an
// odd number of times (it passed through a hole) does not vote, and where no majority stands
// the nearest feature's angle-weighted pseudo-normal decides (Bærentzen & Aanæs, "Signed distance computation using the angle
// weighted pseudonormal", IEEE TVCG 11(3), 2005). The closest point on a triangle follows
// Ericson, "Real-Time Collision Detection" (2005), §5.1.5.
//
// Coordinates are the grid's local frame: voxel (i, j, k) spans [i, i + 1] × … with its centre
// at (i + ½, j + ½, k + ½); distances are measured in voxels and written in world units.

import package::shared::row_crossing::row_inside;

struct SdfParams {
    grid: vec3<u32>,
    // Triangles in all.
    count: u32,
    // Half-width of the band in which distances are exact, voxels.
    band: f32,
    // Low bits of a key that hold the triangle's index.
    id_bits: u32,
    // Edge of a voxel in world units: the output's unit.
    voxel: f32,
    // 1: signed output (negative inside), 0: unsigned.
    signed: u32,
    // Word offsets in `parity` of the rows along y and z (the rows along x start at 0) and of
    // the three axes' per-row totals.
    rows_y: u32,
    rows_z: u32,
    totals: vec3<u32>,
}

@group(0) @binding(0) var<uniform> params: SdfParams;
// Three vertices per triangle, grid-local.
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Seven unit pseudo-normals per triangle: the face, the edges ab, bc, ca, the vertices a, b, c.
@group(0) @binding(2) var<storage, read> normals: array<vec4<f32>>;
// Per voxel, 0xffffffff minus the least key offered (0: no triangle within the band).
@group(0) @binding(3) var<storage, read_write> keys: array<atomic<u32>>;
// Per axis, one bit per voxel in rows along that axis (row r = (w · n_u + u) for the other two
// axes u = axis + 1, w = axis + 2 mod 3; bit r · n_axis + i), set where an odd number of
// crossings lie before the voxel's centre; then per axis one bit per row, set where the row
// crosses an odd number of triangles in all.
@group(0) @binding(4) var<storage, read_write> parity: array<atomic<u32>>;
@group(0) @binding(5) var field: texture_storage_3d<r32float, write>;
// The finished field, read again for the march's copy.
@group(0) @binding(6) var field_in: texture_3d<f32>;
// The field as the SDF march reads it (`metaball::MarchField`).
@group(0) @binding(7) var march: texture_storage_3d<rgba16float, write>;

const THREADS: u32 = 64u;
// How `per_triangle` works (`MeshSdf::with_layout`, for `cargo xtask bench mesh-sdf`): a load
// before each offer's atomic, which turns away most losing offers without a write but waits
// for the load; and the crossings of a triangle that covers few rows in a pass of their own, a
// thread a triangle (`cross_triangles`), or every triangle's in its workgroup after its
// offers, where most of the threads idle (the bunny at 128³ on the H200: 0.48 ms against
// 0.53–0.57).
override LOAD_FIRST: bool = true;
override CROSS_APART: bool = true;
// Rows (along the three axes together) above which a triangle's own workgroup crosses them
// rather than one thread: a large triangle's rows shared by the workgroup's threads.
const MANY_ROWS: u32 = 64u;
const NO_KEY: u32 = 0u;
// Voxels by which the stretches of a column worth measuring are widened against rounding.
const SLACK: f32 = 1e-3;

// The feature of a triangle nearest a point: 0 the face, 1–3 the edges ab, bc, ca, 4–6 the
// vertices a, b, c (the index of its pseudo-normal), and the nearest point relative to p.
struct Nearest {
    offset: vec3<f32>,
    feature: u32,
}

// The point of triangle (a, b, c) nearest the origin, the vertices given relative to the point
// whose distance is wanted (so that the arithmetic stays near zero).
fn nearest_on_triangle(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> Nearest {
    let ab = b - a;
    let ac = c - a;
    let ap = -a;
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return Nearest(a, 4u);
    }
    let bp = -b;
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return Nearest(b, 5u);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return Nearest(a + ab * (d1 / (d1 - d3)), 1u);
    }
    let cp = -c;
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return Nearest(c, 6u);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return Nearest(a + ac * (d2 / (d2 - d6)), 3u);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return Nearest(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))), 2u);
    }
    let inv = 1.0 / (va + vb + vc);
    return Nearest(a + ab * (vb * inv) + ac * (vc * inv), 0u);
}

// The triangle a workgroup serves: dispatches are two-dimensional past 65 535 triangles.
fn triangle_of(wg: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wg.y * groups.x + wg.x;
}

fn vertex(t: u32, k: u32) -> vec3<f32> {
    return triangles[3u * t + k].xyz;
}

// Every voxel centre within the band of the triangle within `lo`..`hi` takes the least of its
// key and the ones it holds. The key orders by distance first, quantized to the bits the index
// leaves, so among triangles nearer than one quantum the least index wins; `resolve` measures
// the exact distance to the one that won. The workgroup's threads share the box's columns
// along z; each measures only the stretch of its column that lies both within a sphere around
// the triangle and within the band of its plane (most of a small triangle's box lies outside
// the one, most of a large one's outside the other), found without a division per voxel.
fn offer_keys(t: u32, lane: u32, a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, lo: vec3<i32>, hi: vec3<i32>) {
    let band = params.band;
    let extent = vec2<u32>(hi.xy - lo.xy + 1);
    let n = cross(b - a, c - a);
    let unit = n / length(n);
    let centre = (a + b + c) / 3.0;
    let reach = max(max(length(a - centre), length(b - centre)), length(c - centre)) + band;
    let quanta = f32((1u << (32u - params.id_bits)) - 2u);
    for (var k = lane; k < extent.x * extent.y; k += THREADS) {
        let column = vec2<i32>(vec2<u32>(k % extent.x, k / extent.x)) + lo.xy;
        let p = vec2<f32>(column) + 0.5;
        let off = p - centre.xy;
        let across = reach * reach - dot(off, off);
        if across < 0.0 {
            continue;
        }
        // Widened by a thousandth of a voxel against rounding: the distance decides below.
        let half = sqrt(across) + SLACK;
        var z0 = centre.z - half;
        var z1 = centre.z + half;
        let plane = dot(unit.xy, p - a.xy);
        if abs(unit.z) > 1e-6 {
            let za = a.z + (-band - SLACK - plane) / unit.z;
            let zb = a.z + (band + SLACK - plane) / unit.z;
            z0 = max(z0, min(za, zb));
            z1 = min(z1, max(za, zb));
        } else if abs(plane) > band + SLACK {
            continue;
        }
        let first = max(i32(ceil(z0 - 0.5)), lo.z);
        let last = min(i32(floor(z1 - 0.5)), hi.z);
        for (var z = first; z <= last; z++) {
            let q3 = vec3<f32>(p, f32(z) + 0.5);
            let d = length(nearest_on_triangle(a - q3, b - q3, c - q3).offset);
            if d > band {
                continue;
            }
            let q = u32(min(d / band, 1.0) * quanta);
            let key = (q << params.id_bits) | t;
            let index = (u32(z) * params.grid.y + u32(column.y)) * params.grid.x + u32(column.x);
            offer(index, key);
        }
    }
}

// Voxel `index` takes `key` where it is less than the one it holds.
fn offer(index: u32, key: u32) {
    let offer = 0xffffffffu - key;
    if LOAD_FIRST {
        // Most offers lose to a nearer triangle's: a load turns them away without a write.
        if offer > atomicLoad(&keys[index]) {
            atomicMax(&keys[index], offer);
        }
    } else {
        atomicMax(&keys[index], offer);
    }
}

// What one triangle does, one workgroup a triangle: offer its keys to the voxels within the
// band of it and, for a signed field, flip the rows it crosses.
@compute @workgroup_size(THREADS)
fn per_triangle(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = triangle_of(wg, groups);
    if t >= params.count {
        return;
    }
    let a = vertex(t, 0u);
    let b = vertex(t, 1u);
    let c = vertex(t, 2u);
    let band = params.band;
    let lo = max(vec3<i32>(ceil(min(min(a, b), c) - band - 0.5)), vec3<i32>(0));
    let hi = min(vec3<i32>(floor(max(max(a, b), c) + band - 0.5)), vec3<i32>(params.grid) - 1);
    if all(lo <= hi) {
        offer_keys(t, lane, a, b, c, lo, hi);
    }
    // A triangle beyond the grid along a row still counts in the row's total.
    if params.signed == 1u && (!CROSS_APART || rows_covered(t) > MANY_ROWS) {
        cross_rows(t, lane, THREADS);
    }
}

// The crossings alone, a thread a triangle of at most `MANY_ROWS` rows (with `CROSS_APART`,
// the default; `per_triangle` crosses the rest).
@compute @workgroup_size(THREADS)
fn cross_triangles(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let t = id.y * groups.x * THREADS + id.x;
    if t < params.count && rows_covered(t) <= MANY_ROWS {
        cross_rows(t, 0u, 1u);
    }
}

// Along each axis, every row of voxel centres that the triangle's projection covers: the
// voxels beyond the crossing flip, and the row's total flips. `threads` threads share the rows,
// this one `lane` (the workgroup's threads, or one thread a triangle).
fn cross_rows(t: u32, lane: u32, threads: u32) {
    let v0 = vertex(t, 0u);
    let n = cross(vertex(t, 1u) - v0, vertex(t, 2u) - v0);
    let g = vec3<i32>(params.grid);
    for (var axis = 0u; axis < 3u; axis++) {
        let u_axis = (axis + 1u) % 3u;
        let w_axis = (axis + 2u) % 3u;
        let along = n[axis];
        if along == 0.0 {
            // Parallel to the rows: the rows along its plane are counted by its neighbours.
            continue;
        }
        // The projection onto (u, w), counter-clockwise.
        let flip = along < 0.0;
        let pa = vec2<f32>(v0[u_axis], v0[w_axis]);
        let v1 = vertex(t, select(1u, 2u, flip));
        let v2 = vertex(t, select(2u, 1u, flip));
        let pb = vec2<f32>(v1[u_axis], v1[w_axis]);
        let pc = vec2<f32>(v2[u_axis], v2[w_axis]);
        let size = vec2<i32>(g[u_axis], g[w_axis]);
        let bounds = row_box(v0, v1, v2, axis);
        let lo = bounds.xy;
        let hi = bounds.zw;
        if any(lo > hi) {
            continue;
        }
        let extent = vec2<u32>(hi - lo + 1);
        let length = params.grid[axis];
        let plane = dot(n, v0);
        for (var i = lane; i < extent.x * extent.y; i += threads) {
            let r = vec2<i32>(vec2<u32>(i % extent.x, i / extent.x)) + lo;
            let p = vec2<f32>(r) + 0.5;
            if !row_inside(pa, pb, pc, p) {
                continue;
            }
            let row = u32(r.y) * u32(size.x) + u32(r.x);
            let at = (plane - n[u_axis] * p.x - n[w_axis] * p.y) / along;
            let first = i32(ceil(clamp(at, -1.0, f32(length) + 1.0) - 0.5));
            flip_from(rows_base(axis), row, length, first);
            atomicXor(&parity[params.totals[axis] + row / 32u], 1u << (row % 32u));
        }
    }
}

// The rows along `axis` that the projection of triangle (a, b, c) may cover, within the grid:
// the least (xy) and the greatest (zw) row coordinates.
fn row_box(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>, axis: u32) -> vec4<i32> {
    let u_axis = (axis + 1u) % 3u;
    let w_axis = (axis + 2u) % 3u;
    let pa = vec2<f32>(a[u_axis], a[w_axis]);
    let pb = vec2<f32>(b[u_axis], b[w_axis]);
    let pc = vec2<f32>(c[u_axis], c[w_axis]);
    let size = vec2<i32>(i32(params.grid[u_axis]), i32(params.grid[w_axis]));
    let lo = max(vec2<i32>(ceil(min(min(pa, pb), pc) - 0.5)), vec2<i32>(0));
    let hi = min(vec2<i32>(floor(max(max(pa, pb), pc) - 0.5)), size - 1);
    return vec4<i32>(lo, hi);
}

// Rows triangle `t`'s three projections may cover: who crosses them (`MANY_ROWS`).
fn rows_covered(t: u32) -> u32 {
    let a = vertex(t, 0u);
    let b = vertex(t, 1u);
    let c = vertex(t, 2u);
    var rows = 0u;
    for (var axis = 0u; axis < 3u; axis++) {
        let bounds = row_box(a, b, c, axis);
        if all(bounds.xy <= bounds.zw) {
            let extent = vec2<u32>(bounds.zw - bounds.xy + 1);
            rows += extent.x * extent.y;
        }
    }
    return rows;
}

// Flip the bits of row `row` (along an axis of `length` voxels, section at word `base`) from
// voxel `first` on.
fn flip_from(base: u32, row: u32, length: u32, first: i32) {
    if first >= i32(length) {
        return;
    }
    let start = row * length;
    var i = start + u32(max(first, 0));
    let last = start + length - 1u;
    while i <= last {
        let word = i / 32u;
        let top = min(last, word * 32u + 31u);
        let lo_bit = i % 32u;
        let width = top % 32u - lo_bit + 1u;
        let mask = select(((1u << width) - 1u) << lo_bit, 0xffffffffu, width == 32u);
        atomicXor(&parity[base + word], mask);
        i = top + 1u;
    }
}

fn rows_base(axis: u32) -> u32 {
    return select(select(0u, params.rows_y, axis == 1u), params.rows_z, axis == 2u);
}

fn bit(word: u32, index: u32) -> bool {
    return ((atomicLoad(&parity[word + index / 32u]) >> (index % 32u)) & 1u) == 1u;
}

// +1 for a majority of voting rows outside, -1 inside, 0 where none stands.
fn vote(v: vec3<u32>) -> i32 {
    var votes = 0;
    for (var axis = 0u; axis < 3u; axis++) {
        let u_axis = (axis + 1u) % 3u;
        let w_axis = (axis + 2u) % 3u;
        let row = v[w_axis] * params.grid[u_axis] + v[u_axis];
        if bit(params.totals[axis], row) {
            // An odd number of crossings in all: the row passed through a hole.
            continue;
        }
        let inside = bit(rows_base(axis), row * params.grid[axis] + v[axis]);
        votes += select(1, -1, inside);
    }
    return sign(votes);
}

// Each voxel's distance to the triangle its key names, signed by the rows' vote or, where no
// majority stands, by the nearest feature's pseudo-normal; ±band beyond the band.
@compute @workgroup_size(4, 4, 4)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.grid) {
        return;
    }
    let index = (id.z * params.grid.y + id.y) * params.grid.x + id.x;
    let held = atomicLoad(&keys[index]);
    var distance = params.band;
    var side = 1;
    if held != NO_KEY {
        let t = (0xffffffffu - held) & ((1u << params.id_bits) - 1u);
        let p = vec3<f32>(id) + 0.5;
        let near = nearest_on_triangle(vertex(t, 0u) - p, vertex(t, 1u) - p, vertex(t, 2u) - p);
        distance = length(near.offset);
        // The point lies on the side its offset from the surface points to.
        side = select(-1, 1, dot(-near.offset, normals[7u * t + near.feature].xyz) >= 0.0);
    }
    if params.signed == 1u {
        let voted = vote(id);
        if voted != 0 {
            side = voted;
        }
    } else {
        side = 1;
    }
    textureStore(field, id, vec4<f32>(f32(side) * distance * params.voxel, 0.0, 0.0, 0.0));
}

// The field in the SDF march's format: red the signed distance in voxels, green its negation,
// a density whose level 0 is the surface (its gradient the outward normal's negation).
@compute @workgroup_size(4, 4, 4)
fn march_texture(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.grid) {
        return;
    }
    let d = textureLoad(field_in, id, 0).r / params.voxel;
    textureStore(march, id, vec4<f32>(d, -d, 0.0, 0.0));
}
