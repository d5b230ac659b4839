// A sparse voxel octree built level by level from a list of voxel fragments (OpenGL Insights
// ch. 22, Crassin & Green, part 2): flag the children that hold voxels, give the flagged
// children their entries, repeat to the leaves.
//
// The tree covers a cube of 2^log_side voxels. Level 0 is the root; a node of level l covers
// 2^(log_side − l) voxels; the nodes of level `leaf_level` cover 4 and are bricks of 4³ voxels.
// Every node is one entry of two u32 in `pool`:
//   inner node: (child mask: bit o for child octant o = x + 2y + 4z, entry of its first child);
//               child o is entry first + countOneBits(mask & ((1 << o) − 1)).
//   brick:      64 occupancy bits, voxel (x, y, z) of the brick (each 0..3) is bit x + 4y + 16z.
// Entries are laid out breadth first: level l is entries [starts[l], starts[l + 1]), and the
// children of a level come in the order of their parents, each parent's in octant order. The
// children's entries come from a prefix sum of the parents' child counts rather than an atomic
// counter, so the layout depends on the voxels alone: two builds give identical bytes.
//
// Per level l (each pass a dispatch; the counts stay on the GPU):
//   `flag`         each fragment steps from its level l − 1 node (`cursor`) to its level l node
//                  and sets its child's bit there; at the leaf level it sets its voxel's bit;
//   `scan_nodes`   children before each node of level l, per block of 1024 nodes;
//   `scan_blocks`  children before each block, and starts[l + 2];
//   `link`         each node's first child entry.
// With attributes, the three node passes run once more over the bricks: `brick_voxels` gets
// where each brick's voxels start in a list of the occupied voxels, brick by brick in bit order.
// A pool too small: entries from `capacity` on are not written, and `starts` still says how
// many the levels built so far need (a lower bound on the whole tree's, which the host reads).

import fieldkit::octree::{brick_bit, octree_octant};
import package::shared::scan::{SCAN_THREADS, scan_total, scan_workgroup};

struct BuildParams {
    // log2 of the cube's side in voxels.
    log_side: u32,
    // The level this pass works on.
    level: u32,
    // The level of the bricks.
    leaf_level: u32,
    // Fragments the list holds (the fragment pass may have counted more).
    fragments: u32,
    // Entries the pool holds.
    capacity: u32,
}

@group(0) @binding(0) var<uniform> params: BuildParams;
// Voxel (x, y, z) as (x | y << 16, z); the first min(fragment_count, params.fragments) hold one.
@group(0) @binding(1) var<storage, read> fragments: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> fragment_count: u32;
// Per fragment: its node at the level last flagged, NONE when the pool had no room for it.
@group(0) @binding(3) var<storage, read_write> cursor: array<u32>;
// Two u32 per entry (see above).
@group(0) @binding(4) var<storage, read_write> pool: array<atomic<u32>>;
// starts[l]: the first entry of level l, for l = 0 ..= leaf_level + 1 (the last is the number
// of entries the tree needs); then, where the bricks' voxels were counted (for attributes),
// starts[leaf_level + 1] + the occupied voxels. The host sets starts[0] = 0, starts[1] = 1.
@group(0) @binding(5) var<storage, read_write> starts: array<u32>;
// Per node of the level: children before it in its block; per block: its children, then the
// children before it.
@group(0) @binding(6) var<storage, read_write> node_offsets: array<u32>;
@group(0) @binding(7) var<storage, read_write> block_offsets: array<u32>;
// Per entry, for the bricks: where the brick's voxels' attributes start (written by `link` at
// the leaf level).
@group(0) @binding(8) var<storage, read_write> brick_voxels: array<u32>;

const NONE: u32 = 0xffffffffu;
const NODES_PER_THREAD: u32 = 4u;
// Nodes one workgroup of `scan_nodes` covers.
const BLOCK_NODES: u32 = 1024u;

var<workgroup> level_nodes: u32;

fn voxel(f: u32) -> vec3<u32> {
    let v = fragments[f];
    return vec3<u32>(v.x & 0xffffu, v.x >> 16u, v.y);
}

