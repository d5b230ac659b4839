// 3D (and buffer-held 2D) resolve: nearest-seed buffers to distance textures, unsigned or signed,
// in world units, clamped to an optional narrow band.
//
// Integer seeds: as the 2D resolve, signed distance comes from two fields (inside seeds and
// outside seeds) and half a voxel is taken off so zero lies between voxel centres. Sub-voxel
// seeds lie on the surface itself: the distance is to the seed point, and the sign comes from
// the volume (negative where the voxel's value is ≥ threshold), as the sources' metaball SDF does.

import fieldkit::seed::{FAR, NO_SEED, key_index, seed_distance2, seed_distance3, signed_at2, signed_at3, signed_distance};

struct ResolveParams {
    size: vec3<u32>,
    // World units per voxel.
    voxel_size: f32,
    // Distances are clamped to ±band (world units); FAR when no band is set.
    band: f32,
    // Inside test for `resolve_points_signed`: the volume's red channel ≥ threshold.
    threshold: f32,
    // What a voxel no seed reached holds (±FAR before the band): −unreached_inside inside,
    // unreached_outside outside (world units; the band by default).
    unreached_inside: f32,
    unreached_outside: f32,
}

@group(0) @binding(0) var<uniform> params: ResolveParams;
@group(0) @binding(1) var<storage, read> nearest: array<u32>;
@group(0) @binding(2) var<storage, read> nearest_outside: array<u32>;
@group(0) @binding(3) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(4) var volume: texture_3d<f32>;
@group(0) @binding(5) var distance: texture_storage_3d<r32float, write>;
@group(0) @binding(6) var distance_2d: texture_storage_2d<r32float, write>;

fn index_of(p: vec3<u32>) -> u32 {
    return (p.z * params.size.y + p.y) * params.size.x + p.x;
}

fn world(d_voxels: f32) -> f32 {
    return d_voxels * params.voxel_size;
}

// The narrow band: distances beyond it are clamped, as its JFA never looked farther; a voxel no
// seed reached takes the unreached values.
fn banded(d: f32) -> f32 {
    if d >= FAR {
        return params.unreached_outside;
    }
    if d <= -FAR {
        return -params.unreached_inside;
    }
    return clamp(d, -params.band, params.band);
}


// Signed from the two fields: `own` is the packed seed naming this voxel itself.
fn signed(inside_seed: u32, own: u32, to_inside: f32, to_outside: f32, outside_seed: u32) -> f32 {
    return signed_distance(inside_seed, own, to_inside, to_outside, outside_seed, 0.5 * params.voxel_size);
}

@compute @workgroup_size(32, 4, 2)
fn resolve_unsigned(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    textureStore(distance, id, vec4<f32>(banded(seed_distance3(nearest[index_of(id)], id, params.voxel_size)), 0.0, 0.0, 0.0));
}

@compute @workgroup_size(32, 4, 2)
fn resolve_signed(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let i = index_of(id);
    let s_in = nearest[i];
    let s_out = nearest_outside[i];
    let d = signed_at3(s_in, id, seed_distance3(s_out, id, params.voxel_size), s_out, params.voxel_size);
    textureStore(distance, id, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
}

fn point_distance(key: u32, p: vec3<u32>) -> f32 {
    if key == NO_SEED {
        return FAR;
    }
    return world(length(points[key_index(key)].xyz - vec3<f32>(p)));
}

@compute @workgroup_size(32, 4, 2)
fn resolve_points(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    textureStore(distance, id, vec4<f32>(banded(point_distance(nearest[index_of(id)], id)), 0.0, 0.0, 0.0));
}

@compute @workgroup_size(32, 4, 2)
fn resolve_points_signed(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id >= params.size) {
        return;
    }
    let d = point_distance(nearest[index_of(id)], id);
    let inside = textureLoad(volume, id, 0).r >= params.threshold;
    textureStore(distance, id, vec4<f32>(banded(select(d, -d, inside)), 0.0, 0.0, 0.0));
}

@compute @workgroup_size(16, 16)
fn resolve_unsigned_2d(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let d = seed_distance2(nearest[id.y * params.size.x + id.x], id.xy, params.voxel_size);
    textureStore(distance_2d, id.xy, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
}

@compute @workgroup_size(16, 16)
fn resolve_signed_2d(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.size.xy) {
        return;
    }
    let i = id.y * params.size.x + id.x;
    let s_in = nearest[i];
    let s_out = nearest_outside[i];
    let d = signed_at2(s_in, id.xy, seed_distance2(s_out, id.xy, params.voxel_size), s_out, params.voxel_size);
    textureStore(distance_2d, id.xy, vec4<f32>(banded(d), 0.0, 0.0, 0.0));
}
