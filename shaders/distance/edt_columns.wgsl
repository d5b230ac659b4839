// Exact EDT, column passes (y, then z): the lower envelope of parabolas along each column, with
// integer separators (Meijster, Roerdink & Hesselink 2000) so every comparison is exact.
//
// Parallelism and coalescing: a workgroup takes 32 neighbouring columns (consecutive x, so each
// warp's reads and writes are contiguous) and splits every column into BANDS bands, one thread
// each, as the Parallel Banding Algorithm does (Cao et al. 2010). A band builds the envelope of
// its own sites over the whole column, kept as a stack in `stack` at the band's own positions.
// After a barrier each thread answers the positions of its band: the nearest site is on some
// band's envelope, so it evaluates its own band's envelope and those of the other bands that are
// not already farther away than the best so far. Along one envelope the cost is unimodal and its
// minimum only moves forward with the query position, so a pointer per band walks each envelope
// once. The answer overwrites `nearest` in place; all of it was read before the barrier.
//
// A site's cost at a query position is the full squared distance from that voxel to the site's
// seed, because the seed of a site at position i of a column lies in the plane through i.

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

const COLUMNS: u32 = 32u;
const BANDS: u32 = 8u;
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

@compute @workgroup_size(32, 8)
fn columns(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let x = wg.x * COLUMNS + lid.x;
    let other = wg.y;
    let band = lid.y;
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
    // Only sites are stored; a segment's start t[k] = 1 + Sep(s[k-1], s[k]) is recomputed.
    var top = -1;
    if valid {
        let at = base + lo * stride;
        for (var i = lo; i < hi; i++) {
            let s = nearest[base + i * stride];
            if s == NO_SEED {
                continue;
            }
            let u = i32(i);
            let gu = cost(s, voxel(x, other, i));
            loop {
                if top < 0 {
                    break;
                }
                let sq = stack[at + u32(top) * stride];
                var t = 0;
                if top > 0 {
                    let sp = stack[at + u32(top - 1) * stride];
                    let a = position(sp);
                    let b = position(sq);
                    let ga = cost(sp, voxel(x, other, u32(a)));
                    let gb = cost(sq, voxel(x, other, u32(b)));
                    t = 1 + floor_div(b * b - a * a + gb - ga, 2 * (b - a));
                }
                let pt = voxel(x, other, u32(t));
                if cost(sq, pt) > cost(s, pt) {
                    top -= 1;
                } else {
                    break;
                }
            }
            if top < 0 {
                top = 0;
                stack[at] = s;
            } else {
                let sq = stack[at + u32(top) * stride];
                let b = position(sq);
                let gb = cost(sq, voxel(x, other, u32(b)));
                let w = 1 + floor_div(u * u - b * b + gu - gb, 2 * (u - b));
                if w < i32(n) {
                    top += 1;
                    stack[at + u32(top) * stride] = s;
                }
            }
        }
    }
    band_size[band * COLUMNS + lid.x] = u32(top + 1);
    storageBarrier();
    workgroupBarrier();
    if !valid {
        return;
    }

    // Query: positions of this band against every band's envelope, nearest bands first.
    var cursor: array<u32, BANDS>;
    for (var i = lo; i < hi; i++) {
        let p = voxel(x, other, i);
        var best = NO_SEED;
        var best_d = FAR_D2;
        for (var j = 0u; j < 2u * BANDS - 1u; j++) {
            // j = 0, 1, 2, 3, 4 … → band, band + 1, band - 1, band + 2, band - 2 …
            let off = (j + 1u) / 2u;
            if (j & 1u) == 0u && off > band {
                continue;
            }
            let c = select(band - off, band + off, (j & 1u) == 1u);
            if c >= BANDS {
                continue;
            }
            let size = band_size[c * COLUMNS + lid.x];
            if size == 0u {
                continue;
            }
            let c_lo = c * band_len;
            let c_hi = min(n, c_lo + band_len) - 1u;
            let gap = i32(select(select(0u, i - c_hi, i > c_hi), c_lo - i, i < c_lo));
            if gap * gap >= best_d {
                continue;
            }
            let at = base + c_lo * stride;
            var k = cursor[c];
            var s = stack[at + k * stride];
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
            if d < best_d {
                best = s;
                best_d = d;
            }
        }
        nearest[base + i * stride] = best;
    }
}
