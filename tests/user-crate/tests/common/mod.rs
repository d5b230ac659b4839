//! What the user crate's tests share: buffers made and read back as a user's app would.
#![allow(dead_code)]

use fieldkit::gpu::{read_buffer, Context};
use wgpu::util::DeviceExt as _;

/// A uniform buffer holding `value`, laid out by encase as the generated struct says.
pub fn uniform<T: encase::ShaderType + encase::internal::WriteInto>(
    ctx: &Context,
    label: &str,
    value: &T,
) -> wgpu::Buffer {
    let mut bytes = encase::UniformBuffer::new(Vec::new());
    bytes.write(value).unwrap();
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes.into_inner(),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// A storage buffer holding `values`, readable back.
pub fn storage(ctx: &Context, label: &str, values: &[f32]) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(values),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        })
}

/// The f32s a buffer holds.
pub fn read_f32(ctx: &Context, buffer: &wgpu::Buffer) -> Vec<f32> {
    bytemuck::cast_slice(&read_buffer(ctx, buffer).unwrap()).to_vec()
}
