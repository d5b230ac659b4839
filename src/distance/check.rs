//! The 3D methods' checks (and the 2D exact transform's): grid sides against the seed packing
//! and the device, field bytes against one binding, volumes' dimension and format. Each returns a
//! typed error naming what was wrong.

use super::STAGE_3D as STAGE;
use super::packing::SeedPacking;
use crate::error::Error;

/// Largest sides the standard 3D packing can name: x and y in 11 bits, z in 10
/// ([`pack_seed3`](super::pack_seed3)); JFA and the point seeds take these. The one grid at all three (2048 × 2048
/// × 1024, whose last voxel's code + 1 would wrap to 0) is refused too. The exact transform
/// takes more ([`SeedPacking::for_size`], [`MAX_SIDE_EXACT_3D`]).
pub const MAX_SIDE_3D: [u32; 3] = [2048, 2048, 1024];

/// Largest side of a 2D exact transform: keeps the integer separators inside i32.
pub const MAX_SIDE_2D_EXACT: u32 = 16384;

/// Longest side of any axis of a 3D exact transform: the separators' arithmetic stays exact in
/// f32 and i32 up to 2048 (squared distances below 2^24).
pub const MAX_SIDE_EXACT_3D: u32 = 2048;

/// Volume texture formats the seed and exact stages read (red channel).
pub const VOLUME_FORMATS: &[wgpu::TextureFormat] = &[
    wgpu::TextureFormat::R8Unorm,
    wgpu::TextureFormat::R16Float,
    wgpu::TextureFormat::R32Float,
];

pub(crate) fn voxels(size: [u32; 3]) -> u64 {
    size.iter().map(|&s| s as u64).product()
}

/// Check a 3D grid size against the packing and the device: its sides, and its field (a `u32`
/// per voxel) against one storage binding. The exact transform ([`Method::Exact`](super::Method::Exact)) takes larger
/// fields too, split across bindings, up to the device's `max_buffer_size`.
pub fn check_size_3d(device: &wgpu::Device, size: [u32; 3]) -> Result<(), Error> {
    check_sides_3d(device, size)?;
    check_bytes(&device.limits(), voxels(size) * 4)
}

/// Check a 3D grid's sides against the packing and the device's 3D textures.
pub(crate) fn check_sides_3d(device: &wgpu::Device, size: [u32; 3]) -> Result<(), Error> {
    check_sides(device, size, MAX_SIDE_3D)?;
    if size == MAX_SIDE_3D {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "a {}×{}×{} grid: its last voxel's packed seed would wrap to \"no seed\"; \
                 take one voxel off any side",
                size[0], size[1], size[2]
            ),
        });
    }
    Ok(())
}

/// Each side of `size` from 1 to its entry of `max` and the device's 3D textures.
pub(crate) fn check_sides(
    device: &wgpu::Device,
    size: [u32; 3],
    max: [u32; 3],
) -> Result<(), Error> {
    let tex = device.limits().max_texture_dimension_3d;
    for (i, what) in ["width", "height", "depth"].into_iter().enumerate() {
        check_side(STAGE, what, size[i], max[i].min(tex))?;
    }
    Ok(())
}

/// [`Error::Size`] from `stage` unless the `what` side `got` is from 1 to `max`.
pub(crate) fn check_side(
    stage: &'static str,
    what: &'static str,
    got: u32,
    max: u32,
) -> Result<(), Error> {
    if got == 0 || got > max {
        return Err(Error::Size {
            stage,
            what,
            got: got as u64,
            max: max as u64,
        });
    }
    Ok(())
}

/// [`Error::Invalid`] from `stage` unless the `what` buffer holds exactly `bytes` (what a field
/// of `size` needs).
pub(crate) fn check_len(
    stage: &'static str,
    what: &str,
    buffer: &wgpu::Buffer,
    bytes: u64,
    size: [u32; 3],
) -> Result<(), Error> {
    if buffer.size() == bytes {
        return Ok(());
    }
    Err(Error::Invalid {
        stage,
        what: format!(
            "{what} buffer has {} bytes, {size:?} needs {bytes}",
            buffer.size()
        ),
    })
}

