// Exact EDT, column passes held in workgroup memory: the same banded lower envelopes as
// `edt_columns.wgsl` (Meijster, Roerdink & Hesselink 2000; bands as in Cao et al.'s PBA), with a
// tile of 2^lg_columns adjacent columns × the whole column loaded into workgroup memory once.
//
// Path of the data: the tile is read from `nearest` once (consecutive x, so a warp reads whole
// runs of a row), every band builds its envelope in place in the tile (the stack never passes the
// element being read), one barrier, then each thread answers its band's positions from its own
// envelope and from neighbour bands only while their nearest position is nearer than the best so
// far, and writes each answer once. Nothing else touches global memory: the global path's
// dependent loads through a stack in `nearest`'s neighbour buffer become workgroup loads.
//
// The host sizes the tile from `max_compute_workgroup_storage_size` (`CELLS`, an override, so a
// workgroup declares only what its columns need) and falls back to `edt_columns.wgsl` where not
// even four columns fit.
//
// No integer division or modulo runs per element: the tile index is `k + (k >> lg_band)` (one pad
// cell per band, and a column stride that keeps a warp's threads in different banks), columns and bands come from
// shifts and masks, and the separator is an f32 division corrected to the exact integer floor.

import fieldkit::seed::{NO_SEED, answer_distance, pack_seed3_bits, row_word_mark, separator, signed_at2, signed_at3_bits, unpack_seed2, unpack_seed3_bits};

// Where voxel (x, y, z) sits in a buffer: (x - origin.x) + row · (y - origin.y) + plane ·
// (z - origin.z). A whole field has origin 0, row = size.x and plane = size.x · size.y; a part of
// a field too large for one binding has its own.
struct Placement {
    origin: vec3<u32>,
    row: u32,
    plane: u32,
}

struct TileParams {
    size: vec3<u32>,
    // The resolving entries: world units per voxel, and the band (world units) distances are
    // clamped to (FAR when none).
    voxel_size: f32,
    band: f32,
    // Columns per tile = 1 << lg_columns; bands per column = 256 >> lg_columns.
    lg_columns: u32,
    // Positions per band = 1 << lg_band.
    lg_band: u32,
    // Bands that hold positions: ceil(n / band length).
    bands: u32,
    // Tile cells per column: n + bands (one pad cell per band), rounded up to 32 / columns
    // (mod 32) so that no two threads of a warp share a bank, loading or sweeping.
    column_cells: u32,
    // This dispatch's first column: the x of workgroup 0's first column and the other
    // coordinate (z for y columns, y for z columns) of workgroup row 0; and the x where its
    // columns end (size.x, or the end of its part of a field split across bindings).
    first: vec2<u32>,
    x_end: u32,
    // Where the pass reads (`source`) and writes (`nearest`, `nearest_inside`).
    src: Placement,
    dst: Placement,
}

@group(0) @binding(0) var<uniform> params: TileParams;
@group(0) @binding(1) var<storage, read_write> nearest: array<u32>;
// The inside seeds' field beside a SIGNED resolving pass (which runs in the outside seeds').
@group(0) @binding(2) var<storage, read> nearest_inside: array<u32>;
@group(0) @binding(3) var distance: texture_storage_3d<r32float, write>;
// The resolving entries of a 2D field write here.
@group(0) @binding(4) var distance_2d: texture_storage_2d<r32float, write>;
// `tile_columns_words` reads each row's nearest marks from `edt_rows.wgsl`'s `row_words` instead
// of a field: marks per 32 voxels, and the marks on either side of them.
@group(0) @binding(5) var<storage, read> words: array<vec2<u32>>;
// What the column passes read where it is not `nearest` itself (SOURCE_APART): a part of a
// field too large for one binding, held apart. In place, a placeholder is bound here.
@group(0) @binding(6) var<storage, read> source: array<u32>;

