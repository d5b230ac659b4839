//! How the water looks: the detail layers (height and normal maps, scrolling), the shading
//! and the depth fade ([`Look`]), the built-in detail texture and the user's maps.

use glam::{DVec2, Vec2, Vec3, Vec4};

use super::render::{MAX_LAYERS, STAGE};
use crate::error::Error;
use crate::shaders::ocean::surface::DetailLayer;

/// A scrolling layer of the detail texture.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Layer {
    /// Metres per repeat of the texture.
    pub tile: f32,
    /// Metres per second the pattern moves.
    pub velocity: Vec2,
    /// Height layers: metres of height per unit of the texture. Normal layers: slope scale.
    pub strength: f32,
    /// Which layer of the user's maps ([`OceanRenderer::set_maps`](super::OceanRenderer::set_maps)) this layer scrolls: the
    /// height-map array for a height layer, the normal-map array for a normal layer. `None`
    /// (default) scrolls the built-in procedural detail.
    #[cfg_attr(feature = "serde", serde(default))]
    pub map: Option<u32>,
}

impl Layer {
    /// Why the ocean would refuse this layer, the field's name first (`tile`, `velocity`,
    /// `strength`), so an editor can mark the field; `Ok` where it takes it.
    ///
    /// ```
    /// use fieldkit::{glam::Vec2, ocean::Layer};
    /// let layer = Layer { tile: 0.0, velocity: Vec2::ZERO, strength: 1.0, map: None };
    /// assert!(layer.check().unwrap_err().starts_with("tile"));
    /// ```
    pub fn check(&self) -> Result<(), String> {
        if !(self.tile.is_finite() && self.tile > 0.0) {
            return Err(format!("tile must be > 0 metres, got {}", self.tile));
        }
        if !self.velocity.is_finite() {
            return Err(format!("velocity must be finite, got {}", self.velocity));
        }
        if !self.strength.is_finite() {
            return Err(format!("strength must be finite, got {}", self.strength));
        }
        Ok(())
    }
}

/// Colours, light and the detail layers.
///
/// [`Look::default`] is fieldkit's; [`Look::seed`] the source's (a 30 cm fade).
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct Look {
    /// Height-map detail layers (at most [`MAX_LAYERS`]).
    pub height_layers: Vec<Layer>,
    /// Normal-map detail layers (at most [`MAX_LAYERS`]).
    pub normal_layers: Vec<Layer>,
    /// Towards the sun (normalised on use).
    pub sun_direction: Vec3,
    /// Sun colour (linear RGB).
    pub sun_colour: Vec3,
    /// Colour of deep water.
    pub deep_colour: Vec3,
    /// Colour of shallow water.
    pub shallow_colour: Vec3,
    /// Colour reflected from the sky.
    pub sky_colour: Vec3,
    /// Surface roughness, 0–1.
    pub roughness: f32,
    /// Metres of water over which the colour fades from shallow to deep.
    pub fade_distance: f32,
    /// G-buffer metallic, 0–1 (0: water is a dielectric).
    pub metallic: f32,
    /// G-buffer specular level, 0–1 (0.5: a dielectric's 4%).
    pub specular: f32,
    /// The fifth G-buffer target's colour ([`Output::GBufferSubsurface`](super::Output::GBufferSubsurface)).
    pub subsurface_colour: Vec3,
    /// Written to the G-buffer's shading-model channel.
    pub shading_model: u8,
    /// Metres the skirts under patch edges reach down (hides cracks between levels).
    pub skirt: f32,
}

impl Default for Look {
    fn default() -> Self {
        Self {
            height_layers: vec![
                Layer {
                    tile: 23.0,
                    velocity: Vec2::new(0.9, 0.4),
                    strength: 0.06,
                    map: None,
                },
                Layer {
                    tile: 7.3,
                    velocity: Vec2::new(-0.5, 0.8),
                    strength: 0.02,
                    map: None,
                },
            ],
            normal_layers: vec![
                Layer {
                    tile: 3.1,
                    velocity: Vec2::new(0.6, 0.2),
                    strength: 0.03,
                    map: None,
                },
                Layer {
                    tile: 1.3,
                    velocity: Vec2::new(-0.3, 0.5),
                    strength: 0.01,
                    map: None,
                },
            ],
            sun_direction: Vec3::new(0.3, 0.6, -0.7),
            sun_colour: Vec3::new(1.0, 0.95, 0.85),
            deep_colour: Vec3::new(0.01, 0.06, 0.12),
            shallow_colour: Vec3::new(0.1, 0.45, 0.45),
            sky_colour: Vec3::new(0.55, 0.7, 0.85),
            roughness: 0.15,
            fade_distance: 3.0,
            metallic: 0.0,
            specular: 0.5,
            subsurface_colour: Vec3::new(0.1, 0.45, 0.45),
            shading_model: 1,
            skirt: 2.0,
        }
    }
}

