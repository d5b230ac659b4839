// Exact EDT, column passes (y, then z): the lower envelope of parabolas along each column, with
// integer separators (Meijster, Roerdink & Hesselink 2000) so every comparison is exact.
//
// Parallelism and coalescing: a workgroup of 256 threads takes 256 / BANDS neighbouring columns
// (consecutive x, so a warp's reads and writes are contiguous runs) and splits every column into
// BANDS bands, one thread each, as the Parallel Banding Algorithm does (Cao et al. 2010). Short
// grids of many columns (3D) use 8 bands; 2D fields, with few long columns, use 32. A band builds the envelope of
// its own sites over the whole column, kept as a stack in `stack` at the band's own positions.
// After a barrier each thread answers the positions of its band: the nearest site is on some
// band's envelope, so it evaluates its own band's envelope and those of the other bands that are
// not already farther away than the best so far. Along one envelope the cost is unimodal and its
// minimum only moves forward with the query position, so a pointer per band walks each envelope
// once. The answer overwrites `nearest` in place; all of it was read before the barrier.
//
// A site's cost at a query position is the full squared distance from that voxel to the site's
// seed, because the seed of a site at position i of a column lies in the plane through i.
//
// Latency, not bandwidth, bounds a sequential walk: the build reads its band eight elements at a
// time (independent loads in flight together) and keeps the top two stack entries in registers;
// the query keeps each band's current and next site in registers so it loads only on advance.

import package::shared::seed::{NO_SEED, dist2, dist2_3, unpack_seed2, unpack_seed3};

struct ColumnParams {
    size: vec3<u32>,
    // 1: columns run along y; 2: along z.
    axis: u32,
}

@group(0) @binding(0) var<uniform> params: ColumnParams;
@group(0) @binding(1) var<storage, read_write> nearest: array<u32>;
@group(0) @binding(2) var<storage, read_write> stack: array<u32>;

// 2D fields pack 16/16 bits (sides to 16384 keep every separator numerator in i32).
override PACK_2D: bool = false;
// Bands per column; 256 / BANDS columns per workgroup. At most MAX_BANDS, a power of two.
override BANDS: u32 = 8u;

const MAX_BANDS: u32 = 32u;
const PREFETCH: u32 = 8u;
// "Nothing found yet": above any squared distance in range.
const FAR_D2: i32 = 0x7fffffff;

// Envelope size per (band, column) of this workgroup.
var<workgroup> band_size: array<u32, 256>;

fn voxel(x: u32, other: u32, i: u32) -> vec3<i32> {
    if params.axis == 1u {
        return vec3<i32>(i32(x), i32(i), i32(other));
    }
    return vec3<i32>(i32(x), i32(other), i32(i));
}

fn cost(s: u32, p: vec3<i32>) -> i32 {
    if PACK_2D {
        return i32(dist2(unpack_seed2(s), p.xy));
    }
    return dist2_3(unpack_seed3(s), p);
}

// A site's position along the column.
fn position(s: u32) -> i32 {
    if PACK_2D {
        return unpack_seed2(s)[params.axis];
    }
    return unpack_seed3(s)[params.axis];
}

fn floor_div(a: i32, b: i32) -> i32 {
    let q = a / b;
    return select(q, q - 1, a % b != 0 && a < 0);
}

// Meijster's separator: the first integer position where site `b` (after `a`) is at least as
// near as `a`, given their costs at their own positions.
fn start_of(a: u32, b: u32, x: u32, other: u32) -> i32 {
    let pa = position(a);
    let pb = position(b);
    let ga = cost(a, voxel(x, other, u32(pa)));
    let gb = cost(b, voxel(x, other, u32(pb)));
    return 1 + floor_div(pb * pb - pa * pa + gb - ga, 2 * (pb - pa));
}

