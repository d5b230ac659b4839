//! What the raymarcher draws and how: its outputs, how each ray ended, how the field is read
//! between voxel centres, and the march's settings.

use glam::Vec3;

use crate::error::Error;
use crate::shaders::metaball::sdf_raymarch;

/// What the raymarcher writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Output {
    /// Lit surface.
    #[default]
    Shaded,
    /// World normal in rgb, 1 + distance from the near plane to the hit (world units) in alpha,
    /// so alpha 0 is "not drawn"; for float targets.
    Normal,
    /// Step count per pixel as a heat map over the whole box: `heat(steps / max_steps)`, black
    /// (none) through red and yellow to white (the cap). For the numbers, [`Output::Distance`].
    Steps,
    /// Density just inside the surface as a heat map.
    Density,
    /// Signed distance where the ray enters the box (red outside, blue inside).
    Sdf,
    /// What each ray through the box found, as numbers, for float targets (`Rgba32Float`): red
    /// the distance from the near plane to the hit in world units (−1 where none), green the
    /// steps taken, blue how the ray ended ([`RayEnd`]: 0 left the box, 1 hit, 2 ran out of
    /// steps, 3 ran out and was taken as a hit, see [`RaymarchSettings::cap_is_hit`]), alpha 1.
    /// Depth is the hit's, or where the ray entered the box; [`RayEnd::of`] reads a texel.
    Distance = 6,
}

/// The direct tracers' step cap: `max_steps` at the default grid (4 cells per blob radius),
/// scaled with the cells per radius above it. Their hit tolerance is a fraction of a cell, so a
/// finer grid takes more steps to close in on a grazing surface: at 12 cells per edge and a
/// fixed cap of 64, 1 386 rays of the global bound ran out of steps along a row of six blobs
/// (llvmpipe, `tests/metaball/grazing.rs`); scaled to 192, none.
pub(super) fn direct_step_cap(max_steps: u32, bins: &super::BlobBins) -> u32 {
    let scale = (bins.bin_size / bins.cell / 4.0).max(1.0);
    (max_steps as f32 * scale).ceil().min(u32::MAX as f32) as u32
}

/// How a ray of the march ended, as [`Output::Distance`] writes it in blue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayEnd {
    /// It left the box (or reached the far plane) without meeting the surface.
    Left,
    /// It met the surface.
    Hit,
    /// It used `max_steps` inside the box without meeting the surface: a miss, not a
    /// finding that nothing is there.
    RanOut,
    /// It ran out of steps and, with [`RaymarchSettings::cap_is_hit`], was drawn as a hit at
    /// its last point.
    RanOutTakenAsHit,
}

impl RayEnd {
    /// How the ray of an [`Output::Distance`] texel ended (`None`: no ray through the box was
    /// marched there, alpha 0).
    pub fn of(texel: [f32; 4]) -> Option<Self> {
        if texel[3] == 0.0 {
            return None;
        }
        Some(match texel[2].round() as u32 {
            1 => Self::Hit,
            2 => Self::RanOut,
            3 => Self::RanOutTakenAsHit,
            _ => Self::Left,
        })
    }

    /// How many rays of an [`Output::Distance`] image ran out of steps (taken as hits or not).
    pub fn count_ran_out(texels: &[[f32; 4]]) -> usize {
        texels
            .iter()
            .filter(|t| matches!(Self::of(**t), Some(Self::RanOut | Self::RanOutTakenAsHit)))
            .count()
    }
}

/// How the march reads the packed field (distance and density) between voxel centres.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Filter {
    /// Hardware trilinear (default): weights linear in the fraction f.
    #[default]
    Trilinear,
    /// The source's Hermite-weighted trilinear: weights 3f² − 2f³, so the field is smooth
    /// (C¹) across voxel faces. Still one hardware fetch: the coordinates are moved so the
    /// hardware's linear weights equal the Hermite ones.
    Hermite,
}

/// How the SDF raymarch shades and what it writes.
///
/// [`RaymarchSettings::default`] is fieldkit's look; [`RaymarchSettings::seed`] is the source's
/// march and shading.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct RaymarchSettings {
    /// Steps per ray before giving up (the pixel is then left as it was).
    pub max_steps: u32,
    /// Smallest hit tolerance, in cells; it grows with distance to one pixel's footprint.
    pub epsilon: f32,
    /// Step = distance × safety (at a distance of one cell or more; see `near_safety`).
    pub safety: f32,
    /// Step factor at distance 0, rising linearly to `safety` at one cell: the source's
    /// `lerp(0.3, 0.5, saturate(d / voxel))`. `None`: `safety` everywhere.
    pub near_safety: Option<f32>,
    /// Shortest step, in cells (the source: 0.003), and at least `min_step_local` local units
    /// (the source: 0.0005). The hit tolerance also bounds the step from below.
    pub min_step_cells: f32,
    /// Shortest step in local units; see `min_step_cells`.
    pub min_step_local: f32,
    /// How the field is read between voxel centres. [`Filter::Hermite`] shapes the texture's
    /// density, so a field's blobs ([`super::MarchField::blobs`]) are not read with it.
    pub filter: Filter,
    /// The source's edge falloff: density × saturate(10 × the distance to the box's faces in
    /// uvw + 0.05), so it fades to 0 at 0.05 (in uvw) outside the box and is halved on its
    /// faces. It shapes the texture's density, so a field's blobs
    /// ([`super::MarchField::blobs`]) are not read with it.
    pub edge_falloff: bool,
    /// World-space direction towards the light.
    pub light_dir: Vec3,
    /// Surface colour.
    pub base_colour: Vec3,
    /// Colour of the rim (Fresnel-like) term.
    pub rim_colour: Vec3,
    /// Where the density just inside the surface piles up (1 to 4 × the threshold), the base
    /// colour moves toward this one; `None` lightens it (fieldkit's look).
    pub pile_colour: Option<Vec3>,
    /// Ambient light, 0–1.
    pub ambient: f32,
    /// What the pass writes: shaded colour or a debug view.
    pub output: Output,
    /// A ray that uses `max_steps` inside the box without meeting the surface is drawn as a hit
    /// at its last point (off: left undrawn). Either way [`Output::Distance`] marks it
    /// ([`RayEnd::RanOut`], [`RayEnd::RanOutTakenAsHit`]), so it is never a silent miss.
    pub cap_is_hit: bool,
    /// Where a field has its blobs ([`super::MarchField::blobs`]): within this many cells of
    /// the texture's surface the march steps on the blobs' own field (segment tracing).
    pub exact_shell: f32,
    /// How much nearer than the texture says the true surface may be, in cells: outside the
    /// shell (and inside it, where that is the longer step) the march steps by the texture's
    /// distance less this. The texture's distance is to the nearest seed point of the trilinear
    /// density's surface: seeds about a cell apart, the line passes' up to half a cell farther
    /// than the nearest seed, and the trilinear surface's own offset.
    pub exact_margin: f32,
}

