//! Drawing the ocean (`ocean/surface`): patches of a grid displaced by the wave sum and the
//! height-map layers, shaded with normal-map layers and depth fade, into one forward colour
//! target or four G-buffer targets, testing and writing your depth target.
//!
//! Depth fade needs the scene's depth behind the water while the water writes depth itself.
//! [`OceanRenderer::encode`] copies the depth target first with a compute pass
//! (`ocean/depth_copy`; the target needs `TEXTURE_BINDING`) and reads the copy, so both happen
//! in one frame, in one draw pass.

use std::sync::Mutex;

use glam::{DMat4, DVec2, DVec3, Mat4, Vec2, Vec3};

use super::Waves;
use super::gpu_lod::{self, GpuLod, LodDraws};
use super::lod::{LodSettings, select};
use super::look::{Look, Maps, detail_texels, layer_uniforms, map_indices};
use super::patches::{Draws, MAX_PATCH_QUADS, Patch, PatchDraw, patch_draws, patch_indices};
use crate::bind::{ComputePipeline, KeptBound, RenderPipeline, RenderTargets};
use crate::error::Error;
use crate::gpu::{KeptView, Record, Recorder, Uploads};
use crate::shaders::ocean::depth_copy;
use crate::shaders::ocean::surface::{self as stage, FrameParams};

pub(super) const STAGE: &str = stage::STAGE;

/// Most height layers and most normal layers.
pub const MAX_LAYERS: usize = 4;
/// Side of the detail texture (texels).
pub const DETAIL_SIZE: u32 = 256;

/// Where the fragments go.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Output {
    /// One lit colour target.
    Forward(wgpu::TextureFormat),
    /// Scene colour (emissive), world normal, metallic/specular/roughness/shading model, base
    /// colour: four targets, in that order.
    GBuffer([wgpu::TextureFormat; 4]),
    /// The four G-buffer targets and a fifth, subsurface colour ([`Look::subsurface_colour`]):
    /// the source's five, in its order (UE's base pass puts its velocity target before
    /// GBufferD when velocity is written there).
    GBufferSubsurface([wgpu::TextureFormat; 5]),
    /// [`Output::GBufferSubsurface`] within WebGPU's default 32 bytes a sample: the material
    /// (target 2) and the subsurface colour (target 4) are `R32Uint`, each four 8-bit unorm
    /// channels packed by WGSL's `pack4x8unorm` (x in the low byte; `unpack4x8unorm` reads them
    /// back). The formats given are the scene colour's, the normal's and the base colour's
    /// (float formats; [`Output::gbuffer_subsurface`] picks ones that fit).
    GBufferSubsurfacePacked([wgpu::TextureFormat; 3]),
}

impl Output {
    /// The four G-buffer targets in [`gpu::GBUFFER_FORMATS`](crate::gpu::GBUFFER_FORMATS):
    /// 32 bytes a sample, within every WebGPU device's limit.
    pub fn gbuffer() -> Self {
        Output::GBuffer(crate::gpu::GBUFFER_FORMATS)
    }

    /// The five targets packed within every WebGPU device's 32 bytes a sample
    /// ([`Output::GBufferSubsurfacePacked`]): scene colour `Rgba16Float`, normal
    /// `Rgb10a2Unorm`, material `R32Uint`, base colour `Rgba8Unorm`, subsurface `R32Uint`.
    pub fn gbuffer_subsurface() -> Self {
        let [scene, normal, _, base] = crate::gpu::GBUFFER_FORMATS;
        Output::GBufferSubsurfacePacked([scene, normal, base])
    }

    /// Colour targets the output writes.
    pub fn targets(&self) -> usize {
        self.formats().len()
    }

