// Attributes of a sparse voxel octree (`octree/build`; OpenGL Insights ch. 22, part 2): each
// occupied voxel's colour and normal averaged over the triangles that touch it, stored brick by
// brick, then filtered up the tree (mipmapping) so every node holds the mean of its children.
//
//   `accumulate` one thread per fragment: its triangle's attributes at its voxel (the arithmetic
//                of the dense attribute pass, `shared/voxel_attribute`, the albedo
//                texture's colour included) added into the voxel's
//                integer sums; the voxel's slot is its brick's first (`brick_voxels`) plus the
//                brick's occupied voxels below it.
//   `average`    one thread per voxel: its sums' average.
//   Both run once per batch of `batch` voxels from `first_voxel` on, the sums cleared between
//   batches, so the sums (32 bytes a voxel) need only one batch's room.
//   `resolve`    one thread per brick: the brick's own attribute, the mean of its voxels'.
//   `filter_level` one thread per node of a level, deepest inner level first: the mean of its
//                children's attributes.
//
// A mean colour is the integer mean of the 8-bit colours rounded to nearest, a mean normal the
// direction of the sum of the normals (in a fixed order: bit order, then octant order), so two
// runs give identical bytes. Normals that cancel are NO_NORMAL, and a mean skips them.

import fieldkit::octahedral::{NO_NORMAL, decode_octahedral, encode_octahedral};
import fieldkit::octree::brick_bit;
import fieldkit::triangle_box::setup;
import package::shared::voxel_attribute::{SUMS, average, closest_weights, contribution, corner_colour, corner_normal, corner_uv};

struct AttributeParams {
    grid: vec3<u32>,
    // The level `filter` works on.
    level: u32,
    leaf_level: u32,
    // Fragments the list holds.
    fragments: u32,
    // Entries the pool holds.
    capacity: u32,
    // The batch: its first voxel slot and its voxels (the sums hold `batch`).
    first_voxel: u32,
    batch: u32,
    // Occupied voxels in all.
    voxels: u32,
    slack: f32,
    // 1: the colour is the corners' colour × the albedo at the corners' texture coordinates,
    // interpolated as the colour is (as the dense attribute pass does).
    textured: u32,
}

@group(0) @binding(0) var<uniform> params: AttributeParams;
// `voxelize/fragments`: voxels as (x | y << 16, z) and their triangles.
@group(0) @binding(1) var<storage, read> fragments: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> triangle_ids: array<u32>;
// Three grid-local vertices per triangle; six words per triangle of corner attributes.
@group(0) @binding(3) var<storage, read> triangles: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> corners: array<vec4<u32>>;
// `octree/build`: each fragment's brick (NONE past the list's fragments), the pool, the levels
// and, per brick entry, its first voxel's slot.
@group(0) @binding(5) var<storage, read> cursor: array<u32>;
@group(0) @binding(6) var<storage, read> pool: array<vec2<u32>>;
@group(0) @binding(7) var<storage, read> starts: array<u32>;
@group(0) @binding(8) var<storage, read> brick_voxels: array<u32>;
// SUMS words per occupied voxel.
@group(0) @binding(9) var<storage, read_write> sums: array<atomic<u32>>;
// Per occupied voxel, brick by brick in bit order: (RGBA8 colour, octahedral normal).
@group(0) @binding(10) var<storage, read_write> voxel_attributes: array<vec2<u32>>;
// Per pool entry: the node's filtered (RGBA8 colour, octahedral normal).
@group(0) @binding(11) var<storage, read_write> node_attributes: array<vec2<u32>>;
// The albedo (a 1×1 stand-in unless `textured`), sampled with repeat and linear filtering.
@group(0) @binding(12) var albedo: texture_2d<f32>;
@group(0) @binding(13) var albedo_sampler: sampler;

const NONE: u32 = 0xffffffffu;

// The slot of voxel `bit` of brick entry e among the occupied voxels.
fn voxel_slot(e: u32, brick: vec2<u32>, bit: u32) -> u32 {
    let below = select((1u << bit) - 1u, 0xffffffffu, bit >= 32u);
    let above = select(0u, (1u << (bit - 32u)) - 1u, bit >= 32u);
    return brick_voxels[e] + countOneBits(brick.x & below)
        + countOneBits(brick.y & above);
}

