// Which ocean patches to draw, chosen on the GPU: the quadtree of `fieldkit::ocean::select`
// (refined by projected height error, culled against the frustum with bounds grown by the
// waves' reach, the fewest quads that keep the error, skirts only where the spacing changes),
// written as indirect draws so the host records the same few draws every frame and never walks
// the tree (the GPU-driven terrain of Far Cry 5 and of Unreal's virtual heightfield mesh, here
// without their cross-frame node lists: every node's fate is recomputed from the root).
//
// - `select_patches`: one invocation a node of each level's window, the nodes whose parent may
//   split (a rectangle around the eye, from the level above's split radius; the host computes
//   it). A node walks its ancestors from the root, deciding each one's fate (culled, drawn or
//   split) as the CPU walk does; a drawn leaf picks its quads, finds its skirts, counts itself
//   into its draws and lists itself.
// - `place_draws`: prefix sums over the draws (a grid draw per quad count, then a skirt draw per
//   quad count and edge: skirts after every grid, as the CPU order has them) give each draw its
//   first instance, written as `draw_indexed_indirect` arguments with that first instance
//   (`wgpu::Features::INDIRECT_FIRST_INSTANCE`), and the counts are zeroed for the next frame.
// - `write_instances`: each listed leaf writes its instance into every draw that takes it.

import package::shared::scan::{SCAN_THREADS, scan_total, scan_workgroup};

// Deepest level + 2: `LodParams::levels` holds a window a level and one more entry whose first
// invocation is the total.
const MAX_LEVELS: u32 = 26u;

struct LodParams {
    // Frustum planes of positions relative to the eye's (x, z): a·x + b·y + c·z + d ≥ 0 inside.
    planes: array<vec4<f32>, 6>,
    // Per level: its window's first node (i, j), its columns, its first invocation.
    levels: array<vec4<u32>, MAX_LEVELS>,
    // The square's smallest corner relative to the eye's (x, z), and its side.
    origin: vec2<f32>,
    size: f32,
    // The eye's height (its x and z are 0 here).
    eye_y: f32,
    // How far the surface reaches sideways, its lowest point (skirts included) and its highest.
    sideways: f32,
    low: f32,
    up: f32,
    // Pixels per unit of tangent at the image centre.
    px_per_tan: f32,
    max_error_px: f32,
    max_depth: u32,
    // Quads per side a patch is drawn with: from `fewest_quads` (half, rounded up) to
    // `patch_quads`.
    patch_quads: u32,
    fewest_quads: u32,
    // Invocations of `select_patches` (every level's window).
    invocations: u32,
}

