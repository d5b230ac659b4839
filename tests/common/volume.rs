//! What the volume tests share.
#![allow(unused_imports)]

use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::harness::Summary;
use fieldkit::view::View;
use fieldkit::volume::{
    Bricks, LightVolume, MarchSettings, Mode, Shadow, TransferFunction, Volume, VolumeMarched,
    VolumeRenderer, fbm_cloud, folds,
};
use glam::{Mat4, Vec3, Vec4};

pub const SIZE: u32 = 32;

pub fn view_from(eye: Vec3, target: Vec3, near: f32) -> View {
    let proj = glam::camera::rh::proj::directx::perspective(0.9, 1.0, near, 60.0);
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
        viewport: [SIZE, SIZE],
        reversed_z: false,
        origin: [0, 0],
    }
}

/// Emission only, white, no light: each pixel's colour and alpha are 1 − transmittance.
pub fn plain(step: f32, reference_step: f32) -> MarchSettings {
    MarchSettings {
        step,
        reference_step,
        mode: Mode::EmissionAbsorption,
        shadow: Shadow::None,
        light_colour: Vec3::ZERO,
        ambient: 1.0,
        jitter: false,
        skip: true,
        min_transmittance: 0.0,
        ..MarchSettings::default()
    }
}

pub struct Rig {
    pub ctx: Context,
    pub renderer: VolumeRenderer,
}

impl Rig {
    pub fn new() -> Self {
        let ctx = Context::shared();
        let renderer =
            VolumeRenderer::new(&ctx.device, &ctx.queue, wgpu::TextureFormat::Rgba8Unorm).unwrap();
        Self { ctx, renderer }
    }

    /// The bricks of `volume`, recorded into `enc`.
    pub fn bricks(&self, enc: &mut wgpu::CommandEncoder, volume: &Volume) -> Bricks {
        (self.renderer.encode_bricks(&self.ctx.device, enc, volume)).unwrap()
    }

    /// The bricks of `volume` and each one's (min, max) density, read back.
    pub fn brick_ranges(&self, volume: &Volume) -> (Bricks, Vec<[f32; 2]>) {
        let ctx = &self.ctx;
        let mut enc = ctx.encoder("bricks");
        let bricks = self.bricks(&mut enc, volume);
        ctx.submit_and_wait("bricks", enc).unwrap();
        let ranges = bytemuck::cast_slice(&read_buffer(ctx, &bricks.ranges).unwrap()).to_vec();
        (bricks, ranges)
    }

    pub fn volume(&self, data: &[f32], dims: [u32; 3], spacing: Vec3, origin: Vec3) -> Volume {
        Volume::upload(
            &self.ctx.device,
            &self.ctx.queue,
            data,
            dims,
            wgpu::TextureFormat::R16Float,
            spacing,
            origin,
        )
        .unwrap()
    }

    /// An fBm cloud of n³ voxels filling the unit box around the origin.
    pub fn cloud(&self, n: u32, seed: u32) -> Volume {
        let dims = [n; 3];
        self.volume(
            &fbm_cloud(dims, seed),
            dims,
            Vec3::splat(1.0 / n as f32),
            Vec3::splat(-0.5),
        )
    }

    /// The brick grid and the light volume of `volume` as `encode_light` builds them.
    pub fn bricks_and_light(
        &self,
        enc: &mut wgpu::CommandEncoder,
        volume: &Volume,
        tf: &TransferFunction,
        settings: &MarchSettings,
    ) -> (Bricks, LightVolume) {
        let device = &self.ctx.device;
        let bricks = self.bricks(enc, volume);
        let light = self
            .renderer
            .encode_light(device, enc, volume, &bricks, tf, Mat4::IDENTITY, settings)
            .unwrap();
        (bricks, light)
    }

    /// A march's output without a light volume or scene depth, submitted and waited for.
    pub fn marched(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        view: &View,
        settings: &MarchSettings,
    ) -> VolumeMarched {
        (self.marched_folded(volume, tf, view, None, settings, None)).expect("on screen")
    }

    /// The marched image (premultiplied rgba per pixel), all zero where the box is off screen.
    pub fn march(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        view: &View,
        depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
    ) -> Vec<[f32; 4]> {
        self.image(self.marched_folded(volume, tf, view, depth, settings, None))
    }

    /// A march's image ([`read_marched`]), all zero for a box off screen (`None`).
    pub fn image(&self, marched: Option<VolumeMarched>) -> Vec<[f32; 4]> {
        match marched {
            None => vec![[0.0; 4]; (SIZE * SIZE) as usize],
            Some(m) => read_marched(&self.ctx, &m),
        }
    }

    /// A march with a light volume folded into the density or not (`None`: as `encode_light`
    /// chooses), submitted and waited for; `None` where the box is off screen.
    pub fn marched_folded(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        view: &View,
        depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
        fold: Option<bool>,
    ) -> Option<VolumeMarched> {
        let ctx = &self.ctx;
        let mut enc = ctx.encoder("volume test");
        let bricks = self.bricks(&mut enc, volume);
        let light = match settings.shadow {
            Shadow::LightVolume { .. } => Some(
                self.renderer
                    .encode_light_folded(
                        &ctx.device,
                        &mut enc,
                        volume,
                        &bricks,
                        tf,
                        Mat4::IDENTITY,
                        settings,
                        fold.unwrap_or(folds(volume)),
                    )
                    .unwrap(),
            ),
            _ => None,
        };
        let marched = self
            .renderer
            .encode_march(
                &ctx.device,
                &mut enc,
                volume,
                &bricks,
                light.as_ref(),
                tf,
                Mat4::IDENTITY,
                view,
                depth,
                settings,
            )
            .unwrap();
        ctx.submit_and_wait("volume test", enc).unwrap();
        marched
    }
}

