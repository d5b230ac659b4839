//! Drawing a metaball field: the full-screen SDF raymarch and the debug voxel cubes, both into a
//! caller's colour and depth targets so they composite with the caller's scene.
//!

use glam::{Mat4, Vec3, Vec4};

use super::{BlobBins, MarchField, MetaballField};
use crate::bind::{ComputePipeline, KeptBound, RenderPipeline, RenderTargets};
use crate::error::Error;
use crate::gpu::{KeptView, Record, Uploads};
use crate::shaders::metaball::{blob_trace, composite, sdf_raymarch};
use crate::view::{View, box_visible, depth_state, load_pass_recorded, screen_rect};

use super::ray_settings::direct_step_cap;
pub use super::ray_settings::{Filter, Output, RayEnd, RaymarchSettings};

/// The march's output mode for a G-buffer: world normal and packed base colour.
const GBUFFER_MODE: u32 = 5;

/// The pile colour for the shaders: rgb, and w = 1 where it is set (0: lighten the base).
fn pile(settings: &RaymarchSettings) -> Vec4 {
    settings.pile_colour.map_or(Vec4::ZERO, |c| c.extend(1.0))
}

/// An affine placement: finite, invertible, no projective row. Scale (non-uniform too),
/// rotation, mirroring and translation are all fine: the march runs in local space, where the
/// SDF's distances are lengths, and normals go back through the inverse transpose.
fn check_placement(m: Mat4, stage: &'static str) -> Result<(), Error> {
    let det = glam::Mat3::from_mat4(m).determinant();
    let affine = m.is_finite() && m.row(3).abs_diff_eq(Vec4::W, 1e-6);
    // A singular matrix (a zero scale) squashes the volume flat: nothing to march.
    let invertible = det.is_finite() && det.abs() > 1e-12 && m.inverse().is_finite();
    if !(affine && invertible) {
        return Err(Error::Invalid {
            stage,
            what: format!(
                "local_to_world must be affine and invertible (rotation, scale, translation; \
                 last row 0 0 0 1), got {m} with determinant {det}"
            ),
        });
    }
    Ok(())
}

/// The march's output images, kept between frames while a resized target still fits them.
struct Scratch {
    size: [u32; 2],
    colour: wgpu::TextureView,
    depth: wgpu::TextureView,
    /// Marches recorded into these images so far: a [`Marched`] is current while it holds the
    /// latest number.
    marches: std::sync::atomic::AtomicU64,
}

impl Scratch {
    fn new(device: &wgpu::Device, size: [u32; 2]) -> Self {
        let make = |label, format| {
            crate::gpu::texture(
                device,
                label,
                [size[0], size[1], 1],
                wgpu::TextureDimension::D2,
                format,
                wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            )
            .create_view(&Default::default())
        };
        Self {
            size,
            colour: make("raymarch colour", wgpu::TextureFormat::Rgba32Float),
            depth: make("raymarch depth", wgpu::TextureFormat::R32Float),
            marches: std::sync::atomic::AtomicU64::new(0),
        }
    }
}

/// The surface's material in a G-buffer ([`Raymarcher::gbuffer`]): the third target holds
/// (metallic, specular, roughness, shading model / 255), as the ocean's does.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct Material {
    /// 0 (dielectric) to 1.
    pub metallic: f32,
    /// Specular level, 0–1 (0.5 is a dielectric's 4%).
    pub specular: f32,
    /// 0 (mirror) to 1.
    pub roughness: f32,
    /// The renderer's shading-model id.
    pub shading_model: u8,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            metallic: 0.0,
            specular: 0.5,
            roughness: 0.5,
            shading_model: 1,
        }
    }
}

