// Conservative surface voxelization (Schwarz & Seidel 2010): every voxel a triangle touches,
// closed boxes, written to an occupancy bitset with atomicOr. Vertices are moved into grid-local
// coordinates (origin 0, voxel size 1) by `to_grid`: the identity when the host moved them in
// f64, a mesh's placement when the mesh stays on the GPU (`GpuMesh`) and only the matrix
// changes. A triangle with no area after the move is skipped (`setup` gives it no columns).
// The overlap tests are
// in `fieldkit::triangle_box`: a voxel passes exactly when the triangle and the box overlap (the
// 13-axis separating-axis test says the same), widened by `slack` against rounding.
//
// One thread per triangle (`first` and `count` select a run of the triangle list). A triangle
// with more than LIGHT columns does not stall its thread: `surface` appends it to a work list
// in chunks of `chunk_columns` columns (CHUNK but past MAX_CHUNKS chunks; a workgroup's threads
// list their heavy triangles' chunks together) and raises the indirect dispatch arguments to
// the list's length, and `surface_heavy` takes one chunk per thread. A giant triangle (one of
// the largest, which the host marks, at most `fieldkit::triangle_box`'s MAX_GIANTS) gets a
// record instead of entries, and `surface_giant` walks its chunks a workgroup per block.
//
// SIX_SEPARATING gives the thinner voxelization of the same paper, through which no
// 6-connected path gets; 26-connected paths can.

import fieldkit::triangle_box::{
    GIANT_BLOCK, GIANT_BLOCKS, GIANT_HEADER, GIANT_RECORDS, LIGHT, MAX_GIANTS, Setup,
    chunk_columns, column_at, column_coords, giant_blocks, giant_chunk_columns, giant_record_of,
    listed_columns, next_column, overlaps_in, setup, setup_moved,
};
import package::shared::scan::{scan_first, scan_partial};

struct SurfaceParams {
    // Mesh coordinates to grid-local ones (affine; composed in f64 on the host).
    to_grid: mat4x4<f32>,
    grid: vec3<u32>,
    first: u32,
    count: u32,
    // Relative rounding bound for the tests (a few ulp of f32).
    slack: f32,
    // How far f32 rounding of `to_grid`'s product can move a vertex, in voxels (0 for the
    // identity): the tests are widened by this much on top of `slack`.
    moved: f32,
    // Entries the work list holds (the host sizes it for every chunk there can be).
    capacity: u32,
    // Heavy triangles whose first vertex's w is 1 ..= giants are giant (the host ranks the
    // largest MAX_GIANTS by their columns or a bound on them, and counts those past its
    // threshold).
    giants: u32,
}

override SIX_SEPARATING: bool = false;
// Invocations per workgroup of `surface_listed`.
override LISTED_WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<uniform> params: SurfaceParams;
// Three vertices per triangle, in the coordinates `to_grid` moves (a first vertex's w: the
// triangle's rank among the giants, or see `listed`; `vertex` ignores it).
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Occupancy, one bit per voxel, x fastest: voxel (x, y, z) is bit i % 32 of word i / 32 with
// i = (z · ny + y) · nx + x.
@group(0) @binding(2) var<storage, read_write> occupancy: array<atomic<u32>>;
// Heavy triangles' chunks: (triangle, first column); `work_count` entries used (it may count
// past `capacity` only if the host's bound were wrong; entries past it are dropped).
@group(0) @binding(3) var<storage, read_write> work: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> work_count: atomic<u32>;
// Indirect dispatch arguments for `surface_heavy` (and the attribute pass's walk of the same
// list): the host creates them as (0, 1, 1) and `surface` raises them as it lists chunks, so
// no pass of its own writes them. Past 65535 workgroups they run in rows of 65535.
@group(0) @binding(5) var<storage, read_write> heavy_dispatch: array<atomic<u32>, 3>;
// `surface_listed`: the heavy triangles' chunks, listed by the host. A listed triangle's first
// vertex carries its chunks' columns in w (`listed_columns`).
@group(0) @binding(6) var<storage, read> listed: array<vec2<u32>>;
// Giant triangles' records and the dispatch arguments of `surface_giant` (the layout is
// `fieldkit::triangle_box`'s GIANT_HEADER; the host creates it as (0, 1, 1) and zeros).
@group(0) @binding(7) var<storage, read_write> giants: array<atomic<u32>>;
// The same buffer, read by `surface_giant` (a dispatch may not write the buffer it takes its
// arguments from).
@group(0) @binding(8) var<storage, read> giant_list: array<u32>;

