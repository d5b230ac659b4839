//! CPU references for the metaball stages, in f64: the analytic density field, its iso-surface
//! along a ray (fine sampling, then bisection), and the closed form for one blob.

use glam::{DVec3, Vec4};

use super::Settings;

/// Falloff (1 − d²/R²)³ inside the support, 0 outside.
pub fn falloff(d2: f64, r: f64) -> f64 {
    let q = 1.0 - d2 / (r * r);
    if q > 0.0 { q * q * q } else { 0.0 }
}

/// Analytic density at `p` (local space).
pub fn density_at(voxels: &[Vec4], edge: f32, settings: &Settings, p: DVec3) -> f64 {
    voxels
        .iter()
        .filter(|v| v.w > 0.0)
        .map(|v| {
            let r = settings.radius(edge, v.w) as f64;
            falloff((p - v.truncate().as_dvec3()).length_squared(), r)
        })
        .sum()
}

/// Analytic density gradient at `p`.
pub fn gradient_at(voxels: &[Vec4], edge: f32, settings: &Settings, p: DVec3) -> DVec3 {
    voxels
        .iter()
        .filter(|v| v.w > 0.0)
        .map(|v| {
            let r = settings.radius(edge, v.w) as f64;
            let d = p - v.truncate().as_dvec3();
            let q = 1.0 - d.length_squared() / (r * r);
            if q > 0.0 {
                d * (-6.0 * q * q / (r * r))
            } else {
                DVec3::ZERO
            }
        })
        .sum()
}

/// The fixed-point density sums the splat computes, from f64 falloffs (each contribution rounded
/// as the shader rounds it). The GPU evaluates the falloff in f32, so a contribution can differ
/// by one unit where its value lies near a rounding boundary.
pub fn splat_fixed(
    voxels: &[Vec4],
    edge: f32,
    settings: &Settings,
    grid: &crate::distance::Grid,
    scale: f32,
) -> (Vec<u64>, Vec<u32>) {
    let [w, h, d] = grid.size.map(|s| s as usize);
    let mut sum = vec![0u64; w * h * d];
    let mut count = vec![0u32; w * h * d];
    // The centres in f32, as the splat places them.
    let (origin, cell) = (grid.origin.as_vec3(), grid.voxel as f32);
    for v in voxels.iter().filter(|v| v.w > 0.0) {
        let r = settings.radius(edge, v.w) as f64;
        for z in 0..d {
            for y in 0..h {
                for x in 0..w {
                    let i = glam::Vec3::new(x as f32, y as f32, z as f32);
                    let c = (origin + (i + 0.5) * cell).as_dvec3();
                    let f = falloff((c - v.truncate().as_dvec3()).length_squared(), r);
                    let units = (f * scale as f64).round() as u64;
                    if units > 0 {
                        let i = (z * h + y) * w + x;
                        sum[i] += units;
                        count[i] += 1;
                    }
                }
            }
        }
    }
    (sum, count)
}

/// Radius of one blob's iso-surface: (1 − r²/R²)³ = T.
pub fn blob_iso_radius(r: f64, threshold: f64) -> f64 {
    r * (1.0 - threshold.cbrt()).sqrt()
}

/// First crossing of the iso-surface along `origin + t·dir` for t in [0, t_max]: samples every
/// `step`, then 60 bisections. `Some(0)` when the ray starts inside.
pub fn ray_hit(
    voxels: &[Vec4],
    edge: f32,
    settings: &Settings,
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
    step: f64,
) -> Option<f64> {
    let t_iso = settings.threshold as f64;
    let f = |t: f64| density_at(voxels, edge, settings, origin + dir * t) - t_iso;
    if f(0.0) >= 0.0 {
        return Some(0.0);
    }
    let mut a = 0.0;
    while a < t_max {
        let b = (a + step).min(t_max);
        if f(b) >= 0.0 {
            let (mut lo, mut hi) = (a, b);
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if f(m) >= 0.0 { hi = m } else { lo = m }
            }
            return Some(0.5 * (lo + hi));
        }
        a = b;
    }
    None
}

/// [`ray_hit`] for many blobs: the same first crossing (`dir` a unit vector), summing at each
/// sample only the blobs whose support the ray passes through, and sampling only the stretch
/// of the ray those supports cover (up to `t_max`). `Some(0)` when the ray starts inside.
pub fn ray_hit_near(
    voxels: &[Vec4],
    edge: f32,
    settings: &Settings,
    origin: DVec3,
    dir: DVec3,
    t_max: f64,
    step: f64,
) -> Option<f64> {
    let near: Vec<Vec4> = voxels
        .iter()
        .copied()
        .filter(|v| {
            let (c, r) = (v.truncate().as_dvec3(), settings.radius(edge, v.w) as f64);
            let along = (c - origin).dot(dir);
            v.w > 0.0 && (origin + dir * along - c).length() < r && along + r > 0.0
        })
        .collect();
    let reach = |sign: f64| {
        near.iter().map(move |v| {
            (v.truncate().as_dvec3() - origin).dot(dir) + sign * settings.radius(edge, v.w) as f64
        })
    };
    let start = reach(-1.0).fold(f64::INFINITY, f64::min).max(0.0);
    let end = reach(1.0).fold(0.0, f64::max).min(t_max);
    if near.is_empty() || start >= end {
        return None;
    }
    ray_hit(
        &near,
        edge,
        settings,
        origin + dir * start,
        dir,
        end - start,
        step,
    )
    .map(|t| t + start)
}