    /// The colour targets' formats, in location order: what to make the targets with.
    pub fn formats(&self) -> Vec<wgpu::TextureFormat> {
        match *self {
            Output::Forward(f) => vec![f],
            Output::GBuffer(fs) => fs.to_vec(),
            Output::GBufferSubsurface(fs) => fs.to_vec(),
            Output::GBufferSubsurfacePacked([scene, normal, base]) => {
                let packed = wgpu::TextureFormat::R32Uint;
                vec![scene, normal, packed, base, packed]
            }
        }
    }
}

/// The depth target the ocean tests (and, by default, writes).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct DepthMode {
    /// `Depth32Float` (default), `Depth24Plus`, `Depth24PlusStencil8` or `Depth32FloatStencil8`
    /// (the stencil is left as it is).
    pub format: wgpu::TextureFormat,
    /// Write depth (default). Off is the source's `bUseDepthBlend` choice: the water tests the
    /// scene's depth and leaves it for what is drawn after. The water then does not hide its
    /// own far side: skirts (use [`Look::seed`]'s none) and the backs of steep waves seen at a
    /// grazing angle show through.
    pub write: bool,
}

impl Default for DepthMode {
    fn default() -> Self {
        Self {
            format: wgpu::TextureFormat::Depth32Float,
            write: true,
        }
    }
}

impl DepthMode {
    /// The source's depth: tested, not written.
    pub fn seed() -> Self {
        Self {
            write: false,
            ..Self::default()
        }
    }

    fn check(&self) -> Result<(), Error> {
        use wgpu::TextureFormat as F;
        if !matches!(
            self.format,
            F::Depth32Float | F::Depth24Plus | F::Depth24PlusStencil8 | F::Depth32FloatStencil8
        ) {
            return Err(Error::Format {
                stage: STAGE,
                format: self.format,
                supported: "Depth32Float, Depth24Plus, Depth24PlusStencil8, Depth32FloatStencil8",
            });
        }
        Ok(())
    }
}

/// The camera, in f64 world coordinates: the renderer draws relative to its (x, z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OceanCamera {
    /// World to view.
    pub view: DMat4,
    /// View to clip (the depth convention must match the renderer's `reversed_z`).
    pub proj: Mat4,
}

impl OceanCamera {
    /// A right-handed camera at `eye` looking at `target`, y up, in f64 (as the glam
    /// `look_at` functions build it in f32).
    pub fn look_at(eye: DVec3, target: DVec3, proj: Mat4) -> Self {
        let f = (target - eye).normalize();
        let s = f.cross(DVec3::Y).normalize();
        let u = s.cross(f);
        let view = DMat4::from_cols(
            glam::DVec4::new(s.x, u.x, -f.x, 0.0),
            glam::DVec4::new(s.y, u.y, -f.y, 0.0),
            glam::DVec4::new(s.z, u.z, -f.z, 0.0),
            glam::DVec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        );
        Self { view, proj }
    }

    /// The eye's world position.
    pub fn eye(&self) -> DVec3 {
        self.view.inverse().transform_point3(DVec3::ZERO)
    }
}

/// The ocean's pipelines and detail textures. Create once, encode every frame: a frame makes no
/// GPU object (each draw's patches and parameters are staged through a ring it keeps, with the
/// queue given to `new`; up to [`RING_UPLOADS`](crate::gpu::RING_UPLOADS) draws may wait in one
/// encoder).
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder,
/// #      waves: &fieldkit::ocean::Waves, camera: &fieldkit::ocean::OceanCamera,
/// #      colour: &wgpu::TextureView, depth: &wgpu::Texture, time: f64) -> Result<(), fieldkit::Error> {
/// use fieldkit::ocean::{LodSettings, Look, OceanRenderer, Output};
/// let sea = OceanRenderer::new(device, queue, Output::Forward(wgpu::TextureFormat::Rgba8Unorm), false)?;
/// // Each frame: patches chosen on the GPU, drawn against your Depth32Float target.
/// sea.encode_lod(device, encoder, waves, time, camera, &Look::default(), &LodSettings::default(),
///     &[colour], depth, false)?;
/// # Ok(()) }
/// ```
pub struct OceanRenderer {
    output: Output,
    reversed_z: bool,
    depth: DepthMode,
    pipeline: Pipeline,
    /// What a frame draws with, kept from frame to frame: no object made a frame.
    kept: Kept,
    height_maps: Maps,
    normal_maps: Maps,
    /// Index buffers per quad count, made on first use.
    indices: Mutex<std::collections::HashMap<u32, wgpu::Buffer>>,
    /// The built-in detail texture's view.
    detail_view: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// The copy of the scene's depth the fade reads (`R32Float`) and its view, kept while it
    /// still serves the depth's size.
    depth_copy: Mutex<Option<(wgpu::Texture, wgpu::TextureView)>>,
    copy_depth: ComputePipeline<depth_copy::copy_depth::Entry>,
    /// The patches chosen on the GPU, where the device can draw them.
    gpu_lod: Option<GpuLod>,
}

