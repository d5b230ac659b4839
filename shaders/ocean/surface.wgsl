// The ocean surface: the Gerstner wave sum (`fieldkit::gerstner`) drawn as patches of a grid, with
// scrolling height-map layers in the vertex stage, scrolling normal-map layers and depth fade in
// the fragment stage, written to one forward-shaded colour target (`fs_forward`), to four
// G-buffer targets (`fs_gbuffer`) or to five (`fs_gbuffer_subsurface`, or
// `fs_gbuffer_subsurface_packed` within WebGPU's default 32 bytes a sample). `displace_grid`
// evaluates the same sum on a grid for reading back (the f64 reference and the CPU query are
// tested against it).
//
// Positions are relative to the waves' origin (the host puts it at the camera), so f32 holds
// small numbers however far out the camera is; phases and scroll offsets are folded in f64.
//
// Depth: the pass tests and writes the caller's depth target and reads the scene's depth for the
// fade from a copy made just before it (`fieldkit::ocean::OceanRenderer` copies it), which is
// how the write-up's "fade or write, not both" is lifted.

import fieldkit::gerstner::{GerstnerWave, WaveSurface, add_wave, flat_surface, surface_normal};
import fieldkit::field::unproject;

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

// ---- Drawing ----------------------------------------------------------------------------------

// Height-map layers (vertex stage) and normal-map layers (fragment stage) of the detail texture.
const MAX_LAYERS: u32 = 4u;

struct DetailLayer {
    // Texture coordinate = undisplaced (x, z) × per_metre + offset (the offset folded in f64).
    offset: vec2<f32>,
    per_metre: f32,
    // Height layers: metres per unit of the texture's height. Normal layers: slope scale.
    strength: f32,
}

struct FrameParams {
    // Clip from positions relative to the waves' origin.
    view_proj: mat4x4<f32>,
    // View space from clip (for the linear depth of the scene and of the surface).
    inv_proj: mat4x4<f32>,
    // The camera relative to the waves' origin.
    camera: vec3<f32>,
    // Depth of the skirts hung below patch edges to hide cracks between levels (metres).
    skirt: f32,
    height_layers: array<DetailLayer, MAX_LAYERS>,
    normal_layers: array<DetailLayer, MAX_LAYERS>,
    height_layer_count: u32,
    normal_layer_count: u32,
    // Depth fade: fade = 1 − saturate((scene depth − surface depth) / fade_distance).
    fade_distance: f32,
    roughness: f32,
    // Towards the sun, unit.
    sun_direction: vec3<f32>,
    // Written to the G-buffer's shading-model channel (÷ 255).
    shading_model: u32,
    sun_colour: vec3<f32>,
    // 1: the scene depth is read for the fade; 0: no fade (open sea).
    use_fade: u32,
    deep_colour: vec3<f32>,
    // G-buffer material: metallic and specular (the material target's r and g).
    metallic: f32,
    shallow_colour: vec3<f32>,
    specular: f32,
    sky_colour: vec3<f32>,
    // The fifth G-buffer target (`fs_gbuffer_subsurface`).
    subsurface_colour: vec3<f32>,
    // Per layer: the layer of the user's map array it samples, or −1 for the built-in detail.
    height_maps: vec4<i32>,
    normal_maps: vec4<i32>,
    // The targets' size in pixels (the scene's depth copy may be larger: kept across a resize).
    viewport: vec2<f32>,
}

struct SurfaceOut {
    @builtin(position) position: vec4<f32>,
    // Relative to the waves' origin.
    @location(0) world: vec3<f32>,
    @location(1) binormal: vec3<f32>,
    @location(2) tangent: vec3<f32>,
    // Undisplaced (x, z): the normal maps scroll with the water, not with the displacement.
    @location(3) rest: vec2<f32>,
}

struct GBuffer {
    // Scene colour (emissive): the sky's reflection and the sun's highlight.
    @location(0) scene_colour: vec4<f32>,
    // World normal × 0.5 + 0.5.
    @location(1) normal: vec4<f32>,
    // Metallic, specular, roughness, shading model ÷ 255.
    @location(2) material: vec4<f32>,
    @location(3) base_colour: vec4<f32>,
}

// The four targets and a fifth, subsurface colour (the source's order; UE's base pass puts its
// velocity target before GBufferD when it writes velocity there).
struct GBufferSubsurface {
    @location(0) scene_colour: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) material: vec4<f32>,
    @location(3) base_colour: vec4<f32>,
    @location(4) subsurface_colour: vec4<f32>,
}

// The five targets within WebGPU's default 32 bytes a sample (`fs_gbuffer_subsurface_packed`):
// the material and the subsurface colour each packed into one `R32Uint` texel, four 8-bit
// unorm channels (`pack4x8unorm`; `unpack4x8unorm` reads them back), x in the low byte.
struct GBufferSubsurfacePacked {
    @location(0) scene_colour: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) material: u32,
    @location(3) base_colour: vec4<f32>,
    @location(4) subsurface_colour: u32,
}

