// Exact EDT, column passes (y, then z): the lower envelope of parabolas along each column, with
// integer separators (Meijster, Roerdink & Hesselink 2000) so every comparison is exact.
//
// Parallelism and coalescing: a workgroup of 256 threads takes 256 / BANDS neighbouring columns
// (consecutive x, so a warp's reads and writes are contiguous runs) and splits every column into
// BANDS bands, one thread each, as the Parallel Banding Algorithm does (Cao et al. 2010). The host
// picks BANDS so that there are enough threads: 1 for 512³, up to 32 for 2D fields. A band builds the envelope of
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
// Latency, not bandwidth, bounds a sequential walk: the build keeps four loads of its band in
// flight and the top two stack entries in registers;
// the query keeps its own band's current and next site in registers so it loads only on
// advance, and looks other bands up by binary search, keeping no per-band state (private arrays
// live in local memory, and zero-initialising them cost as much traffic as the field itself).

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
        // Four loads in flight: the next elements are requested before this one is processed,
        // rotating through registers (an unrolled chunk would multiply the loop body and the
        // registers it holds, and cut how many threads fit on a core).
        var q0 = NO_SEED;
        var q1 = NO_SEED;
        var q2 = NO_SEED;
        var q3 = NO_SEED;
        if lo < hi {
            q0 = nearest[base + lo * stride];
        }
        if lo + 1u < hi {
            q1 = nearest[base + (lo + 1u) * stride];
        }
        if lo + 2u < hi {
            q2 = nearest[base + (lo + 2u) * stride];
        }
        for (var i = lo; i < hi; i++) {
            if i + 3u < hi {
                q3 = nearest[base + (i + 3u) * stride];
            }
            let s = q0;
            q0 = q1;
            q1 = q2;
            q2 = q3;
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
    band_size[band * columns_per_group + lane] = u32(top + 1);
    storageBarrier();
    workgroupBarrier();
    if !valid {
        return;
    }

    // Query: positions of this band against every band's envelope, nearest bands first.
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
        // Other bands outward, both sides at once; a band whose nearest position is already as
        // far as the best found cannot win, and the ones beyond it are farther still.
        for (var off = 1u; off < BANDS; off++) {
            var open = false;
            if band + off < BANDS {
                let c = band + off;
                let c_lo = c * band_len;
                if c_lo < n && i32((c_lo - i) * (c_lo - i)) < best_d {
                    open = true;
                    let size = band_size[c * columns_per_group + lane];
                    if size > 0u {
                        let s = nearest_on(base + c_lo * stride, size, stride, p);
                        let d = cost(s, p);
                        if d < best_d {
                            best = s;
                            best_d = d;
                        }
                    }
                }
            }
            if off <= band {
                let c = band - off;
                let c_hi = (c + 1u) * band_len - 1u;
                if i32((i - c_hi) * (i - c_hi)) < best_d {
                    open = true;
                    let size = band_size[c * columns_per_group + lane];
                    if size > 0u {
                        let s = nearest_on(base + c * band_len * stride, size, stride, p);
                        let d = cost(s, p);
                        if d < best_d {
                            best = s;
                            best_d = d;
                        }
                    }
                }
            }
            if !open {
                break;
            }
        }
        nearest[base + i * stride] = best;
    }
}
