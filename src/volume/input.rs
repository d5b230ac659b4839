//! What the march reads: a density volume on the GPU ([`Volume`]) and the transfer function
//! that colours it ([`TransferFunction`]).

use glam::Vec3;

use super::STAGE;
use crate::error::Error;

/// Voxels per side of a skipping brick.
pub const BRICK: u32 = 8;

/// A density volume: a 3D texture and where its voxels sit in local space.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, density: &[f32]) -> Result<(), fieldkit::Error> {
/// use fieldkit::glam::Vec3;
/// // 128³ densities in [0, 1], x fastest; 0.1 m voxels, the low corner at the origin.
/// let volume = fieldkit::volume::Volume::upload(device, queue, density, [128; 3],
///     wgpu::TextureFormat::R8Unorm, Vec3::splat(0.1), Vec3::ZERO)?;
/// # let _ = volume; Ok(()) }
/// ```
pub struct Volume {
    /// The density, a 3D texture (R8Unorm, R16Float or R32Float).
    pub texture: wgpu::Texture,
    /// Voxels per axis.
    pub dims: [u32; 3],
    /// Local-space corner of voxel (0, 0, 0); the box runs to `origin + dims × spacing`.
    pub origin: Vec3,
    /// Voxel edge per axis (anisotropic spacing allowed).
    pub spacing: Vec3,
}

/// Most bytes one `write_texture` of [`Volume::upload`] stages.
const UPLOAD_SLAB: usize = 256 * 1024;

impl Volume {
    /// Formats the march samples with hardware trilinear filtering.
    pub const FORMATS: &'static str = "R8Unorm, R16Float, R32Float (with FLOAT32_FILTERABLE)";

    /// Wrap an existing texture (3D, `TEXTURE_BINDING`, one of [`Self::FORMATS`]).
    pub fn new(
        device: &wgpu::Device,
        texture: wgpu::Texture,
        origin: Vec3,
        spacing: Vec3,
    ) -> Result<Self, Error> {
        check_format(device, texture.format())?;
        if texture.dimension() != wgpu::TextureDimension::D3 {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("the density texture is {:?}, not 3D", texture.dimension()),
            });
        }
        if !texture
            .usage()
            .contains(wgpu::TextureUsages::TEXTURE_BINDING)
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "the density texture needs TEXTURE_BINDING usage".into(),
            });
        }
        if !(origin.is_finite() && spacing.is_finite() && spacing.min_element() > 0.0) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "origin must be finite and spacing finite and positive, got {origin} and {spacing}"
                ),
            });
        }
        let dims = [
            texture.width(),
            texture.height(),
            texture.depth_or_array_layers(),
        ];
        Ok(Self {
            texture,
            dims,
            origin,
            spacing,
        })
    }

    /// Upload `data` (x fastest, values as the format stores them: 0..1 for R8Unorm) in
    /// `format`. The texture is written through the queue in slabs of z slices of at most
    /// 256 KiB, so an app that uploads on a worker thread holds up its frame's submission for
    /// no more than one slab's staging.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        data: &[f32],
        dims: [u32; 3],
        format: wgpu::TextureFormat,
        spacing: Vec3,
        origin: Vec3,
    ) -> Result<Self, Error> {
        check_format(device, format)?;
        let max = device.limits().max_texture_dimension_3d;
        for (axis, &d) in dims.iter().enumerate() {
            if d == 0 || d > max {
                return Err(Error::Size {
                    stage: STAGE,
                    what: ["volume width", "volume height", "volume depth"][axis],
                    got: d as u64,
                    max: max as u64,
                });
            }
        }
        let count = dims.iter().map(|&d| d as u64).product::<u64>();
        if data.len() as u64 != count {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("{} densities for {dims:?} ({count} voxels)", data.len()),
            });
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("density {i} is {}", data[i]),
            });
        }
        let (bytes, texel): (Vec<u8>, u32) = match format {
            wgpu::TextureFormat::R8Unorm => (
                data.iter()
                    .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
                    .collect(),
                1,
            ),
            wgpu::TextureFormat::R16Float => (
                data.iter()
                    .flat_map(|&v| half::f16::from_f32(v).to_le_bytes())
                    .collect(),
                2,
            ),
            _ => (bytemuck::cast_slice(data).to_vec(), 4),
        };
        let texture = crate::gpu::scoped(device, STAGE, || {
            let t = crate::gpu::texture(
                device,
                "density volume",
                [dims[0], dims[1], dims[2]],
                wgpu::TextureDimension::D3,
                format,
                wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::COPY_SRC,
            );
            // In slabs of whole z slices of at most UPLOAD_SLAB bytes: each write holds the
            // queue (which the app's own submits wait on, when this runs on a worker thread)
            // only while it stages its slab.
            let slice = dims[0] as usize * dims[1] as usize * texel as usize;
            let slab = (UPLOAD_SLAB / slice).max(1);
            for (i, chunk) in bytes.chunks(slab * slice).enumerate() {
                queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: (i * slab) as u32,
                        },
                        ..t.as_image_copy()
                    },
                    chunk,
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(dims[0] * texel),
                        rows_per_image: Some(dims[1]),
                    },
                    wgpu::Extent3d {
                        depth_or_array_layers: (chunk.len() / slice) as u32,
                        ..t.size()
                    },
                );
            }
            t
        })?;
        Self::new(device, texture, origin, spacing)
    }

    /// Local-space box of the volume.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let size = Vec3::new(
            self.dims[0] as f32,
            self.dims[1] as f32,
            self.dims[2] as f32,
        );
        (self.origin, self.origin + size * self.spacing)
    }
}

