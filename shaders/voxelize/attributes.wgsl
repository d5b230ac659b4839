// Voxel attributes: the colour and normal of the triangles that touch each voxel, averaged
// (OpenGL Insights' voxelization, Crassin & Green, made deterministic). Every triangle adds its
// attributes at each voxel it touches (the same conservative test as `voxelize/surface`) into
// integer sums with atomicAdd, one record per occupied voxel (the indices from
// `voxelize/compact`); `resolve` divides. Integer sums do not depend on the order threads run
// in, so two runs give identical output, which the write-up's compare-exchange loop on an
// RGBA8 texel does not.
//
// A triangle's attribute at a voxel is its vertex attributes interpolated at the voxel centre's
// closest point on the triangle's plane (barycentrics clamped to the triangle),
// written as a0 + b1·(a1 − a0) + b2·(a2 − a0) so a constant attribute stays exact.

import fieldkit::triangle_box::{
    GIANT_BLOCK, GIANT_HEADER, GIANT_RECORDS, LIGHT, MAX_GIANTS, Setup, chunk_columns, column_at,
    column_coords, giant_record_of, next_column, overlaps_in, setup,
};
import package::shared::voxel_attribute::{SUMS, average, closest_weights, contribution, corner_colour, corner_normal, corner_uv};

struct AttributeParams {
    grid: vec3<u32>,
    first: u32,
    count: u32,
    slack: f32,
    // Entries the heavy work list holds.
    capacity: u32,
    // Words in the occupancy bitset.
    words: u32,
    // 1: the colour is the corners' colour × the albedo texture at the corners' texture
    // coordinates, interpolated as the colour is.
    textured: u32,
}

@group(0) @binding(0) var<uniform> params: AttributeParams;
// Three vertices per triangle, grid-local (w unused).
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Two per triangle corner: (RGBA8 colour, the normal's x, y, z as f32 bits), then (u, v as f32
// bits, 0, 0).
@group(0) @binding(2) var<storage, read> corners: array<vec4<u32>>;
// The surface pass's bitset and `voxelize/compact`'s offsets.
@group(0) @binding(3) var<storage, read> occupancy: array<u32>;
@group(0) @binding(4) var<storage, read> word_offsets: array<u32>;
@group(0) @binding(5) var<storage, read> block_offsets: array<u32>;
// The surface pass's heavy triangles, (triangle, first column) per chunk.
@group(0) @binding(6) var<storage, read> work: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read> work_count: u32;
// SUMS words per occupied voxel: colour r, g, b, a (COLOR_SCALE per 8-bit level), normal x, y,
// z (NORMAL_SCALE per unit, two's complement), triangles.
@group(0) @binding(8) var<storage, read_write> sums: array<atomic<u32>>;
// Per occupied voxel in voxel order: (voxel index, RGBA8 colour, octahedral normal as two
// snorm16 or NO_NORMAL, triangles).
@group(0) @binding(9) var<storage, read_write> voxels: array<vec4<u32>>;
// The albedo (a 1×1 stand-in unless `textured`), sampled with repeat and linear filtering at
// (u, 1 − v): OBJ's v runs up, an image's rows down.
@group(0) @binding(10) var albedo: texture_2d<f32>;
@group(0) @binding(11) var albedo_sampler: sampler;
// The surface pass's giant triangles: its records and their dispatch arguments.
@group(0) @binding(12) var<storage, read> giants: array<u32>;

const BLOCK_WORDS: u32 = 1024u;

fn compact_index(i: u32) -> u32 {
    let w = i / 32u;
    let below = occupancy[w] & ((1u << (i % 32u)) - 1u);
    return block_offsets[w / BLOCK_WORDS] + word_offsets[w] + countOneBits(below);
}

fn add_voxel(s: Setup, t: u32, p: vec3<i32>) {
    let b = closest_weights(s, triangles[3u * t].xyz, triangles[3u * t + 1u].xyz,
                            triangles[3u * t + 2u].xyz, p);
    let c0 = corners[6u * t];
    let c1 = corners[6u * t + 2u];
    let c2 = corners[6u * t + 4u];
    var colour = corner_colour(b, c0.x, c1.x, c2.x);
    if params.textured != 0u {
        let uv = corner_uv(b, corners[6u * t + 1u].xy, corners[6u * t + 3u].xy,
                           corners[6u * t + 5u].xy);
        colour *= textureSampleLevel(albedo, albedo_sampler, uv, 0.0);
    }
    let n = corner_normal(b, bitcast<vec3<f32>>(c0.yzw), bitcast<vec3<f32>>(c1.yzw),
                          bitcast<vec3<f32>>(c2.yzw), s.n);
    let add = contribution(colour, n);
    let rgba = add.rgba;
    let nq = add.normal;
    let g = vec3<i32>(params.grid);
    let at = SUMS * compact_index(u32((p.z * g.y + p.y) * g.x + p.x));
    atomicAdd(&sums[at], rgba.x);
    atomicAdd(&sums[at + 1u], rgba.y);
    atomicAdd(&sums[at + 2u], rgba.z);
    atomicAdd(&sums[at + 3u], rgba.w);
    atomicAdd(&sums[at + 4u], nq.x);
    atomicAdd(&sums[at + 5u], nq.y);
    atomicAdd(&sums[at + 6u], nq.z);
    atomicAdd(&sums[at + 7u], 1u);
}

fn load(t: u32) -> Setup {
    return setup(triangles[3u * t].xyz, triangles[3u * t + 1u].xyz, triangles[3u * t + 2u].xyz,
                 vec3<i32>(params.grid), params.slack, false);
}

fn accumulate_columns(s: Setup, t: u32, first: u32, count: u32) {
    let end = min(first + count, s.columns);
    var square = column_coords(s, first);
    for (var j = first; j < end; j++) {
        let c = column_at(s, square.x, square.y);
        square = next_column(s, square);
        for (var z = c.k0; z < c.k1; z++) {
            let p = c.p + s.ek * z;
            if overlaps_in(s, c, z, false) {
                add_voxel(s, t, p);
            }
        }
    }
}

// Light triangles, one per thread; heavy ones (more than LIGHT columns) are in the work list.
@compute @workgroup_size(64)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let t = params.first + id.x;
    let s = load(t);
    if s.columns <= LIGHT {
        accumulate_columns(s, t, 0u, s.columns);
    }
}