// 2D fields pack 16/16 bits.
override PACK_2D: bool = false;
// 1: columns run along y; 2: along z. A constant, so no vector is indexed at run time (a
// dynamically indexed vector can be lowered to a private array in memory).
override AXIS: u32 = 1u;
// The y pass runs after the z pass (a field split across bindings): its sites lie off the
// column's plane in z as well as in x. A constant, so the usual order pays nothing for it.
override Y_AFTER_Z: bool = false;
// The pass reads `source`, not `nearest` (a field split across bindings).
override SOURCE_APART: bool = false;
// Tile cells: (column_cells << lg_columns), set by the host per column length.
// The default is the most WebGPU's default 16 KiB of workgroup memory holds beside
// `envelope_size` and `far_sites`.
override CELLS: u32 = 3839u;
// 3D seeds' widths (`SeedPacking`): x in the low SEED_X_BITS bits, y in the next SEED_Y_BITS,
// z above; 11 and 11 for every grid up to 2048 × 2048 × 1024.
override SEED_X_BITS: u32 = 11u;
override SEED_Y_BITS: u32 = 11u;
// The resolving entries write signed distances: they run in the outside seeds' field with the
// inside seeds' field (`nearest_inside`) beside it. Unsigned, a placeholder is bound there.
override SIGNED: bool = false;

const THREADS: u32 = 256u;
// "Nothing found yet": above any squared distance in range.
const FAR_D2: i32 = 0x7fffffff;

var<workgroup> tile: array<u32, CELLS>;
// Per thread (band b of column c at b << lg_columns | c): its envelope's size (low 8 bits: the host
// keeps bands to 128 positions) and the least own cost of its sites (high 24 bits, saturated
// there: still a lower bound), which lets a far band be passed over skipped.
var<workgroup> envelope_size: array<u32, THREADS>;
// The resolving 3D entries: set where some position of the tile holds no site within
// SCAN_REACH of its column (`load_near`), so the tile takes the envelopes; else the scan.
var<workgroup> far_sites: atomic<u32>;

// One thread's view: column c of the tile, band b of it.
struct Lane {
    // The column's x and its other coordinate (z for y columns, y for z columns).
    x: u32,
    other: u32,
    // First tile cell of the column, and its first global element.
    col: u32,
    at: u32,
    stride: u32,
    n: u32,
    c: u32,
    b: u32,
    lo: u32,
    hi: u32,
    valid: bool,
}

// Voxel (x, y, z)'s index in a buffer placed as `p`.
fn place(p: Placement, v: vec3<u32>) -> u32 {
    return (v.x - p.origin.x) + p.row * (v.y - p.origin.y) + p.plane * (v.z - p.origin.z);
}

// The first voxel of the column at x, other (position 0 along the axis).
fn column_start(x: u32, other: u32) -> vec3<u32> {
    return select(vec3<u32>(x, other, 0u), vec3<u32>(x, 0u, other), AXIS == 1u);
}

// Elements between a column's positions in a buffer placed as `p`.
fn column_stride(p: Placement) -> u32 {
    return select(p.plane, p.row, AXIS == 1u);
}

fn lane_of(li: u32, wg: vec3<u32>) -> Lane {
    var l: Lane;
    l.c = li & ((1u << params.lg_columns) - 1u);
    l.b = li >> params.lg_columns;
    l.x = params.first.x + (wg.x << params.lg_columns) + l.c;
    l.other = params.first.y + wg.y;
    l.n = select(params.size.z, params.size.y, AXIS == 1u);
    l.at = place(params.dst, column_start(l.x, l.other));
    l.stride = column_stride(params.dst);
    l.col = l.c * params.column_cells;
    l.lo = min(l.n, l.b << params.lg_band);
    l.hi = min(l.n, l.lo + (1u << params.lg_band));
    l.valid = l.x < params.x_end;
    return l;
}

fn cell(col: u32, k: u32) -> u32 {
    return col + k + (k >> params.lg_band);
}

// A site's squared distance within the plane through its position (its cost there), and its
// position along the column.
fn own_cost(s: u32, l: Lane) -> i32 {
    if PACK_2D {
        let d = unpack_seed2(s).x - i32(l.x);
        return d * d;
    }
    let p = unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS);
    let dx = p.x - i32(l.x);
    if AXIS == 1u && !Y_AFTER_Z {
        return dx * dx;
    }
    if AXIS == 1u {
        let dz = p.z - i32(l.other);
        return dx * dx + dz * dz;
    }
    let dy = p.y - i32(l.other);
    return dx * dx + dy * dy;
}

