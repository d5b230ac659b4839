//! Volume raymarching of a 3D density texture that keeps working with the camera inside
//! (`shaders/volume/`): emission-absorption with single scattering toward one light (shadow rays
//! or a precomputed light volume), maximum-intensity projection and the first-hit iso-surface;
//! empty-space skipping over a min-max brick grid; depth-aware, premultiplied compositing over
//! the caller's scene.
//!
#![doc = include_str!("../../docs/volume.md")]

mod cloud;
mod function;
mod input;
mod kept;
mod light;
pub mod load;

pub use cloud::{fbm_cloud, fbm_cloud_at};
pub use function::{CloudMarch, DensityMarch, FunctionVolume};
pub use input::{BRICK, TransferFunction, Volume};
pub use light::{FOLD_MAX_BYTES, LightVolume, folds};

use glam::{Mat4, Vec3};

use crate::bind::{ComputePipeline, RenderPipeline, RenderTargets, Variants};
use crate::error::Error;
use crate::gpu::{Lease, Record, uniform_buffer as uniform};
use crate::shaders::volume::{bricks, volume_composite, volume_march};
use crate::view::{View, box_visible, screen_rect};
use kept::{Kept, Target};
use light::LitPipelines;

const STAGE: &str = volume_march::STAGE;

/// What a ray accumulates.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Mode {
    /// Front-to-back emission-absorption: C += T·α·c, T *= 1 − α.
    EmissionAbsorption,
    /// The largest density along the ray, through the transfer function.
    MaximumIntensity,
    /// The first point where the density reaches `iso`, refined by bisection and lit.
    IsoSurface {
        /// The density of the surface.
        iso: f32,
    },
}

/// Shadowing toward the light.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Shadow {
    /// Unshadowed light.
    None,
    /// A shadow ray per sample, segments of `step` world units.
    Rays {
        /// Segment length, world units.
        step: f32,
    },
    /// A light volume: transmittance at every other voxel centre, built by
    /// [`VolumeRenderer::encode_light`] with shadow rays of `step`, read trilinearly. Folded
    /// into a copy of the density (one fetch per sample for both) up to [`FOLD_MAX_BYTES`].
    LightVolume {
        /// Segment length of the rays that build it, world units.
        step: f32,
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
/// How the volume is marched and lit.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MarchSettings {
    /// Segment length Δs, world units.
    pub step: f32,
    /// Δ₀, the segment length the transfer function's opacities are for, world units.
    pub reference_step: f32,
    /// Emission-absorption, maximum intensity or iso-surface.
    pub mode: Mode,
    /// How single scattering finds the light.
    pub shadow: Shadow,
    /// World direction towards the light.
    pub light_dir: Vec3,
    /// Light colour (linear RGB).
    pub light_colour: Vec3,
    /// Light that reaches every sample unshadowed.
    pub ambient: f32,
    /// Jitter each pixel's lattice (interleaved gradient noise, shifted by `frame`).
    pub jitter: bool,
    /// Frame number for the jitter pattern.
    pub frame: u32,
    /// Skip bricks the transfer function leaves clear.
    pub skip: bool,
    /// Stop rays once the transmittance falls below this (0: never stop early).
    pub min_transmittance: f32,
    /// Debug output: the number of density samples each ray took, in red, instead of colour.
    pub count_samples: bool,
}

impl Default for MarchSettings {
    fn default() -> Self {
        Self {
            step: 1.0 / 128.0,
            reference_step: 1.0 / 128.0,
            mode: Mode::EmissionAbsorption,
            shadow: Shadow::LightVolume { step: 1.0 / 64.0 },
            light_dir: Vec3::new(0.4, 1.0, 0.3),
            light_colour: Vec3::splat(1.2),
            ambient: 0.35,
            jitter: true,
            frame: 0,
            skip: true,
            min_transmittance: 1e-3,
            count_samples: false,
        }
    }
}

