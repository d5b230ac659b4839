//! Seed 002: the volume.

use super::*;
use std::sync::Arc;

/// The volume's settings: the cloud, its transfer function and how it is marched.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VolumeSettings {
    /// Voxels per side of the fBm cloud.
    pub size: u32,
    /// The cloud's noise seed.
    pub seed: u32,
    /// Density → colour and opacity.
    pub tf: TransferFunction,
    /// Step, shadows, mode, skipping.
    pub march: MarchSettings,
    /// March the cloud as a function evaluated at every sample, as the source does
    /// (`CloudMarch`: seed 0, `size` cells per side for its bricks; a light volume becomes
    /// shadow rays), instead of the baked texture.
    pub function: bool,
}

impl VolumeSettings {
    /// The source's cloud: the fBm function evaluated per sample, shadowed by rays through it.
    pub fn seed() -> Self {
        let d = Self::default();
        Self {
            function: true,
            march: MarchSettings {
                shadow: fieldkit::volume::Shadow::Rays { step: 1.0 / 32.0 },
                ..d.march
            },
            ..d
        }
    }
}

impl Default for VolumeSettings {
    fn default() -> Self {
        Self {
            function: false,
            size: 96,
            seed: 7,
            tf: TransferFunction::cloud(),
            march: MarchSettings {
                step: 1.0 / 96.0,
                ..MarchSettings::default()
            },
        }
    }
}

/// A cloud being made and uploaded on a worker thread, and its (size, seed).
pub(super) type PendingCloud = ((u32, u32), Job<Result<Volume, Error>>);

/// March settings whose pipelines a worker thread makes (`prepare`) while the frames march
/// with the last settings whose pipelines were made: a new mode, shadow or skipping costs the
/// frame no pipeline.
#[derive(Default)]
pub(super) struct Prepared {
    /// The settings last marched with.
    drawn: Option<MarchSettings>,
    making: Option<(MarchSettings, Job<Result<(), Error>>)>,
    /// Settings whose pipelines failed, and why: not tried again until they change.
    failed: Option<(MarchSettings, Error)>,
}

impl Prepared {
    /// The settings to march with: `wanted` where its pipelines are made (`ready`), else
    /// the last marched with while `prepare` makes them on a worker thread (`None` before
    /// any).
    fn settings(
        &mut self,
        wanted: MarchSettings,
        ready: bool,
        prepare: impl FnOnce() -> Result<(), Error> + Send + 'static,
    ) -> Result<Option<MarchSettings>, Error> {
        if let Some((_, job)) = &mut self.making
            && let Some(result) = job.try_take()
        {
            let (settings, _) = self.making.take().expect("checked");
            if let Err(e) = result.unwrap_or_else(|| Err(cloud_stopped())) {
                self.failed = Some((settings, e));
            }
        }
        if ready {
            self.drawn = Some(wanted);
            return Ok(Some(wanted));
        }
        if let Some((settings, e)) = &self.failed
            && *settings == wanted
        {
            return Err(e.clone());
        }
        if self.making.is_none() {
            self.making = Some((wanted, Job::spawn(prepare)));
        }
        Ok(self.drawn)
    }

    fn busy(&self) -> bool {
        self.making.is_some()
    }

    fn wait(&mut self) {
        if let Some((settings, job)) = self.making.take() {
            self.making = Some((settings, job.wait()));
        }
    }
}

/// The volume's GPU state.
pub struct VolumeScene {
    pub(super) renderer: Arc<VolumeRenderer>,
    /// The baked cloud's march settings, their pipelines made ahead.
    pub(super) prepared: Prepared,
    /// The cloud function's.
    pub(super) function_prepared: Prepared,
    pub(super) volume: Option<((u32, u32), Volume, fieldkit::volume::Bricks)>,
    /// The cloud as a function, made on a worker thread on first use (its pipelines), and its
    /// bricks for a lattice size.
    pub(super) cloud: Option<Arc<fieldkit::volume::CloudMarch>>,
    pub(super) cloud_making: Option<Job<Result<fieldkit::volume::CloudMarch, Error>>>,
    pub(super) cloud_bricks: Option<(u32, fieldkit::volume::Bricks)>,
    /// The light volume, kept while the cloud, its transfer function, the light and the
    /// transform stay (`LightVolume::is_for`): rebuilt only when one changes.
    pub(super) light: Option<fieldkit::volume::LightVolume>,
    /// A cloud being made on a worker thread for a new (size, seed): the frame draws the one
    /// it has until this one is ready, so a new size costs the frame no wait.
    pub(super) pending: Option<PendingCloud>,
}

