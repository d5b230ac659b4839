// The light volume folded into a copy of the density: per density voxel one texel, density in
// red (copied exactly: the format keeps the density's precision) and transmittance toward the
// light in green. The march then takes density and light in one trilinear fetch per sample
// instead of two: from inside the 256³ cloud on the H100, 0.89 against 1.16 ms a frame.
//
// The light volume's node i lies on the centre of density voxel 2i (`light_volume` in
// `volume/volume_march`). A voxel's light is the nodes' trilinear interpolant there: the node
// itself along an axis where the voxel's index is even, the mean of the two nodes beside it
// where odd (one filtered fetch, its weights 0 or ½, exact). The march's trilinear filter over
// these texels then reproduces that interpolant exactly, so folding adds no second
// interpolation (centres of the two grids that did not line up blurred the light: 0.0098
// against 0.0080 mean error in red against shadow rays on the 24³ test cloud). The one
// difference from fetching the nodes themselves is in the last half voxel before each high
// face, where the copy is clamped like the density and keeps the last voxel centre's light.
//
// Formats are the smallest that WebGPU lets a shader write: two-channel 8- and 16-bit formats
// are not storage formats, so an R8Unorm density folds into Rgba8Unorm and an R16Float one into
// Rgba16Float, with blue and alpha unused; R32Float folds into Rg32Float. The wider texel did
// not slow the march (Rgba8Unorm against Rg8Unorm at 256³ on the H100: 0.89 against 0.89 ms
// from inside), and writing it directly kept the light build at 256³ to 0.42 ms, where Rg8Unorm
// packed into a buffer and copied into the texture took 1.27 (0.92 of it the copy). One entry
// point per format.

@group(0) @binding(0) var density: texture_3d<f32>;
@group(0) @binding(1) var light: texture_3d<f32>;
@group(0) @binding(2) var linear_clamp: sampler;
@group(0) @binding(3) var lit_out_unorm8: texture_storage_3d<rgba8unorm, write>;
@group(0) @binding(4) var lit_out_float16: texture_storage_3d<rgba16float, write>;
@group(0) @binding(5) var lit_out_float32: texture_storage_3d<rg32float, write>;

// (density, light, 0, 1) of one voxel.
fn lit(voxel: vec3<u32>) -> vec4<f32> {
    // Node coordinate v / 2, as a texture coordinate of the nodes.
    let uvw = (vec3<f32>(voxel) * 0.5 + 0.5) / vec3<f32>(textureDimensions(light));
    let l = textureSampleLevel(light, linear_clamp, uvw, 0.0).r;
    return vec4<f32>(textureLoad(density, voxel, 0).r, l, 0.0, 1.0);
}

@compute @workgroup_size(8, 8, 1)
fn lit_unorm8(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id < textureDimensions(lit_out_unorm8)) {
        textureStore(lit_out_unorm8, id, lit(id));
    }
}

@compute @workgroup_size(8, 8, 1)
fn lit_float16(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id < textureDimensions(lit_out_float16)) {
        textureStore(lit_out_float16, id, lit(id));
    }
}

@compute @workgroup_size(8, 8, 1)
fn lit_float32(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id < textureDimensions(lit_out_float32)) {
        textureStore(lit_out_float32, id, lit(id));
    }
}