@compute @workgroup_size(64)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>,
              @builtin(num_workgroups) groups: vec3<u32>) {
    let f = id.x + id.y * groups.x * 64u;
    if f >= params.fragments {
        return;
    }
    let e = cursor[f];
    if e == NONE || e >= params.capacity {
        return;
    }
    let packed = fragments[f];
    let v = vec3<u32>(packed.x & 0xffffu, packed.x >> 16u, packed.y);
    let slot = voxel_slot(e, pool[e], brick_bit(v));
    if slot < params.first_voxel || slot - params.first_voxel >= params.batch {
        return;
    }
    let t = triangle_ids[f];
    let v0 = triangles[3u * t].xyz;
    let v1 = triangles[3u * t + 1u].xyz;
    let v2 = triangles[3u * t + 2u].xyz;
    let s = setup(v0, v1, v2, vec3<i32>(params.grid), params.slack, false);
    let p = vec3<i32>(v);
    let b = closest_weights(s, v0, v1, v2, p);
    let c0 = corners[6u * t];
    let c1 = corners[6u * t + 2u];
    let c2 = corners[6u * t + 4u];
    var colour = corner_colour(b, c0.x, c1.x, c2.x);
    if params.textured != 0u {
        let uv = corner_uv(b, corners[6u * t + 1u].xy, corners[6u * t + 3u].xy,
                           corners[6u * t + 5u].xy);
        colour *= textureSampleLevel(albedo, albedo_sampler, uv, 0.0);
    }
    let add = contribution(colour,
                           corner_normal(b, bitcast<vec3<f32>>(c0.yzw), bitcast<vec3<f32>>(c1.yzw),
                                         bitcast<vec3<f32>>(c2.yzw), s.n));
    let at = SUMS * (slot - params.first_voxel);
    atomicAdd(&sums[at], add.rgba.x);
    atomicAdd(&sums[at + 1u], add.rgba.y);
    atomicAdd(&sums[at + 2u], add.rgba.z);
    atomicAdd(&sums[at + 3u], add.rgba.w);
    atomicAdd(&sums[at + 4u], add.normal.x);
    atomicAdd(&sums[at + 5u], add.normal.y);
    atomicAdd(&sums[at + 6u], add.normal.z);
    atomicAdd(&sums[at + 7u], 1u);
}

// A running mean of attributes: colour sums per channel, the normals' sum, and counts.
struct Mean {
    colour: vec4<u32>,
    normal: vec3<f32>,
    n: u32,
}

fn add_to(m: Mean, a: vec2<u32>) -> Mean {
    var out = m;
    out.colour += vec4<u32>(a.x & 0xffu, (a.x >> 8u) & 0xffu, (a.x >> 16u) & 0xffu, a.x >> 24u);
    if a.y != NO_NORMAL {
        out.normal += decode_octahedral(a.y);
    }
    out.n += 1u;
    return out;
}

fn mean_of(m: Mean) -> vec2<u32> {
    let n = max(m.n, 1u);
    let c = (m.colour + n / 2u) / n;
    var normal = NO_NORMAL;
    if dot(m.normal, m.normal) > 0.0 {
        normal = encode_octahedral(normalize(m.normal));
    }
    return vec2<u32>(c.x | (c.y << 8u) | (c.z << 16u) | (c.w << 24u), normal);
}

@compute @workgroup_size(64)
fn average_voxels(@builtin(global_invocation_id) id: vec3<u32>,
                  @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= params.batch || params.first_voxel + i >= params.voxels {
        return;
    }
    let at = SUMS * i;
    voxel_attributes[params.first_voxel + i] =
        average(vec4<u32>(atomicLoad(&sums[at]), atomicLoad(&sums[at + 1u]),
                          atomicLoad(&sums[at + 2u]), atomicLoad(&sums[at + 3u])),
                vec3<u32>(atomicLoad(&sums[at + 4u]), atomicLoad(&sums[at + 5u]),
                          atomicLoad(&sums[at + 6u])),
                atomicLoad(&sums[at + 7u]));
}

@compute @workgroup_size(64)
fn resolve(@builtin(global_invocation_id) id: vec3<u32>,
           @builtin(num_workgroups) groups: vec3<u32>) {
    let e = starts[params.leaf_level] + id.x + id.y * groups.x * 64u;
    if e >= starts[params.leaf_level + 1u] || e >= params.capacity {
        return;
    }
    let brick = pool[e];
    let first = brick_voxels[e];
    let count = countOneBits(brick.x) + countOneBits(brick.y);
    var m = Mean(vec4<u32>(0u), vec3<f32>(0.0), 0u);
    for (var k = 0u; k < count; k++) {
        if first + k < params.voxels {
            m = add_to(m, voxel_attributes[first + k]);
        }
    }
    node_attributes[e] = mean_of(m);
}

@compute @workgroup_size(64)
fn filter_level(@builtin(global_invocation_id) id: vec3<u32>,
          @builtin(num_workgroups) groups: vec3<u32>) {
    let e = starts[params.level] + id.x + id.y * groups.x * 64u;
    if e >= starts[params.level + 1u] || e >= params.capacity {
        return;
    }
    let node = pool[e];
    var m = Mean(vec4<u32>(0u), vec3<f32>(0.0), 0u);
    let children = countOneBits(node.x);
    for (var k = 0u; k < children; k++) {
        if node.y + k < params.capacity {
            m = add_to(m, node_attributes[node.y + k]);
        }
    }
    node_attributes[e] = mean_of(m);
}
