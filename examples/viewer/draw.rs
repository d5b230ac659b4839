//! The viewer's own drawing, beside fieldkit's: a textured rectangle (the 2D field) and
//! coloured lines (the ocean's patch quadtree). Plain wgpu, as an application writes it.

use fieldkit::gpu::Recorder;
use glam::{Mat4, Vec3, Vec4};

const BLIT_WGSL: &str = r#"
// The rectangle as fractions of the target (for the vertices) and in whole pixels (for the
// texel each pixel shows: integer arithmetic, so every GPU picks the same texel even where a
// pixel centre falls exactly on a texel boundary).
struct Rect { lo: vec2<f32>, hi: vec2<f32>, lo_px: vec2<u32>, size_px: vec2<u32> }
@group(0) @binding(0) var<uniform> rect: Rect;
@group(0) @binding(1) var image: texture_2d<f32>;

struct Out { @builtin(position) position: vec4<f32>, @location(0) uv: vec2<f32> }

@vertex
fn vs(@builtin(vertex_index) i: u32) -> Out {
    var corners = array(vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
                        vec2(0.0, 0.0), vec2(1.0, 1.0), vec2(0.0, 1.0));
    let uv = corners[i];
    let p = mix(rect.lo, rect.hi, uv);
    return Out(vec4(p.x * 2.0 - 1.0, 1.0 - p.y * 2.0, 0.0, 1.0), uv);
}

@fragment
fn fs(v: Out) -> @location(0) vec4<f32> {
    let size = textureDimensions(image);
    // The pixel centre k + ½ truncates to k.
    let p = vec2<u32>(v.position.xy);
    let rel = max(p, rect.lo_px) - rect.lo_px;
    let texel = min(rel * size / max(rect.size_px, vec2(1u)), size - 1u);
    return textureLoad(image, texel, 0);
}
"#;

const LINES_WGSL: &str = r#"
struct Camera { view_proj: mat4x4<f32> }
@group(0) @binding(0) var<uniform> camera: Camera;

struct Out { @builtin(position) position: vec4<f32>, @location(0) colour: vec4<f32> }

@vertex
fn vs(@location(0) p: vec3<f32>, @location(1) c: vec4<f32>) -> Out {
    return Out(camera.view_proj * vec4(p, 1.0), c);
}

@fragment
fn fs(v: Out) -> @location(0) vec4<f32> { return v.colour; }
"#;

/// Draws an RGBA8 image into a rectangle of the colour target (nearest texel, no blending).
/// A redraw of the same image into the same rectangle makes no GPU object and writes nothing:
/// the rectangle is written only when it changes, the bind group made only for a new image.
pub struct Blit {
    pipeline: wgpu::RenderPipeline,
    rect: wgpu::Buffer,
    /// What `rect` holds.
    written: std::cell::Cell<Option<[u32; 8]>>,
    /// The bind group of the image drawn last.
    group: std::cell::RefCell<Option<(wgpu::TextureView, wgpu::BindGroup)>>,
}