/// The detail texture's octaves: value-noise cells per repeat, and amplitude. It is band-limited
/// to 32 cells a repeat: the vertex stage displaces by it, and detail finer than the vertices
/// can hold would only force finer patches: in `tests/ocean/lod.rs`'s view 1 px of error took
/// 1.25 M triangles with 128 cells, 0.86 M with 32 (0.36 M with no height layers at all). The
/// normal layers, with small repeats, carry the fine detail.
pub const DETAIL_OCTAVES: [(u32, f32); 3] = [(8, 0.5), (16, 0.25), (32, 0.125)];

/// A tileable detail texture: fBm height in r (about −1 to 1), its slope per texture unit in g
/// (along u) and b (along v), from a periodic value noise so every layer repeats seamlessly.
pub fn detail_texels(size: u32, seed: u32) -> Vec<Vec4> {
    let n = size as usize;
    let hash = |x: u32, y: u32, o: u32| -> f32 {
        let mut h = x.wrapping_mul(0x8da6b343)
            ^ y.wrapping_mul(0xd8163841)
            ^ (seed.wrapping_add(o)).wrapping_mul(0xcb1ab31f);
        h ^= h >> 13;
        h = h.wrapping_mul(0x5bd1e995);
        h ^= h >> 15;
        (h & 0xffff) as f32 / 32767.5 - 1.0
    };
    let mut height = vec![0f32; n * n];
    for (octave, &(period, amp)) in DETAIL_OCTAVES.iter().enumerate() {
        let octave = octave as u32;
        for y in 0..n {
            for x in 0..n {
                let fx = x as f32 * period as f32 / size as f32;
                let fy = y as f32 * period as f32 / size as f32;
                let (x0, y0) = (fx.floor() as u32, fy.floor() as u32);
                let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
                let s = |t: f32| t * t * (3.0 - 2.0 * t);
                let c = |i: u32, j: u32| hash(i % period, j % period, octave);
                let a = c(x0, y0) + (c(x0 + 1, y0) - c(x0, y0)) * s(tx);
                let b = c(x0, y0 + 1) + (c(x0 + 1, y0 + 1) - c(x0, y0 + 1)) * s(tx);
                height[y * n + x] += amp * (a + (b - a) * s(ty));
            }
        }
    }
    let at = |x: usize, y: usize| height[(y % n) * n + (x % n)];
    (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let du = (at(x + 1, y) - at(x + n - 1, y)) * 0.5 * n as f32;
            let dv = (at(x, y + 1) - at(x, y + n - 1)) * 0.5 * n as f32;
            Vec4::new(at(x, y), du, dv, 0.0)
        })
        .collect()
}

pub(super) fn layer_uniforms(
    layers: &[Layer],
    origin: DVec2,
    time: f64,
) -> [DetailLayer; MAX_LAYERS] {
    let mut out = [DetailLayer::default(); MAX_LAYERS];
    for (slot, l) in out.iter_mut().zip(layers) {
        let tile = l.tile as f64;
        // (origin − v t) / tile, folded to [0, 1) in f64.
        let o = (origin - l.velocity.as_dvec2() * time) / tile;
        *slot = DetailLayer {
            offset: Vec2::new(o.x.rem_euclid(1.0) as f32, o.y.rem_euclid(1.0) as f32),
            per_metre: (1.0 / tile) as f32,
            strength: l.strength,
        };
    }
    out
}

impl Look {
    /// The source's look: the depth fade over 30 cm of water (its sea is 2560 m across, as
    /// [`super::lod::LodSettings::default`]) and no skirts under patch edges. fieldkit's
    /// default fades over 3 m: at 30 cm the shallow colour shows only in a thin line where the
    /// water meets the scene, and the gallery's shelf shows none of its gradient. Skirts hide
    /// the cracks between LOD levels through the depth test; with the source's depth read only
    /// ([`DepthMode::seed`](super::DepthMode::seed)) they would show through the water, so the preset has none (and the
    /// cracks between levels show instead).
    pub fn seed() -> Self {
        Self {
            fade_distance: 0.3,
            skirt: 0.0,
            ..Self::default()
        }
    }

