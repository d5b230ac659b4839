// Narrow-band nearest sub-voxel seed in three line passes (x, then y, then z), each scanning
// ±reach voxels of its axis: the separable scheme of Saito–Toriwaki / Meijster et al., cut to the
// band instead of running parabola envelopes over whole lines.
//
// For integer seeds the three minimisations compose to the exact nearest seed. Sub-voxel seeds
// sit up to √3/2 off their voxel's row, so a row's winner for one voxel centre may not be its
// winner for a voxel k rows away: about a third of the voxels in the band keep a seed up to
// about half a voxel farther than the nearest (tests/distance_3d_points.rs, against brute force
// and JFA+2). The metaball raymarch only sizes its steps with the field and refines hits on the
// density, so its surface error does not change (`cargo xtask bench metaball`). In exchange
// no pass gathers: `lines_x` reads its row of keys and points, and the later passes carry each
// candidate's position with it (8 bytes: its key's voxel and its offset from it). The z pass
// also resolves the distance, as `field_resolve.wgsl` would in a pass of its own.
//
// `reach` must cover the band: a point within `band` of a voxel has its key within
// floor(band + √3/2) voxels along every axis (the host sets it). Beyond the band voxels may keep
// no seed; the resolve clamps them to ±band.

import fieldkit::seed::{FAR, NO_SEED, key_index, pack_seed3, unpack_seed3};

struct LineParams {
    size: vec3<u32>,
    reach: u32,
    // The last pass resolves distances as `field_resolve.wgsl` does: world units per voxel,
    // the band (world units) they are clamped to, and the inside threshold for the sign.
    voxel_size: f32,
    band: f32,
    threshold: f32,
}

@group(0) @binding(0) var<uniform> params: LineParams;
@group(0) @binding(1) var<storage, read> keys: array<u32>;
@group(0) @binding(2) var<storage, read> points: array<vec4<f32>>;
// Candidates: x = the voxel holding the seed's key (packed as `pack_seed3`, NO_SEED for none),
// y = the seed's offset from that voxel's centre (`pack_offset`). 8 bytes, half a vec4.
@group(0) @binding(3) var<storage, read> src: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> dst: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> nearest: array<u32>;
@group(0) @binding(6) var volume: texture_3d<f32>;
@group(0) @binding(7) var distance: texture_storage_3d<r32float, write>;

// Offsets of up to one voxel per axis in 10 bits each: steps of 1/511 voxel, which only decide
// near-ties between seeds; the resolve measures the kept seed at full precision.
const OFFSET_STEPS: f32 = 511.0;

fn pack_offset(o: vec3<f32>) -> u32 {
    let q = vec3<u32>(round((clamp(o, vec3<f32>(-1.0), vec3<f32>(1.0)) + 1.0) * OFFSET_STEPS));
    return q.x | (q.y << 10u) | (q.z << 20u);
}

fn unpack_offset(w: u32) -> vec3<f32> {
    let q = vec3<u32>(w & 0x3ffu, (w >> 10u) & 0x3ffu, w >> 20u);
    return vec3<f32>(q) / OFFSET_STEPS - 1.0;
}

fn index_of(p: vec3<u32>) -> u32 {
    return (p.z * params.size.y + p.y) * params.size.x + p.x;
}

fn seed_point(c: vec2<u32>) -> vec3<f32> {
    return vec3<f32>(unpack_seed3(c.x)) + unpack_offset(c.y);
}

// Nearer wins; equal distances keep the smaller holder, so the result does not depend on scan
// order or adapter.
struct Best {
    c: vec2<u32>,
    d: f32,
}

fn consider(best: ptr<function, Best>, c: vec2<u32>, p: vec3<f32>) {
    if c.x == NO_SEED {
        return;
    }
    let e = seed_point(c) - p;
    let d = dot(e, e);
    if d < (*best).d || (d == (*best).d && c.x < (*best).c.x) {
        *best = Best(c, d);
    }
}