pub(super) fn check_format(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
) -> Result<(), Error> {
    use wgpu::TextureFormat as F;
    match format {
        F::R8Unorm | F::R16Float => Ok(()),
        F::R32Float
            if device
                .features()
                .contains(wgpu::Features::FLOAT32_FILTERABLE) =>
        {
            Ok(())
        }
        F::R32Float => Err(Error::Invalid {
            stage: STAGE,
            what: "R32Float volumes are sampled trilinearly, which needs the device feature \
                   FLOAT32_FILTERABLE; enable it or upload as R16Float"
                .into(),
        }),
        format => Err(Error::Format {
            stage: STAGE,
            format,
            supported: Volume::FORMATS,
        }),
    }
}

/// Density → colour (rgb) and opacity (α for a segment of length `reference_step`), as evenly
/// spaced entries over `range`, interpolated linearly and clamped at the ends.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TransferFunction {
    /// RGBA entries, evenly spaced over `range`; alpha is opacity per `reference_step`.
    pub entries: Vec<[f32; 4]>,
    /// The densities the first and last entries are for.
    pub range: [f32; 2],
}

impl TransferFunction {
    /// One colour and opacity for every density.
    pub fn constant(rgb: Vec3, alpha: f32) -> Self {
        let e = [rgb.x, rgb.y, rgb.z, alpha];
        Self {
            entries: vec![e, e],
            range: [0.0, 1.0],
        }
    }

    /// Extinction proportional to density: σ = `sigma` × density per world unit, so
    /// α(ρ) = 1 − exp(−σ·ρ·Δ₀), sampled at `n` entries over `range`.
    pub fn extinction(
        rgb: Vec3,
        sigma: f32,
        reference_step: f32,
        range: [f32; 2],
        n: usize,
    ) -> Self {
        let entries = (0..n)
            .map(|i| {
                let rho = range[0] + (range[1] - range[0]) * i as f32 / (n - 1) as f32;
                [
                    rgb.x,
                    rgb.y,
                    rgb.z,
                    1.0 - (-sigma * rho * reference_step).exp(),
                ]
            })
            .collect();
        Self { entries, range }
    }

    /// A white cloud: clear below 0.1, then denser toward 1.
    pub fn cloud() -> Self {
        let entries = (0..64)
            .map(|i| {
                let d = i as f32 / 63.0;
                let a = ((d - 0.1) / 0.9).clamp(0.0, 1.0);
                let c = 0.75 + 0.25 * d;
                [c, c, c * 1.02, 0.35 * a]
            })
            .collect();
        Self {
            entries,
            range: [0.0, 1.0],
        }
    }

    pub(super) fn check(&self) -> Result<(), Error> {
        let bad = |what: String| Error::Invalid {
            stage: STAGE,
            what: format!("transfer function: {what}"),
        };
        if self.entries.len() < 2 {
            return Err(bad(format!(
                "{} entries, needs at least 2",
                self.entries.len()
            )));
        }
        if !(self.range[0].is_finite()
            && self.range[1].is_finite()
            && self.range[1] > self.range[0])
        {
            return Err(bad(format!(
                "range {:?} must be finite and increasing",
                self.range
            )));
        }
        if let Some(e) = self
            .entries
            .iter()
            .find(|e| e.iter().any(|v| !v.is_finite()) || !(0.0..=1.0).contains(&e[3]))
        {
            return Err(bad(format!(
                "entry {e:?}: values must be finite, opacity in [0, 1]"
            )));
        }
        Ok(())
    }

    /// Densities at or below this map to zero opacity (what a skipped brick must not exceed).
    pub fn clear_below(&self) -> f32 {
        match self.entries.iter().position(|e| e[3] > 0.0) {
            None => f32::INFINITY,
            Some(0) => f32::NEG_INFINITY,
            Some(i) => {
                let n = (self.entries.len() - 1) as f32;
                self.range[0] + (self.range[1] - self.range[0]) * (i - 1) as f32 / n
            }
        }
    }
}
