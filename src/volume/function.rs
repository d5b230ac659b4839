//! The volume march over a density *function*: `fn density(p: vec3<f32>) -> f32` linked into
//! fieldkit's march at build time by `fieldkit_build::Builder::density_march`, run here.

use std::marker::PhantomData;

use glam::{Mat4, UVec3, Vec3};

use super::kept::{self, Target};
use super::{
    Bricks, MarchScalars, MarchSettings, Shadow, TransferFunction, VolumeMarched,
    check_scene_depth, check_transform, check_view, march_rect, step_guard, tf_rows,
};
use crate::bind::{ComputePipeline, Entry, EntryInfo, KeptBound, Resource, Slot, Variants};
use crate::error::Error;
use crate::gpu::{Leased, Record, Uploads, uniform_buffer as uniform};
use crate::shaders::volume::cloud_march;
use crate::view::View;

const STAGE: &str = cloud_march::STAGE;

/// Where a density function is marched: the box it fills in local space, and a lattice of
/// `dims` cells over it on which bricks are bounded, the function baked and iso-surface normals
/// differentiated (a cell plays a voxel's part).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct FunctionVolume {
    /// Local-space corner of the box.
    pub min: Vec3,
    /// Opposite corner.
    pub max: Vec3,
    /// Lattice cells per axis.
    pub dims: [u32; 3],
}

impl FunctionVolume {
    /// The unit box [0, 1]³ with `n`³ cells (the built-in cloud's box).
    pub fn unit(n: u32) -> Self {
        Self {
            min: Vec3::ZERO,
            max: Vec3::ONE,
            dims: [n; 3],
        }
    }

    fn check(&self) -> Result<(), Error> {
        if !(self.min.is_finite() && self.max.is_finite() && self.min.cmplt(self.max).all()) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "the box needs finite corners with min < max on every axis, got {} and {}",
                    self.min, self.max
                ),
            });
        }
        for (axis, &d) in self.dims.iter().enumerate() {
            if d == 0 || d > 1 << 16 {
                return Err(Error::Size {
                    stage: STAGE,
                    what: [
                        "lattice cells along x",
                        "lattice cells along y",
                        "lattice cells along z",
                    ][axis],
                    got: d as u64,
                    max: 1 << 16,
                });
            }
        }
        Ok(())
    }

    fn cell(&self) -> Vec3 {
        (self.max - self.min) / Vec3::from_array(self.dims.map(|d| d as f32))
    }

    fn bricks(&self) -> [u32; 3] {
        self.dims.map(|d| d.div_ceil(super::BRICK))
    }
}

/// One entry point `E` of a density march stage generated in any crate, bound through the
/// parameter struct generated for the same entry point `T` of the built-in cloud. Every such
/// stage is made from one template (`fieldkit_build::DENSITY_MARCH_TEMPLATE`), so it has the
/// template's bindings; [`check_entry`] holds `E` to `T`'s.
struct AsTemplate<E, T>(PhantomData<(E, T)>);

impl<E: Entry, T: Entry> Entry for AsTemplate<E, T> {
    type Resources<'a> = T::Resources<'a>;
    const INFO: &'static EntryInfo = E::INFO;

    fn resources<'a>(r: &Self::Resources<'a>) -> Vec<Resource<'a>> {
        let given = T::resources(r);
        let at = |name| T::INFO.slots.iter().position(|t| t.name == name);
        E::INFO
            .slots
            .iter()
            .filter_map(|s| at(s.name).map(|i| given[i].clone()))
            .collect()
    }
}

/// The density march entry point `M`, bricks `B` and bake `K` of a stage from the template.
type March<M> = AsTemplate<M, cloud_march::march::Entry>;
type BricksEntry<B> = AsTemplate<B, cloud_march::bricks::Entry>;
type Bake<K> = AsTemplate<K, cloud_march::bake::Entry>;

/// `entry`, an entry point of a density march stage, checked against the template's
/// (`template`, the built-in cloud's): the same entry point, every binding one the template's
/// has in the same place.
fn check_entry(entry: &EntryInfo, template: &EntryInfo) -> Result<(), Error> {
    let bad = |what: String| Error::Invalid {
        stage: entry.stage,
        what: format!("not a density march stage (fieldkit_build::Builder::density_march): {what}"),
    };
    let name = template.entry_point;
    if entry.entry_point != name {
        return Err(bad(format!(
            "expected the entry point `{name}`, got `{}`",
            entry.entry_point
        )));
    }
    for slot in entry.slots {
        let same =
            |t: &&Slot| (t.name, t.group, t.binding) == (slot.name, slot.group, slot.binding);
        if !template.slots.iter().any(|t| same(&t)) {
            return Err(bad(format!(
                "`{name}` binds `{}` at @group({}) @binding({}), which the template's `{name}` \
                 does not",
                slot.name, slot.group, slot.binding
            )));
        }
    }
    Ok(())
}

