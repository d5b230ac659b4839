// Surface voxelization through the rasterizer, the write-up's path (OpenGL Insights, Crassin &
// Green) kept for comparison with `voxelize/surface`: vertices are pulled from the triangle
// buffer by vertex index, the vertex stage projects each triangle onto the plane of its
// normal's dominant axis (one pixel per voxel column) and enlarges it by half a pixel's
// diagonal (Hasselgren et al., GPU Gems 2 ch. 42) so every column the triangle touches gets a
// fragment, since WebGPU has neither geometry shaders nor conservative rasterization. Each
// fragment then runs the exact tests of `fieldkit::triangle_box` on its column and sets bits with
// atomicOr, so the voxels are the compute path's, and only the way columns are found differs.

import fieldkit::triangle_box::{Setup, column_at, in_box, overlaps, setup};

struct RasterParams {
    grid: vec3<u32>,
    // Side of the square render target: the grid's largest side.
    side: u32,
    slack: f32,
    // Pixels the enlargement adds beyond half a diagonal, for the rasterizer's snapping.
    margin: f32,
}

struct Raster {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

@group(0) @binding(0) var<uniform> params: RasterParams;
// Three vertices per triangle, grid-local (w unused).
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Occupancy, one bit per voxel: voxel (x, y, z) is bit i % 32 of word i / 32 with
// i = (z · ny + y) · nx + x.
@group(0) @binding(2) var<storage, read_write> occupancy: array<atomic<u32>>;

fn load(t: u32) -> Setup {
    return setup(triangles[3u * t].xyz, triangles[3u * t + 1u].xyz, triangles[3u * t + 2u].xyz,
                 vec3<i32>(params.grid), params.slack, false);
}

// p on the (u, w) axes.
fn flat(s: Setup, p: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(dot(p, vec3<f32>(s.eu)), dot(p, vec3<f32>(s.ew)));
}

// The line through a and b as (n, d) with n · x + d = 0 and n pointing away from `inside`'s
// side, moved outward by `r` in the L1 sense (a square of half-side r just touches it).
fn shifted_edge(a: vec2<f32>, b: vec2<f32>, sign: f32, r: f32) -> vec3<f32> {
    let n = vec2<f32>(b.y - a.y, a.x - b.x) * sign;
    return vec3<f32>(n, -dot(n, a) - r * (abs(n.x) + abs(n.y)));
}

@vertex
fn vs_raster(@builtin(vertex_index) index: u32) -> Raster {
    let t = index / 3u;
    let corner = index % 3u;
    let s = load(t);
    let v = array<vec2<f32>, 3>(flat(s, triangles[3u * t].xyz), flat(s, triangles[3u * t + 1u].xyz),
                                flat(s, triangles[3u * t + 2u].xyz));
    // Edges oriented so their normals point out of the projected triangle.
    let area = (v[1].x - v[0].x) * (v[2].y - v[0].y) - (v[1].y - v[0].y) * (v[2].x - v[0].x);
    let sign = select(-1.0, 1.0, area >= 0.0);
    let r = 0.5 + params.margin;
    let before = shifted_edge(v[(corner + 2u) % 3u], v[corner], sign, r);
    let after = shifted_edge(v[corner], v[(corner + 1u) % 3u], sign, r);
    // The enlarged corner: where the two moved edges meet (homogeneous line intersection).
    let h = cross(before, after);
    var p = v[corner];
    if abs(h.z) > 1e-20 {
        p = h.xy / h.z;
    }
    let side = f32(params.side);
    var out: Raster;
    // Framebuffer pixel (a, b) covers column (a, b): x = u, y = w (y down).
    out.position = vec4<f32>(p.x / side * 2.0 - 1.0, 1.0 - p.y / side * 2.0, 0.5, 1.0);
    out.triangle = t;
    return out;
}

@fragment
fn fs_raster(in: Raster) -> @location(0) vec4<f32> {
    let s = load(in.triangle);
    let c = column_at(s, i32(floor(in.position.x)), i32(floor(in.position.y)));
    let g = vec3<i32>(params.grid);
    for (var z = c.k0; z < c.k1; z++) {
        let p = c.p + s.ek * z;
        // The enlarged triangle reaches columns outside the box; those hold nothing. The
        // whole test (`overlaps`, which the package offers for a voxel found any way), though
        // `column_at` has tested the projection along k: this path's cost is the rasterizer's.
        if in_box(s, p) && overlaps(s, p, false) {
            let i = u32((p.z * g.y + p.y) * g.x + p.x);
            atomicOr(&occupancy[i / 32u], 1u << (i % 32u));
        }
    }
    // The target only gives the rasterizer a size; nothing is written to it.
    return vec4<f32>(0.0);
}
