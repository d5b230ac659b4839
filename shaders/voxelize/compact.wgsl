// Dense indices for the occupied voxels of a bitset, in voxel order: exclusive prefix sums of
// the words' popcounts in two levels. `scan_words` scans each block of BLOCK_WORDS words in one
// workgroup and leaves the block's total; `scan_blocks` scans the totals in one workgroup and
// writes the number of occupied voxels. Voxel i (word w = i / 32) then has the index
//   block_offsets[w / BLOCK_WORDS] + word_offsets[w] + countOneBits(word w's bits below i),
// which is what the attribute stage computes.

import package::shared::scan::{SCAN_THREADS, scan_total, scan_workgroup};

struct CompactParams {
    // Words in the bitset.
    words: u32,
}

@group(0) @binding(0) var<uniform> params: CompactParams;
// Voxel i is bit i % 32 of word i / 32.
@group(0) @binding(1) var<storage, read> occupancy: array<u32>;
// Occupied voxels before word w within its block.
@group(0) @binding(2) var<storage, read_write> word_offsets: array<u32>;
// Per block: its total after `scan_words`, the occupied voxels before it after `scan_blocks`.
@group(0) @binding(3) var<storage, read_write> block_offsets: array<u32>;
// Occupied voxels in all.
@group(0) @binding(4) var<storage, read_write> total: array<u32, 1>;

const THREADS: u32 = SCAN_THREADS;
const WORDS_PER_THREAD: u32 = 4u;
// Words one workgroup of `scan_words` covers.
const BLOCK_WORDS: u32 = 1024u;

@compute @workgroup_size(256)
fn scan_words(@builtin(workgroup_id) group: vec3<u32>,
              @builtin(local_invocation_index) local: u32) {
    let first = group.x * BLOCK_WORDS + local * WORDS_PER_THREAD;
    var before: array<u32, WORDS_PER_THREAD>;
    var sum = 0u;
    for (var k = 0u; k < WORDS_PER_THREAD; k++) {
        before[k] = sum;
        if first + k < params.words {
            sum += countOneBits(occupancy[first + k]);
        }
    }
    let inclusive = scan_workgroup(local, sum);
    for (var k = 0u; k < WORDS_PER_THREAD; k++) {
        if first + k < params.words {
            word_offsets[first + k] = inclusive - sum + before[k];
        }
    }
    if local == THREADS - 1u {
        block_offsets[group.x] = inclusive;
    }
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(local_invocation_index) local: u32) {
    let blocks = (params.words + BLOCK_WORDS - 1u) / BLOCK_WORDS;
    var carry = 0u;
    for (var base = 0u; base < blocks; base += THREADS) {
        let i = base + local;
        var v = 0u;
        if i < blocks {
            v = block_offsets[i];
        }
        let inclusive = scan_workgroup(local, v);
        if i < blocks {
            block_offsets[i] = carry + inclusive - v;
        }
        carry += scan_total();
        // Every thread has read the total before the next round overwrites it.
        workgroupBarrier();
    }
    if local == 0u {
        total[0] = carry;
    }
}