@group(0) @binding(4) var<uniform> frame: FrameParams;
// Tileable detail: height in r, its slope per texture unit in g (along u = x) and b (v = z).
@group(0) @binding(5) var detail: texture_2d<f32>;
@group(0) @binding(6) var detail_sampler: sampler;
// A copy of the scene's depth (`ocean/depth_copy`), read as unfilterable float.
@group(0) @binding(7) var scene_depth: texture_2d<f32>;
// The user's height maps (height in r) and normal maps (tangent-space normal × ½ + ½ in rgb,
// +y along +z), one layer each; 1×1 stand-ins when none are set.
@group(0) @binding(8) var height_maps: texture_2d_array<f32>;
@group(0) @binding(9) var normal_maps: texture_2d_array<f32>;

// Undisplaced (x, z) of vertex `index` of the patch `square` (its smallest corner x, z, then
// its largest) of n quads per side (the host draws it with an index buffer made for n), and
// whether it is a skirt vertex: (n + 1)² grid vertices x fastest, then a ring of 4 (n + 1)
// skirt vertices under the edges z = 0, x = n, z = n, x = 0.
//
// Both ends of a row come straight from the corners, never from corner + side: a neighbour of
// the same size and quads then computes the shared edge's vertices from the very same f32
// values and gets them bit for bit, so the two meet without a crack and need no skirt.
fn patch_vertex(index: u32, square: vec4<f32>, n: u32) -> vec3<f32> {
    let row = n + 1u;
    var ij: vec2<u32>;
    var skirt = 0.0;
    if index < row * row {
        ij = vec2<u32>(index % row, index / row);
    } else {
        let k = index - row * row;
        let t = k % row;
        skirt = 1.0;
        switch k / row {
            case 0u: { ij = vec2<u32>(t, 0u); }
            case 1u: { ij = vec2<u32>(n, t); }
            case 2u: { ij = vec2<u32>(t, n); }
            default: { ij = vec2<u32>(0u, t); }
        }
    }
    let p = select(square.xy + (square.zw - square.xy) * (vec2<f32>(ij) / f32(n)), square.zw,
                   ij == vec2<u32>(n));
    return vec3<f32>(p, skirt);
}

fn detail_at(layer: DetailLayer, rest: vec2<f32>) -> vec3<f32> {
    return textureSampleLevel(detail, detail_sampler, rest * layer.per_metre + layer.offset, 0.0).rgb;
}

// A height layer's height (r) and slope per texture unit (g along u, b along v): the built-in
// detail holds all three; a user's height map holds the height, and its slope is a central
// difference one texel wide.
fn height_at(layer: DetailLayer, map: i32, rest: vec2<f32>) -> vec3<f32> {
    if map < 0 {
        return detail_at(layer, rest);
    }
    let uv = rest * layer.per_metre + layer.offset;
    let texel = 1.0 / vec2<f32>(textureDimensions(height_maps));
    let h = textureSampleLevel(height_maps, detail_sampler, uv, map, 0.0).r;
    let du = textureSampleLevel(height_maps, detail_sampler, uv + vec2<f32>(texel.x, 0.0), map, 0.0).r
        - textureSampleLevel(height_maps, detail_sampler, uv - vec2<f32>(texel.x, 0.0), map, 0.0).r;
    let dv = textureSampleLevel(height_maps, detail_sampler, uv + vec2<f32>(0.0, texel.y), map, 0.0).r
        - textureSampleLevel(height_maps, detail_sampler, uv - vec2<f32>(0.0, texel.y), map, 0.0).r;
    return vec3<f32>(h, du / (2.0 * texel.x), dv / (2.0 * texel.y));
}

// A normal layer's slope per metre (along x, along z), before its strength: the built-in
// detail's slopes per texture unit × repeats per metre, or a user's normal map's tilt
// (−n.x / n.z, −n.y / n.z), which is per metre whatever the tiling.
fn normal_slope(layer: DetailLayer, map: i32, rest: vec2<f32>) -> vec2<f32> {
    if map < 0 {
        return layer.per_metre * detail_at(layer, rest).gb;
    }
    let uv = rest * layer.per_metre + layer.offset;
    let n = textureSampleLevel(normal_maps, detail_sampler, uv, map, 0.0).rgb * 2.0 - 1.0;
    return -n.xy / max(n.z, 1e-3);
}

@vertex
// Per instance: the patch's corners (`patch_vertex`) and its quads per side in x (y to w
// unused: a whole vec4 keeps the instance 32 bytes with no padding).
fn vs_surface(@builtin(vertex_index) index: u32, @location(0) instance_patch: vec4<f32>,
              @location(1) instance_quads: vec4<u32>) -> SurfaceOut {
    let v = patch_vertex(index, instance_patch, instance_quads.x);
    let p = v.xy;
    var s = flat_surface(p);
    for (var i = 0u; i < waves.count; i++) {
        s = add_wave(s, waves.waves[i], p);
    }
    // Height-map layers: height and its slope per metre, added to the wave's frame.
    for (var l = 0u; l < frame.height_layer_count; l++) {
        let layer = frame.height_layers[l];
        let h = height_at(layer, frame.height_maps[l], p);
        s.position.y += layer.strength * h.r;
        let slope = layer.strength * layer.per_metre * h.gb;
        s.binormal.y += slope.x;
        s.tangent.y += slope.y;
    }
    s.position.y -= v.z * frame.skirt;
    var out: SurfaceOut;
    out.position = frame.view_proj * vec4<f32>(s.position, 1.0);
    out.world = s.position;
    out.binormal = s.binormal;
    out.tangent = s.tangent;
    out.rest = p;
    return out;
}