impl VolumeScene {
    pub(super) fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Self, Error> {
        Ok(Self {
            renderer: Arc::new(VolumeRenderer::new(device, queue, COLOUR)?),
            prepared: Prepared::default(),
            function_prepared: Prepared::default(),
            light: None,
            volume: None,
            cloud: None,
            cloud_making: None,
            cloud_bricks: None,
            pending: None,
        })
    }

    /// The fBm cloud for `key` (size, seed), made and uploaded on a worker thread (its
    /// densities checked and packed to R8 there: about a million voxels at 106³), and taken
    /// when it is ready. No frame waits for it: until the first cloud arrives the scene draws
    /// without one, and later ones are drawn from the frame they are ready on, the previous
    /// one until then.
    fn cloud_for(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        key: (u32, u32),
    ) -> Option<Result<Volume, Error>> {
        if self.pending.as_ref().map(|p| p.0) != Some(key) {
            let (device, queue) = (device.clone(), queue.clone());
            let job = Job::spawn(move || {
                let n = key.0;
                Volume::upload(
                    &device,
                    &queue,
                    &fbm_cloud([n; 3], key.1),
                    [n; 3],
                    wgpu::TextureFormat::R8Unorm,
                    Vec3::splat(1.0 / n as f32),
                    Vec3::splat(-0.5),
                )
            });
            self.pending = Some((key, job));
        }
        let (_, job) = self.pending.as_mut().expect("set above");
        let ready = job
            .try_take()
            .map(|cloud| cloud.unwrap_or_else(|| Err(cloud_stopped())));
        if ready.is_some() {
            self.pending = None;
        }
        ready
    }

    /// Work on a worker thread not yet drawn: a cloud, or the cloud function's pipelines.
    pub(super) fn busy(&self) -> bool {
        self.pending.is_some()
            || self.cloud_making.is_some()
            || self.prepared.busy()
            || self.function_prepared.busy()
    }

    /// Wait for the cloud being made on the worker thread, if any; the next frame takes it.
    pub(super) fn wait_for_cloud(&mut self) {
        if let Some(job) = self.cloud_making.take() {
            self.cloud_making = Some(job.wait());
        }
        if let Some((key, job)) = self.pending.take() {
            self.pending = Some((key, job.wait()));
        }
        self.prepared.wait();
        self.function_prepared.wait();
    }

    /// March the cloud *function* (`VolumeSettings::function`) into the frame.
    pub(super) fn draw_function(
        &mut self,
        s: &VolumeSettings,
        local_to_world: Mat4,
        frame: &mut Frame,
    ) -> PanelLines {
        let device = frame.device;
        use fieldkit::volume::{CloudMarch, FunctionVolume, Shadow};
        let mut march = s.march;
        if let Shadow::LightVolume { step } = march.shadow {
            march.shadow = Shadow::Rays { step };
        }
        if self.cloud.is_none() {
            let job = self.cloud_making.get_or_insert_with(|| {
                let (device, queue) = (frame.device.clone(), frame.queue.clone());
                let viewport = frame.size;
                // The march's pipeline for these settings and its image for this screen too,
                // made ahead of the first march.
                Job::spawn(move || {
                    let cloud = CloudMarch::cloud(&device, &queue)?;
                    cloud.prepare(&device, &march)?;
                    cloud.reserve(&device, viewport)?;
                    Ok(cloud)
                })
            });
            let Some(made) = job.try_take() else {
                return Ok(vec![
                    "volume: the cloud function's pipelines are being made on a worker thread"
                        .into(),
                ]);
            };
            let made = made.unwrap_or_else(|| Err(cloud_stopped()));
            self.cloud_making = None;
            self.cloud = Some(Arc::new(made?));
        }
        let cloud = self.cloud.clone().expect("set above");
        let (c, d) = (cloud.clone(), device.clone());
        let ready = cloud.prepared(&march);
        let prepare = move || c.prepare(&d, &march);
        let Some(mut march) = self.function_prepared.settings(march, ready, prepare)? else {
            return Ok(vec!["volume: the march's pipelines are being made".into()]);
        };
        march.frame = frame.number;
        let lattice = FunctionVolume::unit(s.size.clamp(4, 512));
        if self.cloud_bricks.as_ref().map(|b| b.0) != Some(lattice.dims[0]) {
            let bricks = cloud.encode_bricks(device, frame.rec, &lattice)?;
            self.cloud_bricks = Some((lattice.dims[0], bricks));
        }
        let (_, bricks) = self.cloud_bricks.as_ref().expect("set above");
        let view = frame.camera.view(frame.size);
        // The function's box is its unit cube of texture coordinates, centred as the texture.
        let placed = local_to_world * Mat4::from_translation(Vec3::splat(-0.5));
        if let Some(m) = cloud.encode_march(
            device,
            frame.rec,
            &lattice,
            bricks,
            &s.tf,
            placed,
            &view,
            Some(&frame.targets.depth_view),
            &march,
        )? {
            self.renderer.encode_composite(
                device,
                &mut *frame.rec,
                &frame.targets.colour_view,
                &m,
            )?;
        }
        Ok(vec![format!(
            "volume: the fBm function per sample (seed 0), bricks over {0}³ cells, {1:?}",
            lattice.dims[0], march.shadow
        )])
    }

