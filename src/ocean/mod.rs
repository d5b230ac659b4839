//! Ocean surface from Gerstner waves (GPU Gems 1, chapter 1), y-up.
//!
//! [`Waves`] holds a validated wave set: N waves with direction, amplitude, wavelength and
//! speed, and one steepness Q shared as Qᵢ = Q / (wᵢ·Aᵢ·N). It evaluates the surface in f64
//! on the CPU ([`Waves::surface`], the reference the GPU is tested against), answers "how high
//! is the water here, and which way does it face" at a world position for floating objects
//! ([`Waves::sample`]), and packs itself for the GPU ([`Waves::gpu`]) with every phase folded
//! and wrapped in f64 around an origin you choose (the camera), so positions 100 km out and
//! hours in keep millimetre accuracy in f32.
//!
//! ```
//! use fieldkit::ocean::{Wave, Waves};
//! use glam::{DVec2, Vec2};
//! let waves = Waves::new(
//!     vec![
//!         Wave { direction: Vec2::new(1.0, 0.2), amplitude: 0.6, wavelength: 24.0, speed: 6.0 },
//!         Wave { direction: Vec2::new(0.3, 1.0), amplitude: 0.25, wavelength: 9.0, speed: 3.7 },
//!     ],
//!     0.7,
//! )?;
//! let buoy = waves.sample(DVec2::new(120.0, -40.0), 3.5);
//! assert!(buoy.height.abs() <= 0.85 && buoy.normal.y > 0.0);
//! # Ok::<(), fieldkit::Error>(())
//! ```
//!
#![doc = include_str!("../../docs/ocean.md")]

mod gpu_lod;
mod lod;
mod look;
mod patches;
mod render;

pub use gpu_lod::LodDraws;
pub use lod::{
    LodSettings, MAX_LOD_NODES, Selection, WriteupLayout, height_error, patch_triangles, select,
    writeup_patches,
};
pub use look::{DETAIL_OCTAVES, Layer, Look, detail_texels};
pub use patches::{ALL_SKIRTS, MAX_PATCH_QUADS, PATCH_QUADS, Patch, patch_indices};
pub use render::{DETAIL_SIZE, DepthMode, MAX_LAYERS, OceanCamera, OceanRenderer, Output};

use std::sync::{Arc, RwLock};

use glam::{DVec2, DVec3, UVec2, Vec2, Vec4};

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Record, uniform_buffer as uniform};
use crate::shaders::ocean::surface::{self as stage, GerstnerWave, GridParams, WaveSet};

const STAGE: &str = stage::STAGE;

/// Most waves one set holds: the length of the shader's wave array.
pub const MAX_WAVES: usize = {
    const fn len<T, const N: usize>(_: fn(&WaveSet) -> &[T; N]) -> usize {
        N
    }
    len(|s: &WaveSet| &s.waves)
};

/// Largest grid side [`WaveGrid::encode`] takes.
pub const MAX_GRID_SIDE: u32 = 4096;

/// One Gerstner wave.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Wave {
    /// Direction of travel in the horizontal (x, z) plane; normalised on use, must not be zero.
    pub direction: Vec2,
    /// Crest height above the mean level (> 0).
    pub amplitude: f32,
    /// Crest-to-crest distance Lᵢ (> 0); wᵢ = 2π / Lᵢ.
    pub wavelength: f32,
    /// Speed Sᵢ of a crest (any finite value); φᵢ = Sᵢ · 2π / Lᵢ.
    pub speed: f32,
}

impl Wave {
    /// Why this wave cannot be drawn, naming the field (`direction`, `amplitude`,
    /// `wavelength` or `speed`) and the value: a direction not finite or zero, an amplitude or
    /// wavelength not finite or not above 0, a speed not finite. [`Waves::new`] refuses a set
    /// with such a wave as [`Error::Invalid`], "wave i: " before this text.
    ///
    /// ```
    /// use fieldkit::{glam::Vec2, ocean::Wave};
    /// let wave = Wave { direction: Vec2::X, amplitude: 0.1, wavelength: 0.0, speed: 1.0 };
    /// assert!(wave.check().unwrap_err().starts_with("wavelength"));
    /// ```
    pub fn check(&self) -> Result<(), String> {
        if !(self.direction.is_finite() && self.direction.length_squared() > 0.0) {
            return Err(format!(
                "direction must be finite and not zero, got {}",
                self.direction
            ));
        }
        if !(self.amplitude.is_finite() && self.amplitude > 0.0) {
            return Err(format!(
                "amplitude must be finite and > 0, got {}",
                self.amplitude
            ));
        }
        if !(self.wavelength.is_finite() && self.wavelength > 0.0) {
            return Err(format!(
                "wavelength must be finite and > 0, got {}",
                self.wavelength
            ));
        }
        if !self.speed.is_finite() {
            return Err(format!("speed must be finite, got {}", self.speed));
        }
        Ok(())
    }
}

