//! Copy buffers and 2D/3D textures back to the CPU.

use super::Context;
use crate::error::Error;

fn map_and_read(ctx: &Context, staging: &wgpu::Buffer) -> Result<Vec<u8>, Error> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Readback(e.to_string()))?;
    rx.recv()
        .map_err(|e| Error::Readback(e.to_string()))?
        .map_err(|e| Error::Readback(e.to_string()))?;
    let data = staging
        .get_mapped_range(..)
        .map_err(|e| Error::Readback(format!("{e:?}")))?
        .to_vec();
    staging.unmap();
    Ok(data)
}

/// Read a whole buffer (it needs `COPY_SRC` usage).
pub fn read_buffer(ctx: &Context, buffer: &wgpu::Buffer) -> Result<Vec<u8>, Error> {
    if !buffer.usage().contains(wgpu::BufferUsages::COPY_SRC) {
        return Err(Error::Readback(format!(
            "buffer lacks COPY_SRC usage ({:?})",
            buffer.usage()
        )));
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("fieldkit readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.encoder("readback");
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.submit_and_wait("readback", enc)?;
    map_and_read(ctx, &staging)
}

/// Read mip 0 of a 2D or 3D texture into texels of type `T` (e.g. `u32` for `R32Uint`,
/// `f32` for `R32Float` and `Depth32Float`, `[u8; 4]` for `Rgba8Unorm`), rows tightly packed, x fastest, then y, then z.
pub fn read_texture<T: bytemuck::Pod>(
    ctx: &Context,
    texture: &wgpu::Texture,
) -> Result<Vec<T>, Error> {
    let format = texture.format();
    // Depth formats are read through their depth aspect (`f32` for `Depth32Float`).
    let aspect = if format.has_depth_aspect() {
        wgpu::TextureAspect::DepthOnly
    } else {
        wgpu::TextureAspect::All
    };
    let texel = format
        .block_copy_size(Some(aspect))
        .ok_or_else(|| Error::Readback(format!("{format:?} cannot be copied")))?;
    if texel as usize != std::mem::size_of::<T>() {
        return Err(Error::Readback(format!(
            "{format:?} has {texel}-byte texels, asked for {}-byte values",
            std::mem::size_of::<T>()
        )));
    }
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return Err(Error::Readback(format!(
            "texture lacks COPY_SRC usage ({:?})",
            texture.usage()
        )));
    }
    let size = texture.size();
    let row = size.width * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("fieldkit texture readback"),
        size: padded as u64 * size.height as u64 * size.depth_or_array_layers as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.encoder("texture readback");
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            aspect,
            ..texture.as_image_copy()
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        size,
    );
    ctx.submit_and_wait("texture readback", enc)?;
    let bytes = map_and_read(ctx, &staging)?;
    let mut out =
        Vec::with_capacity((size.width * size.height * size.depth_or_array_layers) as usize);
    for chunk in bytes.chunks(padded as usize) {
        out.extend_from_slice(bytemuck::cast_slice::<u8, T>(&chunk[..row as usize]));
    }
    Ok(out)
}