impl MarchSettings {
    fn check(&self) -> Result<(), Error> {
        let bad = |what: String| Error::Invalid { stage: STAGE, what };
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(format!("{name} must be finite and positive, got {v}")))
            }
        };
        positive("step", self.step)?;
        positive("reference_step", self.reference_step)?;
        match self.shadow {
            Shadow::None => {}
            Shadow::Rays { step } | Shadow::LightVolume { step } => positive("shadow step", step)?,
        }
        if let Mode::IsoSurface { iso } = self.mode
            && !iso.is_finite()
        {
            return Err(bad(format!("iso must be finite, got {iso}")));
        }
        if !(self.light_dir.is_finite() && self.light_dir.length() > 0.0) {
            return Err(bad(format!(
                "light_dir {} must be finite and nonzero",
                self.light_dir
            )));
        }
        if !(self.light_colour.is_finite() && self.ambient.is_finite()) {
            return Err(bad("light_colour and ambient must be finite".into()));
        }
        if !(0.0..1.0).contains(&self.min_transmittance) {
            return Err(bad(format!(
                "min_transmittance must be in [0, 1), got {}",
                self.min_transmittance
            )));
        }
        Ok(())
    }
}

/// The min-max brick grid of one volume ([`VolumeRenderer::encode_bricks`]).
pub struct Bricks {
    /// Min and max density per brick.
    pub ranges: wgpu::Buffer,
    /// Bricks per axis.
    pub count: [u32; 3],
}

/// The march's `MODE` and `SHADOW` overrides for `settings` with `light`.
fn march_variant(settings: &MarchSettings, light: Option<&LightVolume>) -> (usize, usize) {
    let mode = match settings.mode {
        Mode::EmissionAbsorption => 0,
        Mode::MaximumIntensity => 1,
        Mode::IsoSurface { .. } => 2,
    };
    let shadow = match settings.shadow {
        Shadow::None => 0,
        Shadow::Rays { .. } => 1,
        Shadow::LightVolume { .. } => match light.and_then(|l| l.lit_density.as_ref()) {
            Some(_) => 2,
            None => 3,
        },
    };
    (mode, shadow)
}

/// The march variants' shadow indices `settings` may take: both light-volume layouts (the
/// density folded with the light, and apart) for [`Shadow::LightVolume`].
fn march_shadows(settings: &MarchSettings) -> Vec<usize> {
    match settings.shadow {
        Shadow::LightVolume { .. } => vec![2, 3],
        _ => vec![march_variant(settings, None).1],
    }
}

/// The march pipeline's overrides for `settings` with the shadow variant `shadow`.
fn march_overrides(settings: &MarchSettings, shadow: usize) -> volume_march::Overrides {
    volume_march::Overrides {
        mode: march_variant(settings, None).0 as u32,
        shadow: shadow as u32,
        skip: settings.skip,
        count_samples: settings.count_samples,
    }
}

/// A march waiting to be composited: premultiplied colour and coverage over `rect`. The
/// renderer takes its texture back for a later march once this is dropped (see
/// [`gpu::Lease`](crate::gpu::Lease)).
pub struct VolumeMarched {
    /// Pixels marched: `[x0, y0, x1, y1)`.
    pub rect: [u32; 4],
    /// The viewport marched for: the size of the targets it composites into.
    pub viewport: [u32; 2],
    /// Premultiplied colour and transmittance of the marched rectangle at the viewport's
    /// pixels (`Rgba16Float`; texels outside `rect` are left from earlier marches). At least
    /// the viewport's size: kept across a resize it still holds, so it can be larger (each side
    /// is made rounded up to a multiple of 128 pixels).
    pub colour: wgpu::Texture,
    /// The view the composite samples.
    view: wgpu::TextureView,
    _lease: Lease,
}

impl VolumeMarched {
    fn new(rect: [u32; 4], viewport: [u32; 2], target: Target, lease: Lease) -> Self {
        Self {
            rect,
            viewport,
            colour: target.texture,
            view: target.view,
            _lease: lease,
        }
    }
}