/// The steepness a set asked for and the one it got (see [`Waves::new_clamped`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SteepnessClamped {
    /// The steepness asked for.
    pub requested: f32,
    /// The steepness used.
    pub used: f32,
}

/// A validated wave set.
#[derive(Clone, Debug, PartialEq)]
pub struct Waves {
    waves: Vec<Wave>,
    steepness: f32,
}

/// The surface at one undisplaced point, in f64: displaced position, B = ∂P/∂x, T = ∂P/∂z and
/// the unit normal T × B.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// The displaced point.
    pub position: DVec3,
    /// ∂P/∂x.
    pub binormal: DVec3,
    /// ∂P/∂z.
    pub tangent: DVec3,
    /// The unit normal.
    pub normal: DVec3,
}

impl Surface {
    /// Determinant of the horizontal map (x, z) → (X, Z): B.x·T.z − B.z·T.x. Positive where the
    /// surface is a graph over the plane; zero at a cusp, negative inside a loop.
    pub fn horizontal_jacobian(&self) -> f64 {
        self.binormal.x * self.tangent.z - self.binormal.z * self.tangent.x
    }
}

/// The water at a world position (x, z), for floating objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Surface height above the mean level at exactly that (x, z).
    pub height: f64,
    /// Unit normal there.
    pub normal: DVec3,
    /// The undisplaced point whose displaced position lands on (x, z).
    pub undisplaced: DVec2,
}

