//! The voxel sets a scene starts from and moves by: the source's packed grid, a grid that
//! fills an extent, and the per-frame animation of scales and centres.

use glam::{Vec3, Vec4};

use super::STAGE;
use crate::error::Error;

/// Most voxels [`packed_grid`] builds (16.7 M; 256 MiB of instances, past any device's
/// default storage binding).
pub const MAX_PACKED: u64 = 1 << 24;

/// The source's grid builder: `region` voxels per axis of edge `block`, packed, centred on the
/// origin, scale 1 (xyz: centre, w: scale). A non-finite or non-positive `block`, or more than
/// [`MAX_PACKED`] voxels, is a typed error.
pub fn packed_grid(region: [u32; 3], block: f32) -> Result<Vec<Vec4>, Error> {
    if !(block.is_finite() && block > 0.0) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("block size must be finite and positive, got {block}"),
        });
    }
    let count = region
        .iter()
        .try_fold(1u64, |c, &n| c.checked_mul(n as u64))
        .unwrap_or(u64::MAX);
    if count > MAX_PACKED {
        return Err(Error::Size {
            stage: STAGE,
            what: "packed voxels (region x × y × z)",
            got: count,
            max: MAX_PACKED,
        });
    }
    if count == 0 {
        // A zero side: nothing to build (and no loop over the other sides).
        return Ok(Vec::new());
    }
    let half = Vec3::new(region[0] as f32, region[1] as f32, region[2] as f32) * block * 0.5;
    if !half.is_finite() {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("region {region:?} × block {block} overflows f32"),
        });
    }
    let mut v = Vec::with_capacity(count as usize);
    for z in 0..region[2] {
        for y in 0..region[1] {
            for x in 0..region[0] {
                let c = (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * block - half;
                v.push(c.extend(1.0));
            }
        }
    }
    Ok(v)
}

/// The source's grid builder from a region *extent* and a block size: NX = max(1,
/// ⌊extent / block⌋) per axis, so a region smaller than one block still holds one voxel.
/// Returns the voxel counts [`packed_grid`] takes. A negative or non-finite extent, or a
/// non-finite or non-positive block, is a typed error.
pub fn region_for_extent(extent: Vec3, block: f32) -> Result<[u32; 3], Error> {
    if !(block.is_finite() && block > 0.0) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("block size must be finite and positive, got {block}"),
        });
    }
    if !(extent.is_finite() && extent.min_element() >= 0.0) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("extent must be finite and ≥ 0, got {extent}"),
        });
    }
    let count = |e: f32| {
        let n = (e / block).floor();
        // Past u32 the packed grid refuses it anyway (MAX_PACKED).
        if n >= u32::MAX as f32 {
            u32::MAX
        } else {
            (n as u32).max(1)
        }
    };
    Ok([count(extent.x), count(extent.y), count(extent.z)])
}

/// [`packed_grid`] from an extent and a block size, as the source's actor takes them
/// ([`region_for_extent`]): voxels of edge `block` (scale 1), centred on the origin.
pub fn extent_grid(extent: Vec3, block: f32) -> Result<Vec<Vec4>, Error> {
    packed_grid(region_for_extent(extent, block)?, block)
}

/// A per-frame animation of a voxel set: each instance's scale pulses and its centre moves on a
/// Lissajous curve, instance `i` a phase `phase_step · i` behind instance 0.
///
/// - scale: s₀ · (1 − a + a · sin(2π · `scale_frequency` · t + `phase_step` · i)), a =
///   `scale_amplitude`;
/// - centre: c₀ + `offset_amplitude` · edge · (sin(rₓ·φ + pₓ), sin(r_y·φ + p_y), sin(r_z·φ +
///   p_z)) with φ = 2π · `offset_frequency` · t + `phase_step` · i, r = `ratios`, p =
///   `axis_phases`.
///
/// [`Animation::default`] is fieldkit's (ratios 1 : 2 : 3, phase step 0.13: a closed curve that
/// repeats each period, so a looping GIF of one period has no seam); [`Animation::seed`] is the
/// source's (ratios 1 : 1.37 : 1.91, phase step 0.19: a curve that never closes, so the motion
/// does not visibly repeat).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct Animation {
    /// Fraction of the scale that pulses (0: none; 0.5: between 0 and s₀).
    pub scale_amplitude: f32,
    /// Pulses per second.
    pub scale_frequency: f32,
    /// Largest centre offset, in voxel edges.
    pub offset_amplitude: f32,
    /// Offset cycles per second (along x; the other axes × their ratio).
    pub offset_frequency: f32,
    /// Frequency of each axis's offset relative to x's.
    pub ratios: [f32; 3],
    /// Phase of each axis's offset, radians.
    pub axis_phases: [f32; 3],
    /// Phase between one instance and the next, radians.
    pub phase_step: f32,
}