fn position(s: u32) -> i32 {
    if PACK_2D {
        return unpack_seed2(s).y;
    }
    let p = unpack_seed3_bits(s, SEED_X_BITS, SEED_Y_BITS);
    return select(p.z, p.y, AXIS == 1u);
}

// A site (cost g at position p) at position i.
fn cost_at(g: i32, p: i32, i: i32) -> i32 {
    let d = p - i;
    return g + d * d;
}

fn cost(s: u32, l: Lane, i: i32) -> i32 {
    return cost_at(own_cost(s, l), position(s), i);
}

// Load the tile: column c's position i at cell(c · column_cells, i). Positions past the grid's x
// (or past the column) hold no seed.
struct Loader {
    at: u32,
    stride: u32,
    total: u32,
    mask: u32,
    live: u32,
}

fn fetch(ld: Loader, e: u32) -> u32 {
    let c = e & ld.mask;
    if e >= ld.total || c >= ld.live {
        return NO_SEED;
    }
    let i = ld.at + (e >> params.lg_columns) * ld.stride + c;
    if SOURCE_APART {
        return source[i];
    }
    return nearest[i];
}

fn put(ld: Loader, e: u32, s: u32) {
    if e < ld.total {
        tile[cell((e & ld.mask) * params.column_cells, e >> params.lg_columns)] = s;
    }
}

// Eight loads in flight per thread before the first store: a thread's loads are independent,
// and issuing them together hides the memory latency that a load-then-store loop waits out
// once per element (the tile is 8 to 32 elements per thread).
fn load(li: u32, wg: vec3<u32>) {
    let n = select(params.size.z, params.size.y, AXIS == 1u);
    let x0 = params.first.x + (wg.x << params.lg_columns);
    var ld: Loader;
    ld.at = place(params.src, column_start(x0, params.first.y + wg.y));
    ld.stride = column_stride(params.src);
    ld.total = n << params.lg_columns;
    ld.mask = (1u << params.lg_columns) - 1u;
    ld.live = min(params.x_end - x0, 1u << params.lg_columns);
    for (var e = li; e < ld.total; e += 8u * THREADS) {
        let s0 = fetch(ld, e);
        let s1 = fetch(ld, e + THREADS);
        let s2 = fetch(ld, e + 2u * THREADS);
        let s3 = fetch(ld, e + 3u * THREADS);
        let s4 = fetch(ld, e + 4u * THREADS);
        let s5 = fetch(ld, e + 5u * THREADS);
        let s6 = fetch(ld, e + 6u * THREADS);
        let s7 = fetch(ld, e + 7u * THREADS);
        put(ld, e, s0);
        put(ld, e + THREADS, s1);
        put(ld, e + 2u * THREADS, s2);
        put(ld, e + 3u * THREADS, s3);
        put(ld, e + 4u * THREADS, s4);
        put(ld, e + 5u * THREADS, s5);
        put(ld, e + 6u * THREADS, s6);
        put(ld, e + 7u * THREADS, s7);
    }
}

// Where `load_words` reads: the tile's first column, its other coordinate, and words per row.
struct WordLoader {
    x0: u32,
    other: u32,
    count: u32,
    total: u32,
    mask: u32,
    live: u32,
}

// The row (y, z) of tile element e: its column's position e >> lg_columns.
fn word_row(ld: WordLoader, e: u32) -> vec2<u32> {
    let i = e >> params.lg_columns;
    return select(vec2<u32>(ld.other, i), vec2<u32>(i, ld.other), AXIS == 1u);
}

// The row word that holds tile element e.
fn word_of(ld: WordLoader, e: u32) -> vec2<u32> {
    if e >= ld.total || (e & ld.mask) >= ld.live {
        return vec2<u32>(0u);
    }
    let r = word_row(ld, e);
    let x = ld.x0 + (e & ld.mask);
    return words[(r.y * params.size.y + r.x) * ld.count + (x >> 5u)];
}

// The nearest mark along x to tile element e's voxel (x, y, z), packed (NO_SEED: none), from
// the row word that holds it (`row_word_mark`; a column past the grid has a zero word: no seed).
fn put_word(ld: WordLoader, e: u32, word: vec2<u32>) {
    if e >= ld.total {
        return;
    }
    let r = word_row(ld, e);
    let near = row_word_mark(word, ld.x0 + (e & ld.mask));
    let s = select(NO_SEED, pack_seed3_bits(vec3<u32>(near - 1u, r.x, r.y), SEED_X_BITS, SEED_Y_BITS), near != 0u);
    tile[cell((e & ld.mask) * params.column_cells, e >> params.lg_columns)] = s;
}