@compute @workgroup_size(32, 8)
fn columns(@builtin(local_invocation_index) li: u32, @builtin(workgroup_id) wg: vec3<u32>) {
    let columns_per_group = 256u / BANDS;
    let lane = li % columns_per_group;
    let band = li / columns_per_group;
    let x = wg.x * columns_per_group + lane;
    let other = wg.y;
    let n = params.size[params.axis];
    let row = params.size.x;
    let plane = params.size.x * params.size.y;
    let base = select(other * row + x, other * plane + x, params.axis == 1u);
    let stride = select(plane, row, params.axis == 1u);
    let band_len = (n + BANDS - 1u) / BANDS;
    let lo = min(n, band * band_len);
    let hi = min(n, lo + band_len);
    let valid = x < params.size.x;

    // Build: Meijster's stack over this band's sites, valid for the whole column [0, n).
    var top = -1;
    var s_top = NO_SEED;
    var s_below = NO_SEED;
    if valid {
        let at = base + lo * stride;
        for (var i0 = lo; i0 < hi; i0 += PREFETCH) {
            var chunk: array<u32, PREFETCH>;
            for (var j = 0u; j < PREFETCH; j++) {
                if i0 + j < hi {
                    chunk[j] = nearest[base + (i0 + j) * stride];
                }
            }
            for (var j = 0u; j < PREFETCH; j++) {
                let s = chunk[j];
                if s == NO_SEED {
                    continue;
                }
                loop {
                    if top < 0 {
                        break;
                    }
                    var t = 0;
                    if top > 0 {
                        t = start_of(s_below, s_top, x, other);
                    }
                    let pt = voxel(x, other, u32(t));
                    if cost(s_top, pt) <= cost(s, pt) {
                        break;
                    }
                    top -= 1;
                    s_top = s_below;
                    if top > 0 {
                        s_below = stack[at + u32(top - 1) * stride];
                    }
                }
                if top < 0 || start_of(s_top, s, x, other) < i32(n) {
                    top += 1;
                    s_below = s_top;
                    s_top = s;
                    stack[at + u32(top) * stride] = s;
                }
            }
        }
    }
    band_size[band * columns_per_group + lane] = u32(top + 1);
    storageBarrier();
    workgroupBarrier();
    if !valid {
        return;
    }

    // Query: positions of this band against every band's envelope, nearest bands first.
    var cursor: array<u32, MAX_BANDS>;
    var current: array<u32, MAX_BANDS>;
    var own_k = 0u;
    let own_size = u32(top + 1);
    let own_at = base + lo * stride;
    var own_s = select(NO_SEED, stack[own_at], own_size > 0u);
    var own_next = select(NO_SEED, stack[own_at + stride], own_size > 1u);
    for (var i = lo; i < hi; i++) {
        let p = voxel(x, other, i);
        var best = NO_SEED;
        var best_d = FAR_D2;
        if own_size > 0u {
            var d = cost(own_s, p);
            while own_k + 1u < own_size {
                let d_next = cost(own_next, p);
                if d_next >= d {
                    break;
                }
                own_k += 1u;
                own_s = own_next;
                d = d_next;
                if own_k + 1u < own_size {
                    own_next = stack[own_at + (own_k + 1u) * stride];
                }
            }
            best = own_s;
            best_d = d;
        }
        for (var j = 1u; j < 2u * BANDS - 1u; j++) {
            // j = 1, 2, 3, 4 … → band + 1, band - 1, band + 2, band - 2 …
            let off = (j + 1u) / 2u;
            if (j & 1u) == 0u && off > band {
                continue;
            }
            let c = select(band - off, band + off, (j & 1u) == 1u);
            if c >= BANDS {
                continue;
            }
            let c_lo = c * band_len;
            let c_hi = min(n, c_lo + band_len) - 1u;
            let gap = i32(select(select(0u, i - c_hi, i > c_hi), c_lo - i, i < c_lo));
            // A skipped band keeps its cursor: the first minimiser only moves forward with i.
            if gap * gap >= best_d {
                continue;
            }
            let size = band_size[c * columns_per_group + lane];
            if size == 0u {
                continue;
            }
            let at = base + c_lo * stride;
            var k = cursor[c];
            var s = current[c];
            if s == NO_SEED {
                s = stack[at];
            }
            var d = cost(s, p);
            while k + 1u < size {
                let s_next = stack[at + (k + 1u) * stride];
                let d_next = cost(s_next, p);
                if d_next >= d {
                    break;
                }
                k += 1u;
                s = s_next;
                d = d_next;
            }
            cursor[c] = k;
            current[c] = s;
            if d < best_d {
                best = s;
                best_d = d;
            }
        }
        nearest[base + i * stride] = best;
    }
}
