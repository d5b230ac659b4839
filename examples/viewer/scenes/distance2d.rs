//! Seed 003: the 2D distance tool.

use super::*;

/// The 2D distance tool's settings: the seed texels, the method, and how the field is shown.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DistanceSettings {
    /// Mask width and height, texels.
    pub size: [u32; 2],
    /// Exact (default) or a JFA variant; signed or not; texel size.
    pub options: Settings2d,
    /// The seed texels.
    pub seeds: Vec<[u32; 2]>,
    /// Texels between iso-lines.
    pub iso_period: f32,
    /// Brush radius, texels.
    pub brush: u32,
}

impl Default for DistanceSettings {
    fn default() -> Self {
        // A sparse scatter (where JFA goes wrong) and a short wall.
        let mut seeds = Vec::new();
        let mut x = 12345u32;
        for _ in 0..24 {
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            let a = (x >> 8) % 200;
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            let b = (x >> 8) % 120;
            seeds.push([a, b]);
        }
        seeds.extend((60..140).map(|i| [i, 60]));
        Self {
            size: [200, 120],
            options: Settings2d::default(),
            seeds,
            iso_period: 8.0,
            brush: 1,
        }
    }
}

impl DistanceSettings {
    /// The mask: 255 at every seed texel inside the size.
    pub fn mask(&self) -> Result<Vec<u8>, Error> {
        self.check_size()?;
        let [w, h] = self.size;
        let mut mask = vec![0u8; (w * h) as usize];
        for &[x, y] in &self.seeds {
            if x < w && y < h {
                mask[(y * w + x) as usize] = 255;
            }
        }
        Ok(mask)
    }

    /// The mask's size, refused when a side is 0 or it holds more than 4096² texels.
    pub fn check_size(&self) -> Result<(), Error> {
        let [w, h] = self.size;
        if w == 0 || h == 0 || w as u64 * h as u64 > 4096 * 4096 {
            return Err(Error::Size {
                stage: "viewer: distance 2D",
                what: "mask texels (width × height, each side ≥ 1)",
                got: w as u64 * h as u64,
                max: 4096 * 4096,
            });
        }
        Ok(())
    }

    /// Add (or, `erase`, remove) seeds in a disc of the brush radius around texel `at`.
    /// The brush along the stroke from `from` to `to` (texels), every texel of the line
    /// stamped, so a fast drag leaves a line and not separate dots.
    pub fn paint_stroke(&mut self, from: [u32; 2], to: [u32; 2], erase: bool) {
        for at in line(from, to) {
            self.paint(at, erase);
        }
    }

    pub fn paint(&mut self, at: [u32; 2], erase: bool) {
        let r = self.brush as i64;
        let inside = |p: [u32; 2]| {
            let (dx, dy) = (p[0] as i64 - at[0] as i64, p[1] as i64 - at[1] as i64);
            dx * dx + dy * dy <= r * r
        };
        if erase {
            self.seeds.retain(|&p| !inside(p));
            return;
        }
        for y in (at[1] as i64 - r)..=(at[1] as i64 + r) {
            for x in (at[0] as i64 - r)..=(at[0] as i64 + r) {
                if x < 0 || y < 0 || x >= self.size[0] as i64 || y >= self.size[1] as i64 {
                    continue;
                }
                let p = [x as u32, y as u32];
                if inside(p) && !self.seeds.contains(&p) {
                    self.seeds.push(p);
                }
            }
        }
    }
}

/// The texels of the line from `a` to `b`, both included, each a step of one texel along the
/// longer axis (a DDA).
pub fn line(a: [u32; 2], b: [u32; 2]) -> Vec<[u32; 2]> {
    let (dx, dy) = (b[0] as f64 - a[0] as f64, b[1] as f64 - a[1] as f64);
    let steps = dx.abs().max(dy.abs()) as u32;
    (0..=steps)
        .map(|i| {
            let t = if steps == 0 {
                0.0
            } else {
                i as f64 / steps as f64
            };
            [
                (a[0] as f64 + dx * t).round() as u32,
                (a[1] as f64 + dy * t).round() as u32,
            ]
        })
        .collect()
}

pub(super) struct Pending2d {
    pub(super) key: DistanceSettings,
    pub(super) field: Readback<Vec<f32>>,
    pub(super) exact: Readback<Vec<f32>>,
}

/// A mask size, method and sign: what the transform's pipelines are specialised by (the seed
/// channels and threshold are uniforms).
pub(super) type Prepare2d = ([u32; 2], Method2d, bool);

