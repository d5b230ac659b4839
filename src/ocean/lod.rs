//! Which patches to draw: a CPU quadtree over the ocean square, refined where a patch's height
//! error, projected to pixels, is above a threshold, and culled against the view frustum with
//! bounds grown by the waves' largest displacement. Patches whose vertex spacing differs meet
//! with T-junctions; skirts hide the cracks. Only those edges get one: a patch beside one of
//! the same size and quad count shares its edge's vertices bit for bit (the renderer computes
//! both from the same corner values), and an edge beside nothing drawn has no crack to hide.
//!
//! The error of a patch is how far its triangles can be from the surface they sample: a wave of
//! amplitude A and frequency w sampled every h metres is off by up to A·(1 − cos(w·h/2)) midway
//! between samples (all of A once w·h ≥ 2π), summed over the waves and the height layers'
//! octaves. Divided by the distance from the eye to the patch's bounds and multiplied by the
//! pixels per unit of tangent at the image centre, it is the error in pixels.

use std::collections::HashMap;

use glam::{DMat4, DVec2, DVec3, DVec4};

use super::Waves;
use super::look::{DETAIL_OCTAVES, Look};
use super::patches::{MAX_PATCH_QUADS, Patch};
use super::render::OceanCamera;
use crate::error::Error;

/// Most quadtree nodes [`select`] visits (split, culled or drawn) before it refuses the settings
/// with [`Error::Size`]: 2¹⁸ nodes are ~200 000 patches, far past any frame's budget; an error
/// of a millionth of a pixel at depth 24 would otherwise walk 4²⁴ nodes.
pub const MAX_LOD_NODES: u64 = 1 << 18;

/// The ocean square and the error to refine to.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// within `max_error_px`, then drawn with the fewest quads, down to half of this, that keep
    /// it there. Smaller patches follow the error more closely (fewer triangles) for more CPU
    /// time in [`select`] and more instances to draw.
    pub patch_quads: u32,
}

impl Default for LodSettings {
    fn default() -> Self {
        Self {
            centre: DVec2::ZERO,
            size: 2560.0,
            max_error_px: 1.0,
            max_depth: 12,
            patch_quads: 16,
        }
    }
}

/// The patches chosen (nearest first), and what they cost and miss.
#[derive(Clone, Debug, PartialEq)]
pub struct Selection {
    /// The patches to draw.
    pub patches: Vec<Patch>,
    /// Largest projected height error of a drawn patch (pixels).
    pub max_error_px: f64,
    /// Patches left out as outside the view.
    pub culled: usize,
    /// Triangles drawn (grid and skirts).
    pub triangles: u64,
}

/// Triangles one patch of `quads` per side draws with all four skirts: its grid and its skirts
/// ([`Patch::triangles`] counts the skirts it has).
pub fn patch_triangles(quads: u32) -> u64 {
    Patch::new(DVec2::ZERO, 1.0).with_quads(quads).triangles()
}

/// What the quadtree made of a node: a drawn leaf of so many quads, split, or culled.
#[derive(Clone, Copy, PartialEq)]
enum Node {
    Leaf(u32),
    Split,
    Culled,
}

/// Edge order of `render::patch_indices` and [`Patch::skirts`]: z low, x high, z high, x low,
/// as the step to the node across.
const ACROSS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

/// Whether a drawn leaf inside node `(depth, i, j)` touches its side facing `toward` (a step of
/// [`ACROSS`] pointing out of the node).
fn drawn_along(
    nodes: &HashMap<(u32, u32, u32), Node>,
    (depth, i, j): (u32, u32, u32),
    toward: (i64, i64),
) -> bool {
    match nodes.get(&(depth, i, j)) {
        Some(Node::Leaf(_)) => true,
        // The two children on that side.
        Some(Node::Split) => [(0i64, 0i64), (1, 0), (0, 1), (1, 1)]
            .into_iter()
            .filter(|&(a, b)| {
                (toward.0 == 0 || a == (toward.0 + 1) / 2)
                    && (toward.1 == 0 || b == (toward.1 + 1) / 2)
            })
            .any(|(a, b)| {
                drawn_along(
                    nodes,
                    (depth + 1, 2 * i + a as u32, 2 * j + b as u32),
                    toward,
                )
            }),
        Some(Node::Culled) | None => false,
    }
}