// `load` from the row words: each cell's row answer is made as it is loaded,
// four words in flight per thread (eight, as in `load`, took 49 registers where four take 42,
// and were no faster).
fn load_words(li: u32, wg: vec3<u32>) {
    var ld: WordLoader;
    ld.x0 = params.first.x + (wg.x << params.lg_columns);
    ld.other = params.first.y + wg.y;
    ld.count = (params.size.x + 31u) / 32u;
    ld.total = select(params.size.z, params.size.y, AXIS == 1u) << params.lg_columns;
    ld.mask = (1u << params.lg_columns) - 1u;
    ld.live = min(params.x_end - ld.x0, 1u << params.lg_columns);
    for (var e = li; e < ld.total; e += 4u * THREADS) {
        let w0 = word_of(ld, e);
        let w1 = word_of(ld, e + THREADS);
        let w2 = word_of(ld, e + 2u * THREADS);
        let w3 = word_of(ld, e + 3u * THREADS);
        put_word(ld, e, w0);
        put_word(ld, e + THREADS, w1);
        put_word(ld, e + 2u * THREADS, w2);
        put_word(ld, e + 3u * THREADS, w3);
    }
}

// This band's envelope over the whole column, in place at the band's own cells; returns its
// size and the least own cost of its sites, packed as `envelope_size` holds them. The top two
// sites stay in registers.
fn build(l: Lane) -> u32 {
    var top = -1;
    var p_top = 0;
    var g_top = 0;
    var t_top = 0;
    var p_below = 0;
    var g_below = 0;
    var min_g = FAR_D2;
    let n = i32(l.n);
    for (var i = l.lo; i < l.hi; i++) {
        let s = tile[cell(l.col, i)];
        if s == NO_SEED {
            continue;
        }
        let gs = own_cost(s, l);
        let pi = i32(i);
        loop {
            if top < 0 || cost_at(g_top, p_top, t_top) <= cost_at(gs, pi, t_top) {
                break;
            }
            top -= 1;
            p_top = p_below;
            g_top = g_below;
            t_top = 0;
            if top > 0 {
                let below = tile[cell(l.col, l.lo + u32(top - 1))];
                p_below = position(below);
                g_below = own_cost(below, l);
                t_top = separator(p_below, g_below, p_top, g_top);
            }
        }
        var t = 0;
        if top >= 0 {
            t = separator(p_top, g_top, pi, gs);
        }
        if t < n {
            top += 1;
            p_below = p_top;
            g_below = g_top;
            p_top = pi;
            g_top = gs;
            t_top = t;
            min_g = min(min_g, gs);
            tile[cell(l.col, l.lo + u32(top))] = s;
        }
    }
    return u32(top + 1) | (u32(min(min_g, 0xffffff)) << 8u);
}

// A walk along a band's envelope: site k, and its cost at the position.
struct Step {
    k: u32,
    s: u32,
    d: i32,
}

// From site k of a band's envelope (size m, first cell at `first`) forward while the next site
// is strictly nearer to position i: from a site at or before the nearest, the first of the
// equally near ones (costs along an envelope fall to the minimum, then never fall again).
fn forward(l: Lane, first: u32, m: u32, k: u32, i: i32) -> Step {
    var st: Step;
    st.k = k;
    st.s = tile[cell(l.col, first + k)];
    st.d = cost(st.s, l, i);
    loop {
        if st.k + 1u >= m {
            break;
        }
        let t = tile[cell(l.col, first + st.k + 1u)];
        let dt = cost(t, l, i);
        if dt >= st.d {
            break;
        }
        st.k += 1u;
        st.s = t;
        st.d = dt;
    }
    return st;
}

// From the last site of a band's envelope back while the site before is as near to position i:
// the first of the equally near ones, as `forward` finds it.
fn backward(l: Lane, first: u32, m: u32, i: i32) -> Step {
    var st: Step;
    st.k = m - 1u;
    st.s = tile[cell(l.col, first + st.k)];
    st.d = cost(st.s, l, i);
    loop {
        if st.k == 0u {
            break;
        }
        let t = tile[cell(l.col, first + st.k - 1u)];
        let dt = cost(t, l, i);
        if dt > st.d {
            break;
        }
        st.k -= 1u;
        st.s = t;
        st.d = dt;
    }
    return st;
}