/// Fields recorded into a frame not yet submitted: read back once it is.
pub(super) struct Recorded2d {
    pub(super) key: DistanceSettings,
    pub(super) field: wgpu::Texture,
    pub(super) exact: wgpu::Texture,
}

/// The 2D tool's state: the field is computed when the settings change, read back without
/// waiting, coloured on the CPU and shown until the next change.
pub struct Distance2dScene {
    pub(super) distance: std::sync::Arc<Distance2d>,
    /// The mask sizes and settings whose pipelines are made (`Distance2d::prepare`), and the
    /// ones a worker thread is making: a new sign or method costs the frame no pipeline.
    pub(super) prepared: Vec<Prepare2d>,
    pub(super) preparing: Option<(Prepare2d, Job<Result<(), Error>>)>,
    pub(super) blit: Blit,
    pub(super) recorded: Option<Recorded2d>,
    pub(super) pending: Option<Pending2d>,
    pub(super) shown: Option<(DistanceSettings, wgpu::TextureView, usize, f32)>,
}

/// Where the field image sits in the frame: the largest rectangle of its aspect, centred
/// (fractions of the frame, y down).
pub fn field_rect(size: [u32; 2], field: [u32; 2]) -> [f32; 4] {
    let (fw, fh) = (size[0] as f32, size[1] as f32);
    let s = (fw / field[0] as f32).min(fh / field[1] as f32);
    let (w, h) = (field[0] as f32 * s / fw, field[1] as f32 * s / fh);
    [
        (1.0 - w) / 2.0,
        (1.0 - h) / 2.0,
        (1.0 + w) / 2.0,
        (1.0 + h) / 2.0,
    ]
}

impl Distance2dScene {
    pub(super) fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            distance: std::sync::Arc::new(Distance2d::new(device)?),
            prepared: Vec::new(),
            preparing: None,
            blit: Blit::new(device, COLOUR),
            recorded: None,
            pending: None,
            shown: None,
        })
    }

    /// Work started and not yet shown.
    pub fn busy(&self, s: &DistanceSettings) -> bool {
        self.preparing.is_some()
            || self.recorded.is_some()
            || self.pending.is_some()
            || self.shown.as_ref().map(|x| &x.0) != Some(s)
    }

    /// Whether the pipelines `s` needs (its method's and the exact transform's it is compared
    /// with) are made; if not, a worker thread makes them (`Distance2d::prepare`).
    fn prepare(&mut self, device: &wgpu::Device, s: &DistanceSettings) -> Result<bool, Error> {
        if let Some((_, job)) = &mut self.preparing
            && let Some(result) = job.try_take()
        {
            let (key, _) = self.preparing.take().expect("checked");
            // Refused settings count as tried: the encode that follows gives their error.
            self.prepared.push(key);
            result.unwrap_or_else(|| Err(invalid("the 2D tool's worker thread stopped")))?;
        }
        let key = (s.size, s.options.method, s.options.signed);
        if self.prepared.contains(&key) {
            return Ok(true);
        }
        if self.preparing.is_none() {
            let (distance, device) = (self.distance.clone(), device.clone());
            let options = s.options;
            let exact = Settings2d {
                method: Method2d::Exact,
                ..options
            };
            let job = Job::spawn(move || {
                distance.prepare(&device, key.0, &options)?;
                distance.prepare(&device, key.0, &exact)
            });
            self.preparing = Some((key, job));
        }
        Ok(false)
    }

    /// Wait for the pipelines being made; the next frame takes them.
    pub fn wait_for_worker(&mut self) {
        if let Some((key, job)) = self.preparing.take() {
            self.preparing = Some((key, job.wait()));
        }
    }

    /// The frame that recorded the fields was submitted: start reading them.
    pub(super) fn submitted(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) {
        if let Some(r) = self.recorded.take() {
            self.pending = Some(Pending2d {
                key: r.key,
                field: readback_texture(device, queue, &r.field),
                exact: readback_texture(device, queue, &r.exact),
            });
        }
    }

    pub(super) fn encode(&mut self, s: &DistanceSettings, frame: &mut Frame) -> PanelLines {
        let (device, queue) = (frame.device, frame.queue);
        clear(frame, [0.05, 0.05, 0.06]);
        // Take a finished readback.
        if let Some(p) = &mut self.pending
            && p.field.is_ready()
            && p.exact.is_ready()
        {
            let p = self.pending.take().expect("checked");
            let (mut field, mut exact) = (p.field, p.exact);
            let field = field.try_take().expect("ready")?;
            let exact = exact.try_take().expect("ready")?;
            let is_wrong = |(a, b): (&f32, &f32)| (a - b).abs() > 1e-3 * b.abs().max(1.0);
            let wrong = field.iter().zip(&exact).filter(|&p| is_wrong(p)).count();
            let worst = field
                .iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            let [w, h] = p.key.size;
            let mut pixels = colour_field(&field, &p.key);
            // The texels the method got wrong, in magenta on the image itself.
            for (px, pair) in pixels.chunks_mut(4).zip(field.iter().zip(&exact)) {
                if is_wrong(pair) {
                    px.copy_from_slice(&WRONG);
                }
            }
            let texture = upload_rgba(device, queue, &pixels, w, h);
            let view = texture.create_view(&Default::default());
            self.shown = Some((p.key, view, wrong, worst));
        }
        // Start a new computation when the settings changed, none is running and the
        // pipelines it needs are made (a worker makes them meanwhile; the last field stays
        // shown).
        if self.pending.is_none()
            && self.recorded.is_none()
            && self.shown.as_ref().map(|x| &x.0) != Some(s)
            && self.prepare(device, s)?
        {
            let [w, h] = s.size;
            let mask = upload_mask(device, queue, &s.mask()?, w, h)?;
            // Each method's passes grouped under its name: the panel adds up what each costs.
            frame.rec.group(Some(&method_name(s.options.method)));
            let field = self.distance.encode(device, frame.rec, &mask, &s.options);
            let exact_options = Settings2d {
                method: Method2d::Exact,
                ..s.options
            };
            frame.rec.group(Some(EXACT_GROUP));
            let exact = self
                .distance
                .encode(device, frame.rec, &mask, &exact_options);
            frame.rec.group(None);
            let (field, exact) = (field?, exact?);
            self.recorded = Some(Recorded2d {
                key: s.clone(),
                field: field.distance,
                exact: exact.distance,
            });
        }
        let mut stats = vec![format!("seeds: {}", s.seeds.len())];
        if self.preparing.is_some() {
            stats.push("the method's pipelines are being made on a worker thread".into());
        }
        if let Some((key, view, wrong, worst)) = &self.shown {
            let rect = field_rect(frame.size, key.size);
            self.blit.encode(
                device,
                queue,
                &mut *frame.rec,
                &frame.targets.colour_view,
                frame.size,
                view,
                rect,
            );
            stats.push(format!(
                "{}: {wrong} wrong texels against the exact transform, in magenta (worst {worst:.2} texels)",
                method_name(key.options.method)
            ));
        }
        Ok(stats)
    }
}

