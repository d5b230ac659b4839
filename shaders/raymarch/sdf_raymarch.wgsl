// Full-screen SDF raymarch of one volume: sphere tracing on a signed-distance texture, refined by
// bisection on the density's iso-surface, shaded, and written with depth so it composites with the
// caller's scene (after the source's Unreal metaball pass; sphere tracing: Hart 1996).
//
// Rays come from the inverse view-projection through each pixel, from the near plane, so a camera
// inside the volume works; they are moved into the volume's local space (a rigid transform keeps
// distances) and clipped to its box. The step is the sampled distance × `safety`, and the hit
// tolerance grows with distance (a pixel's footprint). A sample below the tolerance, or a sign
// change, is refined by bisection on density − threshold, whose zero set the seeds came from.

import package::shared::field::{ray_box, trilinear};

struct RaymarchParams {
    inv_view_proj: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    world_to_local: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    // Local-space box of the grid.
    box_min: vec3<f32>,
    // Grid cell edge (local units): distances in the SDF are in these units too.
    cell: f32,
    box_max: vec3<f32>,
    threshold: f32,
    // World-space direction towards the light.
    light_dir: vec3<f32>,
    max_steps: u32,
    base_colour: vec3<f32>,
    // Smallest hit tolerance, in cells.
    epsilon: f32,
    rim_colour: vec3<f32>,
    // Added tolerance per unit of distance: the angle one pixel spans.
    pixel_angle: f32,
    viewport: vec2<f32>,
    // NDC depth of the near and far planes (0 and 1; 1 and 0 for reversed Z).
    near_z: f32,
    far_z: f32,
    // Step = distance × safety (≤ 1 keeps sphere tracing conservative on an approximate SDF).
    safety: f32,
    // 0 shaded, 1 normal (rgb) and 1 + hit distance (a), 2 step count, 3 density, 4 SDF at entry.
    mode: u32,
    ambient: f32,
    // Distances in the SDF are clamped to ±band (local units).
    band: f32,
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
}

struct FragmentOut {
    @location(0) colour: vec4<f32>,
    @builtin(frag_depth) depth: f32,
}

@group(0) @binding(0) var<uniform> params: RaymarchParams;
@group(0) @binding(1) var sdf: texture_3d<f32>;
@group(0) @binding(2) var density: texture_3d<f32>;

const BISECTIONS: u32 = 12u;

fn grid_coord(p: vec3<f32>) -> vec3<f32> {
    return (p - params.box_min) / params.cell - 0.5;
}

fn distance_at(p: vec3<f32>) -> f32 {
    return trilinear(sdf, grid_coord(p));
}

fn density_at(p: vec3<f32>) -> f32 {
    return trilinear(density, grid_coord(p));
}

fn unproject(ndc: vec3<f32>) -> vec3<f32> {
    let h = params.inv_view_proj * vec4<f32>(ndc, 1.0);
    return h.xyz / h.w;
}

// Root of density − threshold on [a, b], with density(a) below and density(b) at or above it.
fn bisect(o: vec3<f32>, dir: vec3<f32>, a_in: f32, b_in: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    for (var k = 0u; k < BISECTIONS; k++) {
        let m = 0.5 * (a + b);
        if density_at(o + m * dir) >= params.threshold {
            b = m;
        } else {
            a = m;
        }
    }
    return 0.5 * (a + b);
}

// Outward normal: minus the density gradient (central differences, one cell apart).
fn normal_at(p: vec3<f32>) -> vec3<f32> {
    let h = params.cell;
    let g = vec3<f32>(
        density_at(p + vec3<f32>(h, 0.0, 0.0)) - density_at(p - vec3<f32>(h, 0.0, 0.0)),
        density_at(p + vec3<f32>(0.0, h, 0.0)) - density_at(p - vec3<f32>(0.0, h, 0.0)),
        density_at(p + vec3<f32>(0.0, 0.0, h)) - density_at(p - vec3<f32>(0.0, 0.0, h)),
    );
    let len = length(g);
    if len < 1e-12 {
        return vec3<f32>(0.0, 0.0, 1.0);
    }
    return -g / len;
}

fn depth_of(world: vec3<f32>) -> f32 {
    let clip = params.view_proj * vec4<f32>(world, 1.0);
    return clip.z / clip.w;
}

