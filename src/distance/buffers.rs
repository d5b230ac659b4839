//! The buffers and textures the distance methods allocate: new ones, the fields handed back
//! with `recycle` (a [`Pool`] the methods draw their outputs from), and scratch kept from call to
//! call ([`kept_buffer`]).

use super::check::voxels;
use super::{Field3d, FieldBuf2d};
pub(crate) use crate::gpu::kept_buffer;
use crate::gpu::{storage_buffer, texture};

/// What [`Distance3d::recycle`] was handed: nearest-seed buffers (all made by `field_buffer`,
/// so of one usage) and distance textures (all made by `distance_texture`).
#[derive(Default)]
pub(crate) struct Recycled {
    buffers: Vec<wgpu::Buffer>,
    textures: Vec<wgpu::Texture>,
}

/// A new nearest-seed field of `size`: a `u32` per voxel.
pub(crate) fn new_field_buffer(device: &wgpu::Device, label: &str, size: [u32; 3]) -> wgpu::Buffer {
    storage_buffer(
        device,
        label,
        voxels(size) * 4,
        wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
    )
}

/// A new `R32Float` distance texture of `size` (2D where `dimension` says so).
pub(crate) fn new_distance_texture(
    device: &wgpu::Device,
    size: [u32; 3],
    dimension: wgpu::TextureDimension,
) -> wgpu::Texture {
    texture(
        device,
        "distance",
        size,
        dimension,
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    )
}

pub(crate) fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// Fields handed back with `recycle`, taken by the next calls instead of new allocations.
#[derive(Default)]
pub(crate) struct Pool {
    recycled: std::sync::Mutex<Recycled>,
}

impl Pool {
    /// Hand back a field no longer needed, so that the next calls take its buffers and
    /// texture instead of allocating new ones: a loop that runs the transform every frame
    /// allocates nothing a frame once it recycles the field before the next (on the H200 the
    /// new buffers of a 512³ field cost the CPU about 26 ms a call, 190 ms at 1024³).
    ///
    /// Kept until a call takes them or the next `recycle` replaces them (this keeps one field's
    /// worth, the last handed back). A call takes a buffer of exactly the size it needs and a
    /// texture of the same size and dimension; what it takes it writes whole before reading,
    /// so the field's old contents never show. Commands are ordered as recorded, so a field may
    /// be recycled as soon as the passes that read it are recorded, even into the same encoder.
    /// A clone of one of its buffers or its texture kept elsewhere would see the next field's
    /// values.
    ///
    /// ```
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, volume: &wgpu::Texture) -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance3d, Settings3d};
    /// let d3 = Distance3d::new(device)?;
    /// let mut last = None;
    /// for _frame in 0..3 {
    ///     if let Some(field) = last.take() {
    ///         d3.recycle(field);
    ///     }
    ///     let mut encoder = device.create_command_encoder(&Default::default());
    ///     last = Some(d3.encode(device, &mut encoder, volume, &Settings3d::default())?);
    ///     queue.submit([encoder.finish()]);
    /// }
    /// # Ok(()) }
    /// ```
    pub(crate) fn recycle(&self, field: Field3d) {
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        r.buffers = field.nearest.buffers;
        r.buffers
            .extend(field.nearest_outside.into_iter().flat_map(|s| s.buffers));
        r.textures = vec![field.distance];
    }

    /// [`Self::recycle`] for a 2D field of the exact transform.
    pub(crate) fn recycle_2d(&self, field: FieldBuf2d) {
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        r.buffers = std::iter::once(field.nearest)
            .chain(field.nearest_outside)
            .collect();
        r.textures = vec![field.distance];
    }

    /// A buffer for a field of `size`: one handed back to [`Self::recycle`] of exactly its
    /// bytes where there is one, else a new one.
    pub(crate) fn field_buffer(
        &self,
        device: &wgpu::Device,
        label: &str,
        size: [u32; 3],
    ) -> wgpu::Buffer {
        let bytes = voxels(size) * 4;
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        match r.buffers.iter().position(|b| b.size() == bytes) {
            Some(i) => r.buffers.swap_remove(i),
            None => new_field_buffer(device, label, size),
        }
    }

    /// A distance texture of `size`: one handed back to [`Self::recycle`] of that size and
    /// dimension where there is one, else a new one.
    pub(crate) fn distance_texture(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        dimension: wgpu::TextureDimension,
    ) -> wgpu::Texture {
        let extent = wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: size[2],
        };
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        match r
            .textures
            .iter()
            .position(|t| t.size() == extent && t.dimension() == dimension)
        {
            Some(i) => r.textures.swap_remove(i),
            None => new_distance_texture(device, size, dimension),
        }
    }
}

/// One byte per texel of `data` (x fastest) uploaded as a new `R8Unorm` texture of `size`
/// (2D: depth 1), for masks and volumes; a wgpu error names `stage`.
pub(crate) fn upload_r8(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    stage: &'static str,
    label: &str,
    data: &[u8],
    size: [u32; 3],
    dimension: wgpu::TextureDimension,
) -> Result<wgpu::Texture, crate::Error> {
    crate::gpu::scoped(device, stage, || {
        let t = texture(
            device,
            label,
            size,
            dimension,
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
        );
        queue.write_texture(
            t.as_image_copy(),
            data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size[0]),
                rows_per_image: Some(size[1]),
            },
            t.size(),
        );
        t
    })
}
