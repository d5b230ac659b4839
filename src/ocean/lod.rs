//! Which patches to draw: a CPU quadtree over the ocean square, refined where a patch's height
//! error, projected to pixels, is above a threshold, and culled against the view frustum with
//! bounds grown by the waves' largest displacement. Patches of different sizes meet with
//! T-junctions; the renderer's skirts hide the cracks.
//!
//! The error of a patch is how far its triangles can be from the surface they sample: a wave of
//! amplitude A and frequency w sampled every h metres is off by up to A·(1 − cos(w·h/2)) midway
//! between samples (all of A once w·h ≥ 2π), summed over the waves and the height layers'
//! octaves. Divided by the distance from the eye to the patch's bounds and multiplied by the
//! pixels per unit of tangent at the image centre, it is the error in pixels.

use glam::{DMat4, DVec2, DVec3, DVec4};

use super::Waves;
use super::render::{DETAIL_OCTAVES, Look, MAX_PATCH_QUADS, OceanCamera, Patch};
use crate::error::Error;

/// The ocean square and the error to refine to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodSettings {
    /// World (x, z) of the square's centre.
    pub centre: DVec2,
    /// Side of the square (the write-up's ocean: 2560 m).
    pub size: f64,
    /// Refine until no patch's height error covers more than this many pixels.
    pub max_error_px: f64,
    /// Deepest level (the root is 0): patches are at least `size / 2^max_depth` across.
    pub max_depth: u32,
    /// Most quads per patch side: a patch is split until its error at this many quads is
    /// within `max_error_px`, then drawn with the fewest of this, ¾ and ½ of it that keep it
    /// there.
    pub patch_quads: u32,
}

impl Default for LodSettings {
    fn default() -> Self {
        Self {
            centre: DVec2::ZERO,
            size: 2560.0,
            max_error_px: 1.0,
            max_depth: 12,
            patch_quads: 32,
        }
    }
}

/// The patches chosen (nearest first), and what they cost and miss.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    pub patches: Vec<Patch>,
    /// Largest projected height error of a drawn patch (pixels).
    pub max_error_px: f64,
    /// Patches left out as outside the view.
    pub culled: usize,
    /// Triangles drawn (grid and skirts).
    pub triangles: u64,
}

/// Triangles one patch of `quads` per side draws: its grid and its skirts.
pub fn patch_triangles(quads: u32) -> u64 {
    let n = quads as u64;
    2 * n * n + 8 * n
}

/// The height error of sampling the waves and `look`'s height layers every `h` metres.
pub fn height_error(waves: &Waves, look: &Look, h: f64) -> f64 {
    let sampled = |amplitude: f64, wavelength: f64| {
        let half_step = std::f64::consts::PI * h / wavelength;
        amplitude * (1.0 - half_step.min(std::f64::consts::PI).cos())
    };
    let mut e: f64 = waves
        .waves()
        .iter()
        .map(|w| sampled(w.amplitude as f64, w.wavelength as f64))
        .sum();
    // The detail texture's octaves (`render::DETAIL_OCTAVES`), each taken as a wave as long as
    // one noise cell (shorter than the noise's own wavelengths: the error is overestimated).
    for l in &look.height_layers {
        for &(cells, amp) in &DETAIL_OCTAVES {
            e += sampled(
                l.strength.abs() as f64 * amp as f64,
                l.tile as f64 / cells as f64,
            );
        }
    }
    e
}

/// Largest sideways and vertical reach of the surface from its undisplaced point.
fn reach(waves: &Waves, look: &Look) -> (f64, f64) {
    let n = waves.waves().len() as f64;
    let q = waves.steepness() as f64;
    let sideways: f64 = waves
        .waves()
        .iter()
        .map(|w| q * w.wavelength as f64 / (std::f64::consts::TAU * n))
        .sum();
    let up: f64 = waves
        .waves()
        .iter()
        .map(|w| w.amplitude as f64)
        .sum::<f64>()
        + look
            .height_layers
            .iter()
            .map(|l| l.strength.abs() as f64)
            .sum::<f64>();
    (sideways, up)
}

/// Frustum planes (a·x + b·y + c·z + d ≥ 0 inside) of a world-to-clip matrix with depth in
/// [0, 1].
fn planes(view_proj: DMat4) -> [DVec4; 6] {
    let r = |i: usize| view_proj.row(i);
    [
        r(3) + r(0),
        r(3) - r(0),
        r(3) + r(1),
        r(3) - r(1),
        r(2),
        r(3) - r(2),
    ]
}

fn outside(planes: &[DVec4; 6], lo: DVec3, hi: DVec3) -> bool {
    planes.iter().any(|p| {
        // The box corner farthest along the plane's normal.
        let c = DVec3::new(
            if p.x >= 0.0 { hi.x } else { lo.x },
            if p.y >= 0.0 { hi.y } else { lo.y },
            if p.z >= 0.0 { hi.z } else { lo.z },
        );
        p.truncate().dot(c) + p.w < 0.0
    })
}

