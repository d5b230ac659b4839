// Debug view of voxelization's output: one cube per occupied voxel, pulled by instance index
// from the compact attribute list of `voxelize/attributes` (no vertex or instance buffer),
// coloured by the voxel's averaged normal or colour and lit by one directional or point light
// (per cube corner).

import package::shared::cube::{cube_corner, cube_face_normal};
import fieldkit::octahedral::decode_octahedral;

struct ViewParams {
    view_proj: mat4x4<f32>,
    // Grid-local (voxel units, origin at voxel (0, 0, 0)'s min corner) to world.
    grid_to_world: mat4x4<f32>,
    // w = 0: unit vector toward the light, world space; w = 1: a point light's world position.
    light: vec4<f32>,
    grid: vec3<u32>,
    // 0: the averaged normal as a colour (n · ½ + ½); 1: the averaged colour.
    colour_by: u32,
    // A point light reaches 0 here: N·L × (1 − (d / range)²)².
    light_range: f32,
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) colour: vec3<f32>,
}

@group(0) @binding(0) var<uniform> params: ViewParams;
// Per occupied voxel: (voxel index, RGBA8 colour, octahedral normal or NO_NORMAL, triangles).
@group(0) @binding(1) var<storage, read> voxels: array<vec4<u32>>;

@vertex
fn vs_view(@builtin(vertex_index) index: u32, @builtin(instance_index) instance: u32) -> VertexOut {
    let v = voxels[instance];
    let g = params.grid;
    let cell = vec3<f32>(vec3<u32>(v.x % g.x, (v.x / g.x) % g.y, v.x / (g.x * g.y)));
    let local = cell + 0.5 + cube_corner(index);
    let world = (params.grid_to_world * vec4<f32>(local, 1.0)).xyz;
    var out: VertexOut;
    out.position = params.view_proj * vec4<f32>(world, 1.0);
    var base = unpack4x8unorm(v.y).rgb;
    if params.colour_by == 0u {
        base = decode_octahedral(v.z) * 0.5 + 0.5;
    }
    // The grid maps to the world by a scale and a translation, so face normals keep their
    // direction.
    var to_light = params.light.xyz;
    var atten = 1.0;
    if params.light.w > 0.5 {
        let to = params.light.xyz - world;
        let d = length(to);
        let q = max(1.0 - (d / params.light_range) * (d / params.light_range), 0.0);
        to_light = to / max(d, 1e-6);
        atten = q * q;
    }
    let lambert = max(dot(cube_face_normal(index), to_light), 0.0) * atten;
    out.colour = base * (0.35 + 0.65 * lambert);
    return out;
}

@fragment
fn fs_view(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.colour, 1.0);
}