/// The volume pipelines. Create once, encode every frame: a frame makes no GPU object once its
/// outputs are dropped (parameters staged through a ring it keeps, with the queue given to
/// `new`; up to [`RING_UPLOADS`](crate::gpu::RING_UPLOADS) marches may wait in one encoder).
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder,
/// #      volume: &fieldkit::volume::Volume, view: &fieldkit::view::View,
/// #      colour: &wgpu::TextureView) -> Result<(), fieldkit::Error> {
/// use fieldkit::volume::{MarchSettings, TransferFunction, VolumeRenderer};
/// let renderer = VolumeRenderer::new(device, queue, wgpu::TextureFormat::Rgba8Unorm)?; // once
/// let bricks = renderer.encode_bricks(device, encoder, volume)?; // once per volume
/// let (tf, march) = (TransferFunction::cloud(), MarchSettings::default());
/// let identity = fieldkit::glam::Mat4::IDENTITY;
/// if let Some(marched) = renderer.encode_march(device, encoder, volume, &bricks, None, &tf,
///     identity, view, None, &march)? {
///     renderer.encode_composite(device, encoder, colour, &marched)?; // blended over colour
/// }
/// # Ok(()) }
/// ```
pub struct VolumeRenderer {
    bricks: ComputePipeline<bricks::bricks::Entry>,
    /// One march pipeline per mode × shadow × skip × sample count (`march_index`), made on
    /// first use.
    march: Variants<volume_march::march::Entry, volume_march::Overrides>,
    light: ComputePipeline<volume_march::light_volume::Entry>,
    composite: RenderPipeline<volume_composite::fs_main::Entry>,
    lit: LitPipelines,
    sampler: wgpu::Sampler,
    /// What a frame draws with, kept from frame to frame: no object made a frame.
    kept: Kept,
}

