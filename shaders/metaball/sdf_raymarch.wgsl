// SDF raymarch of one volume: sphere tracing on a signed-distance texture, refined by bisection on
// the density's iso-surface and shaded, both read with one hardware-trilinear fetch from the
// packed volume of `metaball/march_field` (distance in cells in r, density in g), one thread per pixel of the volume's screen rectangle
// (after the source's Unreal metaball pass; sphere tracing: Hart 1996). `metaball/composite` then
// writes the result with depth into the caller's targets, so it composites with their scene.
//
// The march is a compute pass, not a full-screen fragment shader: some adapters run fragment
// work on a small part of the chip (on the H100 only two TPCs are graphics-capable), and a compute
// dispatch also covers just the box's screen rectangle.
//
// Rays come from the inverse view-projection through each pixel, from the near plane, so a camera
// inside the volume works; they are moved into the volume's local space (any affine placement: the march
// measures t in local units, as the SDF holds them) and clipped to its box. The step is the sampled distance × `safety`, and the hit
// tolerance grows with distance (a pixel's footprint). A sample below the tolerance, or a sign
// change, is refined by bisection on density − threshold, whose zero set the seeds came from.
//
// Where the blobs themselves are bound (`shared/blobs`, a metaball field built with
// `Settings::exact_surface`), the texture only brings the ray near the surface: within
// `exact_shell` of the texture's surface the march steps by segment tracing on the blobs' own field,
// finds the crossing and the normal on it, and so loses no grazing hit to the trilinear density
// (which moves the iso-surface by up to about a tenth of a cell at 4 cells per blob edge, and
// at a grazing angle a ray may cross the true surface only that deep). Outside the shell a
// step of the texture's distance less `exact_margin` cannot reach the true surface (inside it
// too, where that step is the longer). The source's
// Hermite filter and edge falloff shape the texture's density itself, so with either the
// texture decides.

import fieldkit::field::{ndc_depth, pixel_ray, ray_box};
import package::shared::blobs::{BlobMarch, blob_field, blob_march, blob_normal, blobs_present};
import package::shared::shading::{heat, ray_numbers, surface_colour};

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
    // The pixels marched: the box's screen rectangle (origin, size).
    rect_origin: vec2<u32>,
    rect_size: vec2<u32>,
    // NDC depth of the near and far planes (0 and 1; 1 and 0 for reversed Z).
    near_z: f32,
    far_z: f32,
    // Step = distance × safety (≤ 1 keeps sphere tracing conservative on an approximate SDF).
    safety: f32,
    // 0 shaded, 1 normal (rgb) and 1 + hit distance (a), 2 step count, 3 density, 4 SDF at entry,
    // 5 G-buffer (normal and packed base colour), 6 numbers (hit distance, steps, how it ended).
    mode: u32,
    ambient: f32,
    // Distances in the SDF are clamped to ±band (local units).
    band: f32,
    // The colour piled-up density moves the base toward (w = 1), or lighten it (w = 0).
    pile_colour: vec4<f32>,
    // Step factor at distance 0, rising linearly to `safety` at one cell.
    near_safety: f32,
    // Shortest step, local units.
    min_step: f32,
    // 1: Hermite-weighted trilinear reads (weights 3f² − 2f³); 0: hardware trilinear.
    hermite: u32,
    // 1: density × saturate(10 × (distance to the box's faces in uvw + 0.05)).
    edge_falloff: u32,
    // Top-left pixel of the view's viewport in the target: pixels are traced in viewport
    // coordinates and stored at + view_origin.
    view_origin: vec2<u32>,
    // 1: a ray out of steps inside the box is a hit at its last point (0: a miss); both are
    // marked in mode 6.
    cap_is_hit: u32,
    // Where the blobs are bound: the shell around the texture's surface in which they decide,
    // and how much nearer than the texture says the true surface may be (local units).
    exact_shell: f32,
    exact_margin: f32,
}

struct Shaded {
    colour: vec4<f32>,
    // NDC depth; MISS where nothing is drawn.
    depth: f32,
}