/// Choose patches for `camera` with a viewport `viewport_height` pixels high.
pub fn select(
    waves: &Waves,
    look: &Look,
    camera: &OceanCamera,
    viewport_height: u32,
    settings: &LodSettings,
) -> Result<Selection, Error> {
    let s = settings;
    if !(s.centre.is_finite() && s.size.is_finite() && s.size > 0.0) {
        return Err(Error::Invalid {
            stage: "ocean::lod",
            what: format!("the ocean square needs a finite centre and size > 0, got {s:?}"),
        });
    }
    if !(s.max_error_px.is_finite() && s.max_error_px > 0.0)
        || s.max_depth > 24
        || !(2..=MAX_PATCH_QUADS).contains(&s.patch_quads)
    {
        return Err(Error::Invalid {
            stage: "ocean::lod",
            what: format!(
                "max_error_px must be > 0, max_depth ≤ 24 and patch_quads 2 to \
                 {MAX_PATCH_QUADS}, got {s:?}"
            ),
        });
    }
    if viewport_height == 0 || !(camera.view.is_finite() && camera.proj.is_finite()) {
        return Err(Error::Invalid {
            stage: "ocean::lod",
            what: "the viewport must be at least a pixel high and the camera finite".into(),
        });
    }
    let eye = camera.eye();
    let proj = camera.proj.as_dmat4();
    let frustum = planes(proj * camera.view);
    // Pixels per unit of tangent: half the height times the projection's y scale.
    let px_per_tan = 0.5 * viewport_height as f64 * proj.y_axis.y.abs();
    let (sideways, up) = reach(waves, look);
    let low = -up - look.skirt as f64;
    let mut out = Selection {
        patches: Vec::new(),
        max_error_px: 0.0,
        culled: 0,
        triangles: 0,
    };
    let mut stack = vec![(s.centre - DVec2::splat(s.size / 2.0), s.size, 0u32)];
    while let Some((corner, size, depth)) = stack.pop() {
        let lo = DVec3::new(corner.x - sideways, low, corner.y - sideways);
        let hi = DVec3::new(corner.x + size + sideways, up, corner.y + size + sideways);
        if outside(&frustum, lo, hi) {
            out.culled += 1;
            continue;
        }
        let nearest = eye.clamp(lo, hi);
        let dist = (nearest - eye).length().max(1e-6);
        let error_at =
            |quads: u32| height_error(waves, look, size / quads as f64) * px_per_tan / dist;
        let error_px = error_at(s.patch_quads);
        if error_px > s.max_error_px && depth < s.max_depth {
            let half = size / 2.0;
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                stack.push((
                    corner + DVec2::new(i as f64, j as f64) * half,
                    half,
                    depth + 1,
                ));
            }
            continue;
        }
        // The fewest quads that keep the error: a patch's error falls off with its distance,
        // so leaves far from where their parent was split need fewer.
        let (mut quads, mut error_px) = (s.patch_quads, error_px);
        for fewer in [s.patch_quads * 3 / 4, s.patch_quads / 2] {
            let e = error_at(fewer);
            if e <= s.max_error_px {
                (quads, error_px) = (fewer, e);
            }
        }
        out.max_error_px = out.max_error_px.max(error_px);
        out.triangles += patch_triangles(quads);
        out.patches.push(Patch {
            corner,
            size,
            quads,
        });
    }
    // Nearest first, so the depth test rejects what nearer water hides before it is shaded.
    let dist = |p: &Patch| {
        let c = p.corner + DVec2::splat(p.size / 2.0);
        (c - DVec2::new(eye.x, eye.z)).length_squared()
    };
    out.patches.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
    Ok(out)
}

/// The write-up's layout, for comparison: the square split where the camera is nearer a node
/// than its side, down to an eighth of the square, each patch `quads` per side (255: 256
/// vertices per row). The write-up had 20–30 such patches and about 4 million triangles; this
/// rule gives 43 patches and 5.6 million for the camera of `tests/ocean_lod.rs`, 15 of them in
/// view.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteupLayout {
    pub patches: Vec<Patch>,
    /// How many of them are in view (the others a renderer would cull).
    pub visible: usize,
    /// Largest projected height error among the visible ones (pixels).
    pub max_error_px: f64,
}

pub fn writeup_patches(
    waves: &Waves,
    look: &Look,
    camera: &OceanCamera,
    viewport_height: u32,
    settings: &LodSettings,
    quads: u32,
) -> WriteupLayout {
    let eye = camera.eye();
    let proj = camera.proj.as_dmat4();
    let frustum = planes(proj * camera.view);
    let px_per_tan = 0.5 * viewport_height as f64 * proj.y_axis.y.abs();
    let (sideways, up) = reach(waves, look);
    let mut out = WriteupLayout {
        patches: Vec::new(),
        visible: 0,
        max_error_px: 0.0,
    };
    let mut stack = vec![(
        settings.centre - DVec2::splat(settings.size / 2.0),
        settings.size,
    )];
    while let Some((corner, size)) = stack.pop() {
        let lo = DVec3::new(corner.x - sideways, -up, corner.y - sideways);
        let hi = DVec3::new(corner.x + size + sideways, up, corner.y + size + sideways);
        let dist = (eye.clamp(lo, hi) - eye).length().max(1e-6);
        if dist < size && size > settings.size / 8.0 {
            let half = size / 2.0;
            for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                stack.push((corner + DVec2::new(i as f64, j as f64) * half, half));
            }
            continue;
        }
        out.patches.push(Patch {
            corner,
            size,
            quads,
        });
        if !outside(&frustum, lo, hi) {
            out.visible += 1;
            let e = height_error(waves, look, size / quads as f64) * px_per_tan / dist;
            out.max_error_px = out.max_error_px.max(e);
        }
    }
    out
}