impl VolumeRenderer {
    /// `colour`: the format of the targets [`Self::encode_composite`] blends into. `queue`
    /// writes each frame's parameters into buffers the renderer keeps.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        colour: wgpu::TextureFormat,
    ) -> Result<Self, Error> {
        let composite = RenderPipeline::new(
            device,
            &RenderTargets {
                color: &[Some(wgpu::ColorTargetState {
                    format: colour,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
                ..Default::default()
            },
        )?;
        Ok(Self {
            bricks: ComputePipeline::new(device)?,
            march: Variants::default(),
            light: ComputePipeline::new(device)?,
            composite,
            lit: LitPipelines {
                unorm8: ComputePipeline::new(device)?,
                float16: ComputePipeline::new(device)?,
                float32: ComputePipeline::new(device)?,
            },
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("volume trilinear"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            kept: Kept::new(device, queue),
        })
    }

    /// Build the min-max brick grid of `volume` (once per volume, again when it changes).
    pub fn encode_bricks(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &Volume,
    ) -> Result<Bricks, Error> {
        let count = volume.dims.map(|d| d.div_ceil(BRICK));
        let n = count.iter().map(|&c| c as u64).product::<u64>();
        let ranges = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("volume bricks"),
            size: n * 8,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = uniform(
            device,
            "brick params",
            &bricks::BrickParams {
                dims: volume.dims.into(),
                brick: BRICK,
                bricks: count.into(),
            },
        );
        let dv = volume.texture.create_view(&Default::default());
        let groups = ComputePipeline::<bricks::bricks::Entry>::groups_for(count);
        self.bricks.record(
            device,
            rec,
            &bricks::bricks::Resources {
                params: (&params).into(),
                density: (&dv).into(),
                ranges: (&ranges).into(),
            },
            groups,
            bricks::STAGE,
        )?;
        Ok(Bricks { ranges, count })
    }

    #[allow(clippy::too_many_arguments)]
    fn params(
        &self,
        volume: &Volume,
        bricks: &Bricks,
        tf: &TransferFunction,
        local_to_world: Mat4,
        view: &View,
        settings: &MarchSettings,
        rect: [u32; 4],
        use_depth: bool,
    ) -> Result<volume_march::MarchParams, Error> {
        let (lo, hi) = volume.bounds();
        let world_to_local = local_to_world.inverse();
        let light_local = world_to_local.transform_vector3(settings.light_dir.normalize());
        let guard = step_guard(local_to_world, lo, hi);
        let MarchScalars {
            iso,
            shadow_step,
            tf_scale,
            tf_offset,
            near_z,
            far_z,
        } = MarchScalars::new(settings, tf, view);
        Ok(volume_march::MarchParams {
            inv_view_proj: view.view_proj.inverse(),
            world_to_local,
            box_min: lo,
            step: settings.step,
            box_max: hi,
            reference_step: settings.reference_step,
            dims: volume.dims.into(),
            bricks: bricks.count.into(),
            brick_scale: Vec3::from_array(volume.dims.map(|d| d as f32)) / BRICK as f32,
            brick_size: BRICK as f32 / Vec3::from_array(volume.dims.map(|d| d as f32)),
            // Voxel-centre index v = uvw · dims − ½, node coordinate v / 2, light texture
            // coordinate (v / 2 + ½) / nodes.
            light_scale: Vec3::from_array(volume.dims.map(|d| d as f32 / (2 * (d / 2 + 1)) as f32)),
            light_offset: Vec3::from_array(volume.dims.map(|d| 0.25 / (d / 2 + 1) as f32)),
            // Unit world length along the light per unit of its parameter.
            light_local,
            light_colour: settings.light_colour,
            ambient: settings.ambient,
            viewport: glam::Vec2::new(view.viewport[0] as f32, view.viewport[1] as f32),
            rect_origin: glam::UVec2::new(rect[0], rect[1]),
            rect_size: glam::UVec2::new(rect[2] - rect[0], rect[3] - rect[1]),
            near_z,
            far_z,
            tf_count: tf.entries.len() as u32,
            tf_offset,
            skip_below: tf.clear_below().clamp(f32::MIN, f32::MAX),
            iso,
            min_transmittance: settings.min_transmittance,
            jitter: settings.jitter as u32,
            frame: settings.frame,
            max_steps: guard(settings.step),
            shadow_step,
            shadow_max_steps: guard(shadow_step),
            use_depth: use_depth as u32,
            inv_extent: (hi - lo).recip(),
            tf_scale,
            inv_reference_step: settings.reference_step.recip(),
        })
    }

    /// The transfer function as the march reads it, in the buffer kept for it.
    fn kept_tf(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        tf: &TransferFunction,
    ) -> wgpu::Buffer {
        let kept = &self.kept;
        let rows = tf_rows(tf);
        let usage = wgpu::BufferUsages::STORAGE;
        let bytes = bytemuck::cast_slice(&rows);
        kept.uploads
            .kept(device, encoder, &kept.tf, "transfer function", usage, bytes)
    }

    /// Make the march pipelines `settings` need, which [`Self::encode_march`] would otherwise
    /// make on its first call with them (one per mode × shadow × skip × sample count; for
    /// [`Shadow::LightVolume`] both, the folded light volume's and the one apart): call it
    /// ahead, on any thread, so that no frame waits for a pipeline. [`Self::prepared`] says
    /// whether any is still to make.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::volume::{MarchSettings, Mode, VolumeRenderer};
    /// let renderer = VolumeRenderer::new(device, queue, wgpu::TextureFormat::Rgba8Unorm)?;
    /// let mip = MarchSettings { mode: Mode::MaximumIntensity, ..Default::default() };
    /// if !renderer.prepared(&mip) {
    ///     renderer.prepare(device, &mip)?; // on a worker thread, while frames march the last
    /// }
    /// # Ok(()) }
    /// ```
    pub fn prepare(&self, device: &wgpu::Device, settings: &MarchSettings) -> Result<(), Error> {
        settings.check()?;
        for shadow in march_shadows(settings) {
            self.march
                .get(device, &march_overrides(settings, shadow), true)?;
        }
        Ok(())
    }

    /// Make the march's output image for a `viewport` of this size ahead, on any thread: the
    /// first [`Self::encode_march`] of that size then makes no texture (a new texture costs
    /// the frame milliseconds where the driver takes a new block of memory for it: 4.2 ms for
    /// 1920×1080 on the H200). Kept as a march's own output is, while it still serves. A
    /// viewport with a zero side or wider than the device's 2D textures is a typed error.
    pub fn reserve(&self, device: &wgpu::Device, viewport: [u32; 2]) -> Result<(), Error> {
        crate::gpu::check_screen(device, STAGE, viewport)?;
        let _ = kept::march_target(&self.kept.marched, device, viewport);
        Ok(())
    }

    /// Whether the march pipelines `settings` need are made ([`Self::prepare`]).
    pub fn prepared(&self, settings: &MarchSettings) -> bool {
        march_shadows(settings)
            .into_iter()
            .all(|shadow| self.march.has(&march_overrides(settings, shadow), true))
    }

    /// March `volume` under `local_to_world` for `view` into a premultiplied image. Rays stop at
    /// `scene_depth` (the caller's depth target, `Depth32Float`, viewport-sized) when given.
    /// `light` is needed for [`Shadow::LightVolume`]. `None` when the box is off screen.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_march(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &Volume,
        bricks: &Bricks,
        light: Option<&LightVolume>,
        tf: &TransferFunction,
        local_to_world: Mat4,
        view: &View,
        scene_depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
    ) -> Result<Option<VolumeMarched>, Error> {
        settings.check()?;
        tf.check()?;
        check_transform(local_to_world)?;
        check_view(view)?;
        if bricks.count != volume.dims.map(|d| d.div_ceil(BRICK)) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "the brick grid was built for a volume of another size".into(),
            });
        }
        // With a folded light volume the march samples the lit density in place of the density;
        // with one not folded, its texture as well.
        let kept = &self.kept;
        let density_view = || {
            kept.density_view
                .get(&volume.texture, |t| t.create_view(&Default::default()))
        };
        let (dv, lv) = match (settings.shadow, light) {
            (Shadow::LightVolume { .. }, Some(l)) => {
                if !l.is_for(volume, tf, local_to_world, settings) {
                    return Err(Error::Invalid {
                        stage: STAGE,
                        what: "the light volume was built for another volume, light, shadow \
                               step, transform or transfer function: rebuild it with \
                               encode_light"
                            .into(),
                    });
                }
                match &l.views {
                    (_, Some(lit)) => (lit.clone(), kept.no_light.clone()),
                    (light, None) => (density_view(), light.clone()),
                }
            }
            (Shadow::LightVolume { .. }, None) => {
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: "Shadow::LightVolume needs the light volume from encode_light".into(),
                });
            }
            _ => (density_view(), kept.no_light.clone()),
        };
        check_scene_depth(scene_depth, view)?;
        let (lo, hi) = volume.bounds();
        let Some(rect) = march_rect(view, local_to_world, lo, hi) else {
            return Ok(None);
        };
        let params = self.params(
            volume,
            bricks,
            tf,
            local_to_world,
            view,
            settings,
            rect,
            scene_depth.is_some(),
        )?;
        let (colour, lease) = kept::march_target(&kept.marched, device, view.viewport);
        let recorder = &mut rec.recorder();
        let label = "volume march params";
        let params =
            (kept.uploads).uniform(device, recorder.encoder, &kept.march_params, label, &params);
        let tf_buffer = self.kept_tf(device, recorder.encoder, tf);
        let (_, shadow) = march_variant(settings, light);
        let march = self
            .march
            .get(device, &march_overrides(settings, shadow), true)?;
        let groups = [
            (rect[2] - rect[0]).div_ceil(8),
            (rect[3] - rect[1]).div_ceil(8),
            1,
        ];
        march.record_kept(
            device,
            recorder,
            &kept.march_bound,
            &volume_march::march::Resources {
                params: (&params).into(),
                density: (&dv).into(),
                linear_clamp: (&self.sampler).into(),
                tf: (&tf_buffer).into(),
                ranges: (&bricks.ranges).into(),
                light_in: (&lv).into(),
                scene_depth: scene_depth.unwrap_or(&kept.no_depth).into(),
                colour_out: (&colour.view).into(),
            },
            groups,
            STAGE,
        )?;
        Ok(Some(VolumeMarched::new(rect, view.viewport, colour, lease)))
    }

    /// Blend a march over `colour` (the format this renderer was made for, the size of the
    /// march's viewport).
    pub fn encode_composite(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        colour: &wgpu::TextureView,
        marched: &VolumeMarched,
    ) -> Result<(), Error> {
        let t = colour.texture();
        if [t.width(), t.height()] != marched.viewport {
            let [w, h] = marched.viewport;
            return Err(Error::Invalid {
                stage: volume_composite::STAGE,
                what: format!(
                    "colour target is {}×{}, the march's viewport {w}×{h}",
                    t.width(),
                    t.height(),
                ),
            });
        }
        let bound = self.composite.bind_kept(
            device,
            &self.kept.composite_bound,
            &volume_composite::fs_main::Resources {
                marched: (&marched.view).into(),
            },
        )?;
        let mut rec = rec.recorder();
        let desc = wgpu::RenderPassDescriptor {
            label: Some(volume_composite::STAGE),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: colour,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        };
        let mut pass = rec.render_pass(&desc, volume_composite::STAGE);
        pass.set_pipeline(&self.composite.pipeline);
        bound.set_render(&mut pass);
        let [x0, y0, x1, y1] = marched.rect;
        pass.set_scissor_rect(x0, y0, x1 - x0, y1 - y0);
        pass.draw(0..3, 0..1);
        Ok(())
    }
}

