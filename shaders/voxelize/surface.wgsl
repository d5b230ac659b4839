// Conservative surface voxelization (Schwarz & Seidel 2010): every voxel a triangle touches,
// closed boxes, written to an occupancy bitset with atomicOr. Vertices arrive in grid-local
// coordinates (origin 0, voxel size 1; the host transforms them in f64).
//
// Per triangle: the bounding-box pre-test, then for each 2D column along the dominant axis of
// the triangle's normal, only the voxels whose column the plane crosses, each tested against
// the plane (the critical-point form) and the three 2D edge functions of the xy, yz and zx
// projections. A voxel passes exactly when the triangle and the box overlap (the 13-axis
// separating-axis test says the same). Every test is widened by `slack`, a bound on the f32
// rounding of its terms, so rounding can add voxels within that margin but never drop one.
//
// One thread per triangle (`first` and `count` select a run of the triangle list). A triangle
// with more than CHUNK columns does not stall its thread: `surface` appends it to a work list
// in chunks of CHUNK columns, `heavy_args` sizes an indirect dispatch from the list's length,
// and `surface_heavy` takes one chunk per thread.
//
// SIX_SEPARATING gives the thinner voxelization of the same paper: a voxel is kept when the
// plane crosses the voxel's inner cross (|n·(centre − v0)| ≤ ‖n‖∞ / 2) and each projection of
// its centre lies within half a voxel, in the edge's dominant direction, of the projected
// triangle. No 6-connected path gets through it; 26-connected paths can.

struct SurfaceParams {
    grid: vec3<u32>,
    first: u32,
    count: u32,
    // Relative rounding bound for the tests (a few ulp of f32).
    slack: f32,
    // Entries the work list holds (the host sizes it for every chunk there can be).
    capacity: u32,
}

// Columns per chunk of a heavy triangle.
const CHUNK: u32 = 64u;

override SIX_SEPARATING: bool = false;

@group(0) @binding(0) var<uniform> params: SurfaceParams;
// Three vertices per triangle, grid-local (w unused).
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>;
// Occupancy, one bit per voxel, x fastest: voxel (x, y, z) is bit i % 32 of word i / 32 with
// i = (z · ny + y) · nx + x.
@group(0) @binding(2) var<storage, read_write> occupancy: array<atomic<u32>>;
// Heavy triangles' chunks: (triangle, first column); `work_count` entries used (it may count
// past `capacity` only if the host's bound were wrong; entries past it are dropped).
@group(0) @binding(3) var<storage, read_write> work: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> work_count: atomic<u32>;
// Indirect dispatch arguments for `surface_heavy`.
@group(0) @binding(5) var<storage, read_write> heavy_dispatch: array<u32, 3>;

fn set_voxel(p: vec3<i32>) {
    let g = vec3<i32>(params.grid);
    let i = u32((p.z * g.y + p.y) * g.x + p.x);
    atomicOr(&occupancy[i / 32u], 1u << (i % 32u));
}

// 2D edge functions of one projection: normals and offsets for the three edges, oriented by
// the sign of the normal's component along the dropped axis so the inside is positive. A
// voxel's projection (its min corner q, side 1) overlaps the triangle's when every edge
// function at q plus its critical offset is ≥ 0.
struct Edges {
    n0: vec2<f32>,
    n1: vec2<f32>,
    n2: vec2<f32>,
    d: vec3<f32>,
    slack: vec3<f32>,
}

fn edges(a: vec2<f32>, b: vec2<f32>, c: vec2<f32>, facing: f32, scale: f32) -> Edges {
    let s = select(-1.0, 1.0, facing >= 0.0);
    var e: Edges;
    let v = array<vec2<f32>, 3>(a, b, c);
    var n: array<vec2<f32>, 3>;
    var d: vec3<f32>;
    var sl: vec3<f32>;
    for (var i = 0u; i < 3u; i++) {
        let p = v[i];
        let q = v[(i + 1u) % 3u];
        let edge = q - p;
        let ni = vec2<f32>(-edge.y, edge.x) * s;
        n[i] = ni;
        if SIX_SEPARATING {
            // Tested at the square's centre q + ½, reaching half a voxel along the edge
            // normal's larger component.
            d[i] = -dot(ni, p) + 0.5 * (ni.x + ni.y) + 0.5 * max(abs(ni.x), abs(ni.y));
        } else {
            d[i] = -dot(ni, p) + max(0.0, ni.x) + max(0.0, ni.y);
        }
        sl[i] = params.slack * (abs(ni.x) + abs(ni.y)) * scale;
    }
    e.n0 = n[0];
    e.n1 = n[1];
    e.n2 = n[2];
    e.d = d;
    e.slack = sl;
    return e;
}

fn inside(e: Edges, q: vec2<f32>) -> bool {
    return dot(e.n0, q) + e.d.x >= -e.slack.x
        && dot(e.n1, q) + e.d.y >= -e.slack.y
        && dot(e.n2, q) + e.d.z >= -e.slack.z;
}

// One triangle, ready to test voxels: its bounding box, plane and edge functions, and its
// columns along the dominant axis k ((u, w) the other two).
struct Setup {
    v0: vec3<f32>,
    n: vec3<f32>,
    lo: vec3<i32>,
    hi: vec3<i32>,
    d1: f32,
    d2: f32,
    plane_slack: f32,
    exy: Edges,
    eyz: Edges,
    ezx: Edges,
    k: i32,
    u: i32,
    w: i32,
    // Columns of the box along (u, w); 0 when the box misses the grid.
    columns: u32,
}

