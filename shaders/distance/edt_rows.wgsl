// Exact EDT, first pass: per row, the nearest marked voxel along x (seeding and the 1D transform
// in one pass; the column passes in `edt_columns` finish the transform).
//
// One workgroup per row; every global read and write is a contiguous run of the row, so the pass
// is coalesced although the row is the direction a thread-per-line scheme would stride across.
// `rows` (3D, rows ≤ 2048) holds whole rows in workgroup memory, as many as fit (ROWS): each
// thread sweeps a short segment, a scan over the row's segments carries the nearest marks across
// them, and the volume is read once and the field written once (5 bytes per voxel). `rows_2d` (rows to 16384, too long
// to hold as seeds) holds the row as a bitmask (16384 bits: 2 KiB), carries each word's
// nearest mark to the left and right across the words with one scan, and finds every texel's
// nearest mark in its own word with firstLeadingBit / firstTrailingBit: the mask is read once
// and the field written once (5 bytes per texel, where walking the row twice took 14), packed
// 16/16 bits. `row_words` (3D) writes no field at all: per 32 voxels of a row, their marks as a
// word and the nearest marks on either side of it, which the y column pass reads in place of a
// field (`tile_columns_words` in `edt_tile.wgsl`): 1.25 bytes per voxel moved where `rows` moves 5.

import fieldkit::seed::{NO_SEED, pack_seed2, pack_seed3_bits, seed_value};