// The surface pass's work list, in the rows of workgroups its dispatch arguments give.
@compute @workgroup_size(64)
fn accumulate_heavy(@builtin(global_invocation_id) id: vec3<u32>,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= min(work_count, params.capacity) {
        return;
    }
    let item = work[i];
    let s = load(item.x);
    accumulate_columns(s, item.x, item.y, chunk_columns(s.columns));
}

// The surface pass's giant triangles, a workgroup per block of their chunks.
@compute @workgroup_size(GIANT_BLOCK)
fn accumulate_giant(@builtin(workgroup_id) group: vec3<u32>,
                    @builtin(local_invocation_index) local: u32,
                    @builtin(num_workgroups) groups: vec3<u32>) {
    let b = group.x + group.y * groups.x;
    let mine = GIANT_HEADER + 4u * local;
    let held = local < min(giants[GIANT_RECORDS], MAX_GIANTS);
    let r = giant_record_of(b, local, giants[mine + 2u], giants[mine + 3u], held);
    if r == 0u {
        return;
    }
    let at = GIANT_HEADER + 4u * (r - 1u);
    let t = giants[at];
    let size = giants[at + 1u];
    let chunk = (b - giants[at + 2u]) * GIANT_BLOCK + local;
    accumulate_columns(load(t), t, chunk * size, size);
}

// One bitset word per thread (a 2D dispatch: rows of 65535 workgroups).
@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>,
           @builtin(num_workgroups) groups: vec3<u32>) {
    let w = id.y * groups.x * 64u + id.x;
    if w >= params.words {
        return;
    }
    var bits = occupancy[w];
    var j = block_offsets[w / BLOCK_WORDS] + word_offsets[w];
    while bits != 0u {
        let bit = firstTrailingBit(bits);
        bits &= bits - 1u;
        let at = SUMS * j;
        let n = atomicLoad(&sums[at + 7u]);
        let avg = average(vec4<u32>(atomicLoad(&sums[at]), atomicLoad(&sums[at + 1u]),
                                    atomicLoad(&sums[at + 2u]), atomicLoad(&sums[at + 3u])),
                          vec3<u32>(atomicLoad(&sums[at + 4u]), atomicLoad(&sums[at + 5u]),
                                    atomicLoad(&sums[at + 6u])), n);
        let colour = avg.x;
        let packed_normal = avg.y;
        voxels[j] = vec4<u32>(w * 32u + bit, colour, packed_normal, n);
        j++;
    }
}
