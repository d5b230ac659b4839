// Exact EDT, column passes in global memory (y, then z; z, then y for a field split across
// bindings): the lower envelope of parabolas along each column, with integer separators
// (Meijster, Roerdink & Hesselink 2000) so every comparison is exact.
//
// Parallelism and coalescing: a workgroup of 256 threads takes 256 / BANDS neighbouring columns
// (consecutive x, so a warp's reads and writes are contiguous runs) and splits every column into
// BANDS bands, one thread each, as the Parallel Banding Algorithm does (Cao et al. 2010). The host
// picks BANDS so that there are enough threads (about 2^17, and at least 8 bands in 3D). A band
// builds the envelope of its own sites over the whole column, kept as a stack in `stack` at the
// band's own positions.
// After a barrier each thread answers the positions of its band: the nearest site is on some
// band's envelope, so it evaluates its own band's envelope and those of the other bands that are
// not already farther away than the best so far. Along one envelope the cost is unimodal and its
// minimum only moves forward with the query position, so a pointer per band walks each envelope
// once. The answer overwrites `nearest` in place (all of it was read before the barrier), or,
// for a field split across bindings, goes from the part it was read from into its slab.
//
// A site's cost at a query position is the full squared distance from that voxel to the site's
// seed (the seed of a site at position i lies in the plane through i, or off it in z too where
// y runs after z); separators are exact integers, from an f32 quotient corrected by its
// remainder (`separator`), so no integer division runs.
//
// Latency, not bandwidth, bounds a sequential walk: the build keeps four loads of its band in
// flight (raw loads: a row word becomes a site only when the build reaches it, so the next
// loads go out first) and the top two stack entries in registers;
// the query keeps its own band's current and next site in registers so it loads only on
// advance. The adjacent bands are consulted only near the band's ends, where their nearest site
// is almost always their last (below) or first (above): the first walk starts from that end,
// and each later one goes on from where the last stopped. Farther bands are looked up by
// binary search, keeping no per-band state (private arrays live in local memory, and
// zero-initialising them cost as much traffic as the field itself) but one mask of the
// column's bands that hold sites, so that empty bands are never visited.
//
// The last pass of a 3D transform can resolve distances as `field_resolve.wgsl` would, in the
// same sweep (`columns_resolve`, SIGNED or not): that saves reading the field again.

import fieldkit::seed::{NO_SEED, answer_distance, dist2, dist2_3, pack_seed3_bits, row_word_mark, separator, signed_at2, signed_at3_bits, unpack_seed2, unpack_seed3_bits};

// Where voxel (x, y, z) sits in a buffer: (x - origin.x) + row · (y - origin.y) + plane ·
// (z - origin.z). A whole field has origin 0, row = size.x and plane = size.x · size.y; a part of
// a field too large for one binding has its own (as in `edt_tile.wgsl`).
struct Placement {
    origin: vec3<u32>,
    row: u32,
    plane: u32,
}

struct ColumnParams {
    size: vec3<u32>,
    // The resolving entries: world units per voxel, and the band (world units) distances are
    // clamped to (FAR when none).
    voxel_size: f32,
    band: f32,
    // This dispatch's first column: the x of workgroup 0's first column and the other
    // coordinate (z for y columns, y for z columns) of workgroup row 0; and the x where its
    // columns end (size.x, or the end of its part of a field split across bindings).
    first: vec2<u32>,
    x_end: u32,
    // Where the pass reads its sites (`source`, `nearest` or, from the row words, nowhere) and
    // keeps its envelopes (`stack`), and where it writes its answers (`nearest`,
    // `nearest_inside`).
    src: Placement,
    dst: Placement,
}

@group(0) @binding(0) var<uniform> params: ColumnParams;
@group(0) @binding(1) var<storage, read_write> nearest: array<u32>;
@group(0) @binding(2) var<storage, read_write> stack: array<u32>;
// The inside seeds' field beside a SIGNED resolving pass (which runs in the outside seeds').
@group(0) @binding(3) var<storage, read> nearest_inside: array<u32>;
@group(0) @binding(4) var distance: texture_storage_3d<r32float, write>;
// The resolving entries of a 2D field write here.
@group(0) @binding(5) var distance_2d: texture_storage_2d<r32float, write>;
// What the pass reads where it is not `nearest` itself (SOURCE_APART): a part of a field too
// large for one binding. In place, a placeholder is bound here.
@group(0) @binding(6) var<storage, read> source: array<u32>;
// The row words (`edt_rows.wgsl`'s `row_words`) the pass makes its sites from where FROM_WORDS
// (the y pass where it is not the last, the z pass of a field split across bindings); a
// placeholder elsewhere.
@group(0) @binding(7) var<storage, read> words: array<vec2<u32>>;
// The resolving 3D pass's sweep (SCAN) writes, per workgroup, 1 where it answered the
// workgroup's columns and 0 where it left them to the pass after it (AFTER_SCAN); every entry
// is written each run. A placeholder elsewhere.
@group(0) @binding(8) var<storage, read_write> swept: array<u32>;

