// Traces the metaball field directly, from the blobs in `metaball/bin_blobs`, one thread per
// pixel of the box's screen rectangle; `metaball/composite` writes the result into the caller's
// targets as it does for the SDF-texture march. The field, its two step rules (a global
// Lipschitz bound, or segment tracing) and the bisection are `shared/blobs`'s; this stage
// clips each ray to the bins' box, steps until f ≥ T, and shades with the analytic gradient.

import fieldkit::field::{ndc_depth, pixel_ray, ray_box};
import package::shared::blobs::{BlobMarch, blob_field, blob_march, blob_normal};
import package::shared::shading::{heat, ray_numbers, surface_colour};

struct TraceParams {
    inv_view_proj: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    world_to_local: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    // Local-space box of the bins.
    box_min: vec3<f32>,
    // The first bin's edge: the first segment of segment tracing.
    bin_size: f32,
    box_max: vec3<f32>,
    threshold: f32,
    light_dir: vec3<f32>,
    max_steps: u32,
    base_colour: vec3<f32>,
    // Smallest step and hit tolerance, local units.
    epsilon: f32,
    rim_colour: vec3<f32>,
    pixel_angle: f32,
    // 0: global-bound sphere tracing; 1: segment tracing.
    method: u32,
    viewport: vec2<f32>,
    near_z: f32,
    far_z: f32,
    rect_origin: vec2<u32>,
    rect_size: vec2<u32>,
    // 0 shaded, 1 normal and 1 + distance, 2 step count, 3 density, 6 numbers (as the SDF march).
    mode: u32,
    ambient: f32,
    // How far inside the surface the shading samples the density, local units.
    inner_offset: f32,
    // The colour piled-up density moves the base toward (w = 1), or lighten it (w = 0).
    pile_colour: vec4<f32>,
    // Top-left pixel of the view's viewport in the target: pixels are traced in viewport
    // coordinates and stored at + view_origin.
    view_origin: vec2<u32>,
    // 1: a ray out of steps inside the box is a hit at its last point (0: a miss); both are
    // marked in mode 6.
    cap_is_hit: u32,
}

struct Shaded {
    colour: vec4<f32>,
    depth: f32,
}

@group(0) @binding(0) var<uniform> params: TraceParams;
@group(0) @binding(1) var colour_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(2) var depth_out: texture_storage_2d<r32float, write>;

const MISS: f32 = -1.0;

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
    // Segment tracing's next segment length.
    var seg = params.bin_size;
    loop {
        if steps >= params.max_steps || t > t_exit {
            break;
        }
        steps += 1u;
        let tolerance = max(params.epsilon, t * params.pixel_angle);
        let m = blob_march(o, dir, BlobMarch(t, prev_t, seg, false), tolerance, params.threshold, params.method == 1u);
        t = m.t;
        prev_t = m.prev_t;
        seg = m.seg;
        if m.hit {
            found = true;
            break;
        }
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
    if !found {
        return out;
    }
    let p = o + t * dir;
    let hit_world = (params.local_to_world * vec4<f32>(p, 1.0)).xyz;
    out.depth = ndc_depth(params.view_proj, hit_world);
    let n_local = blob_normal(p);
    // Normals go to world through the inverse transpose (v * M is transpose(M) * v).
    let n = normalize((vec4<f32>(n_local, 0.0) * params.world_to_local).xyz);
    // Density just inside the surface: how deep the blobs pile up here.
    let inner = blob_field(p - n_local * params.inner_offset);
    out.colour = surface_colour(params.mode, n, inner, hit_world, near_w, params.light_dir, params.threshold, params.base_colour, params.rim_colour, params.ambient, params.pile_colour);
    return out;
}

@compute @workgroup_size(8, 8)
fn trace_blobs(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= params.rect_size) {
        return;
    }
    let xy = params.rect_origin + id.xy;
    let shaded = trace(vec2<f32>(xy) + 0.5);
    let at = xy + params.view_origin;
    textureStore(colour_out, at, shaded.colour);
    textureStore(depth_out, at, vec4<f32>(shaded.depth, 0.0, 0.0, 0.0));
}
