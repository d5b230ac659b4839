// Voxel fragments, the input of the sparse voxel octree (`octree/build`; OpenGL Insights ch. 22,
// Crassin & Green, part 2): every voxel a triangle touches — the same conservative test and
// the same walk as `surface_listed` — appended to a list as (x | y << 16, z) instead of ORed
// into a dense bitset, so memory grows with the surface, not with the grid. A voxel touched by
// several triangles is listed once per triangle; the octree's flags do not mind.
//
// The host sorts the triangles as for `surface_listed`: the first `count` threads walk a light
// triangle each, the next `chunks` threads one listed chunk of a heavy triangle. Each thread
// counts its voxels, the workgroup takes one range of the list with one atomicAdd, and each
// thread walks again to write its voxels there. `total` counts every fragment, also those past
// `capacity` (which are dropped), so a list too short is sized exactly on the next try.

import fieldkit::triangle_box::{
    Setup, column_at, column_coords, listed_columns, next_column, overlaps_in, setup,
};

struct FragmentParams {
    grid: vec3<u32>,
    // Light triangles, one per thread.
    count: u32,
    // Relative rounding bound for the tests (a few ulp of f32).
    slack: f32,
    // Listed heavy chunks, one per thread after the light triangles.
    chunks: u32,
    // Fragments the list holds.
    capacity: u32,
    // This dispatch's threads: `threads` of them from `first_thread` on (the triangles are split
    // into parts whose lists each fit one binding).
    first_thread: u32,
    threads: u32,
}

override SIX_SEPARATING: bool = false;
// Also list each fragment's triangle (its index in the sorted list) in `triangle_ids`, for
// attributes.
override TRIANGLE_IDS: bool = false;

@group(0) @binding(0) var<uniform> params: FragmentParams;
// Three grid-local vertices per triangle, light triangles first (a heavy one's first vertex
// carries its chunks' columns in w: `listed_columns`).
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// The heavy triangles' chunks: (triangle, first column).
@group(0) @binding(2) var<storage, read> listed: array<vec2<u32>>;
// Voxel (x, y, z) as (x | y << 16, z).
@group(0) @binding(3) var<storage, read_write> fragments: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> total: atomic<u32>;
@group(0) @binding(5) var<storage, read_write> triangle_ids: array<u32>;

var<workgroup> group_count: atomic<u32>;
var<workgroup> group_base: u32;

fn load(t: u32) -> Setup {
    return setup(triangles[3u * t].xyz, triangles[3u * t + 1u].xyz, triangles[3u * t + 2u].xyz,
                 vec3<i32>(params.grid), params.slack, SIX_SEPARATING);
}

// The voxels of columns [first, first + count) of the triangle: counted, and written from
// list entry `at` on when `emit`.
fn walk(s: Setup, t: u32, first: u32, count: u32, emit: bool, at: u32) -> u32 {
    var n = 0u;
    let end = min(first + count, s.columns);
    var square = column_coords(s, first);
    for (var j = first; j < end; j++) {
        let c = column_at(s, square.x, square.y);
        square = next_column(s, square);
        for (var z = c.k0; z < c.k1; z++) {
            let p = c.p + s.ek * z;
            if overlaps_in(s, c, z, SIX_SEPARATING) {
                if emit && at + n < params.capacity {
                    fragments[at + n] = vec2<u32>(u32(p.x) | (u32(p.y) << 16u), u32(p.z));
                    if TRIANGLE_IDS {
                        triangle_ids[at + n] = t;
                    }
                }
                n++;
            }
        }
    }
    return n;
}

@compute @workgroup_size(64)
fn fragments_listed(@builtin(global_invocation_id) id: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>,
                    @builtin(local_invocation_index) local: u32) {
    let own = id.x + id.y * groups.x * 64u;
    let mine = own < params.threads;
    let i = params.first_thread + own;
    var s: Setup;
    var t = 0u;
    var first = 0u;
    var columns = 0u;
    if mine && i < params.count {
        t = i;
        s = load(i);
        columns = s.columns;
    } else if mine && i - params.count < params.chunks {
        let item = listed[i - params.count];
        t = item.x;
        s = load(item.x);
        first = item.y;
        columns = listed_columns(triangles[3u * item.x]);
    }
    var n = 0u;
    if columns > 0u {
        n = walk(s, t, first, columns, false, 0u);
    }
    let offset = atomicAdd(&group_count, n);
    workgroupBarrier();
    if local == 0u {
        group_base = atomicAdd(&total, atomicLoad(&group_count));
    }
    let base = workgroupUniformLoad(&group_base);
    if n > 0u {
        walk(s, t, first, columns, true, base + offset);
    }
}