/// The march over one density function: the three entry points of a stage that
/// `fieldkit_build::Builder::density_march` made (`M` its `march::Entry`, `B` its
/// `bricks::Entry`, `K` its `bake::Entry`; name them with [`crate::density_march!`]).
/// [`DensityMarch::cloud`] is the built-in one, over seed 002's fBm cloud.
///
/// Settings, transfer functions, views and compositing are the texture march's
/// ([`super::VolumeRenderer`]): the same [`MarchSettings`] (shadowing by shadow rays, or none:
/// a light volume needs a texture, which [`Self::encode_bake`] can give), and the
/// [`VolumeMarched`] it returns blends with [`super::VolumeRenderer::encode_composite`].
pub struct DensityMarch<M, B, K> {
    /// One pipeline per mode × shadow × skip × sample count, made on first use.
    march: Variants<March<M>, cloud_march::Overrides>,
    bricks: ComputePipeline<BricksEntry<B>>,
    bake: ComputePipeline<Bake<K>>,
    no_depth: wgpu::TextureView,
    /// The march's outputs, taken back once dropped.
    marched: Leased<Target>,
    /// What a frame marches with, kept from frame to frame: no object made a frame.
    kept: KeptMarch<M>,
}

/// The march's per-frame parameters and transfer function (written through an upload ring)
/// and its bind group, kept from frame to frame.
struct KeptMarch<M> {
    uploads: Uploads,
    params: std::sync::Mutex<Option<wgpu::Buffer>>,
    tf: std::sync::Mutex<Option<wgpu::Buffer>>,
    bound: KeptBound<March<M>>,
}

/// The density march over seed 002's procedural cloud (`shaders/shared/fbm_cloud.wesl`: the
/// function [`super::fbm_cloud`] samples at voxel centres), in the unit box.
pub type CloudMarch =
    DensityMarch<cloud_march::march::Entry, cloud_march::bricks::Entry, cloud_march::bake::Entry>;

/// The [`DensityMarch`] type of a stage made by `fieldkit_build::Builder::density_march`, from
/// the path of its generated module.
///
/// ```ignore
/// // build.rs: Builder::new("shaders").density_march("clouds::cumulus_march", "shared::cumulus")
/// type Cumulus = fieldkit::density_march!(crate::shaders::clouds::cumulus_march);
/// let march = Cumulus::new(&device, &queue)?;
/// ```
#[macro_export]
macro_rules! density_march {
    ($($stage:ident)::+) => {
        $crate::volume::DensityMarch<
            $($stage)::+::march::Entry,
            $($stage)::+::bricks::Entry,
            $($stage)::+::bake::Entry,
        >
    };
}

impl CloudMarch {
    /// The built-in cloud's march. `queue` writes each frame's parameters into buffers the
    /// march keeps.
    pub fn cloud(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Self, Error> {
        Self::new(device, queue)
    }
}

impl<M: Entry, B: Entry, K: Entry> DensityMarch<M, B, K> {
    /// Check the stage's entry points against the template and make the bricks and bake
    /// pipelines (march pipelines on first use, or ahead with [`Self::prepare`]). `queue`
    /// writes each frame's parameters into buffers the march keeps.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Self, Error> {
        check_entry(M::INFO, &cloud_march::march::INFO)?;
        check_entry(B::INFO, &cloud_march::bricks::INFO)?;
        check_entry(K::INFO, &cloud_march::bake::INFO)?;
        let no_depth = crate::gpu::texture(
            device,
            "no scene depth",
            [1, 1, 1],
            wgpu::TextureDimension::D2,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        Ok(Self {
            march: Variants::default(),
            bricks: ComputePipeline::new(device)?,
            bake: ComputePipeline::new(device)?,
            no_depth: no_depth.create_view(&Default::default()),
            marched: Leased::default(),
            kept: KeptMarch {
                uploads: Uploads::new(queue),
                params: Default::default(),
                tf: Default::default(),
                bound: KeptBound::default(),
            },
        })
    }

    /// Make the march pipeline `settings` need, which [`Self::encode_march`] would otherwise
    /// make on its first call with them (one per mode × shadow × skip × sample count): call it
    /// ahead, on any thread, so that no frame waits for a pipeline. [`Shadow::LightVolume`] is
    /// refused as by `encode_march`.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::volume::{CloudMarch, MarchSettings, Shadow};
    /// let cloud = CloudMarch::cloud(device, queue)?;
    /// let settings = MarchSettings { shadow: Shadow::Rays { step: 1.0 / 64.0 }, ..Default::default() };
    /// cloud.prepare(device, &settings)?;
    /// # Ok(()) }
    /// ```
    pub fn prepare(&self, device: &wgpu::Device, settings: &MarchSettings) -> Result<(), Error> {
        settings.check()?;
        self.march_for(device, settings).map(|_| ())
    }

