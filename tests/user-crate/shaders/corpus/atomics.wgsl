// Golden corpus: atomics in storage and workgroup memory, a runtime-sized array of structs
// with vec3 members (padding the host struct must match), and two entry points sharing them.

struct Cell {
    position: vec3<f32>,
    weight: f32,
    normal: vec3<f32>,
    flags: u32,
}

struct Counters {
    total: atomic<u32>,
    signed: atomic<i32>,
}

@group(0) @binding(0) var<storage, read_write> counters: Counters;
@group(0) @binding(1) var<storage, read> cells: array<Cell>;
@group(0) @binding(2) var<storage, read_write> histogram: array<atomic<u32>>;

var<workgroup> local_total: atomic<u32>;

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if id.x < arrayLength(&cells) {
        atomicAdd(&local_total, cells[id.x].flags & 1u);
        atomicMax(&counters.signed, i32(cells[id.x].weight));
    }
    workgroupBarrier();
    if li == 0u {
        atomicAdd(&counters.total, atomicLoad(&local_total));
    }
}

@compute @workgroup_size(32, 2)
fn bin(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x + id.y * 32u;
    if i < arrayLength(&cells) {
        let bucket = u32(clamp(cells[i].position.x, 0.0, 15.0));
        atomicAdd(&histogram[bucket], 1u);
    }
}
