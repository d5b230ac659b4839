// Ray casts through a sparse voxel octree (`octree/build`): the first occupied cell a ray
// meets at a level of detail, for a first-hit render (`render`, one thread per pixel) and for
// other stages and tests (`cast_rays`, a list of rays; `lookup`, occupancy at a list of points;
// `expand`, a level as a dense bitset for the stages that take one).
//
// A ray walks the cells of its level — voxels at level log_side, nodes of 2^(log_side − m) voxels
// at level m — one cell at a time (Amanatides & Woo), each boundary's distance computed as
// (boundary − start) × (1 / direction), so the cells visited are those of a DDA through the dense
// grid of that level, exactly. It looks the tree up only on entering a cell outside the last
// empty node it found, and leaves an empty node in one step: the DDA's steps are the three axes'
// boundary crossings merged in order of distance (x before y before z on ties), so the crossing
// that leaves the node is the least of its three far faces' (computed by the same formula), and
// on the other axes the walk is then in the cell whose entering boundary comes before that
// crossing and whose leaving one does not (found from the ray's position there, corrected by
// those boundaries). A ray through empty space costs a probe and a jump per empty node, not a
// step per cell. Level m's cell is occupied where the tree has its node (below the bricks: where
// the brick has a voxel of the cell's 2³ block or the voxel).
//
// The render chooses the level per pixel from its footprint: the finest level whose cell is at
// least `footprint` pixels wide where the ray enters the grid (or a fixed level), shades the hit
// with one light, and writes the colour and the hit's depth. With ATTRIBUTES it shades the hit
// cell's filtered colour and normal (`octree/attributes`: the voxel's own at the voxel level, the
// node's above it, the brick's for 2³ blocks); without, the hit face in one colour.

import fieldkit::field::{ndc_depth, pixel_ray, ray_box};
import fieldkit::octahedral::decode_octahedral;
import fieldkit::octree::{brick_bit, brick_block, brick_has, octree_child, octree_has_child, octree_octant};

struct CastParams {
    inv_view_proj: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    // World to grid-local coordinates (voxels of edge 1, the grid's corner at 0) and back.
    world_to_local: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    size: vec3<u32>,
    log_side: u32,
    // Towards the light, grid-local, unit length.
    light: vec3<f32>,
    // The level rays cast at; LOD_BY_FOOTPRINT: chosen per pixel by `footprint`.
    level: u32,
    colour: vec3<f32>,
    // Pixels a cell must cover at least, where the level is chosen by footprint.
    footprint: f32,
    viewport: vec2<f32>,
    near_z: f32,
    far_z: f32,
    // Entries of `rays` / `points`.
    count: u32,
}

@group(0) @binding(0) var<uniform> params: CastParams;
// Two u32 per entry (see fieldkit::octree).
@group(0) @binding(1) var<storage, read> pool: array<vec2<u32>>;
// `cast_rays`: per ray, (start, level as f32 bits) and (1 / direction, 0); the start inside the
// grid, in grid-local coordinates.
@group(0) @binding(2) var<storage, read> rays: array<vec4<f32>>;
// `cast_rays`: per ray, the hit cell and the axis crossed into it (−1: the start cell), or
// (−1, −1, −1, 3) for a miss. `lookup`: per point, 1 where its cell is occupied.
@group(0) @binding(3) var<storage, read_write> hits: array<vec4<i32>>;
// `lookup`: per point, its voxel and the level to look at.
@group(0) @binding(4) var<storage, read> points: array<vec4<u32>>;
@group(0) @binding(5) var colour_out: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(6) var depth_out: texture_storage_2d<r32float, write>;
// With ATTRIBUTES: per entry the node's (RGBA8 colour, octahedral normal), per occupied voxel
// the same, and per brick entry its first voxel's slot.
@group(0) @binding(7) var<storage, read> node_attributes: array<vec2<u32>>;
@group(0) @binding(8) var<storage, read> voxel_attributes: array<vec2<u32>>;
@group(0) @binding(9) var<storage, read> brick_voxels: array<u32>;

// `expand`: the level's cells, one bit each, x fastest (`params.count` words).
@group(0) @binding(10) var<storage, read_write> dense: array<u32>;

override ATTRIBUTES: bool = false;

const NONE: u32 = 0xffffffffu;
const LOD_BY_FOOTPRINT: u32 = 0xffffffffu;
const MISS: i32 = 3;

// x: the shallowest level j ≤ m whose node holding cell c (of level m) is empty, NONE where the
// cell is occupied; y: the deepest entry reached (the cell's node, or its brick).
fn probe(c: vec3<u32>, m: u32) -> vec2<u32> {
    let leaf = params.log_side - 2u;
    let v = c << vec3<u32>(params.log_side - m);
    var entry = 0u;
    var node = pool[0];
    for (var j = 1u; j <= min(m, leaf); j++) {
        let o = octree_octant(v, params.log_side, j);
        if !octree_has_child(node, o) {
            return vec2<u32>(j, entry);
        }
        entry = octree_child(node, o);
        node = pool[entry];
    }
    if m > leaf {
        if !brick_block(node, v) {
            return vec2<u32>(leaf + 1u, entry);
        }
        if m > leaf + 1u && !brick_has(node, v) {
            return vec2<u32>(m, entry);
        }
    }
    return vec2<u32>(NONE, entry);
}