// A patch as the surface's vertex stage takes it (`surface.wgsl`'s instance attributes).
struct PatchInstance {
    // Smallest (x, z) corner then largest, relative to the eye's (x, z).
    square: vec4<f32>,
    quads: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: LodParams;
// Height error of sampling the surface every size / 2^depth / q metres, per depth then per
// quad count from `fewest_quads` (`fieldkit::ocean::height_error`, metres).
@group(0) @binding(1) var<storage, read> errors: array<f32>;
// Instances per draw, then the leaves listed (zeroed by `place_draws` for the next frame).
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;
// Per drawn leaf: node (i, j), then depth | quads << 8 | skirts << 24.
@group(0) @binding(3) var<storage, read_write> leaves: array<vec4<u32>>;
// Per draw, the next free instance; then the leaves listed.
@group(0) @binding(4) var<storage, read_write> cursors: array<atomic<u32>>;
// Per draw, `draw_indexed_indirect` arguments (5 words); then `write_instances`'s dispatch.
@group(0) @binding(5) var<storage, read_write> draws: array<u32>;
@group(0) @binding(6) var<storage, read_write> instances: array<PatchInstance>;

const CULLED: u32 = 0u;
const LEAF: u32 = 1u;
const SPLIT: u32 = 2u;

// What the walk made of a node: culled, drawn or split, at what depth, and the eye's distance
// to its bounds.
struct Fate {
    kind: u32,
    depth: u32,
    dist: f32,
}

fn quad_counts() -> u32 {
    return params.patch_quads - params.fewest_quads + 1u;
}

fn draw_count() -> u32 {
    return 5u * quad_counts();
}

fn grid_draw(quads: u32) -> u32 {
    return quads - params.fewest_quads;
}

fn skirt_draw(quads: u32, edge: u32) -> u32 {
    return quad_counts() + 4u * (quads - params.fewest_quads) + edge;
}

fn node_side(depth: u32) -> f32 {
    return ldexp(params.size, -i32(depth));
}

fn node_corner(depth: u32, node: vec2<u32>) -> vec2<f32> {
    return params.origin + vec2<f32>(node) * node_side(depth);
}

// Projected height error (pixels) of a node at `depth` drawn with `quads`, `dist` away.
fn error_px(depth: u32, quads: u32, dist: f32) -> f32 {
    return errors[depth * quad_counts() + quads - params.fewest_quads] * params.px_per_tan / dist;
}

// A node's own fate, given that its parent split.
fn own_fate(depth: u32, node: vec2<u32>) -> Fate {
    let side = node_side(depth);
    let corner = node_corner(depth, node);
    let reach = params.sideways;
    let lo = vec3<f32>(corner.x - reach, params.low, corner.y - reach);
    let hi = vec3<f32>(corner.x + side + reach, params.up, corner.y + side + reach);
    for (var p = 0u; p < 6u; p++) {
        let plane = params.planes[p];
        // The box corner farthest along the plane's normal.
        let far = select(lo, hi, plane.xyz >= vec3<f32>(0.0));
        if dot(plane.xyz, far) + plane.w < 0.0 {
            return Fate(CULLED, depth, 0.0);
        }
    }
    let eye = vec3<f32>(0.0, params.eye_y, 0.0);
    let dist = max(length(clamp(eye, lo, hi) - eye), 1e-6);
    if error_px(depth, params.patch_quads, dist) > params.max_error_px && depth < params.max_depth {
        return Fate(SPLIT, depth, dist);
    }
    return Fate(LEAF, depth, dist);
}

// The fate of node `node` at `depth` if it was visited, else of its first ancestor that was
// not split (a drawn leaf covering it, or a culled node).
fn fate(depth: u32, node: vec2<u32>) -> Fate {
    for (var k = 0u; k < depth; k++) {
        let f = own_fate(k, node >> vec2<u32>(depth - k));
        if f.kind != SPLIT {
            return f;
        }
    }
    return own_fate(depth, node);
}

// The fewest quads, down to `fewest_quads`, that keep a leaf's error (bisected as the CPU does).
fn leaf_quads(depth: u32, dist: f32) -> u32 {
    var quads = params.patch_quads;
    var fewest_missing = params.fewest_quads - 1u;
    while quads - fewest_missing > 1u {
        let mid = (quads + fewest_missing) / 2u;
        if error_px(depth, mid, dist) <= params.max_error_px {
            quads = mid;
        } else {
            fewest_missing = mid;
        }
    }
    return quads;
}

// Whether a drawn leaf inside the split node `node` touches its side facing `toward` (a unit
// step out of the node): a depth-first walk of the children along that side.
fn drawn_along(depth: u32, node: vec2<u32>, toward: vec2<i32>) -> bool {
    // Each pop pushes two, one level down: the stack never holds more than 2 a level.
    var stack: array<vec3<u32>, 2 * MAX_LEVELS>;
    var n = 0u;
    stack[0] = vec3<u32>(node, depth);
    n = 1u;
    // The children along that side: the high one on an axis the step goes up, else the low.
    let side = vec2<u32>(toward > vec2<i32>(0));
    let along = vec2<u32>(toward == vec2<i32>(0));
    while n > 0u {
        n -= 1u;
        let at = stack[n];
        var f = Fate(SPLIT, at.z, 0.0);
        if at.z != depth {
            f = own_fate(at.z, at.xy);
        }
        if f.kind == LEAF {
            return true;
        }
        if f.kind == SPLIT && n + 2u <= 2u * MAX_LEVELS {
            let first = 2u * at.xy + side * (1u - along);
            stack[n] = vec3<u32>(first, at.z + 1u);
            stack[n + 1u] = vec3<u32>(first + along, at.z + 1u);
            n += 2u;
        }
    }
    return false;
}

// The edges of the drawn leaf that hang a skirt (bit e for the step `e` of z low, x high, z
// high, x low): those beside a drawn patch of another vertex spacing.
fn skirt_edges(depth: u32, node: vec2<u32>, quads: u32) -> u32 {
    var steps = array<vec2<i32>, 4>(vec2<i32>(0, -1), vec2<i32>(1, 0), vec2<i32>(0, 1), vec2<i32>(-1, 0));
    let side = i32(1u << depth);
    var mask = 0u;
    for (var e = 0u; e < 4u; e++) {
        let across = vec2<i32>(node) + steps[e];
        if any(across < vec2<i32>(0)) || any(across >= vec2<i32>(side)) {
            continue;
        }
        let f = fate(depth, vec2<u32>(across));
        var needs = false;
        if f.kind == LEAF {
            needs = f.depth != depth || leaf_quads(depth, f.dist) != quads;
        } else if f.kind == SPLIT {
            needs = drawn_along(depth, vec2<u32>(across), -steps[e]);
        }
        if needs {
            mask |= 1u << e;
        }
    }
    return mask;
}

@compute @workgroup_size(64)
fn select_patches(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    if t >= params.invocations {
        return;
    }
    var depth = 0u;
    while depth < params.max_depth && t >= params.levels[depth + 1u].w {
        depth++;
    }
    let level = params.levels[depth];
    let local = t - level.w;
    let node = level.xy + vec2<u32>(local % level.z, local / level.z);
    let f = fate(depth, node);
    if f.kind != LEAF || f.depth != depth {
        return;
    }
    let quads = leaf_quads(depth, f.dist);
    let skirts = skirt_edges(depth, node, quads);
    atomicAdd(&counts[grid_draw(quads)], 1u);
    for (var e = 0u; e < 4u; e++) {
        if (skirts & (1u << e)) != 0u {
            atomicAdd(&counts[skirt_draw(quads, e)], 1u);
        }
    }
    let at = atomicAdd(&counts[draw_count()], 1u);
    leaves[at] = vec4<u32>(node, depth | (quads << 8u) | (skirts << 24u), 0u);
}

// First index of quad count `quads`'s indices in the renderer's index buffer: the index lists
// of every count from `fewest_quads` up, each its grid then its four skirts.
fn first_index(quads: u32) -> u32 {
    var at = 0u;
    for (var q = params.fewest_quads; q < quads; q++) {
        at += 6u * q * q + 24u * q;
    }
    return at;
}

@compute @workgroup_size(256)
fn place_draws(@builtin(local_invocation_index) local: u32) {
    let total = draw_count();
    var carry = 0u;
    for (var base = 0u; base < total; base += SCAN_THREADS) {
        let d = base + local;
        var count = 0u;
        if d < total {
            count = atomicLoad(&counts[d]);
        }
        let inclusive = scan_workgroup(local, count);
        if d < total {
            let first = carry + inclusive - count;
            atomicStore(&cursors[d], first);
            atomicStore(&counts[d], 0u);
            var quads: u32;
            var index_count: u32;
            var index_first: u32;
            if d < quad_counts() {
                quads = params.fewest_quads + d;
                index_count = 6u * quads * quads;
                index_first = first_index(quads);
            } else {
                let k = d - quad_counts();
                quads = params.fewest_quads + k / 4u;
                index_count = 6u * quads;
                index_first = first_index(quads) + 6u * quads * quads + (k % 4u) * 6u * quads;
            }
            draws[5u * d] = index_count;
            draws[5u * d + 1u] = count;
            draws[5u * d + 2u] = index_first;
            draws[5u * d + 3u] = 0u;
            draws[5u * d + 4u] = first;
        }
        carry += scan_total();
        // `scan_total` is read by every invocation before the next round writes the scan.
        workgroupBarrier();
    }
    if local == 0u {
        let listed = atomicLoad(&counts[total]);
        atomicStore(&counts[total], 0u);
        atomicStore(&cursors[total], listed);
        draws[5u * total] = (listed + 63u) / 64u;
        draws[5u * total + 1u] = 1u;
        draws[5u * total + 2u] = 1u;
    }
}

@compute @workgroup_size(64)
fn write_instances(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= atomicLoad(&cursors[draw_count()]) {
        return;
    }
    let leaf = leaves[id.x];
    let depth = leaf.z & 0xffu;
    let quads = (leaf.z >> 8u) & 0x3ffu;
    let skirts = leaf.z >> 24u;
    // Both corners from the same expression a neighbour uses for its own: shared edges match
    // bit for bit.
    let lo = node_corner(depth, leaf.xy);
    let hi = node_corner(depth, leaf.xy + vec2<u32>(1u));
    let instance = PatchInstance(vec4<f32>(lo, hi), vec4<u32>(quads, 0u, 0u, 0u));
    instances[atomicAdd(&cursors[grid_draw(quads)], 1u)] = instance;
    for (var e = 0u; e < 4u; e++) {
        if (skirts & (1u << e)) != 0u {
            instances[atomicAdd(&cursors[skirt_draw(quads, e)], 1u)] = instance;
        }
    }
}