/// A grid the exact transform takes and a column axis: 1 (y) or 2 (z).
pub(crate) fn check_column_axis(
    device: &wgpu::Device,
    stage: &'static str,
    size: [u32; 3],
    axis: u32,
) -> Result<(), Error> {
    check_size_3d(device, size)?;
    if !(axis == 1 || axis == 2) {
        return Err(Error::Invalid {
            stage,
            what: format!("axis must be 1 (y) or 2 (z), got {axis}"),
        });
    }
    Ok(())
}

/// [`Error::Invalid`] unless the `inside` volume (where given) is a volume of `size`.
pub(crate) fn check_inside(
    device: &wgpu::Device,
    inside: Option<&wgpu::Texture>,
    size: [u32; 3],
) -> Result<(), Error> {
    if let Some(v) = inside {
        let vs = check_volume(device, v)?;
        if vs != size {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("inside volume is {vs:?}, the field {size:?}"),
            });
        }
    }
    Ok(())
}

pub(crate) fn check_bytes(limits: &wgpu::Limits, bytes: u64) -> Result<(), Error> {
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max {
        return Err(Error::Size {
            stage: STAGE,
            what: "field buffer (bytes)",
            got: bytes,
            max,
        });
    }
    Ok(())
}

/// Check a 2D grid for the exact transform.
pub fn check_size_2d_exact(device: &wgpu::Device, w: u32, h: u32) -> Result<(), Error> {
    let limits = device.limits();
    let max = MAX_SIDE_2D_EXACT.min(limits.max_texture_dimension_2d);
    check_side(STAGE, "width", w, max)?;
    check_side(STAGE, "height", h, max)?;
    check_bytes(&limits, w as u64 * h as u64 * 4)
}

pub(crate) fn check_volume(
    device: &wgpu::Device,
    volume: &wgpu::Texture,
) -> Result<[u32; 3], Error> {
    let size = volume_size(device, volume)?;
    check_bytes(&device.limits(), voxels(size) * 4)?;
    Ok(size)
}

/// A volume's size for the exact transform: as [`volume_size`], but its sides checked against
/// [`SeedPacking::for_size`] (any side up to [`MAX_SIDE_EXACT_3D`] where the codes fit) and the
/// device's 3D textures.
pub(crate) fn exact_volume_size(
    device: &wgpu::Device,
    volume: &wgpu::Texture,
) -> Result<[u32; 3], Error> {
    if volume.dimension() != wgpu::TextureDimension::D3
        || !VOLUME_FORMATS.contains(&volume.format())
    {
        return volume_size(device, volume);
    }
    let size = [
        volume.width(),
        volume.height(),
        volume.depth_or_array_layers(),
    ];
    check_sides(device, size, [MAX_SIDE_EXACT_3D; 3])?;
    if SeedPacking::for_size(size).is_none() {
        let bits = size.map(|n| 32 - (n - 1).leading_zeros());
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "a {}×{}×{} grid: its sides need {}, {} and {} bits, and a seed's code + 1 \
                 (0 is \"no seed\") must fit the field's 32; take voxels off a side",
                size[0], size[1], size[2], bits[0], bits[1], bits[2]
            ),
        });
    }
    Ok(size)
}

/// A volume's size, its dimension, format and sides checked (not its field's bytes).
pub(crate) fn volume_size(
    device: &wgpu::Device,
    volume: &wgpu::Texture,
) -> Result<[u32; 3], Error> {
    if volume.dimension() != wgpu::TextureDimension::D3 {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "the volume must be a 3D texture, got {:?}",
                volume.dimension()
            ),
        });
    }
    if !VOLUME_FORMATS.contains(&volume.format()) {
        return Err(Error::Format {
            stage: STAGE,
            format: volume.format(),
            supported: "R8Unorm, R16Float, R32Float",
        });
    }
    let size = [
        volume.width(),
        volume.height(),
        volume.depth_or_array_layers(),
    ];
    check_sides_3d(device, size)?;
    Ok(size)
}