// The axis the columns run along (1: y, 2: z): an override, so that every choice between them
// is made when the pipeline is (read from the uniform, it cost 512³ 0.6% at 1% seeds and 2.5% at
// 1e-5 on the H100).
override AXIS: u32 = 1u;
// Every site lies in its column's plane across the other axis (z for a y column, y for a z
// column): the y pass before the z pass, and any pass from the row words. Its costs leave that
// coordinate out: the y pass at 512³ went from 1.439 to 1.346 ms on the H100, so these passes
// are bound by the instructions of their walks as much as by their loads.
override PLANAR: bool = false;
// 2D fields pack 16/16 bits (sides to 16384 keep every separator numerator in i32).
override PACK_2D: bool = false;
// Bands per column; 256 / BANDS columns per workgroup. At most MAX_BANDS, a power of two.
override BANDS: u32 = 8u;
// The pass reads `source`, not `nearest` (a field split across bindings).
override SOURCE_APART: bool = false;
// The pass makes each site from the row words as it reads it (3D only): the row pass's answers
// never go through memory.
override FROM_WORDS: bool = false;
// The pass reads its sites from `stack`, where the pass before it wrote them, and builds its
// envelopes over them in place (a band's envelope never holds more sites than it has read), so
// that its answers can go to `nearest` from the first: the resolving 3D pass that sweeps
// (SCAN, AFTER_SCAN), which then needs no look at its columns before it writes.
override IN_STACK: bool = false;
// 3D seeds' widths (`SeedPacking`): x in the low SEED_X_BITS bits, y in the next SEED_Y_BITS,
// z above; 11 and 11 for every grid up to 2048 × 2048 × 1024.
override SEED_X_BITS: u32 = 11u;
override SEED_Y_BITS: u32 = 11u;
// The resolving entries write signed distances: they run in the outside seeds' field with the
// inside seeds' field (`nearest_inside`) beside it. Unsigned, a placeholder is bound there.
override SIGNED: bool = false;

// "Nothing found yet": above any squared distance in range.
const FAR_D2: i32 = 0x7fffffff;

// Envelope size per (band, column) of this workgroup.
var<workgroup> band_size: array<u32, 256>;

// The resolving 3D entries' sweep: SCAN answers the workgroups whose every voxel has its nearest
// site within SCAN_REACH, through a ring of RING rows of the workgroup's columns (RING_CELLS =
// columns · RING), and the others as `sweep_end` says; AFTER_SCAN, the pass after it, builds
// the envelopes of those SCAN left to it, marked in `swept`.
override SCAN: bool = false;
override AFTER_SCAN: bool = false;
override RING: u32 = 64u;
override RING_CELLS: u32 = 1u;
var<workgroup> ring: array<u32, RING_CELLS>;
// The voxels of the workgroup's columns found with no site within SCAN_REACH (SCAN), or the
// workgroup's `swept` entry (AFTER_SCAN).
var<workgroup> far_sites: atomic<u32>;
// The voxels of the first SCAN_REACH rows whose own site is past SCAN_REACH in their plane
// (SCAN).
var<workgroup> thin_sites: atomic<u32>;

fn voxel(x: u32, other: u32, i: u32) -> vec3<i32> {
    if AXIS == 1u {
        return vec3<i32>(i32(x), i32(i), i32(other));
    }
    return vec3<i32>(i32(x), i32(other), i32(i));
}

fn cost(s: u32, p: vec3<i32>) -> i32 {
    if PACK_2D {
        return i32(dist2(unpack_seed2(s), p.xy));
    }
    if PLANAR {
        // The third coordinate of every site is the column's own.
        let d = unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS) - p;
        if AXIS == 1u {
            return d.x * d.x + d.y * d.y;
        }
        return d.x * d.x + d.z * d.z;
    }
    return dist2_3(unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS), p);
}

// A site's position along the column.
fn position(s: u32) -> i32 {
    if PACK_2D {
        return unpack_seed2(s).y;
    }
    // No vector indexed at run time: that can be lowered to a private array in memory.
    let p = unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS);
    return select(p.z, p.y, AXIS == 1u);
}

// A site's cost within the plane through its own position (the squared distance from the
// column there to its seed).
fn own_cost(s: u32, x: u32, other: u32) -> i32 {
    return cost(s, voxel(x, other, u32(position(s))));
}