impl Default for RaymarchSettings {
    fn default() -> Self {
        Self {
            max_steps: 128,
            epsilon: 0.05,
            safety: 0.9,
            near_safety: None,
            min_step_cells: 0.0,
            min_step_local: 0.0,
            filter: Filter::Trilinear,
            edge_falloff: false,
            light_dir: Vec3::new(0.4, 0.8, 0.45),
            base_colour: Vec3::new(0.85, 0.35, 0.3),
            rim_colour: Vec3::new(0.5, 0.6, 0.8),
            pile_colour: None,
            ambient: 0.2,
            output: Output::Shaded,
            cap_is_hit: false,
            exact_shell: 2.0,
            exact_margin: 1.5,
        }
    }
}

impl RaymarchSettings {
    /// The source's march and look: 192 steps, step max(d × lerp(0.3, 0.5, saturate(d / cell)),
    /// max(0.003 cells, 0.0005)), Hermite-weighted trilinear reads with the edge falloff, a blue
    /// rim at full strength (Fresnel exponent 5, as fieldkit's), and a base colour that darkens
    /// toward (0.7, 0.3, 0.3) where the density piles up. The light direction stays fieldkit's
    /// (the source lights with its scene's light, whose direction is not written down).
    ///
    /// fieldkit's default keeps two of its own choices, measured on one blob against the
    /// analytic surface (`tests/metaball/render.rs`, llvmpipe): steps of 0.9 × d take 5.3 steps
    /// per pixel where the source's rule takes 9.2, for the same surface; and hardware
    /// trilinear reads put hits at most 0.09 cells off the surface (normals 5.7°) where the
    /// Hermite weights, flat at voxel centres and steep between them, ripple the iso-surface
    /// by 0.25 cells (normals 9.8°).
    pub fn seed() -> Self {
        Self {
            max_steps: 192,
            safety: 0.5,
            near_safety: Some(0.3),
            min_step_cells: 0.003,
            min_step_local: 0.0005,
            filter: Filter::Hermite,
            edge_falloff: true,
            rim_colour: Vec3::new(0.0, 0.0, 1.0),
            pile_colour: Some(Vec3::new(0.7, 0.3, 0.3)),
            ..Self::default()
        }
    }

    /// The step the march takes at distance `d` (local units) in a field of cell `cell`, before
    /// the hit tolerance bounds it from below: the formula the shader uses, for tests and for
    /// sizing `max_steps`.
    pub fn step(&self, d: f32, cell: f32) -> f32 {
        let near = self.near_safety.unwrap_or(self.safety);
        let k = near + (self.safety - near) * (d / cell).clamp(0.0, 1.0);
        (d * k).max(self.min_step(cell))
    }

    /// The shortest step in a field of cell `cell`, local units.
    pub fn min_step(&self, cell: f32) -> f32 {
        (self.min_step_cells * cell).max(self.min_step_local)
    }

    pub(super) fn check(&self) -> Result<(), Error> {
        let stage = sdf_raymarch::STAGE;
        if self.max_steps == 0 {
            return Err(Error::Invalid {
                stage,
                what: "max_steps must be at least 1".into(),
            });
        }
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(Error::Invalid {
                stage,
                what: format!("epsilon must be finite and positive, got {}", self.epsilon),
            });
        }
        if !(self.safety.is_finite() && self.safety > 0.0 && self.safety <= 1.0) {
            return Err(Error::Invalid {
                stage,
                what: format!("safety must be in (0, 1], got {}", self.safety),
            });
        }
        if let Some(n) = self.near_safety
            && !(n.is_finite() && n > 0.0 && n <= 1.0)
        {
            return Err(Error::Invalid {
                stage,
                what: format!("near_safety must be in (0, 1], got {n}"),
            });
        }
        for (what, v) in [
            ("min_step_cells", self.min_step_cells),
            ("min_step_local", self.min_step_local),
            ("exact_shell", self.exact_shell),
            ("exact_margin", self.exact_margin),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::Invalid {
                    stage,
                    what: format!("{what} must be finite and ≥ 0, got {v}"),
                });
            }
        }
        let finite = self.base_colour.is_finite()
            && self.rim_colour.is_finite()
            && self.ambient.is_finite()
            && self.pile_colour.is_none_or(|c| c.is_finite());
        if !(finite && self.light_dir.is_finite() && self.light_dir.length() > 0.0) {
            return Err(Error::Invalid {
                stage,
                what: "light direction (non-zero) and colours must be finite".into(),
            });
        }
        Ok(())
    }
}