    /// Make the march's output image for a `viewport` of this size ahead, on any thread: the
    /// first [`Self::encode_march`] of that size then makes no texture (a new texture costs
    /// the frame milliseconds where the driver takes a new block of memory for it: 4.2 ms for
    /// 1920×1080 on the H200). Kept as a march's own output is, while it still serves. A
    /// viewport with a zero side or wider than the device's 2D textures is a typed error.
    pub fn reserve(&self, device: &wgpu::Device, viewport: [u32; 2]) -> Result<(), Error> {
        crate::gpu::check_screen(device, STAGE, viewport)?;
        let _ = kept::march_target(&self.marched, device, viewport);
        Ok(())
    }

    /// Whether the march pipeline `settings` need is made ([`Self::prepare`]); false for
    /// settings a density march refuses.
    pub fn prepared(&self, settings: &MarchSettings) -> bool {
        march_key(settings).is_ok_and(|o| self.march.has(&o, true))
    }

    /// The march pipeline for `settings`, made on first use.
    fn march_for(
        &self,
        device: &wgpu::Device,
        settings: &MarchSettings,
    ) -> Result<std::sync::Arc<ComputePipeline<March<M>>>, Error> {
        self.march.get(device, &march_key(settings)?, true)
    }

    /// The parameters every entry point reads: the box and lattice, and for the march the
    /// view, light and transfer function.
    #[allow(clippy::too_many_arguments)]
    fn params(
        &self,
        volume: &FunctionVolume,
        tf: &TransferFunction,
        local_to_world: Mat4,
        view: &View,
        settings: &MarchSettings,
        rect: [u32; 4],
        use_depth: bool,
    ) -> cloud_march::DensityMarchParams {
        let world_to_local = local_to_world.inverse();
        let guard = step_guard(local_to_world, volume.min, volume.max);
        let s = MarchScalars::new(settings, tf, view);
        let bricks = volume.bricks();
        let brick_size = volume.cell() * super::BRICK as f32;
        cloud_march::DensityMarchParams {
            inv_view_proj: view.view_proj.inverse(),
            world_to_local,
            box_min: volume.min,
            step: settings.step,
            box_max: volume.max,
            reference_step: settings.reference_step,
            dims: UVec3::from_array(volume.dims),
            frame: settings.frame,
            cell: volume.cell(),
            brick: super::BRICK,
            bricks: UVec3::from_array(bricks),
            jitter: settings.jitter as u32,
            brick_scale: brick_size.recip(),
            brick_size,
            light_local: world_to_local.transform_vector3(settings.light_dir.normalize()),
            light_colour: settings.light_colour,
            ambient: settings.ambient,
            viewport: glam::Vec2::new(view.viewport[0] as f32, view.viewport[1] as f32),
            rect_origin: glam::UVec2::new(rect[0], rect[1]),
            rect_size: glam::UVec2::new(rect[2] - rect[0], rect[3] - rect[1]),
            near_z: s.near_z,
            far_z: s.far_z,
            tf_count: tf.entries.len() as u32,
            tf_offset: s.tf_offset,
            tf_scale: s.tf_scale,
            skip_below: tf.clear_below().clamp(f32::MIN, f32::MAX),
            iso: s.iso,
            min_transmittance: settings.min_transmittance,
            max_steps: guard(settings.step),
            shadow_step: s.shadow_step,
            shadow_max_steps: guard(s.shadow_step),
            use_depth: use_depth as u32,
            inv_reference_step: settings.reference_step.recip(),
        }
    }

    /// Parameters for the bricks and bake passes, which read only the box and lattice.
    fn lattice_params(&self, device: &wgpu::Device, volume: &FunctionVolume) -> wgpu::Buffer {
        let view = View {
            view_proj: Mat4::IDENTITY,
            viewport: [1, 1],
            reversed_z: false,
            origin: [0, 0],
        };
        let params = self.params(
            volume,
            &TransferFunction::constant(Vec3::ONE, 0.0),
            Mat4::IDENTITY,
            &view,
            &MarchSettings::default(),
            [0, 0, 1, 1],
            false,
        );
        uniform(device, "density march lattice params", &params)
    }