// Nearest site of one band's envelope to `p`: the first k whose successor is not strictly
// nearer (costs along an envelope fall strictly to the minimum, then never fall again).
fn nearest_on(at: u32, size: u32, stride: u32, p: vec3<i32>) -> u32 {
    var lo = 0u;
    var hi = size - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if cost(stack[at + (mid + 1u) * stride], p) >= cost(stack[at + mid * stride], p) {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return stack[at + lo * stride];
}

// `nearest_on` from site k0 of a band's envelope, at or before the nearest site: walks forward
// while the next site is strictly nearer. Returns the site's index and the site.
fn nearest_on_from(at: u32, size: u32, stride: u32, p: vec3<i32>, k0: u32) -> vec2<u32> {
    var k = k0;
    var s = stack[at + k * stride];
    var d = cost(s, p);
    for (; k + 1u < size; k++) {
        let t = stack[at + (k + 1u) * stride];
        let e = cost(t, p);
        if e >= d {
            break;
        }
        s = t;
        d = e;
    }
    return vec2<u32>(k, s);
}

// `nearest_on` for a band that lies wholly before `p`: walks back from its last site while the
// one before it is as near or nearer, so it stops at the same site as the binary search.
// Returns the site's index and the site.
fn nearest_on_from_end(at: u32, size: u32, stride: u32, p: vec3<i32>) -> vec2<u32> {
    var k = size - 1u;
    var s = stack[at + k * stride];
    var d = cost(s, p);
    for (; k > 0u; k--) {
        let t = stack[at + (k - 1u) * stride];
        let e = cost(t, p);
        if e > d {
            break;
        }
        s = t;
        d = e;
    }
    return vec2<u32>(k, s);
}

// One band of one column, as the thread that owns it sees it.
struct Column {
    x: u32,
    other: u32,
    band: u32,
    lane: u32,
    columns_per_group: u32,
    // Column length, first element and element stride where the sites are read and the
    // envelopes kept (`source` or `nearest`, and `stack`), and where the answers go; the band
    // is [lo, hi).
    n: u32,
    base: u32,
    stride: u32,
    out: u32,
    out_stride: u32,
    band_len: u32,
    lo: u32,
    hi: u32,
    valid: bool,
}

fn place(p: Placement, v: vec3<u32>) -> u32 {
    return (v.x - p.origin.x) + p.row * (v.y - p.origin.y) + p.plane * (v.z - p.origin.z);
}

fn column_of(li: u32, wg: vec3<u32>) -> Column {
    var c: Column;
    c.columns_per_group = 256u / BANDS;
    c.lane = li % c.columns_per_group;
    c.band = li / c.columns_per_group;
    c.x = params.first.x + wg.x * c.columns_per_group + c.lane;
    c.other = params.first.y + wg.y;
    c.n = select(params.size.z, params.size.y, AXIS == 1u);
    c.valid = c.x < params.x_end;
    let start = vec3<u32>(voxel(min(c.x, params.x_end - 1u), c.other, 0u));
    c.base = place(params.src, start);
    c.stride = select(params.src.plane, params.src.row, AXIS == 1u);
    c.out = place(params.dst, start);
    c.out_stride = select(params.dst.plane, params.dst.row, AXIS == 1u);
    c.band_len = (c.n + BANDS - 1u) / BANDS;
    c.lo = min(c.n, c.band * c.band_len);
    c.hi = min(c.n, c.lo + c.band_len);
    return c;
}

// What a load of position i brings back: the row word that holds the voxel (FROM_WORDS), else
// the site itself in x. The build and the copy keep these raw loads in flight and make the
// site (`site_from`) only when they reach it: making it as it is loaded waits for the load.
fn fetch(c: Column, i: u32) -> vec2<u32> {
    if FROM_WORDS {
        let v = vec3<u32>(voxel(c.x, c.other, i));
        let count = (params.size.x + 31u) / 32u;
        return words[(v.z * params.size.y + v.y) * count + (v.x >> 5u)];
    }
    if SOURCE_APART {
        return vec2<u32>(source[c.base + i * c.stride], 0u);
    }
    if IN_STACK {
        return vec2<u32>(stack[c.base + i * c.stride], 0u);
    }
    return vec2<u32>(nearest[c.base + i * c.stride], 0u);
}

// The site at position i of the column from what `fetch` loaded for it.
fn site_from(c: Column, i: u32, loaded: vec2<u32>) -> u32 {
    if FROM_WORDS {
        let v = vec3<u32>(voxel(c.x, c.other, i));
        let near = row_word_mark(loaded, v.x);
        return select(NO_SEED, pack_seed3_bits(vec3<u32>(near - 1u, v.y, v.z), SEED_X_BITS, SEED_Y_BITS), near != 0u);
    }
    return loaded.x;
}

// A band's sites in order, with the next three positions' loads in flight: each site is
// requested three positions before it is needed, rotating through registers (an unrolled chunk
// would multiply the loop body and the registers it holds, and cut how many threads fit on a
// core; eight in flight made the y pass slower on the H100, 1.51 → 1.68 ms at 512³). What
// rotates is the raw load (`fetch`), not the site made from it.
struct Ahead {
    q0: vec2<u32>,
    q1: vec2<u32>,
    q2: vec2<u32>,
}

fn ahead_of(c: Column) -> Ahead {
    var a = Ahead(vec2<u32>(NO_SEED, 0u), vec2<u32>(NO_SEED, 0u), vec2<u32>(NO_SEED, 0u));
    if c.lo < c.hi {
        a.q0 = fetch(c, c.lo);
    }
    if c.lo + 1u < c.hi {
        a.q1 = fetch(c, c.lo + 1u);
    }
    if c.lo + 2u < c.hi {
        a.q2 = fetch(c, c.lo + 2u);
    }
    return a;
}

// What `fetch` loaded for position i; positions come one after another from the band's first.
fn next_load(c: Column, a: ptr<function, Ahead>, i: u32) -> vec2<u32> {
    var q3 = vec2<u32>(NO_SEED, 0u);
    if i + 3u < c.hi {
        q3 = fetch(c, i + 3u);
    }
    let q = (*a).q0;
    (*a).q0 = (*a).q1;
    (*a).q1 = (*a).q2;
    (*a).q2 = q3;
    return q;
}

// The site at position i; positions come one after another from the band's first.
fn next_site(c: Column, a: ptr<function, Ahead>, i: u32) -> u32 {
    return site_from(c, i, next_load(c, a, i));
}

// Build: Meijster's stack over this band's sites, valid for the whole column [0, n); returns
// its size. Every thread of the workgroup calls it, then records the size in `band_size`.
fn build(c: Column) -> u32 {
    // The top two sites' positions and own costs, and where the top one starts to be the
    // nearest, stay in registers: only a pop reads the stack.
    var top = -1;
    var p_top = 0;
    var g_top = 0;
    var t_top = 0;
    var p_below = 0;
    var g_below = 0;
    if !c.valid {
        return 0u;
    }
    let at = c.base + c.lo * c.stride;
    var ahead = ahead_of(c);
    for (var i = c.lo; i < c.hi; i++) {
        let loaded = next_load(c, &ahead, i);
        var s: u32;
        var gs: i32;
        if FROM_WORDS {
            // The site is the row's nearest mark: its own cost is its offset along x squared,
            // made from the mark, not unpacked from the site made of it (the y pass at 512³
            // with 1e-5 seeds on the H100: 0.816 → 0.791 ms; with 1% seeds the same).
            let near = row_word_mark(loaded, c.x);
            if near == 0u {
                continue;
            }
            let dx = i32(near) - 1 - i32(c.x);
            gs = dx * dx;
            let v = vec3<u32>(voxel(c.x, c.other, i));
            s = pack_seed3_bits(vec3<u32>(near - 1u, v.y, v.z), SEED_X_BITS, SEED_Y_BITS);
        } else {
            s = loaded.x;
            if s == NO_SEED {
                continue;
            }
            gs = own_cost(s, c.x, c.other);
        }
        let pi = i32(i);
        loop {
            if top < 0 || g_top + (p_top - t_top) * (p_top - t_top) <= gs + (pi - t_top) * (pi - t_top) {
                break;
            }
            top -= 1;
            p_top = p_below;
            g_top = g_below;
            t_top = 0;
            if top > 0 {
                let below = stack[at + u32(top - 1) * c.stride];
                p_below = position(below);
                g_below = own_cost(below, c.x, c.other);
                t_top = separator(p_below, g_below, p_top, g_top);
            }
        }
        var t = 0;
        if top >= 0 {
            t = separator(p_top, g_top, pi, gs);
        }
        if t < i32(c.n) {
            top += 1;
            p_below = p_top;
            g_below = g_top;
            p_top = pi;
            g_top = gs;
            t_top = t;
            stack[at + u32(top) * c.stride] = s;
        }
    }
    return u32(top + 1);
}

// The query's walk along its own band's envelope: the current site and the next. And where the
// last walks along the adjacent bands' envelopes stopped: the nearest site's index never falls
// as the position rises, so each goes on from there (the band below starts unset, BELOW_UNSET,
// and is walked back from its last site the first time).
struct Walk {
    k: u32,
    size: u32,
    at: u32,
    s: u32,
    next: u32,
    k_up: u32,
    k_dn: u32,
    // The column's bands that hold sites, above this one and below it (bit b: band b).
    up: u32,
    dn: u32,
}

const BELOW_UNSET: u32 = 0xffffffffu;

fn walk_of(c: Column, size: u32) -> Walk {
    let at = c.base + c.lo * c.stride;
    var held = 0u;
    for (var b = 0u; b < BANDS; b++) {
        held |= u32(band_size[b * c.columns_per_group + c.lane] > 0u) << b;
    }
    return Walk(
        0u,
        size,
        at,
        select(NO_SEED, stack[at], size > 0u),
        select(NO_SEED, stack[at + c.stride], size > 1u),
        0u,
        BELOW_UNSET,
        held & ~((2u << c.band) - 1u),
        held & ((1u << c.band) - 1u),
    );
}

// The nearest site to position `i` of this band, against every band's envelope, nearest bands
// first. Positions must come in increasing order. Returns the site and its squared distance.
// `carry`: the adjacent bands' walks go on from where the last stopped (`Walk`); else each
// starts from the band's near end. Carrying took the y pass from 1.506 to 1.460 ms at 512³ on
// the H100 but the resolving passes, which hold more registers and whose answers are nearer
// (fewer walks), from 1.913 to 1.929 (z) and 1.110 to 1.121 (2D, 8192²): only `columns`
// carries.
fn query(c: Column, walk: ptr<function, Walk>, i: u32, carry: bool) -> vec2<u32> {
    let p = voxel(c.x, c.other, i);
    var best = NO_SEED;
    var best_d = FAR_D2;
    if (*walk).size > 0u {
        var d = cost((*walk).s, p);
        while (*walk).k + 1u < (*walk).size {
            let d_next = cost((*walk).next, p);
            if d_next >= d {
                break;
            }
            (*walk).k += 1u;
            (*walk).s = (*walk).next;
            d = d_next;
            if (*walk).k + 1u < (*walk).size {
                (*walk).next = stack[(*walk).at + ((*walk).k + 1u) * c.stride];
            }
        }
        best = (*walk).s;
        best_d = d;
    }
    // Other bands outward, only those that hold sites (`Walk::up`, `Walk::dn`): above, then
    // below. A band whose nearest position is already as far as the best found cannot win, and
    // the ones beyond it are farther still. (Visiting every band outward, both sides at once,
    // and skipping the empty ones, took the y pass from the words 1.184 ms at 512³ with 1e-5
    // seeds on the H100, where most bands are empty and each position looked through all of
    // them, against 0.816 with the mask; 0.192 against 0.188 ms at 256³ with 1% seeds. The
    // split field's z pass from the words, n = 1024, lost by it: 3.53 → 3.64 ms a part.)
    // The two loops end alike; folded into one loop, the y pass took 1.329 → 1.386 ms at 512³
    // with 1% seeds and 0.789 → 0.873 with 1e-5 (docs/distance.md), so each side keeps its own.
    var up = (*walk).up;
    while up != 0u {
        let b = firstTrailingBit(up);
        let b_lo = b * c.band_len;
        if i32((b_lo - i) * (b_lo - i)) >= best_d {
            break;
        }
        up &= up - 1u;
        let size = band_size[b * c.columns_per_group + c.lane];
        let at = c.base + b_lo * c.stride;
        var s: u32;
        if b == c.band + 1u {
            let found = nearest_on_from(at, size, c.stride, p, select(0u, (*walk).k_up, carry));
            (*walk).k_up = found.x;
            s = found.y;
        } else {
            s = nearest_on(at, size, c.stride, p);
        }
        let d = cost(s, p);
        if d < best_d {
            best = s;
            best_d = d;
        }
    }
    var dn = (*walk).dn;
    while dn != 0u {
        let b = firstLeadingBit(dn);
        let b_hi = (b + 1u) * c.band_len - 1u;
        if i32((i - b_hi) * (i - b_hi)) >= best_d {
            break;
        }
        dn &= ~(1u << b);
        let size = band_size[b * c.columns_per_group + c.lane];
        let at = c.base + b * c.band_len * c.stride;
        var s: u32;
        if b + 1u == c.band {
            var found: vec2<u32>;
            if (*walk).k_dn == BELOW_UNSET || !carry {
                found = nearest_on_from_end(at, size, c.stride, p);
            } else {
                found = nearest_on_from(at, size, c.stride, p, (*walk).k_dn);
            }
            (*walk).k_dn = found.x;
            s = found.y;
        } else {
            s = nearest_on(at, size, c.stride, p);
        }
        let d = cost(s, p);
        if d < best_d {
            best = s;
            best_d = d;
        }
    }
    return vec2<u32>(best, u32(best_d));
}

// The last pass with dense seeds, as `edt_tile.wgsl`'s `scan` does it but with the columns
// streamed through a ring of rows (SCAN): each voxel looks outward along its column, at most
// SCAN_REACH rows either side, until the step's square alone is no less than the best found (a
// site farther along costs at least that). Where the best found is within SCAN_REACH (its squared
// distance at most SCAN_REACH²) the answer is exact: a site past SCAN_REACH rows, or one whose
// cost within its own plane is past SCAN_REACH², costs more, so the ring need not hold those. At
// 1% random seeds every voxel's nearest seed is that near, at the grid's corners too (an eighth of
// a ball of 24 voxels holds about 72 seeds). The columns go once through the ring, BANDS rows a
// step, the ring holding SCAN_REACH rows either side of the rows answered; a warp answers 32
// neighbouring columns at one position, a row read into the ring SCAN_REACH rows before it is
// answered. The sites come from `stack` (IN_STACK), or from `source` (SOURCE_APART: the y pass of
// a field split across bindings, which reads the part the z pass wrote), and the answers go to
// `nearest` as they are found, so nothing is read twice. A workgroup that finds a voxel whose best is farther stops at
// the next step and builds the envelopes over its columns, whose sites it has not touched (what it
// wrote, they overwrite): in the same dispatch where few voxels of the step were far (a pass of
// their own would wait for its slowest workgroup, ~0.13 ms on the H100 at 512³), else in the pass
// after (AFTER_SCAN), whose entry point holds no sweep and so takes fewer registers. Sparse seeds
// go to the pass after from the first rows (`sweep_starts`). (Until 2026-11-27 the workgroup first
// read its columns to find whether every voxel's own site was within SCAN_REACH, the answers going
// in place: a quarter of a millisecond at 512³ on the H100, and workgroups at the grid's edges,
// where part of the disc lies outside, left to the envelopes.)
const SCAN_REACH: u32 = 24u;

// The site at position i of the column at x (NO_SEED past the grid).
fn site_at(x: u32, other: u32, n: u32, i: u32) -> u32 {
    if x >= params.x_end || i >= n {
        return NO_SEED;
    }
    let at = place(params.src, vec3<u32>(voxel(x, other, i)));
    if SOURCE_APART {
        return source[at];
    }
    if IN_STACK {
        return stack[at];
    }
    return nearest[at];
}

// The workgroup's entry in `swept`.
fn swept_entry(wg: vec3<u32>) -> u32 {
    let columns = 256u / BANDS;
    return wg.y * ((params.x_end - params.first.x + columns - 1u) / columns) + wg.x;
}

// What a resolving 3D dispatch does with the workgroup's columns after its sweep, if any (the
// same answer in every thread): nothing more (DONE) where every voxel was answered; else their
// envelopes, HERE or LATER (AFTER_SCAN), as `sweep_end` says.
const HERE: u32 = 1u;
const LATER: u32 = 2u;
const DONE: u32 = 3u;

// AFTER_SCAN's verdict: the envelopes of the workgroups SCAN left to it (marked in `swept`),
// nothing for the others. Called by every thread: it holds the barrier.
fn rest_verdict(li: u32, wg: vec3<u32>) -> u32 {
    if li == 0u {
        atomicStore(&far_sites, swept[swept_entry(wg)]);
    }
    return select(HERE, DONE, workgroupUniformLoad(&far_sites) != 0u);
}

// SCAN's verdict once its sweep ends, from the far voxels of the step that stopped it: DONE
// where none stopped it; LATER where at least a sixteenth of that step's voxels were far, else
// HERE (a few near the grid's edges or a seed-free region); LATER where it did not start
// (`sweep_starts`). Marked in `swept` for AFTER_SCAN. Called by every thread: it holds the
// barrier.
fn sweep_end(li: u32, wg: vec3<u32>, started: bool) -> u32 {
    var verdict = LATER;
    if started {
        let far = workgroupUniformLoad(&far_sites);
        verdict = DONE;
        if far != 0u {
            verdict = select(HERE, LATER, far * 16u >= 256u);
        }
    }
    if li == 0u {
        swept[swept_entry(wg)] = u32(verdict != LATER);
    }
    return verdict;
}

// Whether the sweep goes on past its first rows (the same answer in every thread): not where at
// least a 64th of their voxels have their own site past SCAN_REACH in their plane. Those are
// sparse seeds, where the sweep's looks would go far (or stop it) and the envelopes are faster:
// on the H100 at 512³ with 0.1% seeds, sweeping every workgroup took the z pass from 1.81 to
// 1.99 ms, and at 1e-5 trying the first step 0.02 to 0.28; a sixteenth, not a 64th, left the
// few 0.1% workgroups whose first rows had seeds near to sweep whole columns looking far (the
// sweep's dispatch 0.175 ms against 0.039, the transform 3.109 against 2.987). At 1% seeds a
// workgroup at a corner of the grid expects fewer than one of the 12 (its corner column's voxels
// each about 1%, with a quarter of the disc inside; its edge columns' about 0.01%). Called by
// every thread: it holds the barrier.
fn sweep_starts(sw: Sweep) -> bool {
    let counted = min(sw.n, SCAN_REACH) * (256u / BANDS);
    return workgroupUniformLoad(&thin_sites) * 64u < counted;
}

// One thread's place in the sweep: its column (lane, x) and row of each step, and the site it
// loaded for the next step.
struct Sweep {
    lane: u32,
    x: u32,
    other: u32,
    n: u32,
    row: u32,
    next: u32,
}

fn ring_cell(sw: Sweep, i: u32) -> u32 {
    return (i & (RING - 1u)) * (256u / BANDS) + sw.lane;
}

// The thread's column and first row in the sweep (nothing loaded yet).
fn sweep_place(li: u32, wg: vec3<u32>) -> Sweep {
    var sw: Sweep;
    let columns = 256u / BANDS;
    sw.lane = li % columns;
    sw.row = li / columns;
    sw.x = params.first.x + wg.x * columns + sw.lane;
    sw.other = params.first.y + wg.y;
    sw.n = select(params.size.z, params.size.y, AXIS == 1u);
    return sw;
}

// A site as the sweep's ring holds it: its squared distance from the column within its own
// plane (the low 10 bits) and its offsets from the column along that plane's two axes, + 32 (6
// bits each, above), so that a step's cost is one add. Every site the ring holds lies in the
// plane of its own row (the pass before it answered within planes); one past SCAN_REACH of the
// column in that plane, and NO_SEED, are held as the largest cost (RING_COST, above SCAN_REACH²:
// never the answer of a voxel the sweep keeps), so the rest fit (576 < 2^10, |offset| ≤ 24 <
// 32).
const RING_COST: u32 = 0x3ffu;

fn ring_entry(sw: Sweep, s: u32) -> u32 {
    let d = unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS) - voxel(sw.x, sw.other, 0u);
    let v = select(d.y, d.z, AXIS == 1u);
    let g = d.x * d.x + v * v;
    if s == NO_SEED || g > i32(SCAN_REACH * SCAN_REACH) {
        return RING_COST;
    }
    return u32(g) | (u32(d.x + 32) << 10u) | (u32(v + 32) << 16u);
}