struct Hit {
    cell: vec3<i32>,
    // The axis crossed into the cell, −1 for the start cell, MISS.
    axis: i32,
    // Distance from the start to the cell's entry.
    t: f32,
    // The cell's node, or its brick below the bricks' level.
    entry: u32,
}

// Distance from `start` to boundary k × cell along one axis.
fn boundary(k: i32, cell: f32, start: f32, inv: f32) -> f32 {
    if abs(inv) > 3.0e38 {
        return 3.4e38;
    }
    return (f32(k) * cell - start) * inv;
}

// Whether a crossing on axis b at distance tb comes before one on axis a at ta in the walk's
// order: by distance, then x before y before z.
fn before(tb: f32, b: i32, ta: f32, a: i32) -> bool {
    return tb < ta || (tb == ta && b < a);
}

// Axis b's cell (of a box `cells` wide) when the walk leaves the box on axis a at distance te:
// between `here` (the current cell) and `last` (the box's last along the ray), the cell whose
// entering boundary comes before (te, a) and whose leaving boundary does not.
fn cell_at(b: i32, te: f32, a: i32, here: i32, last: i32, step: i32, ahead: i32, cell: f32,
           start: f32, inv: f32, cells: i32) -> i32 {
    var g = i32(clamp(floor((start + te / inv) / cell), -1.0e9, 1.0e9));
    g = select(clamp(g, last, here), clamp(g, here, last), step > 0);
    for (var i = 0; i < cells && g != here; i++) {
        if before(boundary(g - step + ahead, cell, start, inv), b, te, a) {
            break;
        }
        g -= step;
    }
    for (var i = 0; i < cells && g != last; i++) {
        if !before(boundary(g + ahead, cell, start, inv), b, te, a) {
            break;
        }
        g += step;
    }
    return g;
}

// The first occupied cell of level m along the ray from `start` (inside the grid) with
// reciprocal direction `inv`.
fn walk(start: vec3<f32>, inv: vec3<f32>, m: u32) -> Hit {
    let shift = params.log_side - m;
    let cell = f32(1u << shift);
    let extent = vec3<i32>((params.size + vec3<u32>((1u << shift) - 1u)) >> vec3<u32>(shift));
    let step = select(vec3<i32>(-1), vec3<i32>(1), inv >= vec3<f32>(0.0));
    var c = clamp(vec3<i32>(floor(start / cell)), vec3<i32>(0), extent - 1);
    let ahead = select(vec3<i32>(0), vec3<i32>(1), step > vec3<i32>(0));
    var axis = -1;
    var t = 0.0;
    // The last empty node found, as a box of level-m cells [lo, hi).
    var lo = vec3<i32>(1);
    var hi = vec3<i32>(0);
    let guard = u32(extent.x + extent.y + extent.z) + 3u;
    for (var n = 0u; n < guard; n++) {
        if any(c < vec3<i32>(0)) || any(c >= extent) {
            break;
        }
        if any(c < lo) || any(c >= hi) {
            let found = probe(vec3<u32>(c), m);
            let j = found.x;
            if j == NONE {
                return Hit(c, axis, t, found.y);
            }
            let span = m - j;
            lo = (c >> vec3<u32>(span)) << vec3<u32>(span);
            hi = lo + vec3<i32>(1 << span);
        }
        // c is in the empty box [lo, hi): leave it. Its far faces' crossings; the least (x,
        // then y, then z on ties) is where the walk leaves it.
        let last = select(lo, hi - 1, step > vec3<i32>(0));
        let far = vec3<f32>(boundary(last.x + ahead.x, cell, start.x, inv.x),
                            boundary(last.y + ahead.y, cell, start.y, inv.y),
                            boundary(last.z + ahead.z, cell, start.z, inv.z));
        let cells = hi.x - lo.x;
        if far.x <= far.y && far.x <= far.z {
            axis = 0;
            t = far.x;
            c.y = cell_at(1, t, 0, c.y, last.y, step.y, ahead.y, cell, start.y, inv.y, cells);
            c.z = cell_at(2, t, 0, c.z, last.z, step.z, ahead.z, cell, start.z, inv.z, cells);
            c.x = last.x + step.x;
        } else if far.y <= far.z {
            axis = 1;
            t = far.y;
            c.x = cell_at(0, t, 1, c.x, last.x, step.x, ahead.x, cell, start.x, inv.x, cells);
            c.z = cell_at(2, t, 1, c.z, last.z, step.z, ahead.z, cell, start.z, inv.z, cells);
            c.y = last.y + step.y;
        } else {
            axis = 2;
            t = far.z;
            c.x = cell_at(0, t, 2, c.x, last.x, step.x, ahead.x, cell, start.x, inv.x, cells);
            c.y = cell_at(1, t, 2, c.y, last.y, step.y, ahead.y, cell, start.y, inv.y, cells);
            c.z = last.z + step.z;
        }
    }
    return Hit(vec3<i32>(-1), MISS, t, 0u);
}