/// The ocean's per-frame objects, made on the first frame (or when a size grows) and reused:
/// the patch instances and the two uniforms, written through `uploads`; the views of the
/// caller's depth target; the bind groups of both passes.
struct Kept {
    uploads: Uploads,
    instances: Mutex<Option<wgpu::Buffer>>,
    waves: Mutex<Option<wgpu::Buffer>>,
    frame: Mutex<Option<wgpu::Buffer>>,
    depth_view: KeptView,
    depth_in: KeptView,
    copy_bound: KeptBound<depth_copy::copy_depth::Entry>,
    /// What the last GPU selection drew from.
    last_lod: Mutex<Option<LodDraws>>,
}

/// What [`OceanRenderer::begin`] leaves for the draw.
struct FrameBuffers {
    /// The eye's (x, z): positions are relative to it.
    origin: DVec2,
    waves: wgpu::Buffer,
    frame: wgpu::Buffer,
    copy_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

/// The surface's pipeline: one per [`Output`].
enum Pipeline {
    Forward(Surface<stage::fs_forward::Entry>),
    GBuffer(Surface<stage::fs_gbuffer::Entry>),
    GBufferSubsurface(Surface<stage::fs_gbuffer_subsurface::Entry>),
    GBufferSubsurfacePacked(Surface<stage::fs_gbuffer_subsurface_packed::Entry>),
}

/// The surface pipeline for one fragment entry, and the bind groups it drew with last.
struct Surface<E> {
    pipeline: RenderPipeline<E>,
    bound: KeptBound<E>,
}

impl<E: crate::bind::Entry> Surface<E> {
    fn new(device: &wgpu::Device, targets: &RenderTargets<'_>) -> Result<Self, Error> {
        Ok(Self {
            pipeline: RenderPipeline::new(device, targets)?,
            bound: KeptBound::default(),
        })
    }
}

impl OceanRenderer {
    /// Pipelines for `output`, testing and writing a `Depth32Float` target (`reversed_z`: the
    /// nearer surface has the larger depth).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        output: Output,
        reversed_z: bool,
    ) -> Result<Self, Error> {
        Self::with_depth(device, queue, output, reversed_z, DepthMode::default())
    }

