//! What the volume renderer keeps from frame to frame, so that a frame makes no GPU object:
//! its uniforms and transfer function (written through an upload ring), the views of the
//! caller's textures, its outputs (taken back once the caller drops them) and its bind groups.

use std::sync::Mutex;

use crate::bind::KeptBound;
use crate::gpu::{KeptView, Lease, Leased, Uploads};
use crate::shaders::volume::{lit_density, volume_composite, volume_march};

/// A texture a pass writes and the view it is bound through.
#[derive(Clone)]
pub(super) struct Target {
    pub(super) texture: wgpu::Texture,
    pub(super) view: wgpu::TextureView,
}

impl Target {
    /// A new `format` texture of `size` a pass writes and later passes sample.
    pub(super) fn new(
        device: &wgpu::Device,
        label: &str,
        size: [u32; 3],
        dimension: wgpu::TextureDimension,
        format: wgpu::TextureFormat,
    ) -> Self {
        let texture = crate::gpu::texture(
            device,
            label,
            size,
            dimension,
            format,
            wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let view = texture.create_view(&Default::default());
        Self { texture, view }
    }

    /// Whether this is a `format` texture of `size`.
    pub(super) fn is(&self, size: [u32; 3], format: wgpu::TextureFormat) -> bool {
        let s = self.texture.size();
        [s.width, s.height, s.depth_or_array_layers] == size && self.texture.format() == format
    }
}

pub(super) struct Kept {
    pub(super) uploads: Uploads,
    pub(super) march_params: Mutex<Option<wgpu::Buffer>>,
    pub(super) light_params: Mutex<Option<wgpu::Buffer>>,
    pub(super) tf: Mutex<Option<wgpu::Buffer>>,
    pub(super) density_view: KeptView,
    pub(super) marched: Leased<Target>,
    pub(super) light: Leased<Target>,
    pub(super) lit: Leased<Target>,
    pub(super) march_bound: KeptBound<volume_march::march::Entry>,
    pub(super) light_bound: KeptBound<volume_march::light_volume::Entry>,
    pub(super) lit_bound: LitBound,
    pub(super) composite_bound: KeptBound<volume_composite::fs_main::Entry>,
    /// Bound in place of a light volume's own texture and of the caller's depth when there are
    /// none (the march reads them only when told to).
    pub(super) no_light: wgpu::TextureView,
    pub(super) no_depth: wgpu::TextureView,
}

/// The lit-density pass's groups, one entry point per format.
#[derive(Default)]
pub(super) struct LitBound {
    pub(super) unorm8: KeptBound<lit_density::lit_unorm8::Entry>,
    pub(super) float16: KeptBound<lit_density::lit_float16::Entry>,
    pub(super) float32: KeptBound<lit_density::lit_float32::Entry>,
}

impl Kept {
    pub(super) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let tiny = |label, format, dimension| {
            crate::gpu::texture(
                device,
                label,
                [1, 1, 1],
                dimension,
                format,
                wgpu::TextureUsages::TEXTURE_BINDING,
            )
            .create_view(&Default::default())
        };
        Self {
            uploads: Uploads::new(queue),
            march_params: Mutex::new(None),
            light_params: Mutex::new(None),
            tf: Mutex::new(None),
            density_view: KeptView::default(),
            marched: Leased::default(),
            light: Leased::default(),
            lit: Leased::default(),
            march_bound: KeptBound::default(),
            light_bound: KeptBound::default(),
            lit_bound: LitBound::default(),
            composite_bound: KeptBound::default(),
            no_light: tiny(
                "no light volume",
                wgpu::TextureFormat::Rgba16Float,
                wgpu::TextureDimension::D3,
            ),
            no_depth: tiny(
                "no scene depth",
                wgpu::TextureFormat::Depth32Float,
                wgpu::TextureDimension::D2,
            ),
        }
    }
}

/// The premultiplied image a march for a `viewport` writes (`Rgba16Float`): one of `marched`
/// no longer held that still serves it ([`gpu::screen_fits`](crate::gpu::screen_fits), so a
/// window resized by a little keeps it), else a new one of
/// [`gpu::screen_rounded`](crate::gpu::screen_rounded) of it.
pub(super) fn march_target(
    marched: &Leased<Target>,
    device: &wgpu::Device,
    viewport: [u32; 2],
) -> (Target, Lease) {
    marched.take(
        |t| crate::gpu::screen_fits([t.texture.width(), t.texture.height()], viewport),
        || {
            let [w, h] = crate::gpu::screen_rounded(viewport);
            Target::new(
                device,
                "volume march",
                [w, h, 1],
                wgpu::TextureDimension::D2,
                wgpu::TextureFormat::Rgba16Float,
            )
        },
    )
}