// A band q at least two away (above the thread's own band or below it) at position i: false if
// its nearest position is already as far as the best found; else, unless even its least own
// cost there is no nearer than the best, its envelope is walked from its first site and its
// nearest site replaces the best if nearer. (A binary search took 4.77 ms at 512³ where the walk,
// which shares `forward`'s code, took 4.68 to 4.71: envelopes are short and this is rare.)
fn consult(l: Lane, q: u32, above: bool, i: i32, best: ptr<function, u32>, best_d: ptr<function, i32>) -> bool {
    let first = q << params.lg_band;
    // The band's position nearest i: its first (above) or its last (below).
    let edge = select(first + (1u << params.lg_band) - 1u, first, above);
    let e = i - i32(edge);
    if e * e >= *best_d {
        return false;
    }
    let packed = envelope_size[(q << params.lg_columns) | l.c];
    let m = packed & 0xffu;
    if m > 0u && e * e + i32(packed >> 8u) < *best_d {
        let st = forward(l, first, m, 0u, i);
        if st.d < *best_d {
            *best = st.s;
            *best_d = st.d;
        }
    }
    return true;
}

// The walk along the own envelope: site k and the next, in registers (their positions and own
// costs are unpacked again at each use: caching them took 4 more registers per thread and was
// no faster on the H100, 0.523 against 0.520 ms at 256³).
struct Walk {
    k: u32,
    m: u32,
    s: u32,
    next: u32,
    // The adjacent bands' envelopes: their sizes, and the site nearest the last position
    // answered from them (that site's index never falls as the position rises, so each walk
    // goes on from where the last one stopped). The band below starts unset (BELOW_UNSET) and
    // is walked back from its last site the first time.
    m_up: u32,
    k_up: u32,
    m_dn: u32,
    k_dn: u32,
}

const BELOW_UNSET: u32 = 0xffffffffu;

fn walk_of(l: Lane, m: u32) -> Walk {
    var w: Walk;
    w.k = 0u;
    w.m = m;
    w.s = NO_SEED;
    w.next = NO_SEED;
    if m > 0u {
        w.s = tile[cell(l.col, l.lo)];
    }
    if m > 1u {
        w.next = tile[cell(l.col, l.lo + 1u)];
    }
    w.m_up = 0u;
    w.m_dn = 0u;
    if l.b + 1u < params.bands {
        w.m_up = envelope_size[((l.b + 1u) << params.lg_columns) | l.c] & 0xffu;
    }
    if l.b > 0u {
        w.m_dn = envelope_size[((l.b - 1u) << params.lg_columns) | l.c] & 0xffu;
    }
    w.k_up = 0u;
    w.k_dn = BELOW_UNSET;
    return w;
}

