//! Seed textures: which texels of a mask or image are seeds ([`SeedRule`]), the formats read,
//! the 2D seed packing (16/16 bits, [`pack_seed`]) and a mask uploaded from the CPU.

use super::buffers::upload_r8;
use super::check::check_side;
use crate::error::Error;

pub(crate) const STAGE: &str = "distance::jfa";

/// Largest side the 16-bit-per-axis seed packing can name (x + 1 must fit in 16 bits).
pub const MAX_PACKED_SIDE: u32 = 0xfffe;

/// Packed "no seed" (see `fieldkit-wesl/shaders/seed.wesl`).
pub const NO_SEED: u32 = 0;

/// Distance written where no seed exists (largest finite f32; `-FAR` inside a full mask).
pub const FAR: f32 = f32::MAX;

/// Common seed texture formats; any colour format read as float is taken ([`is_seed_format`]).
pub const SEED_FORMATS: &[wgpu::TextureFormat] = &[
    wgpu::TextureFormat::R8Unorm,
    wgpu::TextureFormat::R16Float,
    wgpu::TextureFormat::R32Float,
    wgpu::TextureFormat::Rgba8Unorm,
];

/// Which channels of a seed texture a texel's value is read from ([`SeedRule`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Channels {
    /// The red channel (default): a mask in any format.
    #[default]
    Red,
    /// The largest of red, green and blue: "any non-black texel", the source's rule, for a
    /// colour image of any format.
    AnyColour,
    /// The alpha channel: a sprite's coverage.
    Alpha,
}

/// Which texels of a seed texture are seeds: those whose value in `channels` is above `above`.
/// The default (red above 0) reads masks; [`SeedRule::seed`] is the source's rule (any channel
/// of red, green and blue above 0: every non-black texel). Any float-sampled colour format is
/// read (`R8Unorm`, `Rgba8UnormSrgb`, `Bgra8Unorm`, `Rgba16Float`, `Rgba32Float`, …); sRGB
/// formats are read as the linear values the hardware decodes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SeedRule {
    /// Where the value comes from.
    pub channels: Channels,
    /// A texel is a seed where its value is greater than this.
    pub above: f32,
}

impl Default for SeedRule {
    fn default() -> Self {
        Self {
            channels: Channels::Red,
            above: 0.0,
        }
    }
}

impl SeedRule {
    /// The source's rule: any non-black texel (red, green or blue above 0), any format.
    pub fn seed() -> Self {
        Self {
            channels: Channels::AnyColour,
            above: 0.0,
        }
    }

    pub(crate) fn check(&self) -> Result<(), Error> {
        if !self.above.is_finite() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("seed threshold must be finite, got {}", self.above),
            });
        }
        Ok(())
    }

    /// The shaders' channel weights (the value is the largest weighted channel).
    pub(crate) fn weights(&self) -> glam::Vec4 {
        match self.channels {
            Channels::Red => glam::Vec4::X,
            Channels::AnyColour => glam::Vec4::new(1.0, 1.0, 1.0, 0.0),
            Channels::Alpha => glam::Vec4::W,
        }
    }

    /// The shaders' test is value ≥ threshold: the least f32 above `above`, kept a normal
    /// number so a GPU that flushes subnormals to zero reads the same test.
    pub(crate) fn threshold(&self) -> f32 {
        let t = self.above.next_up();
        if t > 0.0 && t < f32::MIN_POSITIVE {
            f32::MIN_POSITIVE
        } else if t < 0.0 && t > -f32::MIN_POSITIVE {
            -0.0
        } else {
            t
        }
    }
}

/// Whether a texture format can hold seeds: any colour format read as float.
pub fn is_seed_format(format: wgpu::TextureFormat) -> bool {
    !format.is_depth_stencil_format()
        && matches!(
            format.sample_type(None, None),
            Some(wgpu::TextureSampleType::Float { .. })
        )
}

/// Pack a seed position as the shaders do.
pub fn pack_seed(x: u32, y: u32) -> u32 {
    (x + 1) | ((y + 1) << 16)
}

/// Unpack a seed; `None` for [`NO_SEED`].
pub fn unpack_seed(s: u32) -> Option<(u32, u32)> {
    (s != NO_SEED).then(|| ((s & 0xffff) - 1, (s >> 16) - 1))
}

/// Check a seed texture: 2D, non-empty, a supported format, within the packing range.
pub fn check_seed_texture(
    device: &wgpu::Device,
    seeds: &wgpu::Texture,
) -> Result<(u32, u32), Error> {
    if seeds.dimension() != wgpu::TextureDimension::D2 || seeds.depth_or_array_layers() != 1 {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "the seed texture must be a single 2D texture, got {:?} × {} layers",
                seeds.dimension(),
                seeds.depth_or_array_layers()
            ),
        });
    }
    if !is_seed_format(seeds.format()) {
        return Err(Error::Format {
            stage: STAGE,
            format: seeds.format(),
            supported: "a colour format read as float (R8Unorm, R16Float, R32Float, Rgba8Unorm, \
                        Rgba8UnormSrgb, Bgra8Unorm, Rgba16Float, Rgba32Float, …)",
        });
    }
    check_size(device, seeds.width(), seeds.height())?;
    Ok((seeds.width(), seeds.height()))
}

/// Check a grid size against the device and the seed packing.
pub fn check_size(device: &wgpu::Device, w: u32, h: u32) -> Result<(), Error> {
    let max = device
        .limits()
        .max_texture_dimension_2d
        .min(MAX_PACKED_SIDE);
    check_side(STAGE, "width", w, max)?;
    check_side(STAGE, "height", h, max)
}

/// Upload a CPU mask (`width × height` bytes, row-major, non-zero = seed) as an `R8Unorm` texture.
pub fn upload_mask(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mask: &[u8],
    width: u32,
    height: u32,
) -> Result<wgpu::Texture, Error> {
    check_size(device, width, height)?;
    if mask.len() as u64 != width as u64 * height as u64 {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "mask has {} bytes, {width}×{height} needs {}",
                mask.len(),
                width as u64 * height as u64
            ),
        });
    }
    upload_r8(
        device,
        queue,
        STAGE,
        "seed mask",
        mask,
        [width, height, 1],
        wgpu::TextureDimension::D2,
    )
}