@group(0) @binding(0) var<uniform> params: RaymarchParams;
// Distance (cells) in r, density in g; sampled trilinearly, clamped to the edge.
@group(0) @binding(1) var field: texture_3d<f32>;
@group(0) @binding(2) var field_sampler: sampler;
@group(0) @binding(3) var colour_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var depth_out: texture_storage_2d<r32float, write>;

// Depth written for "no surface here": outside [0, 1] in either depth convention.
const MISS: f32 = -1.0;

const BISECTIONS: u32 = 6u;

// Distance (local units) in x, density in y, at local point `p`.
fn field_at(p: vec3<f32>) -> vec2<f32> {
    let dims = vec3<f32>(textureDimensions(field));
    let uvw = (p - params.box_min) / (params.cell * dims);
    var at = uvw;
    if params.hermite != 0u {
        // Hermite weights from one hardware fetch: between texel centres i and i + 1 the
        // hardware weighs i + 1 by the fraction f; sampling at i + w(f), w = 3f² − 2f³, gives
        // the Hermite weight instead.
        let c = uvw * dims - 0.5;
        let i = floor(c);
        let f = c - i;
        at = (i + 0.5 + f * f * (3.0 - 2.0 * f)) / dims;
    }
    let v = textureSampleLevel(field, field_sampler, at, 0.0).rg;
    var density = v.y;
    if params.edge_falloff != 0u {
        let edge = min(min(uvw.x, min(uvw.y, uvw.z)), 1.0 - max(uvw.x, max(uvw.y, uvw.z)));
        density *= saturate((edge + 0.05) * 10.0);
    }
    return vec2<f32>(v.x * params.cell, density);
}

fn density_at(p: vec3<f32>) -> f32 {
    return field_at(p).y;
}