/// A march's premultiplied image over its viewport, zero outside the rectangle it marched (what
/// lies there is left from earlier marches into the same kept texture, which may be larger
/// than the viewport).
pub fn read_marched(ctx: &Context, m: &VolumeMarched) -> Vec<[f32; 4]> {
    let px: Vec<[u16; 4]> = read_texture(ctx, &m.colour).unwrap();
    let w = m.colour.width();
    let [x0, y0, x1, y1] = m.rect;
    let [vw, vh] = m.viewport;
    (0..vh)
        .flat_map(|y| (0..vw).map(move |x| (x, y)))
        .map(|(x, y)| {
            if (x0..x1).contains(&x) && (y0..y1).contains(&y) {
                px[(y * w + x) as usize].map(|h| half::f16::from_bits(h).to_f32())
            } else {
                [0.0; 4]
            }
        })
        .collect()
}

/// A pixel's ray as the shader builds it: near-plane point, unit direction, length to the far
/// plane (world space; the tests use an identity transform).
pub fn pixel_ray(view: &View, x: u32, y: u32) -> (Vec3, Vec3, f32) {
    let inv = view.view_proj.inverse();
    let [w, h] = view.viewport;
    let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
    let (near_z, far_z) = if view.reversed_z {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    let near = inv.project_point3(Vec3::new(ndc_x, ndc_y, near_z));
    let far = inv.project_point3(Vec3::new(ndc_x, ndc_y, far_z));
    (near, (far - near).normalize(), (far - near).length())
}

/// Entry and exit of a ray through a box (f64 for the references).
pub fn slab(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> (f64, f64) {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        let (o, d, lo, hi) = (o[a] as f64, d[a] as f64, lo[a] as f64, hi[a] as f64);
        if d == 0.0 {
            if o < lo || o > hi {
                return (1.0, 0.0);
            }
            continue;
        }
        let (p, q) = ((lo - o) / d, (hi - o) / d);
        t0 = t0.max(p.min(q));
        t1 = t1.min(p.max(q));
    }
    (t0, t1)
}

/// Chord of a pixel's ray inside `lo..hi`, from the near plane on, cut at `t_max`.
pub fn chord(view: &View, x: u32, y: u32, lo: Vec3, hi: Vec3, t_max: f64) -> f64 {
    let (o, d, len) = pixel_ray(view, x, y);
    let (t0, t1) = slab(o, d, lo, hi);
    (t1.min(len as f64).min(t_max) - t0.max(0.0)).max(0.0)
}

/// Compare every pixel's alpha (and colour, which equals it here) with 1 − T(pixel).
pub fn check_alpha(
    what: &str,
    px: &[[f32; 4]],
    expected_t: impl Fn(u32, u32) -> f64,
    tol: f64,
) -> (usize, f64) {
    let mut covered = 0;
    let mut worst = 0.0f64;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let p = px[(y * SIZE + x) as usize];
            let want = 1.0 - expected_t(x, y);
            if want > 1e-6 {
                covered += 1;
            }
            let err = (p[3] as f64 - want).abs().max((p[0] as f64 - want).abs());
            worst = worst.max(err);
            assert!(
                err <= tol,
                "{what}: pixel ({x}, {y}) alpha {} colour {}, expected {want:.5}",
                p[3],
                p[0]
            );
        }
    }
    (covered, worst)
}

/// ∫ clamp(u0 + u1·t, lo, hi) dt over [t0, t1], in closed form.
pub fn clamped_linear_integral(u0: f64, u1: f64, lo: f64, hi: f64, t0: f64, t1: f64) -> f64 {
    if u1.abs() < 1e-12 {
        return u0.clamp(lo, hi) * (t1 - t0);
    }
    // Split [t0, t1] where u crosses lo and hi; on each piece the integrand is linear or flat.
    let mut cuts = vec![t0, t1];
    for level in [lo, hi] {
        let t = (level - u0) / u1;
        if t > t0 && t < t1 {
            cuts.push(t);
        }
    }
    cuts.sort_by(|a, b| a.partial_cmp(b).unwrap());
    cuts.windows(2)
        .map(|w| {
            let f = |t: f64| (u0 + u1 * t).clamp(lo, hi);
            // Linear on the piece: the midpoint rule is exact.
            f(0.5 * (w[0] + w[1])) * (w[1] - w[0])
        })
        .sum()
}

/// ∫ of the tent max(0, 1 − |u − c|) from −∞ to u.
pub fn tent_cdf(u: f64, c: f64) -> f64 {
    let v = u - c;
    if v <= -1.0 {
        0.0
    } else if v <= 0.0 {
        0.5 * (v + 1.0) * (v + 1.0)
    } else if v <= 1.0 {
        1.0 - 0.5 * (1.0 - v) * (1.0 - v)
    } else {
        1.0
    }
}
