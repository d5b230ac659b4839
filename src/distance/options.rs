//! What [`super::Distance3d`] computes: the method, sign, marks, band and units, and where a
//! volume sits in the world ([`Grid`]).

use super::STAGE_3D as STAGE;
use super::Variant;
use crate::error::Error;

/// Which voxels of the input volume are marked (seeds; for a signed field, inside).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Inside {
    /// Any positive value.
    Mask,
    /// Value ≥ the threshold (a density's iso-level).
    Threshold(f32),
}

impl Inside {
    pub(crate) fn threshold(self) -> f32 {
        match self {
            Inside::Mask => f32::MIN_POSITIVE,
            Inside::Threshold(t) => t,
        }
    }
}

/// How the field is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Method {
    /// The exact transform: zero wrong voxels, and the fastest at every size measured (README).
    #[default]
    Exact,
    /// Jump flooding with the given variant.
    Jfa(Variant),
    /// Sub-voxel seeds within a band: three line passes (x, y, z), each scanning ±band voxels
    /// (`point_lines.wgsl`); the cost grows with the band. Needs [`Settings3d::band`], and each
    /// point within one voxel of the voxel its key is held in (as surface seeds and
    /// [`Distance3d::encode_points`](super::Distance3d::encode_points) without homes place them). Integer seeds take
    /// [`Method::Exact`]. Not exact for sub-voxel seeds: it can keep one up to about half a voxel
    /// farther than the nearest, where JFA+2 keeps one at most a tenth farther (`tests/distance/points_3d.rs` measures
    /// it against brute force and JFA+2).
    Lines,
}