// The site a ring entry at position i of the column holds.
fn ring_site(sw: Sweep, e: u32, i: u32) -> u32 {
    let x = sw.x + ((e >> 10u) & 63u) - 32u;
    let other = sw.other + ((e >> 16u) & 63u) - 32u;
    return pack_seed3_bits(vec3<u32>(voxel(x, other, i)), SEED_X_BITS, SEED_Y_BITS);
}

// Start the sweep: the first SCAN_REACH rows into the ring (counted in `thin_sites`), and the
// first step's row loaded. Called by every thread: it holds the barrier.
fn sweep_of(li: u32, wg: vec3<u32>) -> Sweep {
    var sw = sweep_place(li, wg);
    if li == 0u {
        atomicStore(&far_sites, 0u);
        atomicStore(&thin_sites, 0u);
    }
    workgroupBarrier();
    sw.next = site_at(sw.x, sw.other, sw.n, SCAN_REACH + sw.row);
    var thin = 0u;
    for (var i = sw.row; i < SCAN_REACH; i += BANDS) {
        let e = ring_entry(sw, site_at(sw.x, sw.other, sw.n, i));
        ring[ring_cell(sw, i)] = e;
        thin += u32(e == RING_COST && i < sw.n && sw.x < params.x_end);
    }
    if thin != 0u {
        atomicAdd(&thin_sites, thin);
    }
    return sw;
}