impl Waves {
    /// A wave set with steepness `steepness` in [0, 1]. Errors name the first bad wave or
    /// parameter: no waves, more than [`MAX_WAVES`], NaN or infinite values, a zero direction,
    /// an amplitude or wavelength ≤ 0, and a steepness above 1, where crests fold into loops
    /// (with aligned waves the horizontal Jacobian reaches 1 − Q < 0). Use
    /// [`Self::new_clamped`] to take Q = 1 instead.
    pub fn new(waves: Vec<Wave>, steepness: f32) -> Result<Self, Error> {
        check_waves(&waves)?;
        if !(steepness.is_finite() && steepness >= 0.0) {
            return Err(Error::invalid(
                STAGE,
                format!("steepness must be finite and ≥ 0, got {steepness}"),
            ));
        }
        if steepness > 1.0 {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "steepness {steepness} > 1 folds crests into loops (the cusp is at 1); \
                 lower it, or use Waves::new_clamped"
                ),
            ));
        }
        Ok(Self { waves, steepness })
    }

    /// [`Self::new`], but a steepness above 1 is clamped to 1 (cusped crests, no loops) and
    /// reported.
    pub fn new_clamped(
        waves: Vec<Wave>,
        steepness: f32,
    ) -> Result<(Self, Option<SteepnessClamped>), Error> {
        if steepness.is_finite() && steepness > 1.0 {
            let w = Self::new(waves, 1.0)?;
            return Ok((
                w,
                Some(SteepnessClamped {
                    requested: steepness,
                    used: 1.0,
                }),
            ));
        }
        Ok((Self::new(waves, steepness)?, None))
    }

    /// A moderate open sea of four waves (60 m down to 5.5 m, steepness 0.6): the sea of the
    /// LOD tests and `cargo xtask bench ocean`, and a starting point.
    pub fn open_sea() -> Self {
        let w = |dx: f32, dz: f32, amplitude: f32, wavelength: f32, speed: f32| Wave {
            direction: Vec2::new(dx, dz),
            amplitude,
            wavelength,
            speed,
        };
        Self {
            waves: vec![
                w(1.0, 0.2, 1.2, 60.0, 9.0),
                w(0.3, 1.0, 0.6, 31.0, 7.0),
                w(-0.6, 0.8, 0.25, 13.0, 4.5),
                w(0.9, -0.4, 0.1, 5.5, 2.9),
            ],
            steepness: 0.6,
        }
    }

    /// The waves.
    pub fn waves(&self) -> &[Wave] {
        &self.waves
    }

    /// The global steepness, 0–1.
    pub fn steepness(&self) -> f32 {
        self.steepness
    }

    /// Per wave in f64: unit direction, amplitude, wᵢ, φᵢ and Qᵢ·Aᵢ.
    fn terms(&self) -> impl Iterator<Item = (DVec2, f64, f64, f64, f64)> + '_ {
        let n = self.waves.len() as f64;
        let q = self.steepness as f64;
        self.waves.iter().map(move |w| {
            let d = w.direction.as_dvec2().normalize();
            let a = w.amplitude as f64;
            let freq = std::f64::consts::TAU / w.wavelength as f64;
            let phi = w.speed as f64 * freq;
            // Qᵢ = Q / (wᵢ Aᵢ N), so Qᵢ Aᵢ = Q / (wᵢ N).
            let horizontal = q / (freq * n);
            (d, a, freq, phi, horizontal)
        })
    }

    /// The reference surface at the undisplaced world point `p` = (x, z) and `time`, in f64.
    pub fn surface(&self, p: DVec2, time: f64) -> Surface {
        let mut pos = DVec3::new(p.x, 0.0, p.y);
        let mut b = DVec3::X;
        let mut t = DVec3::Z;
        for (d, a, freq, phi, qa) in self.terms() {
            let theta = freq * d.dot(p) + phi * time;
            let (s, c) = theta.sin_cos();
            pos += DVec3::new(qa * d.x * c, a * s, qa * d.y * c);
            let wq = freq * qa;
            let wa = freq * a;
            b += DVec3::new(-wq * d.x * d.x * s, wa * d.x * c, -wq * d.x * d.y * s);
            t += DVec3::new(-wq * d.x * d.y * s, wa * d.y * c, -wq * d.y * d.y * s);
        }
        Surface {
            position: pos,
            binormal: b,
            tangent: t,
            normal: t.cross(b).normalize(),
        }
    }

    /// Height and normal of the water at world (x, z) and `time`. Gerstner waves move points
    /// sideways, so this first finds the undisplaced point that lands there (fixed-point
    /// iteration p ← target − horizontal offset(p), a contraction by at most Q), to 1e-9.
    pub fn sample(&self, world: DVec2, time: f64) -> Sample {
        let mut p = world;
        for _ in 0..64 {
            let s = self.surface(p, time);
            let landed = DVec2::new(s.position.x, s.position.z);
            let miss = world - landed;
            p += miss;
            if miss.length() < 1e-9 {
                break;
            }
        }
        let s = self.surface(p, time);
        Sample {
            height: s.position.y,
            normal: s.normal,
            undisplaced: p,
        }
    }

    /// The uniform the shaders read, for positions measured from world (x, z) `origin`: each
    /// wave's phase at the origin, wᵢ·Dᵢ·origin + φᵢ·time, is computed in f64 and wrapped to
    /// [0, 2π), so f32 never holds a large coordinate or time.
    pub fn gpu(&self, origin: DVec2, time: f64) -> WaveSet {
        let mut set = WaveSet {
            waves: [GerstnerWave::default(); MAX_WAVES],
            count: self.waves.len() as u32,
        };
        for (slot, (d, a, freq, phi, qa)) in set.waves.iter_mut().zip(self.terms()) {
            let phase = (freq * d.dot(origin) + phi * time).rem_euclid(std::f64::consts::TAU);
            *slot = GerstnerWave {
                direction: d.as_vec2(),
                amplitude: a as f32,
                frequency: freq as f32,
                horizontal: qa as f32,
                phase: phase as f32,
                reserved: Vec2::ZERO,
            };
        }
        set
    }
}