/// The group the exact transform's passes are timed under (the compared method's are under its
/// own name; when it is exact too, both are).
pub const EXACT_GROUP: &str = "exact (reference)";

/// The colour of a texel the compared method got wrong.
pub const WRONG: [u8; 4] = [255, 0, 255, 255];

/// A method's name for the panel.
pub fn method_name(m: Method2d) -> String {
    match m {
        Method2d::Exact => "exact".into(),
        Method2d::Jfa(v) => v.name().into(),
    }
}

/// The JFA variants and exact, for the panel.
pub fn methods_2d() -> Vec<Method2d> {
    let mut v = vec![Method2d::Exact];
    v.extend(
        [
            Variant::Jfa,
            Variant::JfaPlus1,
            Variant::JfaPlus2,
            Variant::OnePlusJfa,
            Variant::OnePlusJfaPlus2,
        ]
        .map(Method2d::Jfa),
    );
    v
}

/// The colour of a distance of `t` texels, before iso-lines: blue inside (negative), orange
/// outside, each darker toward 64 texels and alike beyond.
pub fn field_base(t: f32) -> [f32; 3] {
    let k = (t.abs() / 64.0).min(1.0);
    if t < 0.0 {
        [40.0 + 60.0 * k, 90.0 + 80.0 * k, 200.0]
    } else {
        [230.0 - 90.0 * k, 140.0 - 60.0 * k, 60.0]
    }
}

/// Distance as colour: blue inside (signed), orange outside, dark iso-lines every
/// `iso_period` texels, white seeds.
pub(super) fn colour_field(d: &[f32], s: &DistanceSettings) -> Vec<u8> {
    let texel = s.options.texel_size.max(f32::MIN_POSITIVE);
    d.iter()
        .flat_map(|&v| {
            let t = v / texel;
            if t == 0.0 {
                return [255, 255, 255, 255];
            }
            let base = field_base(t);
            let phase = (t.abs() / s.iso_period.max(0.5)).fract();
            let line = if !(0.08..=0.92).contains(&phase) {
                0.45
            } else {
                1.0
            };
            [
                (base[0] * line) as u8,
                (base[1] * line) as u8,
                (base[2] * line) as u8,
                255,
            ]
        })
        .collect()
}
