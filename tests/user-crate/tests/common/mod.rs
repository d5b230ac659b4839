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

/// A 2D texture of `w` × `h` texels of `format`, for `usage`.
fn texture_2d(
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::TextureDescriptor<'static> {
    wgpu::TextureDescriptor {
        label: Some("user crate test"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    }
}

/// A `w` × `h` render target of `format`, readable back.
pub fn target(ctx: &Context, w: u32, h: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    ctx.device.create_texture(&texture_2d(
        w,
        h,
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    ))
}

/// A render pass over `views`, each cleared to `clear` first.
pub fn colour_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    views: &[wgpu::TextureView],
    clear: wgpu::Color,
) -> wgpu::RenderPass<'e> {
    let attachments: Vec<_> = views
        .iter()
        .map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                resolve_target: None,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("colour"),
        color_attachments: &attachments,
        ..Default::default()
    })
}

/// `n` `R32Float` textures of `w` × `h` texels, texel (x, y) of layer k holding `texel(k, x,
/// y)`, as views for a binding array.
pub fn float_layers(
    ctx: &Context,
    n: u32,
    [w, h]: [u32; 2],
    texel: impl Fn(u32, u32, u32) -> f32,
) -> Vec<wgpu::TextureView> {
    (0..n)
        .map(|k| {
            let data: Vec<f32> = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| texel(k, x, y))
                .collect();
            ctx.device
                .create_texture_with_data(
                    &ctx.queue,
                    &texture_2d(
                        w,
                        h,
                        wgpu::TextureFormat::R32Float,
                        wgpu::TextureUsages::TEXTURE_BINDING,
                    ),
                    wgpu::util::TextureDataOrder::LayerMajor,
                    bytemuck::cast_slice(&data),
                )
                .create_view(&Default::default())
        })
        .collect()
}

/// A storage buffer of `bytes` zeroed bytes, readable back.
pub fn output(ctx: &Context, bytes: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("output"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}
