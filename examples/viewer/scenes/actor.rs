//! Seed 000: the voxel actor (metaballs).

use super::*;

/// What the actor draws.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum ActorDraw {
    /// The raymarched SDF surface (or its debug view, `RaymarchSettings::output`).
    Surface,
    /// The debug cubes alone.
    Cubes,
    /// Surface and cubes.
    Both,
    /// The field traced directly, no SDF.
    Direct(Direct),
}

/// The voxel actor's settings: the source's grid builder (Extent, BlockSize), the field, the
/// march, the cubes and the animation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ActorSettings {
    /// The region the blocks fill, world units per axis.
    pub extent: [f32; 3],
    /// Block size: the voxel edge and the spacing.
    pub block: f32,
    /// How the voxels become a field.
    pub field: Settings,
    /// How the surface is marched and shaded.
    pub raymarch: RaymarchSettings,
    /// Debug cube style.
    pub cubes: CubeStyle,
    /// What is drawn.
    pub draw: ActorDraw,
    /// Animate (scale pulse and Lissajous offsets).
    pub animate: bool,
    /// The animation's frequencies, amplitudes, ratios and phase step.
    pub animation: Animation,
}

impl Default for ActorSettings {
    fn default() -> Self {
        Self {
            extent: [5.0, 4.0, 3.0],
            block: 1.0,
            field: Settings::default(),
            raymarch: RaymarchSettings::default(),
            cubes: CubeStyle::default(),
            draw: ActorDraw::Surface,
            animate: true,
            animation: Animation::default(),
        }
    }
}

impl ActorSettings {
    /// The source's voxel actor: every `seed()` preset (field, march, cubes, animation), the
    /// same extent and block.
    pub fn seed() -> Self {
        Self {
            field: Settings::seed(),
            raymarch: RaymarchSettings::seed(),
            cubes: CubeStyle::seed(),
            animation: Animation::seed(),
            ..Self::default()
        }
    }

    /// Blocks per axis as the source's builder counts them: max(1, ⌊Extent / BlockSize⌋).
    pub fn counts(&self) -> Result<[u32; 3], Error> {
        if !(self.block.is_finite() && self.block > 0.0) {
            return Err(invalid(format!(
                "BlockSize must be finite and > 0, got {}",
                self.block
            )));
        }
        if !self.extent.iter().all(|e| e.is_finite() && *e >= 0.0) {
            return Err(invalid(format!(
                "Extent must be finite and ≥ 0, got {:?}",
                self.extent
            )));
        }
        let n = self
            .extent
            .map(|e| ((e / self.block).floor() as f64).clamp(1.0, u32::MAX as f64));
        let total = n.iter().product::<f64>();
        if total > MAX_ACTOR_INSTANCES as f64 {
            return Err(Error::Size {
                stage: "viewer: voxel actor",
                what: "instances (Extent / BlockSize per axis, multiplied)",
                got: total.min(u64::MAX as f64) as u64,
                max: MAX_ACTOR_INSTANCES,
            });
        }
        Ok(n.map(|v| v as u32))
    }
}

/// The voxel actor's GPU state.
pub struct Actor {
    pub(super) balls: Metaballs,
    pub(super) instances: Option<(Instances, usize)>,
    pub(super) base: Option<([u32; 3], f32, Vec<glam::Vec4>)>,
    /// The raymarcher for the camera's depth convention, made on a worker thread.
    pub(super) marcher: Latest<bool, Raymarcher>,
    /// The debug cubes for the style's pipeline (culling, depth, wireframe), made on a worker
    /// thread; colour, size and culling by frustum restyled in place.
    pub(super) cubes: Latest<CubeStyle, Cubes>,
    /// The grid the field is built on, kept while the blocks, the animation and the field
    /// settings stay: fitted to the animation's envelope, so it holds every frame.
    pub(super) grid: Option<(GridKey, Option<fieldkit::distance::Grid>)>,
}