    pub(super) fn check(&self) -> Result<(), Error> {
        for (kind, layers) in [
            ("height", &self.height_layers),
            ("normal", &self.normal_layers),
        ] {
            if layers.len() > MAX_LAYERS {
                return Err(Error::Size {
                    stage: STAGE,
                    what: if kind == "height" {
                        "height layers"
                    } else {
                        "normal layers"
                    },
                    got: layers.len() as u64,
                    max: MAX_LAYERS as u64,
                });
            }
            for (i, l) in layers.iter().enumerate() {
                l.check()
                    .map_err(|why| Error::invalid(STAGE, format!("{kind} layer {i}: {why}")))?;
            }
        }
        let colours = [
            self.sun_colour,
            self.deep_colour,
            self.shallow_colour,
            self.sky_colour,
        ];
        let finite = colours.iter().all(|c| c.is_finite());
        let sun = self.sun_direction.is_finite() && self.sun_direction.length_squared() > 0.0;
        if !(finite && sun) {
            return Err(Error::invalid(
                STAGE,
                "colours must be finite and the sun direction non-zero",
            ));
        }
        if !(self.roughness.is_finite() && self.roughness > 0.0) {
            return Err(Error::invalid(
                STAGE,
                format!("roughness must be > 0, got {}", self.roughness),
            ));
        }
        if !(self.fade_distance.is_finite() && self.fade_distance > 0.0) {
            return Err(Error::invalid(
                STAGE,
                format!("fade distance must be > 0, got {}", self.fade_distance),
            ));
        }
        if !(self.skirt.is_finite() && self.skirt >= 0.0) {
            return Err(Error::invalid(
                STAGE,
                format!("skirt must be ≥ 0, got {}", self.skirt),
            ));
        }
        for (what, v) in [("metallic", self.metallic), ("specular", self.specular)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::invalid(
                    STAGE,
                    format!("{what} must be in [0, 1], got {v}"),
                ));
            }
        }
        if !self.subsurface_colour.is_finite() {
            return Err(Error::invalid(STAGE, "subsurface colour must be finite"));
        }
        Ok(())
    }
}

/// The user's detail maps: a 2D texture array, one layer per map, and what it may hold.
pub(super) struct Maps {
    pub(super) view: wgpu::TextureView,
    pub(super) layers: u32,
}

impl Maps {
    /// A 1×1 stand-in bound where no maps are set.
    pub(super) fn none(device: &wgpu::Device, label: &str) -> Self {
        let t = crate::gpu::texture(
            device,
            label,
            [1, 1, 1],
            wgpu::TextureDimension::D2,
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        Self {
            view: array_view(&t),
            layers: 0,
        }
    }

    pub(super) fn user(
        t: &wgpu::Texture,
        kind: &str,
        formats: &[wgpu::TextureFormat],
        supported: &'static str,
    ) -> Result<Self, Error> {
        if t.dimension() != wgpu::TextureDimension::D2 {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "{kind} maps must be a 2D texture (array), got {:?}",
                    t.dimension()
                ),
            ));
        }
        if !formats.contains(&t.format()) {
            return Err(Error::Format {
                stage: STAGE,
                format: t.format(),
                supported,
            });
        }
        if !t.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "{kind} maps need TEXTURE_BINDING, they have {:?}",
                    t.usage()
                ),
            ));
        }
        if t.sample_count() != 1 {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "{kind} maps must not be multisampled ({} samples)",
                    t.sample_count()
                ),
            ));
        }
        Ok(Self {
            view: array_view(t),
            layers: t.depth_or_array_layers(),
        })
    }
}

pub(super) fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// Per layer, the user's map it samples (−1: the built-in detail), checked against the maps set.
pub(super) fn map_indices(layers: &[Layer], maps: &Maps, kind: &str) -> Result<glam::IVec4, Error> {
    let mut out = [-1i32; MAX_LAYERS];
    for (i, (slot, l)) in out.iter_mut().zip(layers).enumerate() {
        if let Some(m) = l.map {
            if m >= maps.layers {
                return Err(Error::invalid(
                    STAGE,
                    format!(
                        "{kind} layer {i} samples map {m}, but {} {kind} maps are set \
                     (OceanRenderer::set_maps)",
                        maps.layers
                    ),
                ));
            }
            *slot = m as i32;
        }
    }
    Ok(glam::IVec4::from_array(out))
}