/// The transfer function as the march reads it: per interval i, the line through entries i and
/// i + 1 in the entry position f, as rows `e[i] − i·(e[i+1] − e[i])` and `e[i+1] − e[i]` (taken
/// in f64), so a sample evaluates `row0 + f·row1`.
fn tf_rows(tf: &TransferFunction) -> Vec<[f32; 4]> {
    tf.entries
        .windows(2)
        .enumerate()
        .flat_map(|(i, e)| {
            let slope = std::array::from_fn(|c| e[1][c] as f64 - e[0][c] as f64);
            [
                std::array::from_fn(|c| (e[0][c] as f64 - i as f64 * slope[c]) as f32),
                slope.map(|v| v as f32),
            ]
        })
        .collect()
}

/// Segments a ray through the box [lo, hi] under `local_to_world` can need at a given step:
/// the longest chord through a parallelepiped is one of its four diagonals, and their sum bounds
/// it generously; two more for the partial ends.
fn step_guard(local_to_world: Mat4, lo: Vec3, hi: Vec3) -> impl Fn(f32) -> u32 {
    let d = hi - lo;
    let diagonal_world: f32 = [
        d,
        Vec3::new(d.x, -d.y, d.z),
        Vec3::new(-d.x, d.y, d.z),
        Vec3::new(d.x, d.y, -d.z),
    ]
    .iter()
    .map(|&v| local_to_world.transform_vector3(v).length())
    .sum();
    move |step: f32| ((diagonal_world / step).ceil() + 2.0).min(u32::MAX as f32) as u32
}