fn heat(x: f32) -> vec3<f32> {
    let t = clamp(x, 0.0, 1.0);
    return clamp(vec3<f32>(3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0), vec3<f32>(0.0), vec3<f32>(1.0));
}

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // One triangle covering the viewport: (-1,-1), (3,-1), (-1,3).
    let xy = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    var out: VertexOut;
    out.position = vec4<f32>(xy * 2.0 - 1.0, 0.0, 1.0);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> FragmentOut {
    let ndc_xy = vec2<f32>(
        in.position.x / params.viewport.x * 2.0 - 1.0,
        1.0 - in.position.y / params.viewport.y * 2.0,
    );
    let near_w = unproject(vec3<f32>(ndc_xy, params.near_z));
    let far_w = unproject(vec3<f32>(ndc_xy, params.far_z));
    let o = (params.world_to_local * vec4<f32>(near_w, 1.0)).xyz;
    let far_l = (params.world_to_local * vec4<f32>(far_w, 1.0)).xyz;
    let span = far_l - o;
    let dir = normalize(span);
    let hit_box = ray_box(o, dir, params.box_min, params.box_max);
    let t_enter = max(hit_box.x, 0.0);
    let t_exit = min(hit_box.y, length(span));
    if t_enter > t_exit {
        discard;
    }

    var t = t_enter;
    var prev_t = t_enter;
    var steps = 0u;
    var found = false;
    var first_d = 0.0;
    loop {
        if steps >= params.max_steps || t > t_exit {
            break;
        }
        let p = o + t * dir;
        let d = distance_at(p);
        if steps == 0u {
            first_d = d;
        }
        steps += 1u;
        let tolerance = max(params.epsilon * params.cell, t * params.pixel_angle);
        if d < tolerance {
            if density_at(p) >= params.threshold {
                // Crossed (or started inside): the root lies between the last two samples.
                t = select(bisect(o, dir, prev_t, t), t, t == prev_t);
                found = true;
                break;
            }
            // Close but outside: look a little further for the crossing.
            let ahead = t + 2.0 * tolerance + 0.5 * params.cell;
            if density_at(o + ahead * dir) >= params.threshold {
                t = bisect(o, dir, t, ahead);
                found = true;
                break;
            }
        }
        prev_t = t;
        t += max(d * params.safety, tolerance);
    }

    var out: FragmentOut;
    let entry_world = (params.local_to_world * vec4<f32>(o + t_enter * dir, 1.0)).xyz;
    if params.mode == 2u {
        out.colour = vec4<f32>(heat(f32(steps) / f32(max(params.max_steps, 1u))), 1.0);
        out.depth = depth_of(entry_world);
        return out;
    }
    if params.mode == 4u {
        let s = first_d / params.band;
        out.colour = vec4<f32>(max(s, 0.0), 0.2, max(-s, 0.0), 1.0);
        out.depth = depth_of(entry_world);
        return out;
    }
    if !found {
        discard;
    }
    let p = o + t * dir;
    let hit_world = (params.local_to_world * vec4<f32>(p, 1.0)).xyz;
    out.depth = depth_of(hit_world);
    let n = normalize((params.local_to_world * vec4<f32>(normal_at(p), 0.0)).xyz);
    if params.mode == 1u {
        // Alpha 1 + distance, so 0 still means "not drawn" for a hit on the near plane.
        out.colour = vec4<f32>(n, 1.0 + length(hit_world - near_w));
        return out;
    }
    // Density just inside the surface: how deep the blobs pile up here.
    let inner = density_at(p - normal_at(p) * params.cell);
    if params.mode == 3u {
        out.colour = vec4<f32>(heat(inner / (4.0 * params.threshold)), 1.0);
        return out;
    }
    let view = normalize(near_w - hit_world);
    let lambert = max(dot(n, normalize(params.light_dir)), 0.0);
    let fresnel = pow(1.0 - clamp(dot(n, view), 0.0, 1.0), 5.0);
    let base = mix(params.base_colour, params.base_colour * 0.55 + 0.45, clamp((inner - params.threshold) / (3.0 * params.threshold), 0.0, 1.0));
    let lit = base * (params.ambient + (1.0 - params.ambient) * lambert) + params.rim_colour * fresnel;
    out.colour = vec4<f32>(lit, 1.0);
    return out;
}