impl Material {
    fn check(&self) -> Result<(), Error> {
        for (what, v) in [
            ("metallic", self.metallic),
            ("specular", self.specular),
            ("roughness", self.roughness),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::Invalid {
                    stage: composite::STAGE,
                    what: format!("material {what} must be in [0, 1], got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// Where the raymarcher's composite writes.
enum Composite {
    /// One lit colour target.
    Forward(RenderPipeline<composite::fs_main::Entry>),
    /// Four G-buffer targets.
    GBuffer(RenderPipeline<composite::fs_gbuffer::Entry>),
}

/// The SDF raymarch for one colour and depth format: a compute pass marches and shades the
/// box's screen rectangle, and a scissored full-screen draw writes the hits into the caller's
/// targets through their depth test. [`Raymarcher::gbuffer`] writes a G-buffer instead, so the
/// surface takes the scene's own lighting. A frame makes no GPU object: the view's parameters
/// are staged through a ring it keeps (with the queue given to `new`; up to
/// [`RING_UPLOADS`](crate::gpu::RING_UPLOADS) marches may wait in one encoder).
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder,
/// #      field: &fieldkit::metaball::MetaballField, view: &fieldkit::view::View,
/// #      colour: &wgpu::TextureView, depth: &wgpu::TextureView) -> Result<(), fieldkit::Error> {
/// use fieldkit::metaball::{RaymarchSettings, Raymarcher};
/// // Once, for your targets' formats (standard depth: `reversed_z` false).
/// let marcher = Raymarcher::new(device, queue, wgpu::TextureFormat::Rgba8Unorm,
///     wgpu::TextureFormat::Depth32Float, false)?;
/// // Each frame, into your encoder: colour and depth where the surface is nearer.
/// marcher.encode(device, encoder, colour, depth, field, fieldkit::glam::Mat4::IDENTITY, view,
///     &RaymarchSettings::default())?;
/// # Ok(()) }
/// ```
pub struct Raymarcher {
    march: ComputePipeline<sdf_raymarch::march::Entry>,
    direct: ComputePipeline<blob_trace::trace_blobs::Entry>,
    composite: Composite,
    reversed_z: bool,
    sampler: wgpu::Sampler,
    /// The `shared/blobs` group bound where a field has no blobs.
    no_blobs: crate::bind::Group<crate::shaders::groups::blobs::Entry>,
    scratch: std::sync::Mutex<Option<std::sync::Arc<Scratch>>>,
    /// What a frame draws with, kept from frame to frame: no object made a frame.
    kept: Kept,
}

/// The raymarcher's per-frame parameters (written through an upload ring), the view of the
/// field it marches and the bind groups of its passes, kept from frame to frame.
struct Kept {
    uploads: Uploads,
    march_params: std::sync::Mutex<Option<wgpu::Buffer>>,
    trace_params: std::sync::Mutex<Option<wgpu::Buffer>>,
    material: std::sync::Mutex<Option<wgpu::Buffer>>,
    field_view: KeptView,
    march: KeptBound<sdf_raymarch::march::Entry>,
    trace: KeptBound<blob_trace::trace_blobs::Entry>,
    forward: KeptBound<composite::fs_main::Entry>,
    gbuffer: KeptBound<composite::fs_gbuffer::Entry>,
}

impl Kept {
    fn new(queue: &wgpu::Queue) -> Self {
        Self {
            uploads: Uploads::new(queue),
            march_params: Default::default(),
            trace_params: Default::default(),
            material: Default::default(),
            field_view: KeptView::default(),
            march: KeptBound::default(),
            trace: KeptBound::default(),
            forward: KeptBound::default(),
            gbuffer: KeptBound::default(),
        }
    }

    /// The uniform kept in `slot` holding `value` from the copy recorded now into `rec`.
    fn uniform<T: encase::ShaderType + encase::internal::WriteInto>(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        slot: &std::sync::Mutex<Option<wgpu::Buffer>>,
        label: &str,
        value: &T,
    ) -> wgpu::Buffer {
        self.uploads
            .uniform(device, rec.recorder().encoder, slot, label, value)
    }
}

impl Raymarcher {
    /// `reversed_z` sets the depth test (`Greater` instead of `Less`); it must match the
    /// [`View`]s drawn with it.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        colour: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
        reversed_z: bool,
    ) -> Result<Self, Error> {
        let composite = Composite::Forward(RenderPipeline::new(
            device,
            &RenderTargets {
                color: &[Some(colour.into())],
                depth_stencil: Some(Self::depth_test(depth, reversed_z)?),
                ..Default::default()
            },
        )?);
        Self::with_composite(device, queue, composite, reversed_z)
    }

    /// A raymarcher that writes a G-buffer, as the ocean's `Output::GBuffer` does: scene colour
    /// (emissive: none; the rim is a forward look), world normal (× ½ + ½), material (metallic,
    /// specular, roughness, shading model / 255) and base colour (the pile mix included), with
    /// depth. The source's stated limitation, a surface that cannot receive the scene's
    /// lighting, is what this lifts. Draw with [`Raymarcher::encode_gbuffer`].
    pub fn gbuffer(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        formats: [wgpu::TextureFormat; 4],
        depth: wgpu::TextureFormat,
        reversed_z: bool,
    ) -> Result<Self, Error> {
        let color = formats.map(|f| Some(wgpu::ColorTargetState::from(f)));
        let composite = Composite::GBuffer(RenderPipeline::new(
            device,
            &RenderTargets {
                color: &color,
                depth_stencil: Some(Self::depth_test(depth, reversed_z)?),
                ..Default::default()
            },
        )?);
        Self::with_composite(device, queue, composite, reversed_z)
    }

    fn depth_test(
        depth: wgpu::TextureFormat,
        reversed_z: bool,
    ) -> Result<wgpu::DepthStencilState, Error> {
        depth_state(
            composite::STAGE,
            depth,
            if reversed_z {
                wgpu::CompareFunction::Greater
            } else {
                wgpu::CompareFunction::Less
            },
        )
    }

    fn with_composite(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        composite: Composite,
        reversed_z: bool,
    ) -> Result<Self, Error> {
        Ok(Self {
            march: ComputePipeline::new(device)?,
            direct: ComputePipeline::new(device)?,
            composite,
            reversed_z,
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("raymarch field"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            no_blobs: super::bins::absent_group(device)?,
            scratch: std::sync::Mutex::new(None),
            kept: Kept::new(queue),
        })
    }

    /// Make the march's images for a viewport of this size ahead, where the kept ones do not
    /// serve it (a window grown past them): the first march of that size then makes none. A
    /// pair of screen-sized images can cost milliseconds where the driver takes new memory
    /// for them (the actor's frame after its window grew to 2112×1188: 5–6 ms on the H200), so
    /// an app calls this where it remakes its own targets, or on another thread.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, raymarcher: &fieldkit::metaball::Raymarcher) -> Result<(), fieldkit::Error> {
    /// // In the app's resize handler, beside its own targets.
    /// raymarcher.reserve(device, [2560, 1440])?;
    /// # Ok(()) }
    /// ```
    ///
    /// A viewport with a zero side or wider than the device's 2D textures is a typed error.
    pub fn reserve(&self, device: &wgpu::Device, viewport: [u32; 2]) -> Result<(), Error> {
        crate::gpu::check_screen(device, sdf_raymarch::STAGE, viewport)?;
        let _ = self.scratch(device, viewport);
        Ok(())
    }

    /// Images the march writes for a target of `size`: the kept ones where they still serve it
    /// ([`gpu::screen_fits`](crate::gpu::screen_fits): a window resized by a little keeps
    /// them), else new ones at [`gpu::screen_rounded`](crate::gpu::screen_rounded) of it.
    fn scratch(&self, device: &wgpu::Device, size: [u32; 2]) -> std::sync::Arc<Scratch> {
        let mut slot = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        match &*slot {
            Some(s) if crate::gpu::screen_fits(s.size, size) => s.clone(),
            _ => {
                let s = std::sync::Arc::new(Scratch::new(device, crate::gpu::screen_rounded(size)));
                *slot = Some(s.clone());
                s
            }
        }
    }

    /// Checks shared by the tracers, and what they need of the view; `None` when the box
    /// `lo`..`hi` is off screen.
    fn frame(
        &self,
        stage: &'static str,
        view: &View,
        local_to_world: Mat4,
        lo: Vec3,
        hi: Vec3,
        settings: &RaymarchSettings,
    ) -> Result<Option<Frame>, Error> {
        settings.check()?;
        view.check(stage)?;
        check_placement(local_to_world, stage)?;
        if view.reversed_z != self.reversed_z {
            return Err(Error::Invalid {
                stage,
                what: format!(
                    "the view has reversed_z = {}, the pipeline was made for {}",
                    view.reversed_z, self.reversed_z
                ),
            });
        }
        if !box_visible(view.view_proj, local_to_world, lo, hi) {
            return Ok(None);
        }
        let rect = screen_rect(view, local_to_world, lo, hi);
        let rect_size = [rect[2] - rect[0], rect[3] - rect[1]];
        if rect_size[0] == 0 || rect_size[1] == 0 {
            return Ok(None);
        }
        let inv = view.view_proj.inverse();
        let (near_z, far_z) = if view.reversed_z {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        let unproject = |x: f32, y: f32, z: f32| inv.project_point3(Vec3::new(x, y, z));
        let n0 = unproject(0.0, 0.0, near_z);
        let f0 = unproject(0.0, 0.0, far_z);
        let f1 = unproject(2.0 / view.viewport[0] as f32, 0.0, far_z);
        Ok(Some(Frame {
            rect,
            rect_size,
            inv,
            near_z,
            far_z,
            pixel_angle: (f1 - f0).length() / (f0 - n0).length(),
        }))
    }

    /// Trace the metaball field itself from `bins` (no SDF texture) into `colour` and `depth`,
    /// with `method`'s step rule: the direct half of the speed-against-accuracy comparison.
    /// `settings.max_steps` caps the field evaluations per ray. Returns false when off screen.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_direct(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        bins: &BlobBins,
        method: Direct,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
    ) -> Result<bool, Error> {
        let marched = self.encode_direct_march(
            device,
            encoder,
            bins,
            method,
            local_to_world,
            view,
            settings,
        )?;
        self.composite_if(device, encoder, colour, depth, marched)
    }

    /// The compute half of [`Raymarcher::encode_direct`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode_direct_march(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        bins: &BlobBins,
        method: Direct,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
    ) -> Result<Option<Marched>, Error> {
        if settings.output == Output::Sdf {
            return Err(Error::Invalid {
                stage: blob_trace::STAGE,
                what: "direct tracing has no SDF to show; use Output::Steps or Density".into(),
            });
        }
        let (lo, hi) = (bins.origin, bins.box_max());
        let Some(Frame {
            rect,
            rect_size,
            inv,
            near_z,
            far_z,
            pixel_angle,
        }) = self.frame(blob_trace::STAGE, view, local_to_world, lo, hi, settings)?
        else {
            return Ok(None);
        };
        let params = self.kept.uniform(
            device,
            rec,
            &self.kept.trace_params,
            "blob trace params",
            &blob_trace::TraceParams {
                inv_view_proj: inv,
                view_proj: view.view_proj,
                world_to_local: local_to_world.inverse(),
                local_to_world,
                box_min: lo,
                bin_size: bins.bin_size,
                box_max: hi,
                threshold: bins.threshold,
                light_dir: settings.light_dir.normalize(),
                max_steps: direct_step_cap(settings.max_steps, bins),
                base_colour: settings.base_colour,
                epsilon: settings.epsilon * bins.cell,
                rim_colour: settings.rim_colour,
                pixel_angle,
                method: method as u32,
                viewport: glam::Vec2::new(view.viewport[0] as f32, view.viewport[1] as f32),
                near_z,
                far_z,
                rect_origin: glam::UVec2::new(rect[0], rect[1]),
                rect_size: glam::UVec2::from_array(rect_size),
                mode: settings.output as u32,
                ambient: settings.ambient,
                inner_offset: bins.cell,
                pile_colour: pile(settings),
                view_origin: glam::UVec2::from_array(view.origin),
                cap_is_hit: settings.cap_is_hit as u32,
            },
        );
        let scratch = self.scratch(device, view.target_size());
        let bound = self.direct.bind_kept(
            device,
            &self.kept.trace,
            &blob_trace::trace_blobs::Resources {
                params: (&params).into(),
                blobs: &bins.group,
                colour_out: (&scratch.colour).into(),
                depth_out: (&scratch.depth).into(),
            },
        )?;
        Ok(Some(dispatch_rect(
            rec,
            blob_trace::STAGE,
            &self.direct,
            &bound,
            rect,
            view,
            scratch,
        )))
    }

    /// Draw `field` (placed by the rigid `local_to_world`) into `colour` and `depth`, loading
    /// what they hold. Returns false, drawing nothing, when the box is outside the frustum.
    /// [`Raymarcher::encode_march`] then [`Raymarcher::encode_composite`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        field: &MetaballField,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
    ) -> Result<bool, Error> {
        let marched = self.encode_march(device, encoder, field, local_to_world, view, settings)?;
        self.composite_if(device, encoder, colour, depth, marched)
    }

    /// The compute half: march and shade the box's screen rectangle into the raymarcher's own
    /// colour and depth images (kept between frames of one viewport size). `None` when the box
    /// is outside the frustum.
    pub fn encode_march(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        field: &MetaballField,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
    ) -> Result<Option<Marched>, Error> {
        self.encode_march_field(
            device,
            rec,
            &field.march_field(),
            local_to_world,
            view,
            settings,
        )
    }

    /// [`Self::encode_march`] of any signed distance field in the march's format
    /// ([`MarchField`]): a mesh's (`mesh_sdf::MeshField::march`) as well as a metaball field's.
    pub fn encode_march_field(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        field: &MarchField<'_>,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
    ) -> Result<Option<Marched>, Error> {
        let g = &field.grid;
        let (lo, cell) = (g.origin.as_vec3(), g.voxel as f32);
        let hi = lo + Vec3::new(g.size[0] as f32, g.size[1] as f32, g.size[2] as f32) * cell;
        let Some(Frame {
            rect,
            rect_size,
            inv,
            near_z,
            far_z,
            pixel_angle,
        }) = self.frame(sdf_raymarch::STAGE, view, local_to_world, lo, hi, settings)?
        else {
            return Ok(None);
        };
        let params = self.kept.uniform(
            device,
            rec,
            &self.kept.march_params,
            "raymarch params",
            &sdf_raymarch::RaymarchParams {
                inv_view_proj: inv,
                view_proj: view.view_proj,
                world_to_local: local_to_world.inverse(),
                local_to_world,
                box_min: lo,
                cell,
                box_max: hi,
                threshold: field.threshold,
                light_dir: settings.light_dir.normalize(),
                max_steps: settings.max_steps,
                base_colour: settings.base_colour,
                epsilon: settings.epsilon,
                rim_colour: settings.rim_colour,
                pixel_angle,
                viewport: glam::Vec2::new(view.viewport[0] as f32, view.viewport[1] as f32),
                rect_origin: glam::UVec2::new(rect[0], rect[1]),
                rect_size: glam::UVec2::from_array(rect_size),
                near_z,
                far_z,
                safety: settings.safety,
                mode: match self.composite {
                    Composite::Forward(_) => settings.output as u32,
                    Composite::GBuffer(_) => GBUFFER_MODE,
                },
                ambient: settings.ambient,
                band: field.band,
                pile_colour: pile(settings),
                near_safety: settings.near_safety.unwrap_or(settings.safety),
                min_step: settings.min_step(cell),
                hermite: (settings.filter == Filter::Hermite) as u32,
                edge_falloff: settings.edge_falloff as u32,
                view_origin: glam::UVec2::from_array(view.origin),
                cap_is_hit: settings.cap_is_hit as u32,
                exact_shell: settings.exact_shell * cell,
                exact_margin: settings.exact_margin * cell,
            },
        );
        let scratch = self.scratch(device, view.target_size());
        let fv = self
            .kept
            .field_view
            .get(field.march, |t| t.create_view(&Default::default()));
        let marched = self.march.bind_kept(
            device,
            &self.kept.march,
            &sdf_raymarch::march::Resources {
                params: (&params).into(),
                field: (&fv).into(),
                field_sampler: (&self.sampler).into(),
                blobs: field.blobs.map_or(&self.no_blobs, |b| &b.group),
                colour_out: (&scratch.colour).into(),
                depth_out: (&scratch.depth).into(),
            },
        )?;
        Ok(Some(dispatch_rect(
            rec,
            sdf_raymarch::STAGE,
            &self.march,
            &marched,
            rect,
            view,
            scratch,
        )))
    }

    /// Composite a march if there was one; whether anything was drawn.
    fn composite_if(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        marched: Option<Marched>,
    ) -> Result<bool, Error> {
        let Some(marched) = marched else {
            return Ok(false);
        };
        self.encode_composite(device, encoder, colour, depth, &marched)?;
        Ok(true)
    }

    /// The draw half: write a march's hits into `colour` and `depth` (the formats this
    /// raymarcher was made for, at least the view's `origin + viewport` in size) through the
    /// depth test.
    pub fn encode_composite(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        marched: &Marched,
    ) -> Result<(), Error> {
        let stage = composite::STAGE;
        let latest = marched
            .scratch
            .marches
            .load(std::sync::atomic::Ordering::Relaxed);
        if marched.number != latest {
            return Err(Error::Invalid {
                stage,
                what: format!(
                    "march {} was overwritten by march {latest} of this raymarcher: composite \
                     each march before encoding the next",
                    marched.number
                ),
            });
        }
        for (what, view) in [("colour", colour), ("depth", depth)] {
            let t = view.texture();
            let [w, h] = marched.target;
            if t.width() < w || t.height() < h {
                return Err(Error::Invalid {
                    stage,
                    what: format!(
                        "{what} target is {}×{}, smaller than the march's viewport (origin + \
                         size) {:?}",
                        t.width(),
                        t.height(),
                        marched.target
                    ),
                });
            }
        }
        let Composite::Forward(pipeline) = &self.composite else {
            return Err(Error::Invalid {
                stage,
                what: "this raymarcher writes a G-buffer: draw with encode_gbuffer".into(),
            });
        };
        let bound = pipeline.bind_kept(
            device,
            &self.kept.forward,
            &composite::fs_main::Resources {
                marched_colour: (&marched.scratch.colour).into(),
                marched_depth: (&marched.scratch.depth).into(),
            },
        )?;
        let [x0, y0, x1, y1] = marched.rect;
        let mut rec = rec.recorder();
        let mut pass = load_pass_recorded(&mut rec, composite::STAGE, colour, depth);
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
        pass.draw(0..3, 0..1);
        Ok(())
    }

    /// March `field` and write its G-buffer into `targets` (scene colour, normal, material,
    /// base colour; the formats given to [`Raymarcher::gbuffer`]) and `depth`, loading what they
    /// hold, through the depth test. `settings` sets the march and the base colour (its
    /// `output` is not used: the G-buffer is the output). Returns false, drawing nothing, when
    /// the box is outside the frustum.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_gbuffer(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        targets: [&wgpu::TextureView; 4],
        depth: &wgpu::TextureView,
        field: &MetaballField,
        local_to_world: Mat4,
        view: &View,
        settings: &RaymarchSettings,
        material: &Material,
    ) -> Result<bool, Error> {
        let stage = composite::STAGE;
        material.check()?;
        let Composite::GBuffer(pipeline) = &self.composite else {
            return Err(Error::Invalid {
                stage,
                what: "this raymarcher writes one colour target: make it with \
                       Raymarcher::gbuffer"
                    .into(),
            });
        };
        let Some(marched) =
            self.encode_march(device, encoder, field, local_to_world, view, settings)?
        else {
            return Ok(false);
        };
        let [w, h] = marched.target;
        for (i, t) in targets.iter().chain([&depth]).enumerate() {
            let t = t.texture();
            if t.width() < w || t.height() < h {
                return Err(Error::Invalid {
                    stage,
                    what: format!(
                        "G-buffer target {i} is {}×{}, smaller than the march's viewport \
                         (origin + size) {:?}",
                        t.width(),
                        t.height(),
                        marched.target
                    ),
                });
            }
        }
        let params = self.kept.uniform(
            device,
            &mut *encoder,
            &self.kept.material,
            "metaball material",
            &composite::Material {
                metallic: material.metallic,
                specular: material.specular,
                roughness: material.roughness,
                shading_model: material.shading_model as u32,
            },
        );
        let bound = pipeline.bind_kept(
            device,
            &self.kept.gbuffer,
            &composite::fs_gbuffer::Resources {
                marched_colour: (&marched.scratch.colour).into(),
                marched_depth: (&marched.scratch.depth).into(),
                material: (&params).into(),
            },
        )?;
        let load = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        let attachments = targets.map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: load,
            })
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(stage),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let [x0, y0, x1, y1] = marched.rect;
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
        pass.draw(0..3, 0..1);
        Ok(true)
    }
}

