//! A 3D field on the GPU ([`Field3d`], its nearest seeds in [`Slabs`]) and the 2D exact
//! transform's ([`FieldBuf2d`]).

use super::SeedPacking;

/// A `u32` per voxel (x fastest, then y, then z) in one buffer, or, for a field larger than one
/// buffer or binding may be (the exact transform at 1024³: 4 GiB, where wgpu binds at most
/// 2 GiB − 1 and NVIDIA's `max_buffer_size` is 2 MiB short of 4 GiB), in slabs of whole z
/// planes, one buffer each.
#[derive(Debug)]
pub struct Slabs {
    /// The buffers, in z order: planes `k · depth ..` in buffer `k`.
    pub buffers: Vec<wgpu::Buffer>,
    /// Planes per buffer (the last may hold fewer).
    pub depth: u32,
    /// Planes in all (the field's depth).
    pub planes: u32,
}

impl Slabs {
    pub(crate) fn one(buffer: wgpu::Buffer, depth: u32) -> Self {
        Self {
            buffers: vec![buffer],
            depth,
            planes: depth,
        }
    }

    /// The field's buffer where one holds it; `None` where it is split.
    pub fn whole(&self) -> Option<&wgpu::Buffer> {
        match self.buffers.as_slice() {
            [one] => Some(one),
            _ => None,
        }
    }

    /// Every voxel's word, slab after slab (x fastest, then y, then z): one submission, and a
    /// [`Readback`](crate::gpu::Readback) that completes when every slab is mapped.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> crate::gpu::Readback<Vec<u32>> {
        let buffers: Vec<&wgpu::Buffer> = self.buffers.iter().collect();
        crate::gpu::readback_buffers(device, queue, &buffers)
            .then(|bytes| Ok(bytemuck::cast_slice::<u8, u32>(&bytes).to_vec()))
    }

    /// The buffer holding plane `z`, and the plane's index in it; `None` past the field.
    pub fn plane(&self, z: u32) -> Option<(&wgpu::Buffer, u32)> {
        if z >= self.planes {
            return None;
        }
        let k = (z / self.depth.max(1)) as usize;
        self.buffers.get(k).map(|b| (b, z - k as u32 * self.depth))
    }
}

/// A 3D distance field on the GPU.
#[derive(Debug)]
pub struct Field3d {
    /// Voxels per axis.
    pub size: [u32; 3],
    /// How `nearest` names integer seeds: [`SeedPacking::STANDARD`] ([`unpack_seed3`](super::unpack_seed3)) for
    /// every grid up to 2048 × 2048 × 1024, wider per axis where the exact transform took a
    /// grid past that (`packing.unpack(s)` decodes either).
    pub packing: SeedPacking,
    /// Nearest seed per voxel: packed (`packing`), or a key into `points` ([`key_index`](super::key_index)).
    /// For a signed field of integer seeds, the nearest *inside* voxel. One buffer
    /// ([`Slabs::whole`]) except where the exact transform split a field too large for one.
    pub nearest: Slabs,
    /// For a signed field of integer seeds, the nearest *outside* voxel.
    pub nearest_outside: Option<Slabs>,
    /// `R32Float` 3D texture, voxel (x, y, z) at texel (x, y, z): distance in world units
    /// (`voxel_size` per voxel) to the nearest seed, clamped to the band. Integer seeds are
    /// voxel centres, and a signed field (negative inside) is half a voxel closer to zero than
    /// the centre distance, so zero lies between voxels (see `Settings3d::signed`); sub-voxel
    /// seeds are the points themselves. `±f32::MAX` where no seed exists.
    pub distance: wgpu::Texture,
}

impl Field3d {
    /// A field held whole (one buffer per seed set, as [`Slabs::whole`] reads) with its seeds
    /// packed the standard way: what every method but the exact transform past 2048 × 2048 ×
    /// 1024 makes, and what a stage that wrote its own keys and distances hands to `recycle`.
    pub fn whole(
        size: [u32; 3],
        nearest: wgpu::Buffer,
        nearest_outside: Option<wgpu::Buffer>,
        distance: wgpu::Texture,
    ) -> Self {
        Self {
            size,
            packing: SeedPacking::STANDARD,
            nearest: Slabs::one(nearest, size[2]),
            nearest_outside: nearest_outside.map(|b| Slabs::one(b, size[2])),
            distance,
        }
    }
}

/// A 2D field from the exact transform (nearest seeds in a buffer, packed 16/16 bits).
#[derive(Debug)]
pub struct FieldBuf2d {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Nearest seed per texel, packed 16/16 bits ([`super::pack_seed`]), x fastest.
    pub nearest: wgpu::Buffer,
    /// Signed fields: nearest outside texel.
    pub nearest_outside: Option<wgpu::Buffer>,
    /// `R32Float` 2D texture.
    pub distance: wgpu::Texture,
}