    /// March the cloud under `local_to_world` into the frame, stopping at its depth.
    pub(super) fn draw(
        &mut self,
        s: &VolumeSettings,
        local_to_world: Mat4,
        frame: &mut Frame,
    ) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        if s.function {
            return self.draw_function(s, local_to_world, frame);
        }
        if self.volume.as_ref().map(|v| v.0) != Some((s.size, s.seed)) {
            if !(4..=512).contains(&s.size) {
                return Err(Error::Size {
                    stage: "viewer: volume",
                    what: "cloud voxels per side (4 to 512)",
                    got: s.size as u64,
                    max: 512,
                });
            }
            if let Some(volume) = self.cloud_for(device, queue, (s.size, s.seed)) {
                let volume = volume?;
                let bricks = self.renderer.encode_bricks(device, frame.rec, &volume)?;
                self.volume = Some(((s.size, s.seed), volume, bricks));
            }
        }
        let Some((_, volume, bricks)) = self.volume.as_ref() else {
            return Ok(vec![format!(
                "volume: the {0}³ cloud is being made on a worker thread",
                s.size
            )]);
        };
        let (r, d) = (self.renderer.clone(), device.clone());
        let ready = self.renderer.prepared(&s.march);
        let wanted = s.march;
        let prepare = move || r.prepare(&d, &wanted);
        let Some(mut march) = self.prepared.settings(wanted, ready, prepare)? else {
            return Ok(vec!["volume: the march's pipelines are being made".into()]);
        };
        march.frame = frame.number;
        let light = match march.shadow {
            fieldkit::volume::Shadow::LightVolume { .. } => {
                let kept = self
                    .light
                    .take()
                    .filter(|l| l.is_for(volume, &s.tf, local_to_world, &march));
                let light = match kept {
                    Some(l) => l,
                    None => self.renderer.encode_light(
                        device,
                        frame.rec,
                        volume,
                        bricks,
                        &s.tf,
                        local_to_world,
                        &march,
                    )?,
                };
                Some(&*self.light.insert(light))
            }
            _ => None,
        };
        let view = frame.camera.view(frame.size);
        if let Some(m) = self.renderer.encode_march(
            device,
            frame.rec,
            volume,
            bricks,
            light,
            &s.tf,
            local_to_world,
            &view,
            Some(&frame.targets.depth_view),
            &march,
        )? {
            self.renderer.encode_composite(
                device,
                &mut *frame.rec,
                &frame.targets.colour_view,
                &m,
            )?;
        }
        Ok(vec![format!(
            "volume: {0}³, bricks {1}×{1}×{1}",
            s.size, bricks.count[0]
        )])
    }
}

fn cloud_stopped() -> Error {
    invalid("the cloud's worker thread stopped before making it")
}