/// How [`Raymarcher::encode_direct`] steps along a ray through the blobs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Direct {
    /// Sphere tracing with one Lipschitz bound for the whole field (the largest bin's sum of
    /// per-blob bounds): safe everywhere, small steps everywhere.
    SphereGlobal = 0,
    /// Segment tracing (Galin et al. 2020): the bound over the segment about to be crossed.
    Segment = 1,
}

struct Frame {
    rect: [u32; 4],
    rect_size: [u32; 2],
    inv: Mat4,
    near_z: f32,
    far_z: f32,
    pixel_angle: f32,
}

/// A march recorded by [`Raymarcher::encode_march`], waiting to be composited.
///
/// The march's images belong to the raymarcher and the next march reuses them, so composite
/// each march before encoding another; a stale one is refused.
pub struct Marched {
    /// Pixels marched: `[x0, y0, x1, y1)`.
    pub rect: [u32; 4],
    /// The view's origin + viewport: what a target must hold.
    target: [u32; 2],
    scratch: std::sync::Arc<Scratch>,
    number: u64,
}

/// Record a march over `rect` (viewport pixels, 8×8 per workgroup) into `scratch`, whose
/// pixels lie at + `origin`.
fn dispatch_rect<E: crate::bind::Entry>(
    rec: &mut impl crate::gpu::Record,
    label: &str,
    pipeline: &ComputePipeline<E>,
    bound: &crate::bind::Bound<E>,
    rect: [u32; 4],
    view: &View,
    scratch: std::sync::Arc<Scratch>,
) -> Marched {
    let origin = view.origin;
    let mut rec = rec.recorder();
    let mut pass = rec.compute_pass(label, label);
    let [ox, oy] = origin;
    let groups = [
        (rect[2] - rect[0]).div_ceil(8),
        (rect[3] - rect[1]).div_ceil(8),
        1,
    ];
    pipeline.dispatch(&mut pass, bound, groups);
    let number = scratch
        .marches
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        + 1;
    Marched {
        rect: [rect[0] + ox, rect[1] + oy, rect[2] + ox, rect[3] + oy],
        target: view.target_size(),
        scratch,
        number,
    }
}