    /// [`OceanRenderer::new`] for another depth format, or testing depth without writing it
    /// ([`DepthMode::seed`]).
    pub fn with_depth(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        output: Output,
        reversed_z: bool,
        depth: DepthMode,
    ) -> Result<Self, Error> {
        depth.check()?;
        let needs = depth.format.required_features();
        if !device.features().contains(needs) {
            return Err(Error::Unsupported {
                stage: STAGE,
                what: format!(
                    "{:?} depth needs the device feature {needs:?}",
                    depth.format
                ),
            });
        }
        let depth_stencil = Some(wgpu::DepthStencilState {
            format: depth.format,
            depth_write_enabled: Some(depth.write),
            depth_compare: Some(if reversed_z {
                wgpu::CompareFunction::Greater
            } else {
                wgpu::CompareFunction::Less
            }),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let target = |f| {
            Some(wgpu::ColorTargetState {
                format: f,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let color: Vec<_> = output.formats().into_iter().map(target).collect();
        let targets = RenderTargets {
            color: &color,
            depth_stencil,
            ..Default::default()
        };
        let pipeline = match output {
            Output::Forward(_) => Pipeline::Forward(Surface::new(device, &targets)?),
            Output::GBuffer(_) => Pipeline::GBuffer(Surface::new(device, &targets)?),
            Output::GBufferSubsurface(_) => {
                Pipeline::GBufferSubsurface(Surface::new(device, &targets)?)
            }
            Output::GBufferSubsurfacePacked(_) => {
                Pipeline::GBufferSubsurfacePacked(Surface::new(device, &targets)?)
            }
        };
        use wgpu::util::DeviceExt;
        let texels: Vec<u8> = detail_texels(DETAIL_SIZE, 7)
            .iter()
            .flat_map(|v| v.to_array())
            .flat_map(|c| half::f16::from_f32(c).to_le_bytes())
            .collect();
        let detail = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("ocean detail"),
                size: wgpu::Extent3d {
                    width: DETAIL_SIZE,
                    height: DETAIL_SIZE,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &texels,
        );
        Ok(Self {
            output,
            reversed_z,
            depth,
            pipeline,
            kept: Kept {
                uploads: Uploads::new(queue),
                instances: Mutex::new(None),
                waves: Mutex::new(None),
                frame: Mutex::new(None),
                depth_view: KeptView::default(),
                depth_in: KeptView::default(),
                copy_bound: KeptBound::default(),
                last_lod: Mutex::new(None),
            },
            height_maps: Maps::none(device, "ocean height maps (none)"),
            normal_maps: Maps::none(device, "ocean normal maps (none)"),
            indices: Mutex::new(Default::default()),
            detail_view: detail.create_view(&Default::default()),
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("ocean detail"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            depth_copy: Mutex::new(None),
            copy_depth: ComputePipeline::new(device)?,
            // Without depth writes, the order of the patches decides what is seen where the
            // water overlaps itself on screen: the CPU lists them nearest first, every frame
            // the same; the GPU's selection in no fixed order, which would flicker there.
            gpu_lod: (gpu_lod::supported(device) && depth.write)
                .then(|| GpuLod::new(device))
                .transpose()?,
        })
    }

    /// Where this renderer's fragments go.
    pub fn output(&self) -> Output {
        self.output
    }

    /// Whether the depth test keeps the larger depth (reversed Z).
    pub fn reversed_z(&self) -> bool {
        self.reversed_z
    }

    /// The depth target's format and whether the water writes it.
    pub fn depth_mode(&self) -> DepthMode {
        self.depth
    }

    /// Your own detail maps, as the source scrolls its own textures: `heights` a 2D texture
    /// (array) of heights in r (`R8Unorm`, `R16Float`, `Rgba8Unorm` or `Rgba16Float`), `normals`
    /// one of tangent-space normals × ½ + ½ in rgb, +y along +z (`Rgba8Unorm` or
    /// `Rgba16Float`), each with `TEXTURE_BINDING`; one map per array layer, sampled with
    /// repeat and linear filtering. A layer picks its map with [`Layer::map`](super::Layer::map) (its tile,
    /// velocity and strength as for the built-in detail); `None` keeps the built-in one. A
    /// texture of another format or dimension is a typed error. Replaces earlier maps.
    pub fn set_maps(
        &mut self,
        device: &wgpu::Device,
        heights: Option<&wgpu::Texture>,
        normals: Option<&wgpu::Texture>,
    ) -> Result<(), Error> {
        use wgpu::TextureFormat as F;
        let heights = match heights {
            Some(t) => Maps::user(
                t,
                "height",
                &[F::R8Unorm, F::R16Float, F::Rgba8Unorm, F::Rgba16Float],
                "R8Unorm, R16Float, Rgba8Unorm, Rgba16Float (height in r)",
            )?,
            None => Maps::none(device, "ocean height maps (none)"),
        };
        let normals = match normals {
            Some(t) => Maps::user(
                t,
                "normal",
                &[F::Rgba8Unorm, F::Rgba16Float],
                "Rgba8Unorm, Rgba16Float (tangent-space normal × ½ + ½)",
            )?,
            None => Maps::none(device, "ocean normal maps (none)"),
        };
        self.height_maps = heights;
        self.normal_maps = normals;
        Ok(())
    }

    /// Draw `patches` of `waves` at `time` seen by `camera` into `targets` (one view for
    /// [`Output::Forward`], four for [`Output::GBuffer`], all the depth target's size), loading
    /// and storing what they hold, and testing and writing `depth` (`Depth32Float`, with
    /// `RENDER_ATTACHMENT` and, when `fade` is on, `TEXTURE_BINDING`: a compute pass copies it
    /// for the fade to read). [`Self::encode_lod`] chooses the patches on the GPU instead.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        waves: &Waves,
        time: f64,
        camera: &OceanCamera,
        look: &Look,
        patches: &[Patch],
        targets: &[&wgpu::TextureView],
        depth: &wgpu::Texture,
        fade: bool,
    ) -> Result<(), Error> {
        self.check_encode(time, camera, look, patches, targets, depth, fade)?;
        let rec = &mut rec.recorder();
        let frame = self.begin(device, rec, waves, time, camera, look, depth, fade)?;
        if patches.is_empty() {
            return Ok(());
        }
        let (instances, draws) = patch_draws(patches, frame.origin);
        let parts = self.index_buffers(device, draws);
        let instances = self.kept.uploads.kept(
            device,
            rec.encoder,
            &self.kept.instances,
            "ocean patches",
            wgpu::BufferUsages::VERTEX,
            bytemuck::cast_slice(&instances),
        );
        self.draw(
            device,
            rec,
            &frame,
            targets,
            &instances,
            Draws::Listed(&parts),
        )
    }

    /// [`Self::encode`] with the patches [`select`](super::select) would choose for `lod`
    /// (at the depth target's height), chosen on the GPU: a compute pass walks the quadtree and
    /// leaves indirect draws, so the CPU's share of a frame does not grow with what the camera
    /// sees. Needs [`wgpu::Features::INDIRECT_FIRST_INSTANCE`] on the device and a renderer
    /// that writes depth (the GPU lists the patches in no fixed order, and without depth
    /// writes the order decides what is seen where the water overlaps itself); otherwise the
    /// patches are chosen by [`select`](super::select) on the CPU and drawn the same way
    /// ([`Self::lod_on_gpu`] says which). Errors as [`select`](super::select) for settings it refuses, and
    /// [`Error::Size`] where more than [`MAX_LOD_NODES`](super::MAX_LOD_NODES) nodes would be
    /// looked at.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_lod(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        waves: &Waves,
        time: f64,
        camera: &OceanCamera,
        look: &Look,
        lod: &LodSettings,
        targets: &[&wgpu::TextureView],
        depth: &wgpu::Texture,
        fade: bool,
    ) -> Result<(), Error> {
        let Some(gpu) = &self.gpu_lod else {
            let chosen = select(waves, look, camera, depth.height(), lod)?;
            let patches = &chosen.patches;
            return self.encode(
                device, rec, waves, time, camera, look, patches, targets, depth, fade,
            );
        };
        self.check_encode(time, camera, look, &[], targets, depth, fade)?;
        let rec = &mut rec.recorder();
        let frame = self.begin(device, rec, waves, time, camera, look, depth, fade)?;
        let uploads = &self.kept.uploads;
        let chosen = gpu.encode(
            device,
            rec,
            uploads,
            waves,
            look,
            camera,
            depth.height(),
            lod,
        )?;
        let draws = Draws::Indirect(&chosen);
        self.draw(device, rec, &frame, targets, &chosen.drawn.instances, draws)?;
        *self.kept.last_lod.lock().unwrap_or_else(|e| e.into_inner()) = Some(chosen.drawn);
        Ok(())
    }

    /// Whether [`Self::encode_lod`] chooses the patches on the GPU on this renderer's device.
    pub fn lod_on_gpu(&self) -> bool {
        self.gpu_lod.is_some()
    }

    /// The buffers the last [`Self::encode_lod`] drew from on the GPU (`None` before one, or
    /// where the patches are chosen on the CPU): read them back after its submission to see
    /// the patches ([`LodDraws::patches`]). The next `encode_lod` writes them again.
    pub fn last_lod(&self) -> Option<LodDraws> {
        self.kept
            .last_lod
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// A frame's uniforms (staged through the ring) and depth views, the scene's depth copied
    /// for the fade: everything the draw reads but the patches.
    #[allow(clippy::too_many_arguments)]
    fn begin(
        &self,
        device: &wgpu::Device,
        rec: &mut Recorder<'_>,
        waves: &Waves,
        time: f64,
        camera: &OceanCamera,
        look: &Look,
        depth: &wgpu::Texture,
        fade: bool,
    ) -> Result<FrameBuffers, Error> {
        // Everything relative to the eye's (x, z): f32 sees small numbers.
        let eye = camera.eye();
        let origin = DVec2::new(eye.x, eye.z);
        let wave_set = waves.gpu(origin, time);
        let viewport = Vec2::new(depth.width() as f32, depth.height() as f32);
        let frame = self.frame_params(camera, look, origin, time, fade, viewport)?;
        let copy_view = self.scene_depth(device, rec, depth, fade)?;
        let kept = &self.kept;
        let (up, enc) = (&kept.uploads, &mut *rec.encoder);
        Ok(FrameBuffers {
            origin,
            waves: up.uniform(device, enc, &kept.waves, "ocean waves", &wave_set),
            frame: up.uniform(device, enc, &kept.frame, "ocean frame", &frame),
            copy_view,
            depth_view: kept
                .depth_view
                .get(depth, |d| d.create_view(&Default::default())),
        })
    }

    /// The surface's render pass: `draws` of `instances` into `targets`.
    fn draw(
        &self,
        device: &wgpu::Device,
        rec: &mut Recorder<'_>,
        frame: &FrameBuffers,
        targets: &[&wgpu::TextureView],
        instances: &wgpu::Buffer,
        draws: Draws<'_>,
    ) -> Result<(), Error> {
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = targets
            .iter()
            .map(|v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })
            })
            .collect();
        let desc = wgpu::RenderPassDescriptor {
            label: Some(STAGE),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &frame.depth_view,
                // Read-only where the water does not write depth.
                depth_ops: self.depth.write.then_some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                // The stencil (where the format has one) is left as it is.
                stencil_ops: None,
            }),
            ..Default::default()
        };
        macro_rules! draw {
            ($surface:expr, $module:ident) => {{
                let bound = $surface.pipeline.bind_kept(
                    device,
                    &$surface.bound,
                    &stage::$module::Resources {
                        waves: (&frame.waves).into(),
                        frame: (&frame.frame).into(),
                        detail: (&self.detail_view).into(),
                        detail_sampler: (&self.sampler).into(),
                        scene_depth: (&frame.copy_view).into(),
                        height_maps: (&self.height_maps.view).into(),
                        normal_maps: (&self.normal_maps.view).into(),
                    },
                )?;
                let mut pass = rec.render_pass(&desc, "ocean surface");
                pass.set_pipeline(&$surface.pipeline.pipeline);
                bound.set_render(&mut pass);
                pass.set_vertex_buffer(0, instances.slice(..));
                draws.record(&mut pass);
            }};
        }
        match &self.pipeline {
            Pipeline::Forward(p) => draw!(p, fs_forward),
            Pipeline::GBuffer(p) => draw!(p, fs_gbuffer),
            Pipeline::GBufferSubsurface(p) => draw!(p, fs_gbuffer_subsurface),
            Pipeline::GBufferSubsurfacePacked(p) => draw!(p, fs_gbuffer_subsurface_packed),
        }
        Ok(())
    }