// Root of density − threshold on [a, b], with density(a) below and density(b) at or above it:
// BISECTIONS halvings, then the secant through the bracket's ends (the density is smooth, so the
// secant on a bracket a few hundredths of a cell long is far inside the hit tolerance).
fn bisect(o: vec3<f32>, dir: vec3<f32>, a_in: f32, b_in: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    var fa = density_at(o + a * dir) - params.threshold;
    var fb = density_at(o + b * dir) - params.threshold;
    for (var k = 0u; k < BISECTIONS; k++) {
        let m = 0.5 * (a + b);
        let fm = density_at(o + m * dir) - params.threshold;
        if fm >= 0.0 {
            b = m;
            fb = fm;
        } else {
            a = m;
            fa = fm;
        }
    }
    if fb - fa > 0.0 && fa < 0.0 {
        return a + (b - a) * (-fa / (fb - fa));
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

// March and shade the ray through the pixel centre `pixel`.
fn trace(pixel: vec2<f32>) -> Shaded {
    var out: Shaded;
    out.depth = MISS;
    let ray = pixel_ray(pixel, params.viewport, params.inv_view_proj, params.world_to_local, params.near_z, params.far_z);
    let near_w = ray.near;
    let o = ray.origin;
    let dir = ray.dir;
    let hit_box = ray_box(o, dir, params.box_min, params.box_max);
    let t_enter = max(hit_box.x, 0.0);
    let t_exit = min(hit_box.y, ray.length);
    if t_enter > t_exit {
        return out;
    }

    var t = t_enter;
    var prev_t = t_enter;
    var steps = 0u;
    var found = false;
    var first_d = 0.0;
    // The source's Hermite filter and edge falloff shape the texture's density: where either is
    // asked for, the texture decides.
    let exact = blobs_present() && params.hermite == 0u && params.edge_falloff == 0u;
    // Segment tracing's next segment inside the shell.
    var seg = params.cell;
    loop {
        if steps >= params.max_steps || t > t_exit {
            break;
        }
        let p = o + t * dir;
        let sample = field_at(p);
        let d = sample.x;
        if steps == 0u {
            first_d = d;
        }
        steps += 1u;
        let tolerance = max(params.epsilon * params.cell, t * params.pixel_angle);
        if exact {
            if d < params.exact_shell {
                // Near the surface the blobs decide.
                let m = blob_march(o, dir, BlobMarch(t, prev_t, seg, false), tolerance, params.threshold, true);
                if m.hit {
                    t = m.t;
                    found = true;
                    break;
                }
                t = max(m.t, t + d - params.exact_margin);
                prev_t = m.prev_t;
                seg = m.seg;
            } else {
                seg = params.cell;
                prev_t = t;
                t += max(d - params.exact_margin, tolerance);
            }
            continue;
        }
        // The density comes with the distance: a sample at or above the threshold has crossed
        // (or started inside), whatever the approximate distance says there, so a step past a
        // grazing stretch of surface is caught where it lands; the root lies between the last
        // two samples.
        if sample.y >= params.threshold {
            t = select(bisect(o, dir, prev_t, t), t, t == prev_t);
            found = true;
            break;
        }
        if d < tolerance {
            // Close but outside: look a little further for the crossing.
            let ahead = t + 2.0 * tolerance + 0.5 * params.cell;
            if density_at(o + ahead * dir) >= params.threshold {
                t = bisect(o, dir, t, ahead);
                found = true;
                break;
            }
        }
        prev_t = t;
        // Step factor from near_safety at d = 0 to safety at one cell (both equal by default).
        let k = mix(params.near_safety, params.safety, saturate(d / params.cell));
        t += max(d * k, max(params.min_step, tolerance));
    }

    let entry_world = (params.local_to_world * vec4<f32>(o + t_enter * dir, 1.0)).xyz;
    // Out of steps inside the box with nothing met: marked, and a hit at its last point where
    // the caller asks.
    let ran_out = !found && steps >= params.max_steps && t <= t_exit;
    if ran_out && params.cap_is_hit != 0u {
        found = true;
    }
    if params.mode == 6u {
        let at = (params.local_to_world * vec4<f32>(o + t * dir, 1.0)).xyz;
        out.colour = ray_numbers(found, ran_out, params.cap_is_hit != 0u, steps, at, near_w);
        out.depth = ndc_depth(params.view_proj, select(entry_world, at, found));
        return out;
    }
    if params.mode == 2u {
        out.colour = vec4<f32>(heat(f32(steps) / f32(max(params.max_steps, 1u))), 1.0);
        out.depth = ndc_depth(params.view_proj, entry_world);
        return out;
    }
    if params.mode == 4u {
        let s = first_d / params.band;
        out.colour = vec4<f32>(max(s, 0.0), 0.2, max(-s, 0.0), 1.0);
        out.depth = ndc_depth(params.view_proj, entry_world);
        return out;
    }
    if !found {
        return out;
    }
    let p = o + t * dir;
    let hit_world = (params.local_to_world * vec4<f32>(p, 1.0)).xyz;
    out.depth = ndc_depth(params.view_proj, hit_world);
    var n_local: vec3<f32>;
    var inner: f32;
    // Density just inside the surface: how deep the blobs pile up here.
    if exact {
        n_local = blob_normal(p);
        inner = blob_field(p - n_local * params.cell);
    } else {
        n_local = normal_at(p);
        inner = density_at(p - n_local * params.cell);
    }
    // Normals go to world through the inverse transpose (v * M is transpose(M) * v).
    let n = normalize((vec4<f32>(n_local, 0.0) * params.world_to_local).xyz);
    out.colour = surface_colour(params.mode, n, inner, hit_world, near_w, params.light_dir, params.threshold, params.base_colour, params.rim_colour, params.ambient, params.pile_colour);
    return out;
}

@compute @workgroup_size(8, 8)
fn march(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.rect_size) {
        return;
    }
    let xy = params.rect_origin + id.xy;
    let shaded = trace(vec2<f32>(xy) + 0.5);
    let at = xy + params.view_origin;
    textureStore(colour_out, at, shaded.colour);
    textureStore(depth_out, at, vec4<f32>(shaded.depth, 0.0, 0.0, 0.0));
}