impl Blit {
    /// For a colour target of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let pipeline = fieldkit::harness::wgsl_pipeline(
            device,
            "viewer blit",
            BLIT_WGSL,
            format,
            None,
            &[],
            Default::default(),
        );
        let rect = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewer blit rect"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Self {
            pipeline,
            rect,
            written: Default::default(),
            group: Default::default(),
        }
    }

    /// Draw `image` into `rect` = [x0, y0, x1, y1] (fractions of the `size` target, y down).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rec: &mut Recorder<'_>,
        target: &wgpu::TextureView,
        size: [u32; 2],
        image: &wgpu::TextureView,
        rect: [f32; 4],
    ) {
        // Snap the rectangle to whole pixels, and hand the shader both forms.
        let px = |f: f32, s: u32| (f * s as f32).round().max(0.0) as u32;
        let (x0, y0) = (px(rect[0], size[0]), px(rect[1], size[1]));
        let (x1, y1) = (px(rect[2], size[0]), px(rect[3], size[1]));
        let snapped = [
            x0 as f32 / size[0] as f32,
            y0 as f32 / size[1] as f32,
            x1 as f32 / size[0] as f32,
            y1 as f32 / size[1] as f32,
        ];
        let mut words = [0u32; 8];
        for (w, f) in words.iter_mut().zip(snapped) {
            *w = f.to_bits();
        }
        words[4..].copy_from_slice(&[x0, y0, x1.saturating_sub(x0), y1.saturating_sub(y0)]);
        if self.written.get() != Some(words) {
            queue.write_buffer(&self.rect, 0, bytemuck::cast_slice(&words));
            self.written.set(Some(words));
        }
        let mut group = self.group.borrow_mut();
        if group.as_ref().map(|g| &g.0) != Some(image) {
            let made = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("viewer blit"),
                layout: &self.pipeline.get_bind_group_layout(0),
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: self.rect.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(image),
                    },
                ],
            });
            *group = Some((image.clone(), made));
        }
        let mut pass = colour_pass(rec, "viewer blit", target);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group.as_ref().expect("made above").1, &[]);
        pass.draw(0..6, 0..1);
    }
}

/// Coloured line segments in world space, drawn over the scene without a depth test. A
/// frame's draw makes nothing: the vertices go into a kept buffer (grown when a frame has
/// more), the camera's bind group is made once. Drawn once a frame (a second draw in one
/// encoder would overwrite the first's vertices and camera).
pub struct Lines {
    pipeline: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    group: wgpu::BindGroup,
    vertices: std::sync::Mutex<Option<wgpu::Buffer>>,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    p: [f32; 3],
    c: [f32; 4],
}

impl Lines {
    /// For a colour target of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Self {
        let pipeline = fieldkit::harness::wgsl_pipeline(
            device,
            "viewer lines",
            LINES_WGSL,
            format,
            None,
            &[Some(wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<Vertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x4],
            })],
            wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::LineList,
                ..Default::default()
            },
        );
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewer lines camera"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewer lines"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        Self {
            pipeline,
            camera,
            group,
            vertices: Default::default(),
        }
    }

    /// Draw `segments` (pairs of points) in `colour`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        rec: &mut Recorder<'_>,
        target: &wgpu::TextureView,
        view_proj: Mat4,
        segments: &[[Vec3; 2]],
        colour: Vec4,
    ) {
        if segments.is_empty() {
            return;
        }
        let vertices: Vec<Vertex> = segments
            .iter()
            .flatten()
            .map(|p| Vertex {
                p: p.to_array(),
                c: colour.to_array(),
            })
            .collect();
        let bytes: &[u8] = bytemuck::cast_slice(&vertices);
        let buffer = {
            let mut kept = self.vertices.lock().unwrap_or_else(|e| e.into_inner());
            if kept.as_ref().is_none_or(|b| b.size() < bytes.len() as u64) {
                *kept = Some(device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("viewer lines"),
                    // Room to grow: a few more segments next frame make no new buffer.
                    size: (bytes.len() as u64).next_power_of_two(),
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }));
            }
            kept.clone().expect("made above")
        };
        queue.write_buffer(&buffer, 0, bytes);
        queue.write_buffer(&self.camera, 0, bytemuck::bytes_of(&view_proj));
        let mut pass = colour_pass(rec, "viewer lines", target);
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, buffer.slice(..bytes.len() as u64));
        pass.draw(0..vertices.len() as u32, 0..1);
    }
}

/// A render pass over `target` alone that keeps what it holds.
/// Timed under `label` when the frame is profiled.
fn colour_pass<'e>(
    rec: &'e mut Recorder<'_>,
    label: &str,
    target: &wgpu::TextureView,
) -> wgpu::RenderPass<'e> {
    rec.render_pass(
        &wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        },
        label,
    )
}