// Step t: the rows SCAN_REACH ahead go into the ring and the next step's are loaded. Returns
// the far voxels found so far (the same in every thread: the sweep stops at the first step that
// sees any). The slots a step writes are those of rows no thread reads in the step before (RING
// ≥ 2 · (SCAN_REACH + BANDS)), so one barrier a step does. Called by every thread.
fn sweep_advance(sw: ptr<function, Sweep>, t: u32) -> u32 {
    ring[ring_cell(*sw, t * BANDS + SCAN_REACH + (*sw).row)] = ring_entry(*sw, (*sw).next);
    let far = workgroupUniformLoad(&far_sites);
    (*sw).next = site_at((*sw).x, (*sw).other, (*sw).n, (t + 1u) * BANDS + SCAN_REACH + (*sw).row);
    return far;
}

// The answer at step t for this thread's position t · BANDS + row (within the column): the
// nearest site the ring holds and its squared distance, which is exact where it is at most
// SCAN_REACH² (and the voxel far where it is not). No look goes past SCAN_REACH rows, where the
// ring holds other rows (a site there could not make a far voxel near: the step's square alone
// is more than SCAN_REACH²).
fn sweep_answer(sw: Sweep, t: u32) -> vec2<u32> {
    let i = t * BANDS + sw.row;
    var best = ring[ring_cell(sw, i)];
    var best_d = i32(best & RING_COST);
    var best_at = i;
    for (var r = 1u; r <= SCAN_REACH && i32(r * r) < best_d; r++) {
        if r <= i {
            let e = ring[ring_cell(sw, i - r)];
            let d = i32((e & RING_COST) + r * r);
            if d < best_d {
                best = e;
                best_d = d;
                best_at = i - r;
            }
        }
        if i + r < sw.n {
            let e = ring[ring_cell(sw, i + r)];
            let d = i32((e & RING_COST) + r * r);
            if d < best_d {
                best = e;
                best_d = d;
                best_at = i + r;
            }
        }
    }
    return vec2<u32>(ring_site(sw, best, best_at), u32(best_d));
}

