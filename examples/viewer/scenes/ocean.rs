//! Seed 001: the ocean.

use super::*;

/// The ocean's settings: the waves table, steepness, look (detail layers, depth fade), LOD and
/// which target is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct OceanSettings {
    /// The waves table.
    pub waves: Vec<Wave>,
    /// Steepness Q, shared as Qᵢ = Q / (wᵢ·Aᵢ·N).
    pub steepness: f32,
    /// Colours, light, detail layers, depth fade.
    pub look: Look,
    /// The patch quadtree's square and error target.
    pub lod: LodSettings,
    /// Fade the water's colour with the depth of the scene under it.
    pub fade: bool,
    /// Draw into the four G-buffer targets and show one of them (0–3) instead of forward.
    pub gbuffer: Option<usize>,
    /// Draw the patch quadtree over the water.
    pub overlay: bool,
    /// Depth target: written (default) or read only (the source's).
    #[serde(default)]
    pub depth_write: Option<bool>,
}

impl Default for OceanSettings {
    fn default() -> Self {
        let wave = |d: [f32; 2], a, l, s| Wave {
            direction: Vec2::from_array(d),
            amplitude: a,
            wavelength: l,
            speed: s,
        };
        Self {
            waves: vec![
                wave([1.0, 0.3], 0.35, 21.0, 5.7),
                wave([0.2, 1.0], 0.18, 9.5, 3.8),
                wave([-0.8, 0.5], 0.06, 4.1, 2.5),
            ],
            steepness: 0.7,
            look: Look {
                fade_distance: 3.0,
                sun_direction: Vec3::new(-0.4, 0.5, -0.75),
                ..Look::default()
            },
            lod: LodSettings::default(),
            fade: true,
            gbuffer: None,
            overlay: false,
            depth_write: None,
        }
    }
}

impl OceanSettings {
    /// The source's sea: `Look::seed` (30 cm fade, no skirts) and depth read only, the same
    /// waves and sun.
    pub fn seed() -> Self {
        let d = Self::default();
        Self {
            look: Look {
                sun_direction: d.look.sun_direction,
                ..Look::seed()
            },
            depth_write: Some(false),
            ..d
        }
    }
}

/// The G-buffer's four targets and their size.
pub(super) type GBuffer = ([u32; 2], Vec<Targets>);

/// Four targets of `size` for the G-buffer.
fn gbuffer_targets(device: &wgpu::Device, size: [u32; 2]) -> GBuffer {
    let targets = (0..4)
        .map(|_| Targets::new(device, size, COLOUR, DEPTH))
        .collect();
    (size, targets)
}

/// The ocean's GPU state.
pub struct Ocean {
    /// The renderer for the output (G-buffer or not), the depth direction and depth writes,
    /// made on a worker thread; the last one draws until it arrives.
    /// With a G-buffer renderer, its targets for the frame's size, made on the worker too.
    pub(super) renderer: Latest<(bool, bool, bool), (OceanRenderer, Option<GBuffer>)>,
    pub(super) gbuffer: Option<GBuffer>,
    pub(super) lines: Lines,
}

impl Ocean {
    pub(super) fn new(device: &wgpu::Device) -> Self {
        Self {
            renderer: Latest::default(),
            gbuffer: None,
            lines: Lines::new(device, COLOUR),
        }
    }

    /// Ask for the renderer `s` needs with the depth direction `reversed`, made on a worker
    /// thread; whether one (this one, or the last until it arrives) is there to draw with.
    fn ask_renderer(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        s: &OceanSettings,
        reversed: bool,
        size: [u32; 2],
    ) -> Result<bool, Error> {
        let write = s.depth_write.unwrap_or(true);
        let key = (s.gbuffer.is_some(), reversed, write);
        let (d, q) = (device.clone(), queue.clone());
        let make = move || {
            let output = if key.0 {
                OceanOutput::GBuffer([COLOUR; 4])
            } else {
                OceanOutput::Forward(COLOUR)
            };
            let depth = fieldkit::ocean::DepthMode {
                write,
                ..Default::default()
            };
            let renderer = OceanRenderer::with_depth(&d, &q, output, key.1, depth)?;
            Ok((renderer, key.0.then(|| gbuffer_targets(&d, size))))
        };
        let Some((_, made)) = self.renderer.get(&key, make)? else {
            return Ok(false);
        };
        if let Some(g) = made.take() {
            self.gbuffer = Some(g);
        }
        Ok(true)
    }