fn octant(v: vec3<u32>, l: u32) -> u32 {
    return octree_octant(v, params.log_side, l);
}

fn child(parent: u32, o: u32) -> u32 {
    let mask = atomicLoad(&pool[2u * parent]);
    return atomicLoad(&pool[2u * parent + 1u]) + countOneBits(mask & ((1u << o) - 1u));
}

@compute @workgroup_size(64)
fn flag(@builtin(global_invocation_id) id: vec3<u32>,
        @builtin(num_workgroups) groups: vec3<u32>) {
    let f = id.x + id.y * groups.x * 64u;
    if f >= params.fragments {
        return;
    }
    if f >= fragment_count {
        // Past the list's fragments: no brick (the attribute pass reads every cursor).
        if params.level == 0u {
            cursor[f] = NONE;
        }
        return;
    }
    let v = voxel(f);
    var node = 0u;
    if params.level > 0u {
        let parent = cursor[f];
        if parent == NONE {
            return;
        }
        node = child(parent, octant(v, params.level));
        if node >= params.capacity {
            cursor[f] = NONE;
            return;
        }
    }
    cursor[f] = node;
    if params.level == params.leaf_level {
        let bit = brick_bit(v);
        atomicOr(&pool[2u * node + bit / 32u], 1u << (bit % 32u));
        return;
    }
    atomicOr(&pool[2u * node], 1u << octant(v, params.level + 1u));
}

// The level's node count, uniform across the workgroup.
fn load_level_nodes(local: u32) -> u32 {
    if local == 0u {
        level_nodes = starts[params.level + 1u] - starts[params.level];
    }
    return workgroupUniformLoad(&level_nodes);
}

// Children of node i of the level (none past the pool's end); a brick's occupied voxels.
fn children(i: u32) -> u32 {
    let e = starts[params.level] + i;
    if e >= params.capacity {
        return 0u;
    }
    var n = countOneBits(atomicLoad(&pool[2u * e]));
    if params.level == params.leaf_level {
        n += countOneBits(atomicLoad(&pool[2u * e + 1u]));
    }
    return n;
}

@compute @workgroup_size(256)
fn scan_nodes(@builtin(workgroup_id) group_id: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>,
              @builtin(local_invocation_index) local: u32) {
    let nodes = load_level_nodes(local);
    let group = group_id.x + group_id.y * groups.x;
    if group * BLOCK_NODES >= nodes {
        return;
    }
    let first = group * BLOCK_NODES + local * NODES_PER_THREAD;
    var before: array<u32, NODES_PER_THREAD>;
    var sum = 0u;
    for (var k = 0u; k < NODES_PER_THREAD; k++) {
        before[k] = sum;
        if first + k < nodes {
            sum += children(first + k);
        }
    }
    let inclusive = scan_workgroup(local, sum);
    for (var k = 0u; k < NODES_PER_THREAD; k++) {
        if first + k < nodes {
            node_offsets[first + k] = inclusive - sum + before[k];
        }
    }
    if local == SCAN_THREADS - 1u {
        block_offsets[group] = inclusive;
    }
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(local_invocation_index) local: u32) {
    let nodes = load_level_nodes(local);
    let blocks = (nodes + BLOCK_NODES - 1u) / BLOCK_NODES;
    var carry = 0u;
    for (var base = 0u; base < blocks; base += SCAN_THREADS) {
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
        starts[params.level + 2u] = starts[params.level + 1u] + carry;
    }
}

@compute @workgroup_size(64)
fn link(@builtin(global_invocation_id) id: vec3<u32>,
        @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    let e = starts[params.level] + i;
    if e >= starts[params.level + 1u] || e >= params.capacity {
        return;
    }
    let before = block_offsets[i / BLOCK_NODES] + node_offsets[i];
    if params.level == params.leaf_level {
        brick_voxels[e] = before;
    } else {
        atomicStore(&pool[2u * e + 1u], starts[params.level + 1u] + before);
    }
}