@compute @workgroup_size(64)
fn cast_rays(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let a = rays[2u * id.x];
    let b = rays[2u * id.x + 1u];
    let hit = walk(a.xyz, b.xyz, bitcast<u32>(a.w));
    hits[id.x] = vec4<i32>(hit.cell, hit.axis);
}

@compute @workgroup_size(64)
fn lookup(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let p = points[id.x];
    let m = min(p.w, params.log_side);
    var occupied = 0;
    if all(p.xyz < params.size) && probe(p.xyz >> vec3<u32>(params.log_side - m), m).x == NONE {
        occupied = 1;
    }
    hits[id.x] = vec4<i32>(occupied, 0, 0, 0);
}

@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) id: vec3<u32>) {
    let px = id.xy;
    if f32(px.x) >= params.viewport.x || f32(px.y) >= params.viewport.y {
        return;
    }
    let centre = vec2<f32>(px) + 0.5;
    let ray = pixel_ray(centre, params.viewport, params.inv_view_proj, params.world_to_local,
                        params.near_z, params.far_z);
    let span = ray_box(ray.origin, ray.dir, vec3<f32>(0.0), vec3<f32>(params.size));
    let enter = max(span.x, 0.0);
    let exit = min(span.y, ray.length);
    var colour = vec4<f32>(0.0);
    var depth = params.far_z;
    if enter < exit {
        var m = params.level;
        if m == LOD_BY_FOOTPRINT {
            // A pixel's width in voxels where the ray enters: the distance between this ray and
            // its neighbour's there.
            let next = pixel_ray(centre + vec2<f32>(1.0, 0.0), params.viewport,
                                 params.inv_view_proj, params.world_to_local, params.near_z,
                                 params.far_z);
            let width = length((ray.origin + ray.dir * enter) - (next.origin + next.dir * enter));
            let coarse = floor(log2(max(width * params.footprint, 1.0)));
            m = params.log_side - min(u32(coarse), params.log_side);
        }
        m = min(m, params.log_side);
        // Start a hair inside the grid so the start cell is the one the ray enters.
        let start = clamp(ray.origin + ray.dir * enter, vec3<f32>(0.0), vec3<f32>(params.size));
        let hit = walk(start, 1.0 / ray.dir, m);
        if hit.axis != MISS {
            var normal = -ray.dir;
            if hit.axis >= 0 {
                var n = vec3<f32>(0.0);
                n[hit.axis] = -sign(ray.dir[hit.axis]);
                normal = n;
            }
            var base = params.colour;
            if ATTRIBUTES {
                var a = node_attributes[hit.entry];
                if m == params.log_side {
                    // The voxel's own: its brick's first slot and the brick's voxels below it.
                    let brick = pool[hit.entry];
                    let bit = brick_bit(vec3<u32>(hit.cell));
                    let below = select((1u << bit) - 1u, 0xffffffffu, bit >= 32u);
                    let above = select(0u, (1u << (bit - 32u)) - 1u, bit >= 32u);
                    a = voxel_attributes[brick_voxels[hit.entry] + countOneBits(brick.x & below)
                        + countOneBits(brick.y & above)];
                }
                base = unpack4x8unorm(a.x).rgb;
                let n = decode_octahedral(a.y);
                if dot(n, n) > 0.0 {
                    normal = n;
                }
            }
            let lambert = max(dot(normal, params.light), 0.0);
            colour = vec4<f32>(base * (0.25 + 0.75 * lambert), 1.0);
            let world = (params.local_to_world * vec4<f32>(start + ray.dir * hit.t, 1.0)).xyz;
            depth = ndc_depth(params.view_proj, world);
        }
    }
    textureStore(colour_out, px, colour);
    textureStore(depth_out, px, vec4<f32>(depth, 0.0, 0.0, 0.0));
}

// One thread per 32 cells of level `params.level` (a bitset word of its grid of cells).
@compute @workgroup_size(64)
fn expand(@builtin(global_invocation_id) id: vec3<u32>,
          @builtin(num_workgroups) groups: vec3<u32>) {
    let w = id.x + id.y * groups.x * 64u;
    if w >= params.count {
        return;
    }
    let m = params.level;
    let shift = params.log_side - m;
    let extent = (params.size + vec3<u32>((1u << shift) - 1u)) >> vec3<u32>(shift);
    var word = 0u;
    for (var b = 0u; b < 32u; b++) {
        let i = w * 32u + b;
        let c = vec3<u32>(i % extent.x, (i / extent.x) % extent.y, i / (extent.x * extent.y));
        if c.z < extent.z && probe(c, m).x == NONE {
            word |= 1u << b;
        }
    }
    dense[w] = word;
}