impl Method {
    /// The method's name as the benchmark tables write it.
    pub fn name(self) -> String {
        match self {
            Method::Exact => "exact".into(),
            Method::Jfa(v) => v.name().into(),
            Method::Lines => "lines".into(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
/// What [`Distance3d`](super::Distance3d) computes.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Settings3d {
    /// Exact (default), JFA or the line passes.
    pub method: Method,
    /// Signed distance, negative inside (marked voxels).
    ///
    /// **Convention** (integer seeds): distances are between voxel centres, and a signed field
    /// takes half a voxel off so that zero lies between the last inside and the first outside
    /// voxel: an outside voxel holds (its distance to the nearest inside voxel − ½) ×
    /// `voxel_size`, an inside one −(its distance to the nearest outside voxel − ½) ×
    /// `voxel_size`. Unsigned fields hold the plain centre distance (0 on a seed). Sub-voxel
    /// seeds (`Distance3d::encode_points`) lie on the surface: their distance is to the point.
    pub signed: bool,
    /// Which voxels are marked.
    pub inside: Inside,
    /// World units per voxel.
    pub voxel_size: f32,
    /// Narrow band, in voxels: distances are only needed up to this far. JFA then starts at the
    /// power of two at or above it instead of half the grid; every method clamps to it.
    pub band: Option<f32>,
    /// What a voxel that no seed reached holds (an empty seed set; or, with a band, a voxel
    /// farther than it): by default ±band, or `f32::MAX` without one. JFA only (the pass that
    /// writes these is its resolve); other methods refuse it.
    pub unreached: Option<Unreached>,
}

/// Distances for voxels no seed reached, world units: `-inside` inside and `outside` outside
/// (the metaball source's full-volume field writes −one voxel and 1e6).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Unreached {
    /// Magnitude given inside (the value written is its negation).
    pub inside: f32,
    /// Value given outside.
    pub outside: f32,
}

impl Default for Settings3d {
    fn default() -> Self {
        Self {
            method: Method::Exact,
            signed: false,
            inside: Inside::Mask,
            voxel_size: 1.0,
            band: None,
            unreached: None,
        }
    }
}

impl Settings3d {
    /// The defaults with a signed field, negative inside:
    /// `Settings3d { signed: true, ..Settings3d::default() }`.
    pub fn signed() -> Self {
        Self {
            signed: true,
            ..Self::default()
        }
    }
}

impl Settings3d {
    /// The band in world units distances are clamped to; `f32::MAX` for none.
    pub(crate) fn world_band(&self) -> f32 {
        self.band.map_or(f32::MAX, |b| b * self.voxel_size)
    }

    pub(crate) fn check(&self) -> Result<(), Error> {
        if !(self.voxel_size.is_finite() && self.voxel_size > 0.0) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "voxel_size must be finite and positive, got {}",
                    self.voxel_size
                ),
            });
        }
        if let Some(b) = self.band
            && !(b.is_finite() && b > 0.0)
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("band must be finite and positive, got {b}"),
            });
        }
        if let Some(u) = self.unreached {
            if !(u.inside.is_finite()
                && u.inside >= 0.0
                && u.outside.is_finite()
                && u.outside >= 0.0)
            {
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: format!(
                        "unreached inside ({}) and outside ({}) must be finite and ≥ 0",
                        u.inside, u.outside
                    ),
                });
            }
            if !matches!(self.method, Method::Jfa(_)) {
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: format!(
                        "unreached values are written by JFA's resolve; method {} does not take them",
                        self.method.name()
                    ),
                });
            }
        }
        if let Inside::Threshold(t) = self.inside
            && !t.is_finite()
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("threshold must be finite, got {t}"),
            });
        }
        Ok(())
    }

    /// The methods that take sub-voxel seeds: JFA, and the line passes with a band.
    pub(crate) fn check_points(&self) -> Result<(), Error> {
        match (self.method, self.band) {
            (Method::Jfa(_), _) | (Method::Lines, Some(_)) => Ok(()),
            (Method::Lines, None) => Err(Error::Invalid {
                stage: STAGE,
                what: "Method::Lines scans ±band voxels per axis and needs a band".into(),
            }),
            (Method::Exact, _) => Err(Error::Invalid {
                stage: STAGE,
                what: "sub-voxel seeds need JFA or the line passes; the exact transform takes \
                       integer seeds"
                    .into(),
            }),
        }
    }

    /// JFA step lengths for a grid whose largest side is `max_side`.
    pub fn steps(&self, variant: Variant, max_side: u32) -> Vec<u32> {
        let steps = variant.steps(max_side);
        let Some(band) = self.band else { return steps };
        // Steps p, p/2, …, 1 reach any seed up to 2p − 1 ≥ band voxels away along each axis.
        let full = max_side.max(1).next_power_of_two() / 2;
        // A band as wide as the grid (or wider, up to f32::MAX) keeps every step; compare in f32
        // before converting so a huge band cannot overflow.
        if band.is_nan() || band.ceil() >= full as f32 {
            return steps;
        }
        let first = (band.ceil() as u32).max(1).next_power_of_two();
        if first >= full {
            return steps;
        }
        let skip = (full / first).trailing_zeros() as usize;
        // Drop the long steps at the start of the JFA run (after a leading step-1 pass, if any).
        let lead = usize::from(matches!(
            variant,
            Variant::OnePlusJfa | Variant::OnePlusJfaPlus2
        ));
        let mut s = steps;
        s.drain(lead..lead + skip);
        s
    }
}

/// The voxels a pass marks as seeds: those of `volume` that `inside` marks, or, `invert`, the
/// others (the outside seeds of a signed field). What the stages of [`super::Exact`] and
/// [`super::Jfa3d`] read.
#[derive(Clone, Copy)]
pub struct Marks<'a> {
    /// A volume of one of [`super::VOLUME_FORMATS`].
    pub volume: &'a wgpu::Texture,
    /// Which values mark a voxel.
    pub inside: Inside,
    /// Mark the voxels `inside` does not mark instead.
    pub invert: bool,
}

impl<'a> Marks<'a> {
    /// The voxels of `volume` that `inside` marks (or, `invert`, the others).
    pub fn new(volume: &'a wgpu::Texture, inside: Inside, invert: bool) -> Self {
        Self {
            volume,
            inside,
            invert,
        }
    }
}
