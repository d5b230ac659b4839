// Debug view of a voxel set: one cube per voxel, instanced from the centres/scales buffer (the
// source drew each voxel as a cube before switching to the metaball surface).
//
// The cube's 36 corners come from the vertex index, so no mesh is bound; the per-instance buffer
// is the same centres/scales buffer the density splat reads.

struct CubeParams {
    view_proj: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    colour: vec4<f32>,
    // Cube edge for scale 1 (the voxel edge).
    edge: f32,
    // 1: edge × scale; 0: every cube one edge long.
    scale_size: u32,
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) shade: f32,
}

@group(0) @binding(0) var<uniform> params: CubeParams;

// Triangles of a unit cube, two per face, faces ordered −x, +x, −y, +y, −z, +z, wound
// counter-clockwise seen from outside.
fn corner(index: u32) -> vec3<f32> {
    let face = index / 6u;
    let k = index % 6u;
    // Two triangles over a face's (u, v) square.
    let uv = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 1.0), vec2<f32>(0.0, 1.0),
    )[k] - 0.5;
    let axis = face / 2u;
    let side = select(-0.5, 0.5, face % 2u == 1u);
    // (u, v, normal) axes chosen so that u × v points outward.
    var p: vec3<f32>;
    if axis == 0u {
        p = vec3<f32>(side, uv.x * side * 2.0, uv.y);
    } else if axis == 1u {
        p = vec3<f32>(uv.y, side, uv.x * side * 2.0);
    } else {
        p = vec3<f32>(uv.x * side * 2.0, uv.y, side);
    }
    return p;
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32, @location(0) instance_voxel: vec4<f32>) -> VertexOut {
    let size = params.edge * select(1.0, instance_voxel.w, params.scale_size != 0u);
    let local = instance_voxel.xyz + corner(index) * size;
    var out: VertexOut;
    out.position = params.view_proj * params.local_to_world * vec4<f32>(local, 1.0);
    // Faces shaded by axis so the cubes read as solids without lighting.
    out.shade = array<f32, 3>(0.75, 1.0, 0.55)[(index / 6u) / 2u];
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(params.colour.rgb * in.shade, params.colour.a);
}
