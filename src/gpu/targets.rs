//! Colour targets within a device's limits: what a set of render targets costs per sample
//! (WebGPU's `maxColorAttachmentBytesPerSample`, 32 bytes on a default-limits device), and the
//! G-buffer formats the ocean and the metaball raymarcher write that fit it.

/// The G-buffer both the ocean ([`Output::GBuffer`](crate::ocean::Output::GBuffer)) and the
/// metaball raymarcher ([`Raymarcher::gbuffer`](crate::metaball::Raymarcher::gbuffer))
/// write, in formats that fit WebGPU's default 32 bytes a sample: scene colour (emissive, HDR)
/// `Rgba16Float`, world normal × ½ + ½ `Rgb10a2Unorm` (steps of 1/1023), material (metallic,
/// specular, roughness, shading model ÷ 255) `Rgba8Unorm`, base colour `Rgba8Unorm`. Any float
/// formats may be given instead (`Rgba32Float` for exact values) on a device whose limit
/// holds them: [`target_bytes_per_sample`] says what a set costs.
pub const GBUFFER_FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgb10a2Unorm,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba8Unorm,
];

/// Bytes a sample that colour targets of `formats` (in location order) take against the
/// device's `max_color_attachment_bytes_per_sample`, as WebGPU counts them: each format's
/// render-target byte cost (`Rgba8Unorm` counts 8, `Rg16Float` and `R32Uint` 4,
/// `Rgba32Float` 16), each target aligned to its component size. `None` for a format that is
/// not a colour target.
///
/// ```
/// use fieldkit::gpu::{GBUFFER_FORMATS, target_bytes_per_sample};
/// use wgpu::TextureFormat::Rgba32Float;
/// assert_eq!(target_bytes_per_sample(&GBUFFER_FORMATS), Some(32));
/// assert_eq!(target_bytes_per_sample(&[Rgba32Float; 4]), Some(64));
/// assert!(target_bytes_per_sample(&GBUFFER_FORMATS) <= Some(wgpu::Limits::default().max_color_attachment_bytes_per_sample));
/// ```
pub fn target_bytes_per_sample(formats: &[wgpu::TextureFormat]) -> Option<u32> {
    formats.iter().try_fold(0u32, |total, f| {
        let cost = f.target_pixel_byte_cost()?;
        let align = f.target_component_alignment()?;
        Some(total.next_multiple_of(align) + cost)
    })
}

/// A typed error where colour targets of `formats` do not fit `device`'s
/// `max_color_attachment_bytes_per_sample` (wgpu would refuse the pipeline with a validation
/// error instead), naming the formats, their cost, the limit and the way out.
pub(crate) fn check_target_bytes(
    device: &wgpu::Device,
    stage: &'static str,
    formats: &[wgpu::TextureFormat],
) -> Result<(), crate::Error> {
    let limit = device.limits().max_color_attachment_bytes_per_sample;
    match target_bytes_per_sample(formats) {
        Some(bytes) if bytes <= limit => Ok(()),
        Some(bytes) => Err(crate::Error::Unsupported {
            stage,
            what: format!(
                "max_color_attachment_bytes_per_sample ≥ {bytes} for colour targets {formats:?} \
                 (it allows {limit}; WebGPU's default is 32): give narrower formats, such as \
                 fieldkit::gpu::GBUFFER_FORMATS for a G-buffer, or raise the limit where the \
                 adapter has it"
            ),
        }),
        None => Err(crate::Error::Invalid {
            stage,
            what: format!("colour targets {formats:?}: not every format is a colour target"),
        }),
    }
}

/// Pixels to which an image the size of a caller's target (a march's output, a copy of the
/// scene's depth) rounds each side up, so that a window resized by a little keeps it: a new
/// image of screen size can cost milliseconds of CPU where the driver maps fresh memory for it
/// (5–6 ms on the H200 for the frame after a resize, against 0.06–0.08 ms for one kept).
pub(crate) const SCREEN_STEP: u32 = 128;

/// The size a kept image for targets of `size` is made at: each side rounded up to a multiple
/// of [`SCREEN_STEP`].
pub(crate) fn screen_rounded(size: [u32; 2]) -> [u32; 2] {
    size.map(|n| n.div_ceil(SCREEN_STEP).max(1) * SCREEN_STEP)
}

/// A typed error unless an image for a screen of `size` can be made on `device` (for a
/// stage's `reserve`: each side at least 1 and, rounded up as [`screen_rounded`] makes it, at
/// most the device's largest 2D texture).
// Used by the techniques' renderers.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) fn check_screen(
    device: &wgpu::Device,
    stage: &'static str,
    size: [u32; 2],
) -> Result<(), crate::error::Error> {
    let max = device.limits().max_texture_dimension_2d;
    let widest = screen_rounded(size).into_iter().max().unwrap_or(0);
    if size.contains(&0) || widest > max {
        return Err(crate::error::Error::Size {
            stage,
            what: "screen side, rounded up to 128 pixels (each side at least 1)",
            got: if size.contains(&0) { 0 } else { widest as u64 },
            max: max as u64,
        });
    }
    Ok(())
}

/// Whether a kept image of `kept` pixels serves targets of `size`: it holds them and is not
/// over twice the area a new one would be made at ([`screen_rounded`]), so a window shrunk a
/// long way gets its memory back.
pub(crate) fn screen_fits(kept: [u32; 2], size: [u32; 2]) -> bool {
    let area = |s: [u32; 2]| s[0] as u64 * s[1] as u64;
    kept[0] >= size[0] && kept[1] >= size[1] && area(kept) <= 2 * area(screen_rounded(size))
}

/// A depth attachment cleared to `depth` and stored, without stencil: the start of a frame's
/// depth in a pass of the caller's own (a floor, a shadow map) before fieldkit's stages draw.
///
/// ```no_run
/// # fn f(encoder: &mut wgpu::CommandEncoder, depth: &wgpu::TextureView) {
/// let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
///     depth_stencil_attachment: Some(fieldkit::gpu::depth_cleared(depth, 1.0)),
///     ..Default::default()
/// });
/// # }
/// ```
pub fn depth_cleared(
    view: &wgpu::TextureView,
    depth: f32,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(depth),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// Record a pass that only clears the depth target `view` to `depth` ([`depth_cleared`]).
pub fn clear_depth(encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, depth: f32) {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("fieldkit clear depth"),
        depth_stencil_attachment: Some(depth_cleared(view, depth)),
        ..Default::default()
    });
}

#[cfg(test)]
mod screen_tests {
    use super::*;

    #[test]
    fn a_kept_image_serves_a_window_resized_by_a_little() {
        assert_eq!(screen_rounded([1920, 1080]), [1920, 1152]);
        assert_eq!(screen_rounded([1, 0]), [128, 128]);
        // 90 % of 1080p (the viewer's resize) and the full size again.
        assert!(screen_fits([1920, 1152], [1728, 972]));
        assert!(screen_fits([1920, 1152], [1920, 1080]));
        // Larger than the kept image: a new one.
        assert!(!screen_fits([1920, 1152], [1921, 1080]));
        assert!(!screen_fits([1920, 1152], [1920, 1153]));
        // Shrunk to a quarter: a new, smaller one (1920×1152 is over twice 1024×640).
        assert!(!screen_fits([1920, 1152], [960, 540]));
        assert!(screen_fits([1920, 1152], [1280, 1080]));
    }
}