// Scans run outward from the voxel, both sides at once, and stop at the first distance k along
// the axis where no candidate can be nearer than the best so far: a candidate's seed lies
// within one voxel of its holder (offsets are clamped to ±1), so one held k voxels away is at
// least k − 1 away. The slack covers rounding in the computed distances, so a stop never skips
// a candidate that could win or tie: the result is the same as scanning all 2·reach + 1.
// Near the surface, where most of the band's voxels are, the scan ends after a few steps.
const SLACK: f32 = 1.001;

fn done(best_d: f32, k: u32) -> bool {
    let gap = f32(k) - SLACK;
    return gap > 0.0 && gap * gap > best_d;
}

// The row pass compares the seeds' own positions and packs only its winner.
struct RowBest {
    x: u32,
    point: vec3<f32>,
    d: f32,
}

fn offer_key(best: ptr<function, RowBest>, row: u32, x: u32, p: vec3<f32>) {
    let key = keys[row + x];
    if key == NO_SEED {
        return;
    }
    let point = points[key_index(key)].xyz;
    let e = point - p;
    let d = dot(e, e);
    if d < (*best).d || (d == (*best).d && x < (*best).x) {
        *best = RowBest(x, point, d);
    }
}

@compute @workgroup_size(32, 4, 2)
fn lines_x(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let p = vec3<f32>(id);
    var best = RowBest(0u, vec3<f32>(0.0), 3.4e38);
    let row = index_of(vec3<u32>(0u, id.y, id.z));
    offer_key(&best, row, id.x, p);
    for (var k = 1u; k <= params.reach && !done(best.d, k); k++) {
        if id.x >= k {
            offer_key(&best, row, id.x - k, p);
        }
        if id.x + k < params.size.x {
            offer_key(&best, row, id.x + k, p);
        }
    }
    var c = vec2<u32>(NO_SEED, 0u);
    if best.d < 3.4e38 {
        let holder = vec3<u32>(best.x, id.y, id.z);
        c = vec2<u32>(pack_seed3(holder), pack_offset(best.point - vec3<f32>(holder)));
    }
    dst[index_of(id)] = c;
}

// The best of the candidates along `axis` (1: y, 2: z) for voxel `id`.
fn scan(id: vec3<u32>, axis: u32) -> vec2<u32> {
    let p = vec3<f32>(id);
    var best = Best(vec2<u32>(NO_SEED, 0u), 3.4e38);
    consider(&best, src[index_of(id)], p);
    let c = id[axis];
    var q = id;
    for (var k = 1u; k <= params.reach && !done(best.d, k); k++) {
        if c >= k {
            q[axis] = c - k;
            consider(&best, src[index_of(q)], p);
        }
        if c + k < params.size[axis] {
            q[axis] = c + k;
            consider(&best, src[index_of(q)], p);
        }
    }
    return best.c;
}

@compute @workgroup_size(32, 4, 2)
fn lines_y(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    dst[index_of(id)] = scan(id, 1u);
}

// The last pass names the kept seed by its key, as JFA does, and resolves its distance as
// `field_resolve.wgsl`'s `resolve_points(_signed)` would (world units, from the seed's own
// position, clamped to ±band), which saves a pass over the grid. Returns the unsigned distance.
fn last_pass(id: vec3<u32>) -> f32 {
    let c = scan(id, 2u);
    var key = NO_SEED;
    var d = FAR;
    if c.x != NO_SEED {
        key = keys[index_of(vec3<u32>(unpack_seed3(c.x)))];
        d = length(points[key_index(key)].xyz - vec3<f32>(id)) * params.voxel_size;
    }
    nearest[index_of(id)] = key;
    return d;
}

fn store_distance(id: vec3<u32>, d: f32) {
    textureStore(distance, id, vec4<f32>(clamp(d, -params.band, params.band), 0.0, 0.0, 0.0));
}

@compute @workgroup_size(32, 4, 2)
fn lines_z(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    store_distance(id, last_pass(id));
}

// Signed: negative where the volume's value is ≥ threshold.
@compute @workgroup_size(32, 4, 2)
fn lines_z_signed(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let d = last_pass(id);
    let inside = textureLoad(volume, id, 0).r >= params.threshold;
    store_distance(id, select(d, -d, inside));
}