fn setup(t: u32) -> Setup {
    var s: Setup;
    let v0 = triangles[3u * t].xyz;
    let v1 = triangles[3u * t + 1u].xyz;
    let v2 = triangles[3u * t + 2u].xyz;
    let g = vec3<i32>(params.grid);
    s.v0 = v0;
    // Closed boxes: a triangle reaching x = k also touches the voxel that ends at k.
    s.lo = max(vec3<i32>(ceil(min(min(v0, v1), v2))) - 1, vec3<i32>(0));
    s.hi = min(vec3<i32>(floor(max(max(v0, v1), v2))), g - 1);
    let n = cross(v1 - v0, v2 - v0);
    s.n = n;
    // Largest coordinate involved: the rounding of every product scales with it.
    let scale = max(max(max(abs(v0.x), abs(v0.y)), max(abs(v0.z), abs(v1.x))),
                    max(max(abs(v1.y), abs(v1.z)), max(max(abs(v2.x), abs(v2.y)), abs(v2.z)))) + 2.0;
    // Plane: the voxel with min corner p overlaps it iff (n·p + d1)(n·p + d2) ≤ 0.
    let c = select(vec3<f32>(0.0), vec3<f32>(1.0), n > vec3<f32>(0.0));
    s.d1 = dot(n, c - v0);
    s.d2 = dot(n, vec3<f32>(1.0) - c - v0);
    s.plane_slack = params.slack * (abs(n.x) + abs(n.y) + abs(n.z)) * scale;
    s.exy = edges(v0.xy, v1.xy, v2.xy, n.z, scale);
    s.eyz = edges(v0.yz, v1.yz, v2.yz, n.x, scale);
    s.ezx = edges(v0.zx, v1.zx, v2.zx, n.y, scale);
    let an = abs(n);
    s.k = 2;
    if an.x >= an.y && an.x >= an.z {
        s.k = 0;
    } else if an.y >= an.z {
        s.k = 1;
    }
    s.u = (s.k + 1) % 3;
    s.w = (s.k + 2) % 3;
    if any(s.lo > s.hi) {
        s.columns = 0u;
    } else {
        s.columns = u32(s.hi[s.u] - s.lo[s.u] + 1) * u32(s.hi[s.w] - s.lo[s.w] + 1);
    }
    return s;
}

// Test the voxels of columns [first, first + count) of the triangle (column j is
// (lo_u + j % width, lo_w + j / width)), only where its plane crosses them.
fn voxelize_columns(s: Setup, first: u32, count: u32) {
    let an = abs(s.n);
    let width = u32(s.hi[s.u] - s.lo[s.u] + 1);
    let end = min(first + count, s.columns);
    let base = dot(s.n, s.v0);
    for (var j = first; j < end; j++) {
        let a = s.lo[s.u] + i32(j % width);
        let b = s.lo[s.w] + i32(j / width);
        // The plane's k over the column's square: n_k·x_k = n·v0 − n_u·x_u − n_w·x_w.
        var kmin = f32(s.lo[s.k]);
        var kmax = f32(s.hi[s.k]) + 1.0;
        if an[s.k] > 0.0 {
            var e0 = 3.4e38;
            var e1 = -3.4e38;
            for (var corner = 0; corner < 4; corner++) {
                let xu = f32(a + (corner & 1));
                let xw = f32(b + (corner >> 1));
                let xk = (base - s.n[s.u] * xu - s.n[s.w] * xw) / s.n[s.k];
                e0 = min(e0, xk);
                e1 = max(e1, xk);
            }
            // One voxel of margin each way: the exact tests below decide.
            kmin = max(kmin, floor(e0) - 1.0);
            kmax = min(kmax, floor(e1) + 2.0);
        }
        for (var z = i32(kmin); z < i32(kmax); z++) {
            var p = vec3<i32>(0);
            p[s.k] = z;
            p[s.u] = a;
            p[s.w] = b;
            if any(p < s.lo) || any(p > s.hi) {
                continue;
            }
            let pf = vec3<f32>(p);
            if SIX_SEPARATING {
                let off = dot(s.n, pf + 0.5 - s.v0);
                if abs(off) > 0.5 * max(an.x, max(an.y, an.z)) + s.plane_slack {
                    continue;
                }
            } else {
                let np = dot(s.n, pf);
                let lo_side = np + s.d1;
                let hi_side = np + s.d2;
                if lo_side * hi_side > s.plane_slack * (abs(lo_side) + abs(hi_side) + s.plane_slack) {
                    continue;
                }
            }
            if inside(s.exy, pf.xy) && inside(s.eyz, pf.yz) && inside(s.ezx, pf.zx) {
                set_voxel(p);
            }
        }
    }
}

@compute @workgroup_size(64)
fn surface(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let t = params.first + id.x;
    let s = setup(t);
    if s.columns > CHUNK {
        let chunks = (s.columns + CHUNK - 1u) / CHUNK;
        let at = atomicAdd(&work_count, chunks);
        for (var c = 0u; c < chunks; c++) {
            if at + c < params.capacity {
                work[at + c] = vec2<u32>(t, c * CHUNK);
            }
        }
        return;
    }
    voxelize_columns(s, 0u, s.columns);
}

@compute @workgroup_size(1)
fn heavy_args() {
    let items = min(atomicLoad(&work_count), params.capacity);
    heavy_dispatch[0] = (items + 63u) / 64u;
    heavy_dispatch[1] = 1u;
    heavy_dispatch[2] = 1u;
}

@compute @workgroup_size(64)
fn surface_heavy(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= min(atomicLoad(&work_count), params.capacity) {
        return;
    }
    let item = work[id.x];
    voxelize_columns(setup(item.x), item.y, CHUNK);
}
