//! Inputs from the CPU: occupancy volumes and sub-voxel seed points.

use glam::Vec3;

use super::STAGE_3D as STAGE;
use super::buffers::upload_r8;
use super::check::{MAX_SIDE_EXACT_3D, check_sides, check_size_3d, voxels};
use super::{Grid, MAX_POINTS, pack_seed3};
use crate::error::Error;

/// Sub-voxel seeds on the GPU: `count` points (`vec4<f32>`, xyz in voxel coordinates) and,
/// optionally, each point's home voxel (`u32`, packed as [`pack_seed3`]).
#[derive(Debug)]
pub struct PointSeeds {
    /// `vec4<f32>` per point, xyz in voxel coordinates.
    pub buffer: wgpu::Buffer,
    /// Each point's home voxel, packed, if given.
    pub homes: Option<wgpu::Buffer>,
    /// Number of points.
    pub count: u32,
}

/// Upload a CPU volume (`x` fastest, then `y`, then `z`; one byte per voxel) as an `R8Unorm`
/// 3D texture. Non-zero bytes are marked under [`Inside::Mask`](super::Inside::Mask). Sides up to
/// [`MAX_SIDE_EXACT_3D`] (and the device's 3D textures): the method checks its own range when it
/// runs.
pub fn upload_volume(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &[u8],
    size: [u32; 3],
) -> Result<wgpu::Texture, Error> {
    // Any side a method takes: the exact transform's (the others refuse past theirs when
    // they run).
    check_sides(device, size, [MAX_SIDE_EXACT_3D; 3])?;
    if data.len() as u64 != voxels(size) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "volume has {} bytes, {size:?} needs {}",
                data.len(),
                voxels(size)
            ),
        });
    }
    upload_r8(
        device,
        queue,
        STAGE,
        "volume",
        data,
        size,
        wgpu::TextureDimension::D3,
    )
}

/// Upload sub-voxel seeds given in world coordinates; each seeds the voxel it lies in. Every
/// point must be finite and inside the grid's box; at most [`MAX_POINTS`]. Where several points
/// share a voxel only the one nearest its centre is kept: give homes
/// ([`upload_points_with_homes`]) when points come one per voxel, as from surface extraction.
pub fn upload_points(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid,
    points: &[Vec3],
) -> Result<PointSeeds, Error> {
    upload_points_inner(device, queue, grid, points, None)
}

/// Upload sub-voxel seeds with the voxel each one seeds (typically the voxel that produced it,
/// holding the closest surface point to its centre). Homes must lie inside the grid.
pub fn upload_points_with_homes(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid,
    points: &[Vec3],
    homes: &[[u32; 3]],
) -> Result<PointSeeds, Error> {
    if homes.len() != points.len() {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("{} homes for {} points", homes.len(), points.len()),
        });
    }
    upload_points_inner(device, queue, grid, points, Some(homes))
}

pub(crate) fn upload_points_inner(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid,
    points: &[Vec3],
    homes: Option<&[[u32; 3]]>,
) -> Result<PointSeeds, Error> {
    check_size_3d(device, grid.size)?;
    let (origin, voxel) = grid.as_f32(STAGE)?;
    if points.is_empty() || points.len() as u64 > MAX_POINTS as u64 {
        return Err(Error::Size {
            stage: STAGE,
            what: "number of seed points",
            got: points.len() as u64,
            max: MAX_POINTS as u64,
        });
    }
    let hi = Vec3::new(
        grid.size[0] as f32,
        grid.size[1] as f32,
        grid.size[2] as f32,
    ) - 0.5;
    let mut data = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let v = (p - origin) / voxel - Vec3::splat(0.5);
        if !p.is_finite() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("seed point {i} is not finite: {p}"),
            });
        }
        if v.cmplt(Vec3::splat(-0.5)).any() || v.cmpgt(hi).any() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "seed point {i} at {p} lies outside the volume (voxel coordinates {v})"
                ),
            });
        }
        data.push([v.x, v.y, v.z, 0.0]);
    }
    let packed_homes = match homes {
        None => None,
        Some(h) => {
            let mut packed = Vec::with_capacity(h.len());
            for (i, v) in h.iter().enumerate() {
                if (0..3).any(|a| v[a] >= grid.size[a]) {
                    return Err(Error::Invalid {
                        stage: STAGE,
                        what: format!(
                            "home voxel {v:?} of point {i} lies outside the grid {:?}",
                            grid.size
                        ),
                    });
                }
                packed.push(pack_seed3(v[0], v[1], v[2]));
            }
            Some(packed)
        }
    };
    let storage = |label: &str, contents: &[u8]| {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: contents.len() as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&buffer, 0, contents);
        buffer
    };
    let buffer = storage("seed points", bytemuck::cast_slice(&data));
    let homes = packed_homes.map(|h| storage("seed point homes", bytemuck::cast_slice(&h)));
    Ok(PointSeeds {
        buffer,
        homes,
        count: points.len() as u32,
    })
}
