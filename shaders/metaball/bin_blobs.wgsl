// Blob bins for tracing the metaball field directly: a uniform grid of bins at least one support
// radius wide, each listing every blob whose support box overlaps it, so the field at a point (or
// along a segment inside one bin) is the sum over one bin's list. A counting sort in three
// passes: count per bin, an exclusive scan (one workgroup), then fill.
//
// A bin is at least the largest support radius R wide, so a blob's box (2R) spans at most three
// bins per axis and the host can size the list at 27 entries per blob.

struct BinParams {
    bins: vec3<u32>,
    count: u32,
    // Local-space corner of bin (0, 0, 0).
    origin: vec3<f32>,
    bin_size: f32,
    // Support radius per unit of instance scale: edge × ½ × overlap.
    radius_per_scale: f32,
    // Entries `items` holds.
    capacity: u32,
}

@group(0) @binding(0) var<uniform> params: BinParams;
// xyz: centre (local space); w: scale.
@group(0) @binding(1) var<storage, read> instances: array<vec4<f32>>;
// Per bin: the count, then (after the scan) the fill cursor.
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;
// Per bin: the first entry in `items`; one more at the end holding the total.
@group(0) @binding(3) var<storage, read_write> starts: array<u32>;
// Blobs in bin order: xyz centre, w support radius.
@group(0) @binding(4) var<storage, read_write> items: array<vec4<f32>>;
// [0]: the most blobs in one bin; [1]: the global Lipschitz bound, the largest bin sum of
// 96 / (25√5 · R), as f32 bits (non-negative floats order as their bits do).
@group(0) @binding(5) var<storage, read_write> stats: array<atomic<u32>>;

const SCAN_THREADS: u32 = 256u;
// Steepest slope of (1 − r²/R²)³ times R: 96 / (25√5).
const SLOPE_R: f32 = 1.7173148;

var<workgroup> partial: array<u32, SCAN_THREADS>;

// The bins a blob's support box overlaps (inclusive); empty (lo > hi) for a zero radius.
fn bin_range(inst: vec4<f32>) -> array<vec3<i32>, 2> {
    let r = params.radius_per_scale * inst.w;
    if !(r > 0.0) {
        return array<vec3<i32>, 2>(vec3<i32>(1), vec3<i32>(0));
    }
    let top = vec3<f32>(params.bins) - 1.0;
    let lo = clamp(floor((inst.xyz - r - params.origin) / params.bin_size), vec3<f32>(0.0), top);
    let hi = clamp(floor((inst.xyz + r - params.origin) / params.bin_size), vec3<f32>(0.0), top);
    return array<vec3<i32>, 2>(vec3<i32>(lo), vec3<i32>(hi));
}

fn bin_index(b: vec3<i32>) -> u32 {
    return (u32(b.z) * params.bins.y + u32(b.y)) * params.bins.x + u32(b.x);
}

@compute @workgroup_size(64)
fn bin_count(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let range = bin_range(instances[id.x]);
    for (var z = range[0].z; z <= range[1].z; z++) {
        for (var y = range[0].y; y <= range[1].y; y++) {
            for (var x = range[0].x; x <= range[1].x; x++) {
                atomicAdd(&counts[bin_index(vec3<i32>(x, y, z))], 1u);
            }
        }
    }
}

// Exclusive scan of the counts into `starts`, resetting each count to 0 as the fill cursor.
// Thread t sums a contiguous chunk, the 256 chunk sums are scanned in workgroup memory, then each
// thread writes its chunk's starts.
@compute @workgroup_size(256)
fn bin_scan(@builtin(local_invocation_index) t: u32) {
    let n = params.bins.x * params.bins.y * params.bins.z;
    let chunk = (n + SCAN_THREADS - 1u) / SCAN_THREADS;
    let lo = min(n, t * chunk);
    let hi = min(n, lo + chunk);
    var sum = 0u;
    var most = 0u;
    for (var i = lo; i < hi; i++) {
        let c = atomicLoad(&counts[i]);
        sum += c;
        most = max(most, c);
    }
    atomicMax(&stats[0], most);
    partial[t] = sum;
    workgroupBarrier();
    for (var offset = 1u; offset < SCAN_THREADS; offset <<= 1u) {
        let other = select(0u, partial[max(t, offset) - offset], t >= offset);
        workgroupBarrier();
        partial[t] += other;
        workgroupBarrier();
    }
    var at = partial[t] - sum;
    for (var i = lo; i < hi; i++) {
        starts[i] = at;
        at += atomicLoad(&counts[i]);
        atomicStore(&counts[i], 0u);
    }
    if t == SCAN_THREADS - 1u {
        starts[n] = partial[t];
    }
}

@compute @workgroup_size(64)
fn bin_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let inst = instances[id.x];
    let range = bin_range(inst);
    let item = vec4<f32>(inst.xyz, params.radius_per_scale * inst.w);
    for (var z = range[0].z; z <= range[1].z; z++) {
        for (var y = range[0].y; y <= range[1].y; y++) {
            for (var x = range[0].x; x <= range[1].x; x++) {
                let b = bin_index(vec3<i32>(x, y, z));
                let at = starts[b] + atomicAdd(&counts[b], 1u);
                if at < params.capacity {
                    items[at] = item;
                }
            }
        }
    }
}

// One thread per bin: the sum of its blobs' slope bounds, maximised into the global bound.
@compute @workgroup_size(64)
fn bin_bound(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.bins.x * params.bins.y * params.bins.z;
    if id.x >= n {
        return;
    }
    var sum = 0.0;
    for (var i = starts[id.x]; i < min(starts[id.x + 1u], params.capacity); i++) {
        sum += SLOPE_R / items[i].w;
    }
    atomicMax(&stats[1], bitcast<u32>(sum));
}
