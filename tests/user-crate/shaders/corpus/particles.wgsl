// Golden corpus: one struct as a vertex input (its members carry locations) and as the element
// of a storage buffer, as particle systems write it; the buffer's Rust type is that struct.

struct Particle {
    @location(0) position: vec4<f32>,
    @location(1) velocity: vec4<f32>,
}

@group(0) @binding(0) var<storage, read_write> particles: array<Particle>;

@compute @workgroup_size(64)
fn advance(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&particles) {
        particles[id.x].position += particles[id.x].velocity;
    }
}

@vertex
fn vs(p: Particle) -> @builtin(position) vec4<f32> {
    return p.position;
}