fn set_bit(i: u32) {
    atomicOr(&occupancy[i / 32u], 1u << (i % 32u));
}

fn vertex(i: u32) -> vec3<f32> {
    return (params.to_grid * vec4<f32>(triangles[i].xyz, 1.0)).xyz;
}

fn load(t: u32) -> Setup {
    let a = vertex(3u * t);
    let b = vertex(3u * t + 1u);
    let c = vertex(3u * t + 2u);
    // `setup` scales the relative slack by the largest coordinate + 2 (as here), so adding
    // moved / scale widens every test by `moved` more.
    let m = max(max(abs(a), abs(b)), abs(c));
    let scale = max(max(m.x, m.y), m.z) + 2.0;
    return setup_moved(a, b, c, vec3<i32>(params.grid), params.slack + params.moved / scale,
                       SIX_SEPARATING, params.moved);
}

// `load` for triangles already in grid-local coordinates (`surface_listed`'s, which the host
// moved in f64): no matrix to apply, no widening for it.
fn load_local(t: u32) -> Setup {
    return setup(triangles[3u * t].xyz, triangles[3u * t + 1u].xyz, triangles[3u * t + 2u].xyz,
                 vec3<i32>(params.grid), params.slack, SIX_SEPARATING);
}

// Test the voxels of columns [first, first + count) of the triangle.
fn voxelize_columns(s: Setup, first: u32, count: u32) {
    let end = min(first + count, s.columns);
    // Voxel c.p + ek · z of a column is bit at + z · step of the occupancy.
    let g = params.grid;
    let step = dot(vec3<u32>(s.ek), vec3<u32>(1u, g.x, g.x * g.y));
    var square = column_coords(s, first);
    for (var j = first; j < end; j++) {
        let c = column_at(s, square.x, square.y);
        square = next_column(s, square);
        let at = (u32(c.p.z) * g.y + u32(c.p.y)) * g.x + u32(c.p.x);
        for (var z = c.k0; z < c.k1; z++) {
            if overlaps_in(s, c, z, SIX_SEPARATING) {
                set_bit(at + u32(z) * step);
            }
        }
    }
}

// Invocations per workgroup of `surface`.
const GROUP: u32 = 64u;
// Per thread of a `surface` workgroup: columns per chunk of its triangle, if heavy.
var<workgroup> chunk_sizes: array<u32, GROUP>;
// Whether any of the workgroup's triangles is heavy (`heavy_seen`, then read uniformly).
var<workgroup> heavy_seen: atomic<u32>;
var<workgroup> heavy_flag: u32;
// Where the workgroup's chunks start in the work list.
var<workgroup> group_base: u32;

// The workgroup's heavy triangles list their chunks together: a prefix sum of the threads'
// `chunks`, one atomic on the work list's count for the workgroup, and every thread writing
// entries whichever triangle they belong to, so a triangle of many chunks does not hold up its
// warp's lanes while one of them writes. Every thread of the workgroup calls it.
fn list_chunks(local: u32, chunks: u32, first_thread: u32) {
    scan_first(local, chunks, GROUP);
    let total = scan_partial(GROUP - 1u);
    if local == 0u {
        let at = atomicAdd(&work_count, total);
        // The workgroups `surface_heavy` needs for the chunks listed so far, in rows of 65535;
        // the largest any workgroup sees is the count for them all.
        let groups = (min(at + total, params.capacity) + 63u) / 64u;
        atomicMax(&heavy_dispatch[0], min(groups, 65535u));
        atomicMax(&heavy_dispatch[1], (groups + 65534u) / 65535u);
        group_base = at;
    }
    let base = workgroupUniformLoad(&group_base);
    // Entry e of the workgroup's belongs to the first thread j whose running sum passes e;
    // each thread's entries rise, so j only moves forward.
    var j = 0u;
    var begin = 0u;
    var end = scan_partial(0u);
    for (var e = local; e < total; e += GROUP) {
        while end <= e {
            j++;
            begin = end;
            end = scan_partial(j);
        }
        if base + e < params.capacity {
            work[base + e] = vec2<u32>(first_thread + j, (e - begin) * chunk_sizes[j]);
        }
    }
}