/// The march's scalar parameters that come from the settings, transfer function and view alone.
struct MarchScalars {
    iso: f32,
    shadow_step: f32,
    /// Density to transfer-function entry position (entry i at i): f = d × scale + offset.
    tf_scale: f32,
    tf_offset: f32,
    /// NDC depth of the near and far planes.
    near_z: f32,
    far_z: f32,
}

impl MarchScalars {
    fn new(settings: &MarchSettings, tf: &TransferFunction, view: &View) -> Self {
        let tf_scale =
            ((tf.entries.len() - 1) as f64 / (tf.range[1] as f64 - tf.range[0] as f64)) as f32;
        let (near_z, far_z) = if view.reversed_z {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        Self {
            iso: match settings.mode {
                Mode::IsoSurface { iso } => iso,
                _ => 0.0,
            },
            shadow_step: match settings.shadow {
                Shadow::None => 1.0,
                Shadow::Rays { step } | Shadow::LightVolume { step } => step,
            },
            tf_scale,
            tf_offset: (-tf_scale as f64 * tf.range[0] as f64) as f32,
            near_z,
            far_z,
        }
    }
}

/// A caller's depth target must be `Depth32Float` of the viewport's size.
fn check_scene_depth(scene_depth: Option<&wgpu::TextureView>, view: &View) -> Result<(), Error> {
    if let Some(d) = scene_depth {
        let t = d.texture();
        if t.format() != wgpu::TextureFormat::Depth32Float
            || [t.width(), t.height()] != view.viewport
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "scene depth must be Depth32Float of the viewport's size {:?}, got {:?} {}×{}",
                    view.viewport,
                    t.format(),
                    t.width(),
                    t.height()
                ),
            });
        }
    }
    Ok(())
}