// The voxel the thread answers at step t (xyz) and its position along the column (w).
fn sweep_voxel(sw: Sweep, t: u32) -> vec4<u32> {
    let i = t * BANDS + sw.row;
    return vec4<u32>(vec3<u32>(voxel(sw.x, sw.other, i)), i);
}

// A distance clamped to the band.
fn banded(d: f32) -> f32 {
    return clamp(d, -params.band, params.band);
}

// Every entry starts the same: build this band's envelope, publish its size, wait for the
// workgroup, and start the walk along the own envelope. Called by every thread (it holds the
// barriers); the caller returns if the column is past the grid.
struct Started {
    c: Column,
    walk: Walk,
}

fn start(li: u32, wg: vec3<u32>) -> Started {
    let c = column_of(li, wg);
    let size = build(c);
    band_size[c.band * c.columns_per_group + c.lane] = size;
    storageBarrier();
    workgroupBarrier();
    return Started(c, walk_of(c, size));
}

@compute @workgroup_size(32, 8)
fn columns(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let s = start(li, wg);
    let c = s.c;
    if !c.valid {
        return;
    }
    // In place, the answer overwrites `nearest`; all of it was read before the barrier.
    var walk = s.walk;
    for (var i = c.lo; i < c.hi; i++) {
        nearest[c.out + i * c.out_stride] = query(c, &walk, i, true).x;
    }
}

