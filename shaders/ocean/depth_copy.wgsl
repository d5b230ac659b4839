// Copy of the scene's depth, which the ocean's depth fade reads.
//
// The water tests and writes the depth target while its fragments read what was there before,
// so the depth is copied first (into an R32Float texture the fade reads). A compute pass
// on every SM rather than a texture copy: on the H100 (whose graphics work runs on few units)
// copying the 1920×1080 `Depth32Float` target with `copy_texture_to_texture` took 0.153 ms,
// more than a sixth of the whole ocean frame.

// The caller's Depth32Float target, read as unfilterable float (WebGPU allows it; a depth
// texture type would not translate to GLSL).
@group(0) @binding(0) var depth_in: texture_2d<f32>;
@group(0) @binding(1) var depth_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn copy_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    // The copy may be larger than the scene's depth (kept across a resize): the depth's size.
    if any(id.xy >= textureDimensions(depth_in)) {
        return;
    }
    textureStore(depth_out, id.xy, vec4<f32>(textureLoad(depth_in, id.xy, 0).r, 0.0, 0.0, 1.0));
}