@compute @workgroup_size(GROUP)
fn surface(@builtin(global_invocation_id) id: vec3<u32>,
           @builtin(local_invocation_index) local: u32,
           @builtin(workgroup_id) group: vec3<u32>) {
    let mine = id.x < params.count;
    var s: Setup;
    var chunks = 0u;
    var giant = false;
    if mine {
        s = load(params.first + id.x);
        let rank = u32(triangles[3u * (params.first + id.x)].w);
        if s.columns > LIGHT && rank >= 1u && rank <= params.giants {
            giant = add_giant(params.first + id.x, s.columns);
        }
        if s.columns > LIGHT && !giant {
            let size = chunk_columns(s.columns);
            chunks = (s.columns + size - 1u) / size;
            chunk_sizes[local] = size;
            atomicOr(&heavy_seen, 1u);
        }
    }
    // Workgroups without a heavy triangle (most, at small grids) skip the prefix sum.
    workgroupBarrier();
    if local == 0u {
        heavy_flag = atomicLoad(&heavy_seen);
    }
    if workgroupUniformLoad(&heavy_flag) != 0u {
        list_chunks(local, chunks, params.first + group.x * GROUP);
    }
    if mine && chunks == 0u && !giant {
        voxelize_columns(s, 0u, s.columns);
    }
}

// Record giant triangle `t` for `surface_giant`. The host marks no more giants than there are
// records; the check keeps the writes in the buffer whatever the marks say.
fn add_giant(t: u32, columns: u32) -> bool {
    let slot = atomicAdd(&giants[GIANT_RECORDS], 1u);
    if slot >= MAX_GIANTS {
        return false;
    }
    let size = giant_chunk_columns(columns);
    let blocks = giant_blocks(columns, size);
    let first = atomicAdd(&giants[GIANT_BLOCKS], blocks);
    // The workgroups for the blocks recorded so far, in rows of 65535.
    let total = first + blocks;
    atomicMax(&giants[0], min(total, 65535u));
    atomicMax(&giants[1], (total + 65534u) / 65535u);
    let at = GIANT_HEADER + 4u * slot;
    atomicStore(&giants[at], t);
    atomicStore(&giants[at + 1u], size);
    atomicStore(&giants[at + 2u], first);
    atomicStore(&giants[at + 3u], blocks);
    return true;
}

// Giant triangles, a workgroup per block of GIANT_BLOCK chunks, in the rows of workgroups
// their dispatch gives.
@compute @workgroup_size(GIANT_BLOCK)
fn surface_giant(@builtin(workgroup_id) group: vec3<u32>,
                 @builtin(local_invocation_index) local: u32,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let b = group.x + group.y * groups.x;
    let mine = GIANT_HEADER + 4u * local;
    let held = local < min(giant_list[GIANT_RECORDS], MAX_GIANTS);
    let r = giant_record_of(b, local, giant_list[mine + 2u], giant_list[mine + 3u], held);
    if r == 0u {
        return;
    }
    let at = GIANT_HEADER + 4u * (r - 1u);
    let size = giant_list[at + 1u];
    let chunk = (b - giant_list[at + 2u]) * GIANT_BLOCK + local;
    voxelize_columns(load(giant_list[at]), chunk * size, size);
}

@compute @workgroup_size(64)
fn surface_heavy(@builtin(global_invocation_id) id: vec3<u32>,
                 @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= min(atomicLoad(&work_count), params.capacity) {
        return;
    }
    let item = work[i];
    let s = load(item.x);
    voxelize_columns(s, item.y, chunk_columns(s.columns));
}

// One pass when the host has sorted the triangles (`encode_surface`, `encode_solid`): the
// first `count` triangles are light (their box's largest face has at most LIGHT columns), one
// per thread; the next `capacity` threads take one listed chunk of a heavy triangle each. No
// work-list counter, no second pass, no indirect dispatch. The host moved the triangles into
// grid-local coordinates (`to_grid` and `moved` are not read).
@compute @workgroup_size(LISTED_WORKGROUP)
fn surface_listed(@builtin(global_invocation_id) id: vec3<u32>,
                  @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * LISTED_WORKGROUP;
    if i < params.count {
        let s = load_local(params.first + i);
        voxelize_columns(s, 0u, s.columns);
    } else if i - params.count < params.capacity {
        let item = listed[i - params.count];
        voxelize_columns(load_local(item.x), item.y, listed_columns(triangles[3u * item.x]));
    }
}
