//! Surface voxels on the GPU: the bitset every voxelization writes, made by the voxelizer or
//! from a caller's own bits, and read back.

use super::{KeptWork, STAGE};
use crate::error::Error;
use crate::gpu::{Readback, readback_buffer};

/// Surface voxels on the GPU: one bit per voxel.
pub struct Surface {
    /// Voxels per axis.
    pub size: [u32; 3],
    /// `u32` words; voxel i = (z · ny + y) · nx + x is bit i % 32 of word i / 32.
    pub occupancy: wgpu::Buffer,
    /// Zero-area triangles left out.
    pub degenerate: usize,
    /// The work list kept for refills (`encode_surface_placed_into`), made by the first.
    pub(super) kept: Option<Box<KeptWork>>,
}

impl Surface {
    /// A surface of `size` voxels whose bits are in `occupancy`, with no work list kept.
    pub(crate) fn new(size: [u32; 3], occupancy: wgpu::Buffer, degenerate: usize) -> Self {
        Surface {
            size,
            occupancy,
            degenerate,
            kept: None,
        }
    }

    /// A surface of `size` voxels from an occupancy bitset a stage of the caller's wrote, laid
    /// out as [`Surface::occupancy`] is (bit i % 32 of word i / 32 for voxel i, x fastest):
    /// what takes a voxelization
    /// ([`Voxelizer::encode_volume`](super::Voxelizer::encode_volume), [`Surface::read`])
    /// takes it.
    /// `occupancy` needs a word per 32 voxels; a smaller buffer or a side of 0 is a typed error.
    ///
    /// ```
    /// # fn f(device: &wgpu::Device) -> Result<(), fieldkit::Error> {
    /// let bits = device.create_buffer(&wgpu::BufferDescriptor {
    ///     label: Some("my occupancy"),
    ///     size: 4 * 4 * 4 / 8,
    ///     usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    ///     mapped_at_creation: false,
    /// });
    /// let surface = fieldkit::voxelize::Surface::from_bits([4, 4, 4], bits)?;
    /// # Ok(()) }
    /// ```
    pub fn from_bits(size: [u32; 3], occupancy: wgpu::Buffer) -> Result<Self, Error> {
        if size.contains(&0) {
            return Err(Error::invalid(
                STAGE,
                format!("a surface needs every side ≥ 1, got {size:?}"),
            ));
        }
        let words = size.iter().map(|&s| s as u64).product::<u64>().div_ceil(32);
        if occupancy.size() < words * 4 {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the occupancy bitset holds {} bytes; {size:?} voxels need {} (a word per 32)",
                    occupancy.size(),
                    words * 4
                ),
            ));
        }
        Ok(Self::new(size, occupancy, 0))
    }

    /// One bool per voxel, x fastest, once the encoder that recorded this surface has been
    /// submitted (see [`Readback`] for how to wait or poll).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<bool>> {
        let n = self.size.iter().map(|&s| s as usize).product::<usize>();
        readback_buffer(device, queue, &self.occupancy).then(move |bytes| {
            let words: &[u32] = bytemuck::cast_slice(&bytes);
            Ok((0..n).map(|i| words[i / 32] >> (i % 32) & 1 == 1).collect())
        })
    }
}
