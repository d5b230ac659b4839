// Traces the metaball field directly, from the blobs in `metaball/bin_blobs`, one thread per
// pixel of the box's screen rectangle; `metaball/composite` writes the result into the caller's
// targets as it does for the SDF-texture march. Two step rules for the field f = Σ (1 − r²/R²)³:
//
// - sphere tracing with a global Lipschitz bound (Hart 1996): (T − f) / L never passes the
//   surface when L bounds |∇f| everywhere. Per blob |g'| ≤ 96 / (25√5 · R) ≈ 1.717 / R, and a
//   point sees only its bin's blobs, so L is the largest bin sum of 1.717 / R (`stats[1]`).
// - segment tracing (Galin et al. 2020): the bound is taken over the segment about to be crossed
//   only, blob by blob: |g'(r)| peaks at r = R / √5, so on a segment whose points lie between
//   r_min and r_max from a blob's centre its derivative along the ray is at most
//   |g'(clamp(R / √5, r_min, r_max))|. Far and flat blobs then cost nothing, and the step grows
//   with the segment (× 2 while whole segments are crossed).
//
// Both evaluate f from the bin under the sample, skip empty bins whole, stop a ray where f ≥ T
// and refine the crossing by bisection on f, and shade with the analytic gradient.

import fieldkit::field::{ndc_depth, pixel_ray, ray_box};
import package::shared::shading::{heat, ray_numbers, surface_colour};

struct TraceParams {
    inv_view_proj: mat4x4<f32>,
    view_proj: mat4x4<f32>,
    world_to_local: mat4x4<f32>,
    local_to_world: mat4x4<f32>,
    // Local-space box of the bins.
    box_min: vec3<f32>,
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
    bins: vec3<u32>,
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

// A field value with, for segment tracing, the bound of its derivative along the segment.
struct Sample {
    f: f32,
    bound: f32,
}

@group(0) @binding(0) var<uniform> params: TraceParams;
@group(0) @binding(1) var<storage, read> starts: array<u32>;
@group(0) @binding(2) var<storage, read> items: array<vec4<f32>>;
// [1]: the global Lipschitz bound as f32 bits.
@group(0) @binding(3) var<storage, read> stats: array<u32>;
@group(0) @binding(4) var colour_out: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var depth_out: texture_storage_2d<r32float, write>;

const MISS: f32 = -1.0;
const BISECTIONS: u32 = 6u;
// R / √5, where the falloff is steepest.
const STEEPEST: f32 = 0.4472136;

fn bin_of(p: vec3<f32>) -> vec3<i32> {
    let b = floor((p - params.box_min) / params.bin_size);
    return clamp(vec3<i32>(b), vec3<i32>(0), vec3<i32>(params.bins) - 1);
}

fn bin_index(b: vec3<i32>) -> u32 {
    return (u32(b.z) * params.bins.y + u32(b.y)) * params.bins.x + u32(b.x);
}

// |g'(r)| for the falloff of radius `radius`.
fn slope(r: f32, radius: f32) -> f32 {
    let q = 1.0 - r * r / (radius * radius);
    return select(0.0, 6.0 * r / (radius * radius) * q * q, q > 0.0);
}

// f at `p` from bin `b`, and the bound of df/dt over the segment p + [0, len]·dir.
fn sample_bin(b: u32, p: vec3<f32>, dir: vec3<f32>, len: f32) -> Sample {
    var s = Sample(0.0, 0.0);
    for (var i = starts[b]; i < starts[b + 1u]; i++) {
        let blob = items[i];
        let d = p - blob.xyz;
        let r2 = dot(d, d);
        let q = 1.0 - r2 / (blob.w * blob.w);
        if q > 0.0 {
            s.f += q * q * q;
        }
        if len > 0.0 {
            // Distances from the centre to the segment's points lie in [r_min, r_max].
            let along = -dot(d, dir);
            let closest = clamp(along, 0.0, len);
            let r_min = sqrt(max(r2 - along * along, 0.0) + (closest - along) * (closest - along));
            let r_max = max(sqrt(r2), length(d + len * dir));
            s.bound += slope(clamp(STEEPEST * blob.w, r_min, r_max), blob.w);
        }
    }
    return s;
}

fn field(p: vec3<f32>) -> f32 {
    return sample_bin(bin_index(bin_of(p)), p, vec3<f32>(0.0), 0.0).f;
}

fn gradient(p: vec3<f32>) -> vec3<f32> {
    let b = bin_index(bin_of(p));
    var g = vec3<f32>(0.0);
    for (var i = starts[b]; i < starts[b + 1u]; i++) {
        let blob = items[i];
        let d = p - blob.xyz;
        let inv_r2 = 1.0 / (blob.w * blob.w);
        let q = 1.0 - dot(d, d) * inv_r2;
        if q > 0.0 {
            g -= 6.0 * q * q * inv_r2 * d;
        }
    }
    return g;
}

// Root of f − T on [a, b], f(a) below and f(b) at or above it: BISECTIONS halvings, then the
// secant through the bracket's ends (as the SDF march does).
fn bisect(o: vec3<f32>, dir: vec3<f32>, a_in: f32, b_in: f32) -> f32 {
    var a = a_in;
    var b = b_in;
    var fa = field(o + a * dir) - params.threshold;
    var fb = field(o + b * dir) - params.threshold;
    for (var k = 0u; k < BISECTIONS; k++) {
        let m = 0.5 * (a + b);
        let fm = field(o + m * dir) - params.threshold;
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
    let lipschitz = bitcast<f32>(stats[1]);

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
        let p = o + t * dir;
        // The bin the ray is about to cross (on a face, the one ahead).
        let bin = bin_of(p + dir * (1e-4 * params.bin_size));
        let b = bin_index(bin);
        let lo = params.box_min + vec3<f32>(bin) * params.bin_size;
        let bin_exit = ray_box(o, dir, lo, lo + params.bin_size).y;
        let tolerance = max(params.epsilon, t * params.pixel_angle);
        if starts[b] == starts[b + 1u] {
            // No blob reaches this bin: the field is zero all through it.
            prev_t = t;
            t = max(bin_exit, t + tolerance);
            continue;
        }
        var len = 0.0;
        if params.method == 1u {
            len = max(min(seg, bin_exit - t), tolerance);
        }
        let s = sample_bin(b, p, dir, len);
        if s.f >= params.threshold {
            t = select(bisect(o, dir, prev_t, t), t, t == prev_t);
            found = true;
            break;
        }
        var step: f32;
        if params.method == 1u {
            step = select(len, (params.threshold - s.f) / s.bound, s.bound > 0.0);
            step = min(step, len);
            // Whole segments crossed: try a longer one; otherwise start from this step.
            seg = select(2.0 * step, 2.0 * len, step >= len);
        } else {
            step = (params.threshold - s.f) / lipschitz;
        }
        prev_t = t;
        t += max(step, tolerance);
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
    let g = gradient(p);
    let n_local = select(vec3<f32>(0.0, 0.0, 1.0), -normalize(g), dot(g, g) > 1e-24);
    // Normals go to world through the inverse transpose (v * M is transpose(M) * v).
    let n = normalize((vec4<f32>(n_local, 0.0) * params.world_to_local).xyz);
    // Density just inside the surface: how deep the blobs pile up here.
    let inner = field(p - n_local * params.inner_offset);
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