/// The screen rectangle of the box [lo, hi] under `local_to_world`, `None` when it is off
/// screen.
fn march_rect(view: &View, local_to_world: Mat4, lo: Vec3, hi: Vec3) -> Option<[u32; 4]> {
    if !box_visible(view.view_proj, local_to_world, lo, hi) {
        return None;
    }
    let rect = screen_rect(view, local_to_world, lo, hi);
    (rect[2] > rect[0] && rect[3] > rect[1]).then_some(rect)
}

fn check_transform(m: Mat4) -> Result<(), Error> {
    let det = m.determinant();
    if !m.is_finite() || det == 0.0 || !det.is_finite() || !m.inverse().is_finite() {
        return Err(Error::Invalid {
            stage: STAGE,
            what: "local_to_world must be finite and invertible".into(),
        });
    }
    Ok(())
}

/// An invertible view whose near plane lies in front of the eye.
fn check_view(view: &View) -> Result<(), Error> {
    let bad = |what: String| Error::Invalid { stage: STAGE, what };
    if !view.view_proj.is_finite() || view.view_proj.determinant() == 0.0 {
        return Err(bad(
            "view_proj must be finite and invertible (a near plane at 0 makes it singular)".into(),
        ));
    }
    if view.viewport[0] == 0 || view.viewport[1] == 0 {
        return Err(bad(format!("viewport {:?} has a zero side", view.viewport)));
    }
    if view.origin != [0, 0] {
        return Err(bad(format!(
            "origin {:?}: the volume renderer draws whole targets (origin [0, 0])",
            view.origin
        )));
    }
    let inv = view.view_proj.inverse();
    let (near_z, far_z) = if view.reversed_z {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    // A perspective eye: where clip w vanishes. A near plane at or behind it is refused.
    let eye = inv * glam::Vec4::new(0.0, 0.0, 1.0, 0.0);
    if eye.w.abs() > 1e-12 * eye.truncate().length().max(1.0) {
        let eye = eye.truncate() / eye.w;
        let near = inv.project_point3(Vec3::new(0.0, 0.0, near_z));
        let far = inv.project_point3(Vec3::new(0.0, 0.0, far_z));
        if (near - eye).dot(far - eye) <= 0.0 || (near - eye).length() >= (far - eye).length() {
            return Err(bad(
                "the projection's near plane must lie in front of the eye (near > 0)".into(),
            ));
        }
    }
    Ok(())
}