    /// The checks of [`Self::encode`]'s inputs, each a typed error naming what was wrong.
    #[allow(clippy::too_many_arguments)]
    fn check_encode(
        &self,
        time: f64,
        camera: &OceanCamera,
        look: &Look,
        patches: &[Patch],
        targets: &[&wgpu::TextureView],
        depth: &wgpu::Texture,
        fade: bool,
    ) -> Result<(), Error> {
        look.check()?;
        if !time.is_finite() {
            return Err(Error::invalid(
                STAGE,
                format!("time must be finite, got {time}"),
            ));
        }
        if !(camera.view.is_finite() && camera.proj.is_finite()) {
            return Err(Error::invalid(
                STAGE,
                "the camera's matrices must be finite",
            ));
        }
        for (i, p) in patches.iter().enumerate() {
            if !(p.corner.is_finite()
                && p.size.is_finite()
                && p.size > 0.0
                && (1..=MAX_PATCH_QUADS).contains(&p.quads))
            {
                return Err(Error::invalid(
                    STAGE,
                    format!(
                        "patch {i}: corner must be finite, size > 0 and quads 1 to {MAX_PATCH_QUADS}, got {p:?}"
                    ),
                ));
            }
        }
        let want = self.output.targets();
        if targets.len() != want {
            return Err(Error::invalid(
                STAGE,
                format!("{} targets given, the output takes {want}", targets.len()),
            ));
        }
        for (i, (v, f)) in targets.iter().zip(self.output.formats()).enumerate() {
            if v.texture().format().remove_srgb_suffix() != f.remove_srgb_suffix() {
                return Err(Error::invalid(
                    STAGE,
                    format!(
                        "target {i} is {:?}; this renderer's output writes {f:?} there \
                         (Output::formats)",
                        v.texture().format()
                    ),
                ));
            }
        }
        if depth.format() != self.depth.format {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the depth target is {:?}; this renderer was made for {:?} (OceanRenderer::with_depth)",
                    depth.format(),
                    self.depth.format
                ),
            ));
        }
        let needs = wgpu::TextureUsages::RENDER_ATTACHMENT
            | if fade {
                wgpu::TextureUsages::TEXTURE_BINDING
            } else {
                wgpu::TextureUsages::empty()
            };
        if !depth.usage().contains(needs) {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the depth target needs {needs:?} (depth fade reads a copy of it), it has {:?}",
                    depth.usage()
                ),
            ));
        }
        let size = depth.size();
        for (i, t) in targets.iter().enumerate() {
            let e = t.texture().size();
            if (e.width, e.height) != (size.width, size.height) {
                return Err(Error::invalid(
                    STAGE,
                    format!(
                        "target {i} is {}×{}, the depth target {}×{}",
                        e.width, e.height, size.width, size.height
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The frame's uniforms: the camera with the eye's (x, z) at `origin` taken off, the look,
    /// the detail layers at `time`.
    fn frame_params(
        &self,
        camera: &OceanCamera,
        look: &Look,
        origin: DVec2,
        time: f64,
        fade: bool,
        viewport: Vec2,
    ) -> Result<FrameParams, Error> {
        let height_maps = map_indices(&look.height_layers, &self.height_maps, "height")?;
        let normal_maps = map_indices(&look.normal_layers, &self.normal_maps, "normal")?;
        let eye = camera.eye();
        let shift = DMat4::from_translation(DVec3::new(origin.x, 0.0, origin.y));
        let view = (camera.view * shift).as_mat4();
        Ok(FrameParams {
            view_proj: camera.proj * view,
            inv_proj: camera.proj.inverse(),
            camera: Vec3::new(0.0, eye.y as f32, 0.0),
            skirt: look.skirt,
            height_layers: layer_uniforms(&look.height_layers, origin, time),
            normal_layers: layer_uniforms(&look.normal_layers, origin, time),
            height_layer_count: look.height_layers.len() as u32,
            normal_layer_count: look.normal_layers.len() as u32,
            fade_distance: look.fade_distance,
            roughness: look.roughness,
            sun_direction: look.sun_direction.normalize(),
            shading_model: look.shading_model as u32,
            sun_colour: look.sun_colour,
            use_fade: fade as u32,
            deep_colour: look.deep_colour,
            metallic: look.metallic,
            shallow_colour: look.shallow_colour,
            specular: look.specular,
            sky_colour: look.sky_colour,
            subsurface_colour: look.subsurface_colour,
            height_maps,
            normal_maps,
            viewport,
        })
    }

    /// The copy of the scene's depth the fade reads (a 1×1 stand-in without fade), kept from
    /// frame to frame while it still serves the depth's size
    /// ([`gpu::screen_fits`](crate::gpu::screen_fits): a window resized by a little keeps
    /// it): its view.
    fn scene_depth(
        &self,
        device: &wgpu::Device,
        rec: &mut Recorder<'_>,
        depth: &wgpu::Texture,
        fade: bool,
    ) -> Result<wgpu::TextureView, Error> {
        let size = depth.size();
        let mut cache = self.depth_copy.lock().unwrap_or_else(|e| e.into_inner());
        let kept = |c: &wgpu::Texture| {
            let have = [c.width(), c.height()];
            match fade {
                true => crate::gpu::screen_fits(have, [size.width, size.height]),
                false => have == [1, 1],
            }
        };
        if cache.as_ref().is_none_or(|c| !kept(&c.0)) {
            let [width, height] = match fade {
                true => crate::gpu::screen_rounded([size.width, size.height]),
                false => [1, 1],
            };
            // The old copy goes first, so its memory can hold the new one.
            *cache = None;
            let copy = crate::gpu::texture(
                device,
                "ocean scene depth copy",
                [width, height, 1],
                wgpu::TextureDimension::D2,
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
            );
            let view = copy.create_view(&Default::default());
            *cache = Some((copy, view));
        }
        let copy_view = cache.as_ref().expect("made above").1.clone();
        drop(cache);
        if fade {
            let depth_in = self.kept.depth_in.get(depth, |d| {
                d.create_view(&wgpu::TextureViewDescriptor {
                    aspect: wgpu::TextureAspect::DepthOnly,
                    ..Default::default()
                })
            });
            let resources = depth_copy::copy_depth::Resources {
                depth_in: (&depth_in).into(),
                depth_out: (&copy_view).into(),
            };
            let bound = self
                .copy_depth
                .bind_kept(device, &self.kept.copy_bound, &resources)?;
            let groups = ComputePipeline::<depth_copy::copy_depth::Entry>::groups_for([
                size.width,
                size.height,
                1,
            ]);
            let mut pass = rec.compute_pass(depth_copy::STAGE, depth_copy::STAGE);
            self.copy_depth.dispatch(&mut pass, &bound, groups);
        }
        Ok(copy_view)
    }

    /// One index buffer per quad count of `draws` (made once, kept), with each draw's index
    /// and instance ranges.
    fn index_buffers(
        &self,
        device: &wgpu::Device,
        draws: Vec<PatchDraw>,
    ) -> Vec<(wgpu::Buffer, std::ops::Range<u32>, std::ops::Range<u32>)> {
        use wgpu::util::DeviceExt;
        let mut cache = self.indices.lock().unwrap_or_else(|e| e.into_inner());
        draws
            .into_iter()
            .map(|(q, first, count, range)| {
                let buffer = cache.entry(q).or_insert_with(|| {
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("ocean patch indices"),
                        contents: bytemuck::cast_slice(&patch_indices(q)),
                        usage: wgpu::BufferUsages::INDEX,
                    })
                });
                (buffer.clone(), first..first + count, range)
            })
            .collect()
    }
}
