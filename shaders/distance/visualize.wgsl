// Distance-field view: a full-screen triangle colour-mapping signed distance with iso-lines (after Inigo Quilez's SDF previews).

struct ViewParams {
    // Distance between iso-lines, in the field's units.
    spacing: f32,
    // Distance mapped to full colour saturation.
    range: f32,
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@group(0) @binding(0) var<uniform> params: ViewParams;
@group(0) @binding(1) var distance: texture_2d<f32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let xy = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
    out.uv = vec2<f32>(xy.x, 1.0 - xy.y);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let size = vec2<f32>(textureDimensions(distance));
    let texel = clamp(vec2<i32>(in.uv * size), vec2<i32>(0), vec2<i32>(size) - 1);
    let d = textureLoad(distance, texel, 0).r;
    // Orange outside, blue inside, darker with distance.
    let base = select(vec3<f32>(0.9, 0.6, 0.3), vec3<f32>(0.3, 0.55, 0.9), d < 0.0);
    var colour = base * (1.0 - 0.6 * clamp(abs(d) / params.range, 0.0, 1.0));
    // Thin bands every `spacing`, and a white line at the surface.
    let band = abs(fract(d / params.spacing + 0.5) - 0.5) * params.spacing;
    colour *= mix(0.75, 1.0, smoothstep(0.0, 0.75, band));
    colour = mix(vec3<f32>(1.0), colour, smoothstep(0.5, 1.5, abs(d)));
    return vec4<f32>(colour, 1.0);
}