struct RowParams {
    size: vec3<u32>,
    // A voxel is marked where its value (`seed_value`: red unless `channels` says) is ≥
    // threshold.
    threshold: f32,
    // 1: seeds are the unmarked voxels.
    invert: u32,
    // Channel weights (0 or 1) of the value compared: (1, 0, 0, 0) reads red.
    channels: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: RowParams;
@group(0) @binding(1) var volume: texture_3d<f32>;
@group(0) @binding(2) var mask_2d: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> nearest: array<u32>;
// `row_words`: per row (x fastest, then y, then z), per 32 voxels: their marks (bit b: voxel
// 32·k + b) and, packed, the last mark before them + 1 (low 16 bits) and the first mark after
// them + 1 (high 16 bits), 0 for none.
@group(0) @binding(4) var<storage, read_write> words: array<vec2<u32>>;

const CHUNK: u32 = 256u;
// `row_words`: cells of workgroup memory each thread loads (MAX_ROW / CHUNK).
const WORD_LOADS: u32 = 8u;
// "Nothing to the right yet" for the min-scan.
const NONE_RIGHT: u32 = 0xffffffffu;

// `rows` holds whole rows: the 3D packing's 2048 fits.
const MAX_ROW: u32 = 2048u;
// `rows`: rows per workgroup (a power of two; ROWS × width ≤ MAX_ROW). Short rows share a
// workgroup so that each barrier serves several rows and each thread sweeps a few cells.
override ROWS: u32 = 1u;
// 3D seeds' widths (`SeedPacking`): x in the low SEED_X_BITS bits, y in the next SEED_Y_BITS,
// z above; 11 and 11 for every grid up to 2048 × 2048 × 1024.
override SEED_X_BITS: u32 = 11u;
override SEED_Y_BITS: u32 = 11u;

// `rows`: the rows' marks, then their packed nearest seeds.
// One pad cell after every 8: a thread sweeps a segment of (usually) 8 cells, so without the
// pad the 32 threads of a warp would read and write cells 8 apart, four to a bank.
var<workgroup> row_cells: array<u32, MAX_ROW + MAX_ROW / 8u>;
// `rows`: per segment, the last mark + 1 (0: none) and the first mark (NONE_RIGHT: none),
// scanned into prefix maxima and suffix minima.
var<workgroup> seg_last: array<u32, 256>;
var<workgroup> seg_first: array<u32, 256>;

// Cell i of `row_cells`, padded.
fn padded(i: u32) -> u32 {
    return i + (i >> 3u);
}

// Prefix maxima of `seg_last` and suffix minima of `seg_first` over a row's `lanes` segments
// (Hillis & Steele): `slot` is this thread's entry, `t` its segment in the row. Called by every
// thread (it holds the barriers); `lanes` is the same for all.
fn scan_segments(slot: u32, t: u32, lanes: u32) {
    for (var offset = 1u; offset < lanes; offset <<= 1u) {
        // Indices are clamped so no read leaves the row; select then drops those values.
        let l = select(0u, seg_last[slot - min(t, offset)], t >= offset);
        let r = select(NONE_RIGHT, seg_first[slot + min(lanes - 1u - t, offset)], t + offset < lanes);
        workgroupBarrier();
        seg_last[slot] = max(seg_last[slot], l);
        seg_first[slot] = min(seg_first[slot], r);
        workgroupBarrier();
    }
}

fn is_seed(value: f32) -> bool {
    return (value >= params.threshold) != (params.invert != 0u);
}

// Nearer of the marks left (x + 1, 0: none) and right (x, NONE_RIGHT: none) of x, as x + 1.
fn nearer(x: u32, left: u32, right: u32) -> u32 {
    if right == NONE_RIGHT || (left != 0u && x - (left - 1u) <= right - x) {
        return left;
    }
    return right + 1u;
}

@compute @workgroup_size(256)
fn rows(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let w = params.size.x;
    // ROWS rows per workgroup, `lanes` threads each; row r's cells start at r * w.
    let lanes = CHUNK / ROWS;
    let r = lid.x / lanes;
    let t = lid.x % lanes;
    let y = wg.x * ROWS + r;
    let z = wg.y;
    let live = y < params.size.y;
    let cells = r * w;
    for (var x = t; x < w; x += lanes) {
        if live {
            row_cells[padded(cells + x)] = u32(is_seed(seed_value(textureLoad(volume, vec3<u32>(x, y, z), 0), params.channels)));
        }
    }
    workgroupBarrier();
    // Thread t owns the contiguous segment [s0, s1) of its row.
    let k = (w + lanes - 1u) / lanes;
    let s0 = min(w, t * k);
    let s1 = min(w, s0 + k);
    var last = 0u;
    var first = NONE_RIGHT;
    if live {
        for (var x = s0; x < s1; x++) {
            if row_cells[padded(cells + x)] != 0u {
                last = x + 1u;
                first = min(first, x);
            }
        }
    }
    seg_last[lid.x] = last;
    seg_first[lid.x] = first;
    workgroupBarrier();
    scan_segments(lid.x, t, lanes);
    if live {
        // Sweep the own segment both ways; only this thread touches its cells from here. The
        // right sweep leaves the nearest mark to the right + 1 in the low bits and the mark in
        // bit 31, so nothing is kept in a private array (those live in slow local memory).
        var right = select(NONE_RIGHT, seg_first[lid.x + min(1u, lanes - 1u - t)], t + 1u < lanes);
        for (var x = s1; x > s0; x--) {
            let marked = row_cells[padded(cells + x - 1u)] != 0u;
            if marked {
                right = x - 1u;
            }
            row_cells[padded(cells + x - 1u)] = select(0u, right + 1u, right != NONE_RIGHT) | (u32(marked) << 31u);
        }
        var left = select(0u, seg_last[lid.x - min(t, 1u)], t > 0u);
        for (var x = s0; x < s1; x++) {
            let cell = row_cells[padded(cells + x)];
            if (cell >> 31u) != 0u {
                left = x + 1u;
            }
            let rc = cell & 0x7fffffffu;
            let near = nearer(x, left, select(NONE_RIGHT, rc - 1u, rc != 0u));
            row_cells[padded(cells + x)] = select(NO_SEED, pack_seed3_bits(vec3<u32>(near - 1u, y, z), SEED_X_BITS, SEED_Y_BITS), near != 0u);
        }
    }
    workgroupBarrier();
    if live {
        let row_start = (z * params.size.y + y) * w;
        for (var x = t; x < w; x += lanes) {
            nearest[row_start + x] = row_cells[padded(cells + x)];
        }
    }
}

// `rows_2d`: a word per thread at most this many times (16384 / 32 / 256).
const WORDS_PER_THREAD: u32 = 2u;
const MAX_WORDS: u32 = 512u;

// `rows_2d`: the row's marks, one bit per texel.
var<workgroup> row_bits: array<u32, MAX_WORDS>;

// Marks of the 32 texels from x0 as the bits of a word.
fn mark_word(x0: u32, y: u32) -> u32 {
    var word = 0u;
    for (var b = 0u; b < 32u; b++) {
        let x = x0 + b;
        if x < params.size.x && is_seed(seed_value(textureLoad(mask_2d, vec2<u32>(x, y), 0), params.channels)) {
            word |= 1u << b;
        }
    }
    return word;
}

@compute @workgroup_size(256)
fn rows_2d(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let y = wg.x;
    let w = params.size.x;
    let words = (w + 31u) / 32u;
    let t = lid.x;
    // Thread t owns words t·2 and t·2 + 1: it builds them, and keeps its last mark + 1 (0:
    // none) and first mark (NONE_RIGHT: none) for the scan across threads.
    var last = 0u;
    var first = NONE_RIGHT;
    for (var k = 0u; k < WORDS_PER_THREAD; k++) {
        let i = t * WORDS_PER_THREAD + k;
        var word = 0u;
        if i < words {
            word = mark_word(i * 32u, y);
            row_bits[i] = word;
        }
        if word != 0u {
            last = i * 32u + firstLeadingBit(word) + 1u;
            first = min(first, i * 32u + firstTrailingBit(word));
        }
    }
    seg_last[t] = last;
    seg_first[t] = first;
    workgroupBarrier();
    scan_segments(t, t, CHUNK);
    // Each texel: the nearest mark at or left of it and at or right of it, in its own word
    // first, else carried from the words before (threads before) or after.
    let row_start = y * w;
    for (var x = t; x < w; x += CHUNK) {
        let i = x >> 5u;
        let b = x & 31u;
        let word = row_bits[i];
        // The thread that owns word i, and whether the word is its first or second.
        let owner = i / WORDS_PER_THREAD;
        let second = (i & 1u) == 1u;
        var left = 0u;
        let below = word & (0xffffffffu >> (31u - b));
        if below != 0u {
            left = i * 32u + firstLeadingBit(below) + 1u;
        } else if second && row_bits[i - 1u] != 0u {
            left = (i - 1u) * 32u + firstLeadingBit(row_bits[i - 1u]) + 1u;
        } else if owner > 0u {
            left = seg_last[owner - 1u];
        }
        var right = NONE_RIGHT;
        let above = word & (0xffffffffu << b);
        if above != 0u {
            right = i * 32u + firstTrailingBit(above);
        } else if !second && i + 1u < words && row_bits[i + 1u] != 0u {
            right = (i + 1u) * 32u + firstTrailingBit(row_bits[i + 1u]);
        } else if owner + 1u < CHUNK {
            right = seg_first[owner + 1u];
        }
        let near = nearer(x, left, right);
        nearest[row_start + x] = select(NO_SEED, pack_seed2(vec2<u32>(near - 1u, y)), near != 0u);
    }
}

// `row_words`: the cells of ROWS rows (ROWS · lanes · 32 = 2048), eight adjacent cells per
// thread held as a byte, then one thread per word joins its four bytes. Reading a word's 32
// voxels from one thread instead strides the warp's loads 32 voxels apart: 0.53 ms at 512³ on
// the H100 against 0.63 for the whole `rows`; cells read coalesced (a thread's 8 cells 256
// apart) into workgroup memory and gathered one by one by the word's thread took 0.277 ms,
// the bytes 0.245 (2026-11-26).
// ROWS rows per workgroup of up to 64 words each (rows to 2048 voxels), a thread per word
// (ROWS · lanes = 64 of the 256); one scan across each row's words carries the nearest marks on
// either side.
@compute @workgroup_size(256)
fn row_words(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    let count = (params.size.x + 31u) / 32u;
    let lanes = 64u / ROWS;
    // Cells per row in workgroup memory (a power of two), so a cell's row is a shift away.
    let row_cells_len = lanes * 32u;
    let z = wg.y;
    // ROWS · row_cells_len is always MAX_ROW: WORD_LOADS cells per thread, a count known when
    // the shader is compiled, so every load is issued before the first one is waited on (with
    // the count read from the parameters, each load waited for its store). Thread i loads the
    // cells 8i .. 8i + 7 (in one row: 8 divides a row's cells) and keeps their marks as a byte;
    // a word's thread then joins four bytes (gathering 32 cells one by one took longer).
    let e0 = lid.x * WORD_LOADS;
    let x0 = e0 & (row_cells_len - 1u);
    let y0 = wg.x * ROWS + e0 / row_cells_len;
    var values: array<f32, WORD_LOADS>;
    for (var k = 0u; k < WORD_LOADS; k++) {
        let v = vec3<u32>(min(x0 + k, params.size.x - 1u), min(y0, params.size.y - 1u), z);
        values[k] = seed_value(textureLoad(volume, v, 0), params.channels);
    }
    var byte = 0u;
    for (var k = 0u; k < WORD_LOADS; k++) {
        byte |= u32(x0 + k < params.size.x && y0 < params.size.y && is_seed(values[k])) << k;
    }
    row_cells[lid.x] = byte;
    workgroupBarrier();
    let t = lid.x & (lanes - 1u);
    let y = wg.x * ROWS + lid.x / lanes;
    let live = lid.x < 64u && y < params.size.y && t < count;
    var word = 0u;
    if live {
        let b = lid.x * 4u;
        word = row_cells[b] | (row_cells[b + 1u] << 8u) | (row_cells[b + 2u] << 16u) | (row_cells[b + 3u] << 24u);
    }
    seg_last[lid.x] = select(0u, t * 32u + firstLeadingBit(word) + 1u, word != 0u);
    seg_first[lid.x] = select(NONE_RIGHT, t * 32u + firstTrailingBit(word), word != 0u);
    workgroupBarrier();
    scan_segments(lid.x, t, lanes);
    if live {
        // The scans are inclusive: the entries of the threads before and after hold the marks
        // outside this word (indices clamped so that none leaves the row; select drops them).
        let before = select(0u, seg_last[lid.x - min(t, 1u)], t > 0u);
        let first_after = seg_first[lid.x + min(lanes - 1u - t, 1u)];
        let after = select(0u, first_after + 1u, t + 1u < lanes && first_after != NONE_RIGHT);
        words[(z * params.size.y + y) * count + t] = vec2<u32>(word, before | (after << 16u));
    }
}