// The nearest site to position i (increasing from call to call) and its squared distance.
fn query(l: Lane, w: ptr<function, Walk>, i: u32) -> vec2<u32> {
    let pi = i32(i);
    var best = NO_SEED;
    var best_d = FAR_D2;
    if (*w).m > 0u {
        var d = cost((*w).s, l, pi);
        loop {
            if (*w).k + 1u >= (*w).m {
                break;
            }
            let d_next = cost((*w).next, l, pi);
            if d_next >= d {
                break;
            }
            (*w).k += 1u;
            (*w).s = (*w).next;
            d = d_next;
            if (*w).k + 1u < (*w).m {
                (*w).next = tile[cell(l.col, l.lo + (*w).k + 1u)];
            }
        }
        best = (*w).s;
        best_d = d;
    }
    // The adjacent bands, each walked on from where its last walk stopped (on the H100 this
    // took 4.87 ms at 512³ where walking each from its near end for every position took 5.25).
    // A band whose nearest position is already as far as the best found cannot win, and those
    // beyond it are farther still.
    var open = false;
    if l.b + 1u < params.bands {
        let first = (l.b + 1u) << params.lg_band;
        let e = pi - i32(first);
        if e * e < best_d {
            open = true;
            if (*w).m_up > 0u {
                let st = forward(l, first, (*w).m_up, (*w).k_up, pi);
                (*w).k_up = st.k;
                if st.d < best_d {
                    best = st.s;
                    best_d = st.d;
                }
            }
        }
    }
    if l.b > 0u {
        let first = (l.b - 1u) << params.lg_band;
        let e = pi - i32(first + (1u << params.lg_band) - 1u);
        if e * e < best_d {
            open = true;
            if (*w).m_dn > 0u {
                var st: Step;
                if (*w).k_dn == BELOW_UNSET {
                    st = backward(l, first, (*w).m_dn, pi);
                } else {
                    st = forward(l, first, (*w).m_dn, (*w).k_dn, pi);
                }
                (*w).k_dn = st.k;
                if st.d < best_d {
                    best = st.s;
                    best_d = st.d;
                }
            }
        }
    }
    // Farther bands outward, both sides at once (they are rarely reached: at 1% seeds no answer
    // at 128³ to 512³ came from one).
    for (var off = 2u; open && off < params.bands; off++) {
        var further = false;
        if l.b + off < params.bands {
            further = consult(l, l.b + off, true, pi, &best, &best_d);
        }
        if off <= l.b {
            further = consult(l, l.b - off, false, pi, &best, &best_d) || further;
        }
        open = further;
    }
    return vec2<u32>(best, u32(best_d));
}

// The last pass with dense seeds: after the passes before it, every position's own site lies
// near its column (at 1% random seeds no voxel's own cost passed 24² at 128³ to 512³), and the
// nearest site to a position is found by looking outward from it, one step at a time, until
// the step's square alone is no less than the best found: a site farther along the column
// costs at least that. A position's own site bounds the best, so where every own cost in the
// tile is at most SCAN_REACH², no scan takes more than SCAN_REACH + 1 steps, and the loads of a
// step do not wait on each other as the envelope's do. Other tiles (sparse seeds, planes with no
// seed) build the envelopes.
const SCAN_REACH: i32 = 24;

// Whether every position of this thread's band holds a site within SCAN_REACH of its column.
fn near_band(l: Lane) -> bool {
    for (var i = l.lo; i < l.hi; i++) {
        let s = tile[cell(l.col, i)];
        if s == NO_SEED || own_cost(s, l) > SCAN_REACH * SCAN_REACH {
            return false;
        }
    }
    return true;
}

// Load the tile and say whether every position of it holds a site within SCAN_REACH of its
// column (the same answer in every thread). Called by every thread: it holds the barriers.
fn load_near(li: u32, wg: vec3<u32>) -> bool {
    if li == 0u {
        atomicStore(&far_sites, 0u);
    }
    load(li, wg);
    workgroupBarrier();
    let l = lane_of(li, wg);
    if l.valid && !near_band(l) {
        atomicStore(&far_sites, 1u);
    }
    return workgroupUniformLoad(&far_sites) == 0u;
}

// The nearest site to position i, looking outward from it (a tile that `load_near` passed):
// the nearer step first, and at equal cost the site below, so the answer is deterministic.
fn scan(l: Lane, i: u32) -> vec2<u32> {
    let pi = i32(i);
    var best = tile[cell(l.col, i)];
    var best_d = own_cost(best, l);
    for (var r = 1; r * r < best_d; r++) {
        let below = pi - r;
        if below >= 0 {
            let s = tile[cell(l.col, u32(below))];
            let d = own_cost(s, l) + r * r;
            if d < best_d {
                best = s;
                best_d = d;
            }
        }
        let above = pi + r;
        if above < i32(l.n) {
            let s = tile[cell(l.col, u32(above))];
            let d = own_cost(s, l) + r * r;
            if d < best_d {
                best = s;
                best_d = d;
            }
        }
    }
    return vec2<u32>(best, u32(best_d));
}

fn voxel(l: Lane, i: u32) -> vec3<u32> {
    return select(vec3<u32>(l.x, l.other, i), vec3<u32>(l.x, i, l.other), AXIS == 1u);
}

// A distance clamped to the band.
fn banded(d: f32) -> f32 {
    return clamp(d, -params.band, params.band);
}