fn check_waves(waves: &[Wave]) -> Result<(), Error> {
    if waves.is_empty() {
        return Err(Error::Size {
            stage: STAGE,
            what: "number of waves",
            got: 0,
            max: MAX_WAVES as u64,
        });
    }
    if waves.len() > MAX_WAVES {
        return Err(Error::Size {
            stage: STAGE,
            what: "number of waves",
            got: waves.len() as u64,
            max: MAX_WAVES as u64,
        });
    }
    for (i, w) in waves.iter().enumerate() {
        w.check()
            .map_err(|what| Error::invalid(STAGE, format!("wave {i}: {what}")))?;
    }
    Ok(())
}

/// Waves shared between threads: a game thread [`set`](Self::set)s new parameters while the
/// render thread takes a [`snapshot`](Self::snapshot) per frame. Every set is validated, and a
/// snapshot is always one whole set, never half of an update.
#[derive(Clone, Debug)]
pub struct SharedWaves(Arc<RwLock<Waves>>);

impl SharedWaves {
    /// Share `waves`.
    pub fn new(waves: Waves) -> Self {
        Self(Arc::new(RwLock::new(waves)))
    }

    /// Replace the set (already validated by [`Waves::new`]).
    pub fn set(&self, waves: Waves) {
        // A panic elsewhere while holding the lock cannot leave a half-written `Waves`: the
        // value is replaced whole, so a poisoned lock is still safe to use.
        *self.0.write().unwrap_or_else(|e| e.into_inner()) = waves;
    }

    /// A copy of the current waves.
    pub fn snapshot(&self) -> Waves {
        self.0.read().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

/// The wave sum on a regular grid on the GPU (`ocean/surface`): displaced positions relative to
/// the waves' origin and normals, one `vec4` each per point, x fastest.
pub struct WaveGrid {
    pipeline: ComputePipeline<stage::displace_grid::Entry>,
}

/// A displaced grid on the GPU.
pub struct DisplacedGrid {
    /// Vertices per side (x, z).
    pub size: [u32; 2],
    /// `vec4<f32>` per point: position relative to the origin, w = 1.
    pub positions: wgpu::Buffer,
    /// `vec4<f32>` per point: unit normal, w = 0.
    pub normals: wgpu::Buffer,
}

impl WaveGrid {
    /// Create the displacement pipeline.
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            pipeline: ComputePipeline::new(device)?,
        })
    }

    /// Displace `size` points starting at undisplaced (x, z) `start` (relative to the origin
    /// `waves` was packed for), `spacing` apart. The grid's buffers are new each call (the
    /// caller keeps the [`DisplacedGrid`]): a query, not the renderer's per-frame path, which is
    /// [`OceanRenderer`] and makes nothing a frame.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        waves: &WaveSet,
        start: Vec2,
        spacing: Vec2,
        size: [u32; 2],
    ) -> Result<DisplacedGrid, Error> {
        for (axis, &n) in ["x", "z"].iter().zip(&size) {
            if n == 0 || n > MAX_GRID_SIDE {
                return Err(Error::Size {
                    stage: STAGE,
                    what: if *axis == "x" {
                        "grid points along x"
                    } else {
                        "grid points along z"
                    },
                    got: n as u64,
                    max: MAX_GRID_SIDE as u64,
                });
            }
        }
        if !(start.is_finite() && spacing.is_finite()) {
            return Err(Error::invalid(
                STAGE,
                format!("grid start {start} and spacing {spacing} must be finite"),
            ));
        }
        if waves.count as usize > MAX_WAVES {
            return Err(Error::Size {
                stage: STAGE,
                what: "number of waves",
                got: waves.count as u64,
                max: MAX_WAVES as u64,
            });
        }
        let bytes = size[0] as u64 * size[1] as u64 * std::mem::size_of::<Vec4>() as u64;
        let buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let (positions, normals) = (buffer("ocean positions"), buffer("ocean normals"));
        let wave_buffer = uniform(device, "ocean waves", waves);
        let grid = uniform(
            device,
            "ocean grid",
            &GridParams {
                start,
                spacing,
                size: UVec2::from_array(size),
            },
        );
        self.pipeline.record(
            device,
            rec,
            &stage::displace_grid::Resources {
                waves: (&wave_buffer).into(),
                grid: (&grid).into(),
                positions: (&positions).into(),
                normals: (&normals).into(),
            },
            ComputePipeline::<stage::displace_grid::Entry>::groups_for([size[0], size[1], 1]),
            STAGE,
        )?;
        Ok(DisplacedGrid {
            size,
            positions,
            normals,
        })
    }
}