impl Default for Animation {
    fn default() -> Self {
        Self {
            scale_amplitude: 0.5,
            scale_frequency: 0.5,
            offset_amplitude: 0.15,
            offset_frequency: 0.5,
            ratios: [1.0, 2.0, 3.0],
            axis_phases: [0.0, 0.5, 1.0],
            phase_step: 0.13,
        }
    }
}

impl Animation {
    /// The source's animation: offset frequency ratios 1 : 1.37 : 1.91 and a phase step of
    /// 0.19 per instance (amplitudes and frequencies as [`Animation::default`]).
    pub fn seed() -> Self {
        Self {
            ratios: [1.0, 1.37, 1.91],
            axis_phases: [0.0; 3],
            phase_step: 0.19,
            ..Self::default()
        }
    }

    fn check(&self) -> Result<(), Error> {
        let values = [
            self.scale_amplitude,
            self.scale_frequency,
            self.offset_amplitude,
            self.offset_frequency,
            self.phase_step,
        ]
        .into_iter()
        .chain(self.ratios)
        .chain(self.axis_phases);
        if values.into_iter().any(|v| !v.is_finite()) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("animation parameters must be finite, got {self:?}"),
            });
        }
        if !(0.0..=1.0).contains(&self.scale_amplitude) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "scale_amplitude must be in [0, 1] (scales stay ≥ 0), got {}",
                    self.scale_amplitude
                ),
            });
        }
        Ok(())
    }

    /// The voxel set `base` (edge `edge`) at time `t` seconds. Non-finite parameters or time,
    /// or a scale amplitude outside [0, 1], are a typed error.
    pub fn apply(&self, base: &[Vec4], edge: f32, t: f32) -> Result<Vec<Vec4>, Error> {
        self.check()?;
        if !(t.is_finite() && edge.is_finite()) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("time ({t}) and edge ({edge}) must be finite"),
            });
        }
        Ok(self.apply_unchecked(base, edge, t))
    }

    /// Stand-ins for `base` whose fitted grid ([`Settings::fit_grid`](super::Settings::fit_grid))
    /// holds every frame of the animation: two per instance, at its centre ± the largest
    /// offset along every axis, at its full scale (the pulse never exceeds it). Fit the grid
    /// once to these and keep it while the blocks and the animation stay: the field is then
    /// built on one grid every frame, so nothing is made a frame (a grid fitted to each
    /// frame's voxels changes size as they move, and every size makes new textures).
    pub fn envelope(&self, base: &[Vec4], edge: f32) -> Vec<Vec4> {
        let reach = Vec3::splat(self.offset_amplitude.abs() * edge);
        base.iter()
            .flat_map(|v| {
                let c = v.truncate();
                [(c - reach).extend(v.w), (c + reach).extend(v.w)]
            })
            .collect()
    }

    fn apply_unchecked(&self, base: &[Vec4], edge: f32, t: f32) -> Vec<Vec4> {
        let tau = std::f32::consts::TAU;
        base.iter()
            .enumerate()
            .map(|(i, v)| {
                let lag = self.phase_step * i as f32;
                let pulse = (tau * self.scale_frequency * t + lag).sin();
                let phi = tau * self.offset_frequency * t + lag;
                let axis = |k: usize| (self.ratios[k] * phi + self.axis_phases[k]).sin();
                let offset = Vec3::new(axis(0), axis(1), axis(2)) * self.offset_amplitude * edge;
                let scale = v.w * (1.0 - self.scale_amplitude + self.scale_amplitude * pulse);
                (v.truncate() + offset).extend(scale)
            })
            .collect()
    }
}

/// Per-frame animation of the source's demo with fieldkit's defaults: scales
/// s₀·(0.5 + 0.5·sin(2π f t + 0.13 i)) and Lissajous offsets (ratios 1 : 2 : 3) of the centres,
/// `wobble` × edge at most. [`Animation`] holds every parameter, the source's among them.
pub fn animate(base: &[Vec4], edge: f32, t: f32, frequency: f32, wobble: f32) -> Vec<Vec4> {
    Animation {
        scale_frequency: frequency,
        offset_frequency: frequency,
        offset_amplitude: wobble,
        ..Animation::default()
    }
    .apply_unchecked(base, edge, t)
}
