// The Gerstner wave sum on a regular grid of undisplaced points, written out: the displaced
// position (relative to the waves' origin) and the normal per point. The vertex stage uses the
// same `shared/gerstner` sum; this stage lets it be read back and checked against the f64
// reference, and gives floating objects a GPU-side answer to compare the CPU query with.

import package::shared::gerstner::{GerstnerWave, add_wave, flat_surface, surface_normal};

// Most waves one set holds (`fieldkit::ocean::MAX_WAVES` is read from this array's length).
const MAX_WAVES: u32 = 16u;

struct WaveSet {
    waves: array<GerstnerWave, MAX_WAVES>,
    count: u32,
}

struct GridParams {
    // Undisplaced (x, z) of point (0, 0), relative to the waves' origin, and the spacing.
    start: vec2<f32>,
    spacing: vec2<f32>,
    size: vec2<u32>,
}

@group(0) @binding(0) var<uniform> waves: WaveSet;
@group(0) @binding(1) var<uniform> grid: GridParams;
// Per point, x fastest: position (w = 1) and normal (w = 0).
@group(0) @binding(2) var<storage, read_write> positions: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> normals: array<vec4<f32>>;

@compute @workgroup_size(16, 16)
fn displace_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= grid.size) {
        return;
    }
    let p = grid.start + vec2<f32>(id.xy) * grid.spacing;
    var s = flat_surface(p);
    for (var i = 0u; i < waves.count; i++) {
        s = add_wave(s, waves.waves[i], p);
    }
    let at = id.y * grid.size.x + id.x;
    positions[at] = vec4<f32>(s.position, 1.0);
    normals[at] = vec4<f32>(surface_normal(s), 0.0);
}