    /// Draw the sea into the frame (over what it holds).
    pub(super) fn draw(&mut self, s: &OceanSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        let waves = spent(&mut frame.fieldkit_ms, || {
            Waves::new(s.waves.clone(), s.steepness)
        })?;
        let camera = frame.camera.ocean(frame.size);
        if !self.ask_renderer(device, queue, s, frame.camera.reversed_z, frame.size)? {
            return Ok(vec!["the sea's renderer is being made".into()]);
        }
        // The renderer made for these settings, or the last one until it arrives: drawn into
        // the targets it was made for.
        let (&(gbuffer_on, _, _), (renderer, _)) =
            self.renderer.current_with_key().expect("checked");
        let gbuffer = gbuffer_on.then(|| s.gbuffer.unwrap_or(0));
        // The patches are chosen on the GPU; on the CPU only where the overlay draws them (or
        // the device cannot draw the GPU's choice).
        let selection = (s.overlay || !renderer.lod_on_gpu())
            .then(|| select(&waves, &s.look, &camera, frame.size[1], &s.lod))
            .transpose()?;
        let time = frame.time as f64;
        let draw = |rec: &mut fieldkit::gpu::Recorder<'_>, views: &[&wgpu::TextureView]| {
            let depth = &frame.targets.depth;
            match &selection {
                Some(sel) => renderer.encode(
                    device,
                    rec,
                    &waves,
                    time,
                    &camera,
                    &s.look,
                    &sel.patches,
                    views,
                    depth,
                    s.fade,
                ),
                None => renderer.encode_lod(
                    device, rec, &waves, time, &camera, &s.look, &s.lod, views, depth, s.fade,
                ),
            }
        };
        match gbuffer {
            None => spent(&mut frame.fieldkit_ms, || {
                draw(frame.rec, &[&frame.targets.colour_view])
            })?,
            Some(shown) => {
                if shown > 3 {
                    return Err(invalid(format!("G-buffer target {shown} (0–3)")));
                }
                if self.gbuffer.as_ref().map(|g| g.0) != Some(frame.size) {
                    self.gbuffer = Some(gbuffer_targets(device, frame.size));
                }
                let g = &self.gbuffer.as_ref().expect("set above").1;
                for t in g {
                    t.clear(frame.rec.encoder, wgpu::Color::BLACK, 1.0);
                }
                let views: Vec<&wgpu::TextureView> = g.iter().map(|t| &t.colour_view).collect();
                draw(frame.rec, &views)?;
                frame.rec.encoder.copy_texture_to_texture(
                    g[shown].colour.as_image_copy(),
                    frame.targets.colour.as_image_copy(),
                    frame.targets.colour.size(),
                );
            }
        }
        let Some(selection) = selection else {
            return Ok(vec![
                "patches: chosen on the GPU (the overlay lists them)".into(),
            ]);
        };
        if s.overlay {
            let segments: Vec<[Vec3; 2]> = selection
                .patches
                .iter()
                .flat_map(|p| {
                    let (x0, z0) = (p.corner.x as f32, p.corner.y as f32);
                    let e = p.size as f32;
                    let c = [
                        Vec3::new(x0, 0.0, z0),
                        Vec3::new(x0 + e, 0.0, z0),
                        Vec3::new(x0 + e, 0.0, z0 + e),
                        Vec3::new(x0, 0.0, z0 + e),
                    ];
                    [[c[0], c[1]], [c[1], c[2]], [c[2], c[3]], [c[3], c[0]]]
                })
                .collect();
            let view = frame.camera.view(frame.size);
            self.lines.encode(
                device,
                queue,
                &mut *frame.rec,
                &frame.targets.colour_view,
                view.view_proj,
                &segments,
                Vec4::new(1.0, 0.85, 0.2, 1.0),
            );
        }
        Ok(vec![
            format!(
                "patches: {} ({} culled), triangles: {}",
                selection.patches.len(),
                selection.culled,
                selection.triangles
            ),
            format!("largest height error: {:.2} px", selection.max_error_px),
        ])
    }
}