    /// The min-max brick grid of the function: per brick of [`super::BRICK`]³ cells, the
    /// function's smallest and largest value at the centres of its cells dilated by one cell
    /// (once per function and box; a function that varies within a cell can exceed it, see the
    /// module docs). A bake: the grid is a new buffer each call, which the caller keeps for
    /// every frame its lattice stays (the viewer keys it on the lattice's size).
    pub fn encode_bricks(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &FunctionVolume,
    ) -> Result<Bricks, Error> {
        volume.check()?;
        let count = volume.bricks();
        let n = count.iter().map(|&c| c as u64).product::<u64>();
        let ranges = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("density function bricks"),
            size: n * 8,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = self.lattice_params(device, volume);
        self.bricks.record(
            device,
            rec,
            &cloud_march::bricks::Resources {
                params: (&params).into(),
                ranges_out: (&ranges).into(),
            },
            ComputePipeline::<BricksEntry<B>>::groups_for(count),
            "density function bricks",
        )?;
        Ok(Bricks { ranges, count })
    }

    /// The function at every lattice cell centre, x fastest, in a new `f32` storage buffer
    /// (`COPY_SRC`): to read back, or to upload as a [`super::Volume`] for a light volume.
    pub fn encode_bake(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &FunctionVolume,
    ) -> Result<wgpu::Buffer, Error> {
        volume.check()?;
        let n = volume.dims.iter().map(|&c| c as u64).product::<u64>();
        let limit = device.limits().max_storage_buffer_binding_size;
        if n * 4 > limit {
            return Err(Error::Size {
                stage: STAGE,
                what: "baked function bytes (4 per lattice cell)",
                got: n * 4,
                max: limit,
            });
        }
        let baked = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("baked density function"),
            size: n * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let params = self.lattice_params(device, volume);
        self.bake.record(
            device,
            rec,
            &cloud_march::bake::Resources {
                params: (&params).into(),
                baked: (&baked).into(),
            },
            ComputePipeline::<Bake<K>>::groups_for(volume.dims),
            "density function bake",
        )?;
        Ok(baked)
    }

    /// March the function over `volume`'s box under `local_to_world` for `view`, as
    /// [`super::VolumeRenderer::encode_march`] marches a texture (same settings, same image);
    /// `bricks` from [`Self::encode_bricks`] for the same box. `None` when the box is off
    /// screen. [`Shadow::LightVolume`] is refused: march a baked texture for it.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_march(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &FunctionVolume,
        bricks: &Bricks,
        tf: &TransferFunction,
        local_to_world: Mat4,
        view: &View,
        scene_depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
    ) -> Result<Option<VolumeMarched>, Error> {
        volume.check()?;
        settings.check()?;
        tf.check()?;
        check_transform(local_to_world)?;
        check_view(view)?;
        check_scene_depth(scene_depth, view)?;
        if bricks.count != volume.bricks() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "the brick grid was built for another lattice".into(),
            });
        }
        let march = self.march_for(device, settings)?;
        let Some(rect) = march_rect(view, local_to_world, volume.min, volume.max) else {
            return Ok(None);
        };
        let params = self.params(
            volume,
            tf,
            local_to_world,
            view,
            settings,
            rect,
            scene_depth.is_some(),
        );
        let (colour, lease) = kept::march_target(&self.marched, device, view.viewport);
        let recorder = &mut rec.recorder();
        let k = &self.kept;
        let label = "density march params";
        let params = (k.uploads).uniform(device, recorder.encoder, &k.params, label, &params);
        let tf_buffer = k.uploads.kept(
            device,
            recorder.encoder,
            &k.tf,
            "transfer function",
            wgpu::BufferUsages::STORAGE,
            bytemuck::cast_slice(&tf_rows(tf)),
        );
        march.record_kept(
            device,
            recorder,
            &k.bound,
            &cloud_march::march::Resources {
                params: (&params).into(),
                tf: (&tf_buffer).into(),
                ranges: (&bricks.ranges).into(),
                scene_depth: scene_depth.unwrap_or(&self.no_depth).into(),
                colour_out: (&colour.view).into(),
            },
            [
                (rect[2] - rect[0]).div_ceil(8),
                (rect[3] - rect[1]).div_ceil(8),
                1,
            ],
            STAGE,
        )?;
        Ok(Some(VolumeMarched::new(rect, view.viewport, colour, lease)))
    }
}

/// The density march's overrides for `settings`. Every density march is made from one
/// template, so the built-in cloud's generated overrides name the template's (`check_entry`
/// holds each stage to the template).
fn march_key(settings: &MarchSettings) -> Result<cloud_march::Overrides, Error> {
    let shadow = match settings.shadow {
        Shadow::None => 0,
        Shadow::Rays { .. } => 1,
        Shadow::LightVolume { .. } => {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "a density function is shadowed by Shadow::Rays or not at all; for a \
                       light volume, bake it (encode_bake) and march the texture"
                    .into(),
            });
        }
    };
    let mode = match settings.mode {
        super::Mode::EmissionAbsorption => 0,
        super::Mode::MaximumIntensity => 1,
        super::Mode::IsoSurface { .. } => 2,
    };
    Ok(cloud_march::Overrides {
        mode,
        shadow,
        skip: settings.skip,
        count_samples: settings.count_samples,
    })
}