// The floor of a global column pass, for `bench distance` to compare with: each band's sites
// read as the pass reads them (from the field, a part, or the row words) and written where the
// pass writes its answers, with no envelope and no stack.
@compute @workgroup_size(32, 8)
fn columns_copy(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let c = column_of(li, wg);
    if !c.valid {
        return;
    }
    var ahead = ahead_of(c);
    for (var i = c.lo; i < c.hi; i++) {
        nearest[c.out + i * c.out_stride] = next_site(c, &ahead, i);
    }
}

// `columns_copy` with the distance store of a resolving 3D pass as well (a value converted from
// the site, no distance made): the floor of `columns_resolve`, whose stores include it.
@compute @workgroup_size(32, 8)
fn columns_copy_resolve(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let c = column_of(li, wg);
    if !c.valid {
        return;
    }
    var ahead = ahead_of(c);
    for (var i = c.lo; i < c.hi; i++) {
        let s = next_site(c, &ahead, i);
        nearest[c.out + i * c.out_stride] = s;
        textureStore(distance, vec3<u32>(voxel(c.x, c.other, i)), vec4<f32>(f32(s), 0.0, 0.0, 0.0));
    }
}

// Voxel p's answer at `at`: its site, and its distance clamped to the band; SIGNED, as
// `field_resolve.wgsl`'s `resolve_signed` gives it from both fields.
fn resolve_at(p: vec3<u32>, at: u32, found: vec2<u32>) {
    nearest[at] = found.x;
    var d = answer_distance(found, params.voxel_size);
    if SIGNED {
        d = signed_at3_bits(nearest_inside[at], p, d, found.x, params.voxel_size, SEED_X_BITS, SEED_Y_BITS);
    }
    textureStore(distance, p, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
}

// `columns`, and the distance (SIGNED or not) of every voxel it answers (3D).
@compute @workgroup_size(32, 8)
fn columns_resolve(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    var verdict = HERE;
    if SCAN {
        var sw = sweep_of(li, wg);
        let started = sweep_starts(sw);
        if started {
            for (var t = 0u; t * BANDS < sw.n; t++) {
                if sweep_advance(&sw, t) != 0u {
                    break;
                }
                let p = sweep_voxel(sw, t);
                if p.x < params.x_end && p.w < sw.n {
                    let found = sweep_answer(sw, t);
                    if found.y > SCAN_REACH * SCAN_REACH {
                        atomicAdd(&far_sites, 1u);
                    } else {
                        resolve_at(p.xyz, place(params.dst, p.xyz), found);
                    }
                }
            }
        }
        verdict = sweep_end(li, wg, started);
    } else if AFTER_SCAN {
        verdict = rest_verdict(li, wg);
    }
    if verdict != HERE {
        return;
    }
    let s = start(li, wg);
    let c = s.c;
    if !c.valid {
        return;
    }
    var walk = s.walk;
    for (var i = c.lo; i < c.hi; i++) {
        resolve_at(vec3<u32>(voxel(c.x, c.other, i)), c.out + i * c.out_stride, query(c, &walk, i, false));
    }
}

// `columns` in a 2D field, and the distance (SIGNED or not) of every pixel it answers.
@compute @workgroup_size(32, 8)
fn columns_resolve_2d(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let s = start(li, wg);
    let c = s.c;
    if !c.valid {
        return;
    }
    var walk = s.walk;
    for (var i = c.lo; i < c.hi; i++) {
        let found = query(c, &walk, i, false);
        let at = c.out + i * c.out_stride;
        nearest[at] = found.x;
        let p = vec3<u32>(voxel(c.x, c.other, i)).xy;
        var d = answer_distance(found, params.voxel_size);
        if SIGNED {
            d = signed_at2(nearest_inside[at], p, d, found.x, params.voxel_size);
        }
        textureStore(distance_2d, p, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
    }
}