/// What the actor's grid is fitted from.
type GridKey = (
    [u32; 3],
    f32,
    Option<fieldkit::metaball::Animation>,
    fieldkit::metaball::Settings,
);

impl Actor {
    /// Whether the raymarcher or the cubes the settings ask for are being made.
    pub fn busy(&self) -> bool {
        self.marcher.busy() || self.cubes.busy()
    }

    /// Wait for the raymarcher and cubes being made; the next frame takes them.
    pub fn wait_for_workers(&mut self) {
        self.marcher.wait();
        self.cubes.wait();
    }

    pub(super) fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            balls: Metaballs::new(device)?,
            instances: None,
            base: None,
            marcher: Latest::default(),
            cubes: Latest::default(),
            grid: None,
        })
    }

    pub(super) fn encode(&mut self, s: &ActorSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        clear(frame, [0.09, 0.1, 0.12]);
        // Cubes asked for before the draw mode left them: taken when ready all the same.
        self.cubes.poll();
        let counts = s.counts()?;
        if self.base.as_ref().map(|b| (b.0, b.1)) != Some((counts, s.block)) {
            self.base = Some((counts, s.block, packed_grid(counts, s.block)?));
        }
        let base = &self.base.as_ref().expect("set above").2;
        let voxels = if s.animate {
            spent(&mut frame.fieldkit_ms, || {
                s.animation.apply(base, s.block, frame.time)
            })?
        } else {
            base.clone()
        };
        spent(&mut frame.fieldkit_ms, || {
            self.prepare(device, queue, &voxels, frame.camera.reversed_z)
        })?;
        let reversed = frame.camera.reversed_z;
        let instances = &self.instances.as_ref().expect("prepared").0;
        let view = frame.camera.view(frame.size);
        let (cv, dv) = (&frame.targets.colour_view, &frame.targets.depth_view);
        let mut stats = vec![format!(
            "instances: {} ({}×{}×{})",
            voxels.len(),
            counts[0],
            counts[1],
            counts[2]
        )];
        if matches!(s.draw, ActorDraw::Cubes | ActorDraw::Both) {
            let mut style = s.cubes;
            if reversed {
                style.depth_compare = flip(style.depth_compare);
            }
            // What the pipeline fixes: the rest is restyled in place.
            let key = CubeStyle {
                colour: CubeStyle::default().colour,
                scale_size: true,
                frustum_cull: true,
                ..style
            };
            let (d, q) = (device.clone(), queue.clone());
            let make = move || Cubes::new(&d, &q, COLOUR, DEPTH, key);
            if let Some(cubes) = self.cubes.get(&key, make)? {
                // Cubes made for an earlier style keep theirs until the new ones arrive.
                cubes.restyle(style)?;
                spent(&mut frame.fieldkit_ms, || {
                    cubes.encode(
                        device,
                        &mut *frame.rec,
                        cv,
                        dv,
                        instances,
                        s.block,
                        Mat4::IDENTITY,
                        view.view_proj,
                    )
                })?;
            }
        }
        let animation = s.animate.then_some(s.animation);
        let key = (counts, s.block, animation, s.field);
        if self.grid.as_ref().map(|g| &g.0) != Some(&key) {
            let base = &self.base.as_ref().expect("set above").2;
            let envelope = match animation {
                Some(a) => a.envelope(base, s.block),
                None => base.clone(),
            };
            self.grid = Some((key, s.field.fit_grid(&envelope, s.block)?));
        }
        let Some(grid) = self.grid.as_ref().expect("set above").1 else {
            return Ok(stats);
        };
        stats.push(format!(
            "grid: {}×{}×{}",
            grid.size[0], grid.size[1], grid.size[2]
        ));
        let start = std::time::Instant::now();
        match s.draw {
            ActorDraw::Surface | ActorDraw::Both => self.surface(device, s, &grid, frame)?,
            ActorDraw::Direct(method) => {
                let bins = self
                    .balls
                    .encode_bins(device, frame.rec, instances, &grid, s.block, &s.field)?;
                // A raymarcher for the other depth direction draws nothing: the surface
                // shows from the frame this one arrives on.
                let Some(marcher) = self.marcher.ready(&reversed) else {
                    return Ok(stats);
                };
                if let Some(m) = marcher.encode_direct_march(
                    device,
                    frame.rec,
                    &bins,
                    method,
                    Mat4::IDENTITY,
                    &view,
                    &s.raymarch,
                )? {
                    marcher.encode_composite(device, &mut *frame.rec, cv, dv, &m)?;
                }
            }
            ActorDraw::Cubes => {}
        }
        *frame.fieldkit_ms.get_or_insert(0.0) += start.elapsed().as_secs_f64() * 1e3;
        Ok(stats)
    }
}

