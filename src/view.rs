//! What every renderer in fieldkit shares: the camera [`View`], the host-side frustum test
//! ([`box_visible`]) and screen rectangle ([`screen_rect`]), the depth state the drawing stages
//! test and write with ([`depth_state`]), a pass that loads the caller's targets
//! ([`load_pass`]) and colour + depth [`Targets`] for tests, demos and benches.

use glam::{Mat4, Vec3, Vec4};

use crate::error::Error;

/// A camera: view-projection (world → clip, depth 0..1 or reversed 1..0) and target size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// World → clip space.
    pub view_proj: Mat4,
    /// Viewport size in pixels (the whole target where `origin` is [0, 0] and the target is
    /// this size).
    pub viewport: [u32; 2],
    /// Reversed Z: the near plane at depth 1, far at 0 (depth test `Greater`).
    pub reversed_z: bool,
    /// Top-left pixel of the viewport in the target (the metaball source's `ViewportMin`): a
    /// view drawn into a sub-rectangle, for split screens and editor panels. Targets must be
    /// at least `origin + viewport`. The metaball stages honour it; the volume renderer draws
    /// whole targets and refuses a non-zero origin.
    pub origin: [u32; 2],
}

impl View {
    /// A typed error naming `stage` unless the matrix is finite and invertible and the
    /// viewport has no zero side.
    pub fn check(&self, stage: &'static str) -> Result<(), Error> {
        if !self.view_proj.is_finite() || self.view_proj.determinant() == 0.0 {
            return Err(Error::Invalid {
                stage,
                what: "view_proj must be finite and invertible".into(),
            });
        }
        if self.viewport[0] == 0 || self.viewport[1] == 0 {
            return Err(Error::Invalid {
                stage,
                what: format!("viewport {:?} has a zero side", self.viewport),
            });
        }
        if (0..2).any(|k| self.origin[k].checked_add(self.viewport[k]).is_none()) {
            return Err(Error::Invalid {
                stage,
                what: format!(
                    "origin {:?} + viewport {:?} overflows u32",
                    self.origin, self.viewport
                ),
            });
        }
        Ok(())
    }

    /// The smallest target this view draws into: `origin + viewport`.
    pub fn target_size(&self) -> [u32; 2] {
        [
            self.origin[0].saturating_add(self.viewport[0]),
            self.origin[1].saturating_add(self.viewport[1]),
        ]
    }
}

/// Whether a local box under `local_to_world` can be on screen: false when all 8 corners lie
/// outside one clip plane (the host-side frustum test before drawing).
pub fn box_visible(view_proj: Mat4, local_to_world: Mat4, lo: Vec3, hi: Vec3) -> bool {
    let m = view_proj * local_to_world;
    let corners: Vec<Vec4> = (0..8)
        .map(|i| {
            let c = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            m * c.extend(1.0)
        })
        .collect();
    // Planes: -w ≤ x ≤ w, -w ≤ y ≤ w, 0 ≤ z ≤ w (either depth convention keeps z in [0, w]).
    let planes: [fn(Vec4) -> f32; 6] = [
        |c| c.w + c.x,
        |c| c.w - c.x,
        |c| c.w + c.y,
        |c| c.w - c.y,
        |c| c.z,
        |c| c.w - c.z,
    ];
    planes
        .iter()
        .all(|plane| corners.iter().any(|&c| plane(c) >= 0.0))
}

/// Pixels `[x0, y0]` to `[x1, y1)` of the viewport that the box under `local_to_world` can cover:
/// the bounding rectangle of its projected corners, or the whole viewport when a corner lies
/// behind the eye (then its projection says nothing). Empty when the box is off screen.
pub fn screen_rect(view: &View, local_to_world: Mat4, lo: Vec3, hi: Vec3) -> [u32; 4] {
    let m = view.view_proj * local_to_world;
    let [w, h] = view.viewport;
    let (mut min, mut max) = (
        glam::Vec2::splat(f32::INFINITY),
        glam::Vec2::splat(f32::NEG_INFINITY),
    );
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let clip = m * c.extend(1.0);
        if clip.w <= 1e-6 * clip.truncate().abs().max_element().max(1.0) {
            return [0, 0, w, h];
        }
        let ndc = glam::Vec2::new(clip.x, clip.y) / clip.w;
        let px = glam::Vec2::new(
            (ndc.x + 1.0) * 0.5 * w as f32,
            (1.0 - ndc.y) * 0.5 * h as f32,
        );
        min = min.min(px);
        max = max.max(px);
    }
    // A pixel whose centre the projection only just misses still counts: one pixel of margin.
    let x0 = (min.x.floor() - 1.0).clamp(0.0, w as f32) as u32;
    let y0 = (min.y.floor() - 1.0).clamp(0.0, h as f32) as u32;
    let x1 = (max.x.ceil() + 1.0).clamp(0.0, w as f32) as u32;
    let y1 = (max.y.ceil() + 1.0).clamp(0.0, h as f32) as u32;
    [x0, y0, x1.max(x0), y1.max(y0)]
}