// Every entry starts the same: load the tile, build this band's envelope, publish its size,
// wait. Called by every thread (it holds the barriers).
fn start(li: u32, wg: vec3<u32>) -> Walk {
    load(li, wg);
    return envelopes(li, wg);
}

// After the load: build this band's envelope, publish its size, wait.
fn envelopes(li: u32, wg: vec3<u32>) -> Walk {
    workgroupBarrier();
    let l = lane_of(li, wg);
    let packed = build(l);
    envelope_size[li] = packed;
    let m = packed & 0xffu;
    workgroupBarrier();
    return walk_of(l, m);
}

@compute @workgroup_size(256)
fn tile_columns(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    var walk = start(li, wg);
    let l = lane_of(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        nearest[l.at + i * l.stride] = query(l, &walk, i).x;
    }
}

// `tile_columns` (3D, along y, or along z where a field is split across bindings) with the row
// pass folded into the load: the tile is made from `row_words` instead of read from a field, so
// the rows' answers never go through memory.
@compute @workgroup_size(256)
fn tile_columns_words(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    load_words(li, wg);
    var walk = envelopes(li, wg);
    let l = lane_of(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        nearest[l.at + i * l.stride] = query(l, &walk, i).x;
    }
}

// `tile_columns`, and the distance (SIGNED or not) of every voxel it answers (3D). The scan
// and the envelopes each have a loop of their own: one loop choosing per position (a `near`
// flag beside the walk) made the pass slower on the H100, z + resolve 0.210 → 0.213 ms at 256³
// with 1% seeds and 0.379 → 0.395 with 1e-5.
@compute @workgroup_size(256)
fn tile_columns_resolve(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let l = lane_of(li, wg);
    if load_near(li, wg) {
        if l.valid {
            for (var i = l.lo; i < l.hi; i++) {
                resolve_at(l, i, scan(l, i));
            }
        }
        return;
    }
    var walk = envelopes(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        resolve_at(l, i, query(l, &walk, i));
    }
}

// Write position i's answer and its distance; SIGNED, as `field_resolve.wgsl`'s
// `resolve_signed` gives it from both fields.
fn resolve_at(l: Lane, i: u32, found: vec2<u32>) {
    let at = l.at + i * l.stride;
    nearest[at] = found.x;
    let p = voxel(l, i);
    var d = answer_distance(found, params.voxel_size);
    if SIGNED {
        d = signed_at3_bits(nearest_inside[at], p, d, found.x, params.voxel_size, SEED_X_BITS, SEED_Y_BITS);
    }
    textureStore(distance, p, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
}

// `tile_columns` in a 2D field, and the distance (SIGNED or not) of every pixel it answers.
@compute @workgroup_size(256)
fn tile_columns_resolve_2d(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    var walk = start(li, wg);
    let l = lane_of(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        let found = query(l, &walk, i);
        let at = l.at + i * l.stride;
        nearest[at] = found.x;
        let p = voxel(l, i).xy;
        var d = answer_distance(found, params.voxel_size);
        if SIGNED {
            d = signed_at2(nearest_inside[at], p, d, found.x, params.voxel_size);
        }
        textureStore(distance_2d, p, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
    }
}

// The copies' start: load the tile, wait, and this thread's lane. Called by every thread.
fn loaded_lane(li: u32, wg: vec3<u32>) -> Lane {
    load(li, wg);
    workgroupBarrier();
    return lane_of(li, wg);
}

// The floor of a workgroup column pass: the tile's loads and the answers' stores alone (each
// thread writes back its band's positions as loaded), for `bench distance` to compare with.
@compute @workgroup_size(256)
fn tile_copy(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let l = loaded_lane(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        nearest[l.at + i * l.stride] = tile[cell(l.col, i)];
    }
}

// `tile_copy` with the distance store of a resolving 3D pass as well (a value converted from
// the site, no distance made): the floor of `tile_columns_resolve`, whose stores include it.
@compute @workgroup_size(256)
fn tile_copy_resolve(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let l = loaded_lane(li, wg);
    if !l.valid {
        return;
    }
    for (var i = l.lo; i < l.hi; i++) {
        let s = tile[cell(l.col, i)];
        nearest[l.at + i * l.stride] = s;
        textureStore(distance, voxel(l, i), vec4<f32>(f32(s), 0.0, 0.0, 0.0));
    }
}