// Distance along the view axis of clip-space depth `z` at pixel `ndc_xy`.
fn view_depth(ndc_xy: vec2<f32>, z: f32) -> f32 {
    return -unproject(frame.inv_proj, vec3<f32>(ndc_xy, z)).z;
}

struct Shaded {
    normal: vec3<f32>,
    base: vec3<f32>,
    // Reflection and highlight (the G-buffer's scene colour), and the diffuse factor.
    emissive: vec3<f32>,
    diffuse: vec3<f32>,
}

fn shade(in: SurfaceOut) -> Shaded {
    let b = normalize(in.binormal);
    let t = normalize(in.tangent);
    var n = normalize(cross(in.tangent, in.binormal));
    // Normal-map layers in the tangent frame: the detail's slopes tilt the wave normal along B
    // and T (slopes add, as heights would).
    var slope = vec2<f32>(0.0);
    for (var l = 0u; l < frame.normal_layer_count; l++) {
        let layer = frame.normal_layers[l];
        slope += layer.strength * normal_slope(layer, frame.normal_maps[l], in.rest);
    }
    n = normalize(n - slope.x * b - slope.y * t);
    // Depth fade from the scene's depth behind this pixel.
    var fade = 0.0;
    if frame.use_fade != 0u {
        let size = frame.viewport;
        let ndc = vec2<f32>(in.position.x / size.x * 2.0 - 1.0, 1.0 - in.position.y / size.y * 2.0);
        let scene = view_depth(ndc, textureLoad(scene_depth, vec2<i32>(in.position.xy), 0).r);
        let own = view_depth(ndc, in.position.z);
        fade = 1.0 - saturate((scene - own) / frame.fade_distance);
    }
    let base = mix(frame.deep_colour, frame.shallow_colour, fade);
    let v = normalize(frame.camera - in.world);
    let l = frame.sun_direction;
    let h = normalize(v + l);
    let fresnel = 0.02 + 0.98 * pow(1.0 - saturate(dot(n, v)), 5.0);
    let shininess = 2.0 / max(frame.roughness * frame.roughness, 1e-4);
    let spec = frame.sun_colour * pow(saturate(dot(n, h)), shininess) * fresnel;
    var out: Shaded;
    out.normal = n;
    out.base = base;
    out.emissive = frame.sky_colour * fresnel + spec;
    out.diffuse = base * (1.0 - fresnel) * (0.25 + frame.sun_colour * saturate(dot(n, l)));
    return out;
}

@fragment
fn fs_forward(in: SurfaceOut) -> @location(0) vec4<f32> {
    let s = shade(in);
    return vec4<f32>(s.diffuse + s.emissive, 1.0);
}

// Metallic, specular, roughness, shading model ÷ 255: the material target's four channels.
fn material() -> vec4<f32> {
    return vec4<f32>(frame.metallic, frame.specular, frame.roughness, f32(frame.shading_model) / 255.0);
}

// The four G-buffer targets of the fragment `in`.
fn gbuffer(in: SurfaceOut) -> GBuffer {
    let s = shade(in);
    var out: GBuffer;
    out.scene_colour = vec4<f32>(s.emissive, 1.0);
    out.normal = vec4<f32>(s.normal * 0.5 + 0.5, 1.0);
    out.material = material();
    out.base_colour = vec4<f32>(s.base, 1.0);
    return out;
}

@fragment
fn fs_gbuffer(in: SurfaceOut) -> GBuffer {
    return gbuffer(in);
}

@fragment
fn fs_gbuffer_subsurface(in: SurfaceOut) -> GBufferSubsurface {
    let g = gbuffer(in);
    var out: GBufferSubsurface;
    out.scene_colour = g.scene_colour;
    out.normal = g.normal;
    out.material = g.material;
    out.base_colour = g.base_colour;
    out.subsurface_colour = vec4<f32>(frame.subsurface_colour, 1.0);
    return out;
}

@fragment
fn fs_gbuffer_subsurface_packed(in: SurfaceOut) -> GBufferSubsurfacePacked {
    let g = gbuffer(in);
    var out: GBufferSubsurfacePacked;
    out.scene_colour = g.scene_colour;
    out.normal = g.normal;
    out.material = pack4x8unorm(g.material);
    out.base_colour = g.base_colour;
    out.subsurface_colour = pack4x8unorm(vec4<f32>(frame.subsurface_colour, 1.0));
    return out;
}