/// Depth test and write against the caller's depth target, which must have a depth aspect.
pub fn depth_state(
    stage: &'static str,
    format: wgpu::TextureFormat,
    compare: wgpu::CompareFunction,
) -> Result<wgpu::DepthStencilState, Error> {
    if !format.is_depth_stencil_format() || !format.has_depth_aspect() {
        return Err(Error::Format {
            stage,
            format,
            supported: "a depth format (Depth32Float, Depth24Plus, ...)",
        });
    }
    Ok(wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

/// A render pass over the caller's targets that keeps what they hold.
pub fn load_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    let colour = load_colour(colour);
    encoder.begin_render_pass(&load_desc(label, &colour, depth))
}

/// [`load_pass`] through a recorder: timed under `label` when it carries a profiler.
pub fn load_pass_recorded<'r>(
    rec: &'r mut crate::gpu::Recorder<'_>,
    label: &str,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'r> {
    let colour = load_colour(colour);
    rec.render_pass(&load_desc(label, &colour, depth), label)
}

fn load<T>() -> wgpu::Operations<T> {
    wgpu::Operations {
        load: wgpu::LoadOp::Load,
        store: wgpu::StoreOp::Store,
    }
}

fn load_colour(colour: &wgpu::TextureView) -> [Option<wgpu::RenderPassColorAttachment<'_>>; 1] {
    [Some(wgpu::RenderPassColorAttachment {
        view: colour,
        depth_slice: None,
        resolve_target: None,
        ops: load(),
    })]
}

fn load_desc<'a>(
    label: &'a str,
    colour: &'a [Option<wgpu::RenderPassColorAttachment<'a>>],
    depth: &'a wgpu::TextureView,
) -> wgpu::RenderPassDescriptor<'a> {
    wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: colour,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(load()),
            stencil_ops: None,
        }),
        ..Default::default()
    }
}

/// Colour and depth targets of one size, readable back (`COPY_SRC`) and sampled
/// (`TEXTURE_BINDING`): what a test, the gallery or a benchmark draws into.
pub struct Targets {
    /// The colour target.
    pub colour: wgpu::Texture,
    /// The depth target.
    pub depth: wgpu::Texture,
    /// A view of all of `colour`.
    pub colour_view: wgpu::TextureView,
    /// A view of all of `depth`.
    pub depth_view: wgpu::TextureView,
}

impl Targets {
    /// Targets of `size` in the given formats: render attachments that can also be sampled,
    /// copied from and copied to.
    pub fn new(
        device: &wgpu::Device,
        [width, height]: [u32; 2],
        colour: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
    ) -> Self {
        // Read back by tests, sampled by later stages (the ocean's fade reads the depth), and
        // written by copies (an app putting back a frame it kept: the viewer's last good one).
        let make = |format, label| {
            crate::gpu::texture(
                device,
                label,
                [width, height, 1],
                wgpu::TextureDimension::D2,
                format,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let colour = make(colour, "fieldkit colour target");
        let depth = make(depth, "fieldkit depth target");
        Self {
            colour_view: colour.create_view(&Default::default()),
            depth_view: depth.create_view(&Default::default()),
            colour,
            depth,
        }
    }

    /// Clear both targets.
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder, colour: wgpu::Color, depth: f32) {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("fieldkit clear"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.colour_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(colour),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(crate::gpu::depth_cleared(&self.depth_view, depth)),
            ..Default::default()
        });
    }
}
