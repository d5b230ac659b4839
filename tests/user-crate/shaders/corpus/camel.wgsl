// Golden corpus: names in camelCase, as many public shaders spell them (the boids sample's
// style); the user's crate denies warnings, so none may come from them.

struct SimParams {
    deltaT: f32,
    ruleScale: f32,
}

struct particle_t {
    pos: vec2<f32>,
    vel: vec2<f32>,
}

@group(0) @binding(0) var<uniform> simParams: SimParams;
@group(0) @binding(1) var<storage, read> particlesSrc: array<particle_t>;
@group(0) @binding(2) var<storage, read_write> particlesDst: array<particle_t>;

@compute @workgroup_size(64)
fn mainCS(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&particlesSrc) {
        return;
    }
    var p = particlesSrc[i];
    p.pos += p.vel * simParams.deltaT * simParams.ruleScale;
    particlesDst[i] = p;
}
