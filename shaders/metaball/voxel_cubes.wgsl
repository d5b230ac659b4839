// Debug view of a voxel set: one cube per voxel, instanced from the centres/scales buffer (the
// source drew each voxel as a cube before switching to the metaball surface).
//
// The cube's 36 corners (or its 12 edges' 24) come from the vertex index, so no mesh is bound; the per-instance buffer
// is the same centres/scales buffer the density splat reads.

import package::shared::cube::{cube_corner, cube_edge_corner};

struct CubeParams {
    view_proj: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    colour: vec4<f32>,
    // Cube edge for scale 1 (the voxel edge).
    edge: f32,
    // 1: edge × scale; 0: every cube one edge long.
    scale_size: u32,
    // 1: the 12 edges as a line list (24 vertices); 0: 36 triangle corners.
    edges: u32,
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) shade: f32,
}

@group(0) @binding(0) var<uniform> params: CubeParams;

@vertex
fn vs_main(@builtin(vertex_index) index: u32, @location(0) instance_voxel: vec4<f32>) -> VertexOut {
    let size = params.edge * select(1.0, instance_voxel.w, params.scale_size != 0u);
    let corner = select(cube_corner(index), cube_edge_corner(index), params.edges != 0u);
    let local = instance_voxel.xyz + corner * size;
    var out: VertexOut;
    out.position = params.view_proj * params.local_to_world * vec4<f32>(local, 1.0);
    // Faces shaded by axis so the cubes read as solids without lighting; edges unshaded.
    out.shade = select(array<f32, 3>(0.75, 1.0, 0.55)[(index / 6u) / 2u], 1.0, params.edges != 0u);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(params.colour.rgb * in.shade, params.colour.a);
}