impl Actor {
    /// Upload (or update in place) the voxels, and start making the raymarcher for this depth
    /// convention on a worker thread if the last one was made for the other (the surface is
    /// not drawn until it arrives).
    pub(super) fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxels: &[glam::Vec4],
        reversed: bool,
    ) -> Result<(), Error> {
        match &mut self.instances {
            Some((inst, n)) if *n == voxels.len() => self.balls.update(queue, inst, voxels)?,
            _ => self.instances = Some((self.balls.upload(device, queue, voxels)?, voxels.len())),
        }
        let (d, q) = (device.clone(), queue.clone());
        let make = move || Raymarcher::new(&d, &q, COLOUR, DEPTH, reversed);
        self.marcher.get(&reversed, make)?;
        Ok(())
    }

    /// The field of the prepared voxels on `grid`, marched and composited into the frame (once
    /// the raymarcher has arrived).
    pub(super) fn surface(
        &self,
        device: &wgpu::Device,
        s: &ActorSettings,
        grid: &fieldkit::distance::Grid,
        frame: &mut Frame,
    ) -> Result<(), Error> {
        let instances = &self.instances.as_ref().expect("prepared").0;
        let Some(marcher) = self.marcher.ready(&frame.camera.reversed_z) else {
            return Ok(());
        };
        let view = frame.camera.view(frame.size);
        let field = self
            .balls
            .encode(device, frame.rec, instances, grid, s.block, &s.field)?;
        if let Some(m) = marcher.encode_march(
            device,
            frame.rec,
            &field,
            Mat4::IDENTITY,
            &view,
            &s.raymarch,
        )? {
            marcher.encode_composite(
                device,
                &mut *frame.rec,
                &frame.targets.colour_view,
                &frame.targets.depth_view,
                &m,
            )?;
        }
        Ok(())
    }

    /// The actor drawn as the composite's island: sky cleared, the blocks sunk by half their
    /// height.
    pub(super) fn encode_island(&mut self, s: &ActorSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        let saved_clear = [0.55, 0.7, 0.85];
        clear(frame, saved_clear);
        let counts = s.counts()?;
        let start = std::time::Instant::now();
        let voxels: Vec<glam::Vec4> = packed_grid(counts, s.block)?
            .into_iter()
            .map(|v| v - glam::Vec4::new(0.0, 3.5, 0.0, 0.0))
            .filter(|v| {
                let r = (v.x * v.x + 1.6 * v.z * v.z).sqrt();
                r < 19.0 - 4.0 * (v.y + 3.5)
            })
            .collect();
        self.prepare(device, queue, &voxels, frame.camera.reversed_z)?;
        if let Some(grid) = s.field.fit_grid(&voxels, s.block)? {
            self.surface(device, s, &grid, frame)?;
        }
        *frame.fieldkit_ms.get_or_insert(0.0) += start.elapsed().as_secs_f64() * 1e3;
        Ok(vec![format!("island instances: {}", voxels.len())])
    }
}