/// The edges of the leaf `(depth, i, j)` (node `i`, `j` of the `2^depth` per side) that need a
/// skirt, as [`Patch::skirts`] numbers them: those beside a drawn patch of another vertex
/// spacing (a leaf of another quad count, or of another size: a larger leaf, or smaller leaves
/// of a split node). No skirt beside a leaf of the same size and quads, nor where nothing is
/// drawn (culled nodes, the square's border).
fn skirt_edges(
    nodes: &HashMap<(u32, u32, u32), Node>,
    depth: u32,
    i: u32,
    j: u32,
    quads: u32,
) -> u8 {
    let side = 1i64 << depth;
    let mut mask = 0u8;
    for (e, (di, dj)) in ACROSS.into_iter().enumerate() {
        let (ni, nj) = (i as i64 + di, j as i64 + dj);
        if ni < 0 || nj < 0 || ni >= side || nj >= side {
            continue;
        }
        // The neighbour of the same size, or the first ancestor of it that was visited.
        let (mut d, mut a, mut b) = (depth, ni as u32, nj as u32);
        let found = loop {
            if let Some(n) = nodes.get(&(d, a, b)) {
                break Some((d, *n));
            }
            if d == 0 {
                break None;
            }
            (d, a, b) = (d - 1, a / 2, b / 2);
        };
        let needs = match found {
            Some((d, Node::Leaf(q))) => d != depth || q != quads,
            // Smaller leaves across: a skirt if any of them is drawn along this edge.
            Some((_, Node::Split)) => drawn_along(nodes, (d, a, b), (-di, -dj)),
            Some((_, Node::Culled)) | None => false,
        };
        if needs {
            mask |= 1 << e;
        }
    }
    mask
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
pub(super) fn reach(waves: &Waves, look: &Look) -> (f64, f64) {
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
pub(super) fn planes(view_proj: DMat4) -> [DVec4; 6] {
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

/// What [`select`] refuses: a square, error bound, depth or patch size out of range, an
/// empty viewport or a camera that is not finite.
pub(super) fn check_select(
    camera: &OceanCamera,
    viewport_height: u32,
    settings: &LodSettings,
) -> Result<(), Error> {
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
    Ok(())
}

/// Choose patches for `camera` with a viewport `viewport_height` pixels high.
pub fn select(
    waves: &Waves,
    look: &Look,
    camera: &OceanCamera,
    viewport_height: u32,
    settings: &LodSettings,
) -> Result<Selection, Error> {
    check_select(camera, viewport_height, settings)?;
    let s = settings;
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
    // Nodes as (depth, i, j): corner = origin + (i, j) · size, size = s.size / 2^depth.
    let origin = s.centre - DVec2::splat(s.size / 2.0);
    let mut nodes = HashMap::new();
    let mut spacing_error = HashMap::new();
    let mut leaves = Vec::new();
    let mut stack = vec![(0u32, 0u32, 0u32)];
    let mut visited = 0u64;
    while let Some((depth, i, j)) = stack.pop() {
        visited += 1;
        if visited > MAX_LOD_NODES {
            return Err(Error::Size {
                stage: "ocean::lod",
                what: "quadtree nodes visited (raise max_error_px or lower max_depth)",
                got: visited,
                max: MAX_LOD_NODES,
            });
        }
        let size = s.size / (1u64 << depth) as f64;
        let corner = origin + DVec2::new(i as f64, j as f64) * size;
        let lo = DVec3::new(corner.x - sideways, low, corner.y - sideways);
        let hi = DVec3::new(corner.x + size + sideways, up, corner.y + size + sideways);
        if outside(&frustum, lo, hi) {
            out.culled += 1;
            nodes.insert((depth, i, j), Node::Culled);
            continue;
        }
        let nearest = eye.clamp(lo, hi);
        let dist = (nearest - eye).length().max(1e-6);
        // The height error depends only on the spacing, one of few (levels × quad counts).
        let mut error_at = |quads: u32| {
            *spacing_error
                .entry((depth, quads))
                .or_insert_with(|| height_error(waves, look, size / quads as f64))
                * px_per_tan
                / dist
        };
        let error_px = error_at(s.patch_quads);
        if error_px > s.max_error_px && depth < s.max_depth {
            nodes.insert((depth, i, j), Node::Split);
            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                stack.push((depth + 1, 2 * i + a, 2 * j + b));
            }
            continue;
        }
        // The fewest quads, down to half, that keep the error: a patch's error falls off with
        // its distance, so leaves far from where their parent was split need fewer. (Choosing
        // among q, ¾q and ½q only took 17% more triangles in `tests/ocean/lod.rs`'s view.) The
        // error grows as the quads fall: bisect for the fewest that keep it.
        let (mut quads, mut error_px) = (s.patch_quads, error_px);
        let mut fewest_missing = s.patch_quads.div_ceil(2) - 1;
        while quads - fewest_missing > 1 {
            let mid = (quads + fewest_missing) / 2;
            let e = error_at(mid);
            if e <= s.max_error_px {
                (quads, error_px) = (mid, e);
            } else {
                fewest_missing = mid;
            }
        }
        out.max_error_px = out.max_error_px.max(error_px);
        nodes.insert((depth, i, j), Node::Leaf(quads));
        leaves.push((depth, i, j, corner, size, quads));
    }
    for (depth, i, j, corner, size, quads) in leaves {
        let patch = Patch {
            corner,
            size,
            quads,
            skirts: skirt_edges(&nodes, depth, i, j, quads),
        };
        out.triangles += patch.triangles();
        out.patches.push(patch);
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
/// rule gives 43 patches and 5.6 million for the camera of `tests/ocean/lod.rs`, 15 of them in
/// view.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteupLayout {
    /// The write-up's fixed rings of patches.
    pub patches: Vec<Patch>,
    /// How many of them are in view (the others a renderer would cull).
    pub visible: usize,
    /// Largest projected height error among the visible ones (pixels).
    pub max_error_px: f64,
}

/// The write-up's layout: fixed rings of patches around the camera (for comparison).
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
        out.patches.push(Patch::new(corner, size).with_quads(quads));
        if !outside(&frustum, lo, hi) {
            out.visible += 1;
            let e = height_error(waves, look, size / quads as f64) * px_per_tan / dist;
            out.max_error_px = out.max_error_px.max(e);
        }
    }
    out
}
