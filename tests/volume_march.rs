//! The volume raymarch (`shaders/volume/`) against closed forms: transmittance of a constant
//! density, a linear ramp and a one-voxel slab, with the camera outside, inside and on the
//! boundary; step-length invariance, jitter, brick skipping, the scene's depth, anisotropic
//! spacing, a box longer than any fixed step cap; bad input; per-stage snapshots.
//!
//! Tolerances were set on llvmpipe (lavapipe, Mesa 25): the march writes Rgba16Float (11-bit
//! mantissa, so about 2.5e-4 on values ≤ 1) and samples R16Float densities with the adapter's
//! trilinear filter.

use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::harness::Summary;
use fieldkit::view::View;
use fieldkit::volume::{
    Bricks, LightVolume, MarchSettings, Mode, Shadow, TransferFunction, Volume, VolumeRenderer,
    fbm_cloud, folds,
};
use glam::{Mat4, Vec3, Vec4};

const SIZE: u32 = 32;

fn view_from(eye: Vec3, target: Vec3, near: f32) -> View {
    let proj = glam::camera::rh::proj::directx::perspective(0.9, 1.0, near, 60.0);
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
        viewport: [SIZE, SIZE],
        reversed_z: false,
        origin: [0, 0],
    }
}

/// Emission only, white, no light: each pixel's colour and alpha are 1 − transmittance.
fn plain(step: f32, reference_step: f32) -> MarchSettings {
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

struct Rig {
    ctx: Context,
    renderer: VolumeRenderer,
}

impl Rig {
    fn new() -> Self {
        let ctx = Context::shared();
        let renderer = VolumeRenderer::new(&ctx.device, wgpu::TextureFormat::Rgba8Unorm).unwrap();
        Self { ctx, renderer }
    }

    fn volume(&self, data: &[f32], dims: [u32; 3], spacing: Vec3, origin: Vec3) -> Volume {
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
    fn cloud(&self, n: u32, seed: u32) -> Volume {
        let dims = [n; 3];
        self.volume(
            &fbm_cloud(dims, seed),
            dims,
            Vec3::splat(1.0 / n as f32),
            Vec3::splat(-0.5),
        )
    }

    /// The brick grid and the light volume of `volume` as `encode_light` builds them.
    fn bricks_and_light(
        &self,
        enc: &mut wgpu::CommandEncoder,
        volume: &Volume,
        tf: &TransferFunction,
        settings: &MarchSettings,
    ) -> (Bricks, LightVolume) {
        let device = &self.ctx.device;
        let bricks = self.renderer.encode_bricks(device, enc, volume).unwrap();
        let light = self
            .renderer
            .encode_light(device, enc, volume, &bricks, tf, Mat4::IDENTITY, settings)
            .unwrap();
        (bricks, light)
    }

    /// The marched image (premultiplied rgba per pixel), all zero where the box is off screen.
    fn march(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        view: &View,
        depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
    ) -> Vec<[f32; 4]> {
        self.march_folded(volume, tf, view, depth, settings, None)
    }

    /// [`Self::march`] with a light volume folded into the density or not (`None`: as
    /// `encode_light` chooses).
    fn march_folded(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        view: &View,
        depth: Option<&wgpu::TextureView>,
        settings: &MarchSettings,
        fold: Option<bool>,
    ) -> Vec<[f32; 4]> {
        let ctx = &self.ctx;
        let mut enc = ctx.encoder("volume test");
        let bricks = self
            .renderer
            .encode_bricks(&ctx.device, &mut enc, volume)
            .unwrap();
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
        match marched {
            None => vec![[0.0; 4]; (SIZE * SIZE) as usize],
            Some(m) => {
                let px: Vec<[u16; 4]> = read_texture(ctx, &m.colour).unwrap();
                px.iter()
                    .map(|p| p.map(|h| half::f16::from_bits(h).to_f32()))
                    .collect()
            }
        }
    }
}

/// A pixel's ray as the shader builds it: near-plane point, unit direction, length to the far
/// plane (world space; the tests use an identity transform).
fn pixel_ray(view: &View, x: u32, y: u32) -> (Vec3, Vec3, f32) {
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
fn slab(o: Vec3, d: Vec3, lo: Vec3, hi: Vec3) -> (f64, f64) {
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
fn chord(view: &View, x: u32, y: u32, lo: Vec3, hi: Vec3, t_max: f64) -> f64 {
    let (o, d, len) = pixel_ray(view, x, y);
    let (t0, t1) = slab(o, d, lo, hi);
    (t1.min(len as f64).min(t_max) - t0.max(0.0)).max(0.0)
}

/// Compare every pixel's alpha (and colour, which equals it here) with 1 − T(pixel).
fn check_alpha(
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

#[test]
fn constant_density_transmittance_outside_inside_and_on_the_boundary() {
    let rig = Rig::new();
    let a = 0.05f32;
    let (step, reference) = (1.0 / 50.0, 1.0 / 64.0);
    let tf = TransferFunction::constant(Vec3::ONE, a);
    let t_of = |c: f64| (1.0 - a as f64).powf(c / reference as f64);
    // A cube, and an anisotropic box (different voxel counts and spacings per axis).
    let cases = [
        ([8u32, 8, 8], Vec3::splat(0.125)),
        ([8, 4, 16], Vec3::new(0.125, 0.2, 0.05)),
    ];
    for (dims, spacing) in cases {
        let n = dims.iter().product::<u32>() as usize;
        let size = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32) * spacing;
        let (lo, hi) = (-0.5 * size, 0.5 * size);
        let volume = rig.volume(&vec![1.0; n], dims, spacing, lo);
        let near = 0.05;
        let cameras = [
            (
                "outside",
                view_from(Vec3::new(0.6, 0.7, 2.2), Vec3::ZERO, near),
            ),
            (
                "inside",
                view_from(Vec3::new(0.1, -0.1, 0.15), Vec3::new(0.9, 0.3, -2.0), near),
            ),
            // The near plane's centre exactly on the +z face.
            (
                "on the boundary",
                view_from(
                    Vec3::new(0.0, 0.0, hi.z + near),
                    Vec3::new(0.0, 0.0, -5.0),
                    near,
                ),
            ),
        ];
        for (name, view) in cameras {
            let px = rig.march(&volume, &tf, &view, None, &plain(step, reference));
            let (covered, worst) = check_alpha(
                &format!("{dims:?} {name}"),
                &px,
                |x, y| t_of(chord(&view, x, y, lo, hi, f64::INFINITY)),
                2e-3,
            );
            println!("{dims:?} {name}: {covered} pixels covered, worst |Δα| {worst:.2e}");
            assert!(covered > 100, "{name}: only {covered} pixels see the box");
        }
    }
}

#[test]
fn opacity_correction_makes_the_step_length_irrelevant() {
    let rig = Rig::new();
    let volume = rig.cloud(16, 3);
    let tf = TransferFunction::extinction(Vec3::ONE, 6.0, 1.0 / 64.0, [0.0, 1.0], 64);
    let view = view_from(Vec3::new(0.4, 0.5, 1.6), Vec3::ZERO, 0.05);
    let fine = rig.march(&volume, &tf, &view, None, &plain(1.0 / 256.0, 1.0 / 64.0));
    let mut report = Vec::new();
    for step in [1.0 / 128.0, 1.0 / 64.0, 1.0 / 32.0] {
        let px = rig.march(&volume, &tf, &view, None, &plain(step, 1.0 / 64.0));
        let diff: Vec<f64> = px
            .iter()
            .zip(&fine)
            .map(|(p, f)| (p[3] - f[3]).abs() as f64)
            .collect();
        let max = diff.iter().cloned().fold(0.0, f64::max);
        let mean = diff.iter().sum::<f64>() / diff.len() as f64;
        report.push((step, max, mean));
        // The density varies inside a segment, so coarser steps sample it more coarsely; the
        // correction keeps the optical depth of each segment right. Bounds from llvmpipe.
        assert!(
            max < 0.03 && mean < 0.004,
            "step {step}: max {max}, mean {mean}"
        );
    }
    println!("step vs 1/256: {report:?}");
    let covered = fine.iter().filter(|p| p[3] > 0.05).count();
    assert!(covered > 200, "the cloud covers only {covered} pixels");
}

/// ∫ clamp(u0 + u1·t, lo, hi) dt over [t0, t1], in closed form.
fn clamped_linear_integral(u0: f64, u1: f64, lo: f64, hi: f64, t0: f64, t1: f64) -> f64 {
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

#[test]
fn linear_ramp_matches_its_closed_form() {
    let rig = Rig::new();
    let n = 16u32;
    let dims = [n, 4, 4];
    // Voxel i holds (i + ½)/n: trilinear filtering reproduces u exactly between the first and
    // last centres and clamps to them beyond.
    let data: Vec<f32> = (0..dims.iter().product::<u32>())
        .map(|i| ((i % n) as f32 + 0.5) / n as f32)
        .collect();
    let spacing = Vec3::new(1.0 / n as f32, 0.25, 0.25);
    let (lo, hi) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let volume = rig.volume(&data, dims, spacing, lo);
    let sigma = 3.0f64;
    let reference = 1.0 / 64.0;
    let tf = TransferFunction::extinction(Vec3::ONE, sigma as f32, reference, [0.0, 1.0], 256);
    for (name, eye, target) in [
        ("outside", Vec3::new(1.5, 0.6, 1.4), Vec3::ZERO),
        (
            "inside",
            Vec3::new(-0.2, 0.1, 0.1),
            Vec3::new(2.0, 0.4, -0.9),
        ),
    ] {
        let view = view_from(eye, target, 0.05);
        let px = rig.march(&volume, &tf, &view, None, &plain(1.0 / 40.0, reference));
        let expected = |x: u32, y: u32| {
            let (o, d, len) = pixel_ray(&view, x, y);
            let (t0, t1) = slab(o, d, lo, hi);
            let (t0, t1) = (t0.max(0.0), t1.min(len as f64));
            if t1 <= t0 {
                return 1.0;
            }
            // u = texture coordinate along x.
            let u0 = (o.x as f64 + 0.5) / 1.0;
            let u1 = d.x as f64;
            let half = 0.5 / n as f64;
            (-sigma * clamped_linear_integral(u0, u1, half, 1.0 - half, t0, t1)).exp()
        };
        let (covered, worst) = check_alpha(name, &px, expected, 3e-3);
        println!("ramp {name}: {covered} pixels covered, worst |Δα| {worst:.2e}");
        assert!(covered > 100);
    }
}

/// ∫ of the tent max(0, 1 − |u − c|) from −∞ to u.
fn tent_cdf(u: f64, c: f64) -> f64 {
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

#[test]
fn jittered_mean_matches_a_thin_slab_where_the_fixed_lattice_bands() {
    let rig = Rig::new();
    let n = 16u32;
    let dims = [n, 4, 4];
    // One dense voxel layer: along x the density is a tent one voxel wide each side.
    let layer = n / 2;
    let data: Vec<f32> = (0..dims.iter().product::<u32>())
        .map(|i| if i % n == layer { 1.0 } else { 0.0 })
        .collect();
    let (lo, hi) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let volume = rig.volume(&data, dims, Vec3::new(1.0 / n as f32, 0.25, 0.25), lo);
    let (sigma, reference) = (0.5f64, 1.0 / 64.0);
    let tf = TransferFunction::extinction(Vec3::ONE, sigma as f32, reference, [0.0, 1.0], 256);
    let view = view_from(Vec3::new(1.6, 0.3, 0.9), Vec3::ZERO, 0.05);
    // Steps of 1.5 voxels: a fixed lattice samples the one-voxel tent badly.
    let step = 1.5 / n as f32;
    let expected = |x: u32, y: u32| -> f64 {
        let (o, d, len) = pixel_ray(&view, x, y);
        let (t0, t1) = slab(o, d, lo, hi);
        let (t0, t1) = (t0.max(0.0), t1.min(len as f64));
        if t1 <= t0 {
            return 1.0;
        }
        let u = |t: f64| (o.x as f64 + t * d.x as f64 + 0.5) * n as f64;
        let c = layer as f64 + 0.5;
        let area = (tent_cdf(u(t1), c) - tent_cdf(u(t0), c)).abs();
        (-sigma * area / (d.x.abs() as f64 * n as f64)).exp()
    };
    let fixed = rig.march(&volume, &tf, &view, None, &plain(step, reference));
    let frames = 64;
    let mut mean = vec![0.0f64; (SIZE * SIZE) as usize];
    for frame in 0..frames {
        let s = MarchSettings {
            jitter: true,
            frame,
            ..plain(step, reference)
        };
        for (m, p) in mean
            .iter_mut()
            .zip(rig.march(&volume, &tf, &view, None, &s))
        {
            *m += p[3] as f64 / frames as f64;
        }
    }
    let (mut fixed_err, mut jitter_err) = (Vec::new(), Vec::new());
    for y in 0..SIZE {
        for x in 0..SIZE {
            let want = 1.0 - expected(x, y);
            // Rays that cross the layer; a ray clipping the tent's tail at the box's corner has
            // a chord shorter than a step, sampled at its own midpoint, jitter or not.
            if want < 0.01 {
                continue;
            }
            let i = (y * SIZE + x) as usize;
            fixed_err.push((fixed[i][3] as f64 - want).abs() / want);
            jitter_err.push((mean[i] - want).abs() / want);
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.partial_cmp(b).unwrap());
        v[v.len() / 2]
    };
    let covered = fixed_err.len();
    let (fixed_med, jitter_med) = (median(&mut fixed_err), median(&mut jitter_err));
    println!(
        "slab: {covered} pixels; median relative error of 1 − T: fixed lattice {fixed_med:.4}, \
         mean of {frames} jittered frames {jitter_med:.4}"
    );
    assert!(covered > 100);
    // Bounds from llvmpipe (fixed about 0.085, jittered about 0.002): the interleaved-gradient
    // pattern visits every phase of a pixel's lattice within 64 frames.
    assert!(jitter_med < 0.01, "jittered mean is {jitter_med} off");
    assert!(
        fixed_med > 5.0 * jitter_med,
        "the fixed lattice should band: {fixed_med}"
    );
}

#[test]
fn a_box_longer_than_any_fixed_cap_is_marched_to_its_end() {
    let rig = Rig::new();
    // 32 world units long; at 1/64 per step the march takes over 2000 segments.
    let dims = [4u32, 4, 64];
    let spacing = Vec3::new(0.5, 0.5, 0.5);
    let size = Vec3::new(2.0, 2.0, 32.0);
    let (lo, hi) = (-0.5 * size, 0.5 * size);
    let volume = rig.volume(&vec![1.0; 4 * 4 * 64], dims, spacing, lo);
    let a = 1e-4f32;
    let reference = 1.0 / 64.0;
    let tf = TransferFunction::constant(Vec3::ONE, a);
    let view = view_from(
        Vec3::new(0.0, 0.0, hi.z + 0.3),
        Vec3::new(0.0, 0.0, -100.0),
        0.05,
    );
    let px = rig.march(&volume, &tf, &view, None, &plain(1.0 / 64.0, reference));
    let (covered, worst) = check_alpha(
        "long box",
        &px,
        |x, y| (1.0 - a as f64).powf(chord(&view, x, y, lo, hi, f64::INFINITY) / reference as f64),
        2e-3,
    );
    let centre = px[(SIZE / 2 * SIZE + SIZE / 2) as usize][3];
    println!(
        "long box: {covered} pixels, centre alpha {centre} (32-unit chord), worst {worst:.2e}"
    );
    assert!(
        centre > 0.15,
        "the centre ray was cut short: alpha {centre}"
    );
}

#[test]
fn skipping_bricks_does_not_change_the_image() {
    let rig = Rig::new();
    let volume = rig.cloud(32, 11);
    let tf = TransferFunction::cloud();
    for (name, mode) in [
        ("emission-absorption", Mode::EmissionAbsorption),
        ("maximum intensity", Mode::MaximumIntensity),
        ("iso-surface", Mode::IsoSurface { iso: 0.3 }),
    ] {
        let view = view_from(Vec3::new(0.7, 0.4, 1.5), Vec3::ZERO, 0.05);
        let s = MarchSettings {
            mode,
            shadow: Shadow::Rays { step: 1.0 / 32.0 },
            jitter: true,
            ..MarchSettings::default()
        };
        let on = rig.march(&volume, &tf, &view, None, &s);
        let off = rig.march(
            &volume,
            &tf,
            &view,
            None,
            &MarchSettings { skip: false, ..s },
        );
        let differing = on.iter().zip(&off).filter(|(a, b)| a != b).count();
        let samples = |skip| -> f32 {
            let count = MarchSettings {
                skip,
                count_samples: true,
                ..s
            };
            rig.march(&volume, &tf, &view, None, &count)
                .iter()
                .map(|p| p[0])
                .sum()
        };
        let (with, without) = (samples(true), samples(false));
        println!("{name}: {with} density samples with skipping, {without} without");
        assert!(with < without, "{name}: skipping saved no samples");
        let drawn = on.iter().filter(|p| p[3] > 0.0).count();
        println!("{name}: {drawn} pixels drawn, {differing} differ with skipping off");
        assert_eq!(differing, 0, "{name}");
        assert!(drawn > 100, "{name}: only {drawn} pixels drawn");
    }
    // And there is something to skip: bricks the transfer function leaves clear.
    let ctx = &rig.ctx;
    let mut enc = ctx.encoder("bricks");
    let bricks = rig
        .renderer
        .encode_bricks(&ctx.device, &mut enc, &volume)
        .unwrap();
    ctx.submit_and_wait("bricks", enc).unwrap();
    let ranges: Vec<[f32; 2]> =
        bytemuck::cast_slice(&read_buffer(ctx, &bricks.ranges).unwrap()).to_vec();
    let clear = ranges.iter().filter(|r| r[1] <= tf.clear_below()).count();
    println!("{clear} of {} bricks are clear", ranges.len());
    assert!(clear > 0 && clear < ranges.len());
}

#[test]
fn brick_ranges_are_the_dilated_min_and_max() {
    let rig = Rig::new();
    let dims = [19u32, 12, 9];
    let data: Vec<f32> = (0..dims.iter().product::<u32>())
        .map(|i| (i * 37 % 101) as f32 / 100.0)
        .collect();
    let volume = rig.volume(&data, dims, Vec3::splat(0.1), Vec3::ZERO);
    let ctx = &rig.ctx;
    let mut enc = ctx.encoder("bricks");
    let bricks = rig
        .renderer
        .encode_bricks(&ctx.device, &mut enc, &volume)
        .unwrap();
    ctx.submit_and_wait("bricks", enc).unwrap();
    let got: Vec<[f32; 2]> =
        bytemuck::cast_slice(&read_buffer(ctx, &bricks.ranges).unwrap()).to_vec();
    assert_eq!(bricks.count, [3, 2, 2]);
    // What the texture holds: densities rounded to f16.
    let stored = |x: i32, y: i32, z: i32| {
        let i = (z as u32 * dims[1] + y as u32) * dims[0] + x as u32;
        half::f16::from_f32(data[i as usize]).to_f32()
    };
    let b = 8i32;
    for bz in 0..2 {
        for by in 0..2 {
            for bx in 0..3 {
                let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
                for z in (bz * b - 1).max(0)..=((bz + 1) * b).min(dims[2] as i32 - 1) {
                    for y in (by * b - 1).max(0)..=((by + 1) * b).min(dims[1] as i32 - 1) {
                        for x in (bx * b - 1).max(0)..=((bx + 1) * b).min(dims[0] as i32 - 1) {
                            lo = lo.min(stored(x, y, z));
                            hi = hi.max(stored(x, y, z));
                        }
                    }
                }
                let i = ((bz * 2 + by) * 3 + bx) as usize;
                assert_eq!(got[i], [lo, hi], "brick ({bx}, {by}, {bz})");
            }
        }
    }
    fieldkit::assert_summary!(
        "bricks",
        Summary::floats(&[2, 2, 3, 2], &got.concat(), 4).to_string()
    );
}

#[test]
fn rays_stop_at_the_scene_depth_standard_and_reversed() {
    let rig = Rig::new();
    let dims = [8u32; 3];
    let (lo, hi) = (Vec3::splat(-0.5), Vec3::splat(0.5));
    let volume = rig.volume(&vec![1.0; 512], dims, Vec3::splat(0.125), lo);
    let a = 0.05f32;
    let reference = 1.0 / 64.0;
    let tf = TransferFunction::constant(Vec3::ONE, a);
    for reversed in [false, true] {
        let eye = Vec3::new(0.2, 0.3, 2.0);
        let (near, far) = (0.05, 60.0);
        let proj = if reversed {
            glam::camera::rh::proj::directx::perspective(0.9, 1.0, far, near)
        } else {
            glam::camera::rh::proj::directx::perspective(0.9, 1.0, near, far)
        };
        let view = View {
            view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y),
            viewport: [SIZE, SIZE],
            reversed_z: reversed,
            origin: [0, 0],
        };
        // An opaque wall facing the camera 2 units away (view z = −2): through the box's middle.
        let wall =
            (proj * Vec4::new(0.0, 0.0, -2.0, 1.0)).z / (proj * Vec4::new(0.0, 0.0, -2.0, 1.0)).w;
        let depth = fieldkit::gpu::texture(
            &rig.ctx.device,
            "scene depth",
            [SIZE, SIZE, 1],
            wgpu::TextureDimension::D2,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let dv = depth.create_view(&Default::default());
        let mut enc = rig.ctx.encoder("clear depth");
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wall),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        rig.ctx.submit_and_wait("clear depth", enc).unwrap();
        let px = rig.march(
            &volume,
            &tf,
            &view,
            Some(&dv),
            &plain(1.0 / 50.0, reference),
        );
        let inv = view.view_proj.inverse();
        let (covered, worst) = check_alpha(
            &format!("wall, reversed {reversed}"),
            &px,
            |x, y| {
                let (o, d, _) = pixel_ray(&view, x, y);
                let ndc_x = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
                let ndc_y = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
                let w = inv.project_point3(Vec3::new(ndc_x, ndc_y, wall));
                let t_wall = (w - o).dot(d) as f64;
                (1.0 - a as f64).powf(chord(&view, x, y, lo, hi, t_wall) / reference as f64)
            },
            2e-3,
        );
        println!("wall (reversed {reversed}): {covered} pixels, worst {worst:.2e}");
        assert!(covered > 100);
    }
}

#[test]
fn snapshots_outside_inside_and_across_the_boundary() {
    let rig = Rig::new();
    let volume = rig.cloud(24, 5);
    let tf = TransferFunction::cloud();
    let s = MarchSettings {
        jitter: false,
        ..MarchSettings::default()
    };
    let mut out = String::new();
    // The camera moves in along z through the +z face: outside, crossing, inside.
    for (name, z) in [
        ("outside", 1.4f32),
        ("crossing", 0.5 + 0.05),
        ("inside", 0.2),
    ] {
        let view = view_from(Vec3::new(0.05, 0.1, z), Vec3::new(0.0, 0.0, z - 3.0), 0.05);
        let px = rig.march(&volume, &tf, &view, None, &s);
        let alpha: Vec<f32> = px.iter().map(|p| p[3]).collect();
        out += &format!(
            "{name}\n{}",
            Summary::floats(&[SIZE as usize, SIZE as usize], &alpha, 3)
        );
        let lit: Vec<f32> = px.iter().map(|p| p[0]).collect();
        out += &format!(
            "{}\n",
            Summary::floats(&[SIZE as usize, SIZE as usize], &lit, 3)
        );
    }
    fieldkit::assert_summary!("images", out);
}

#[test]
fn light_volume_and_shadow_rays_agree() {
    let rig = Rig::new();
    let volume = rig.cloud(24, 5);
    let tf = TransferFunction::cloud();
    let view = view_from(Vec3::new(0.6, 0.3, 1.5), Vec3::ZERO, 0.05);
    let base = MarchSettings {
        jitter: false,
        ..MarchSettings::default()
    };
    let rays = rig.march(
        &volume,
        &tf,
        &view,
        None,
        &MarchSettings {
            shadow: Shadow::Rays { step: 1.0 / 64.0 },
            ..base
        },
    );
    let baked_settings = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 64.0 },
        ..base
    };
    let baked = rig.march_folded(&volume, &tf, &view, None, &baked_settings, Some(true));
    let separate = rig.march_folded(&volume, &tf, &view, None, &baked_settings, Some(false));
    let unlit = rig.march(
        &volume,
        &tf,
        &view,
        None,
        &MarchSettings {
            shadow: Shadow::None,
            ..base
        },
    );
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p[0] - q[0]).abs() as f64)
            .sum::<f64>()
            / a.len() as f64
    };
    let (baked_off, unlit_off) = (diff(&baked, &rays), diff(&unlit, &rays));
    println!(
        "mean |Δ red| against shadow rays: light volume {baked_off:.4}, unshadowed {unlit_off:.4}"
    );
    // The half-resolution light volume is an approximation of the shadow rays, far closer to
    // them than no shadowing is. Bounds from llvmpipe.
    assert!(baked_off < 0.25 * unlit_off, "{baked_off} vs {unlit_off}");
    // Opacity does not depend on lighting.
    assert!(rays.iter().zip(&baked).all(|(p, q)| p[3] == q[3]));
    assert!(rays.iter().zip(&separate).all(|(p, q)| p[3] == q[3]));
    // Folded into the density or fetched from its own texture, the light is the same trilinear
    // interpolant of the same nodes, but for the folded copy's rounding (Rg16Float here) and
    // the last half voxel before each high face: there the copy, clamped like the density,
    // holds the last voxel centre's light, while the light texture goes on toward the node
    // half a voxel past the box. So the mean difference is tiny and a few edge pixels differ
    // more. Bounds from llvmpipe (mean 2.6e-5, worst 1.0e-2 on this cloud).
    let diffs: Vec<f32> = baked
        .iter()
        .zip(&separate)
        .map(|(p, q)| (p[0] - q[0]).abs())
        .collect();
    let worst = diffs.iter().copied().fold(0.0f32, f32::max);
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    println!("folded against separate light: mean |Δ red| {mean:.2e}, worst {worst:.2e}");
    assert!(mean < 1e-4 && worst < 0.03, "mean {mean}, worst {worst}");
    // A light volume is refused for a march with another transfer function, transform or
    // volume: it would shadow with the old one.
    let ctx = &rig.ctx;
    let s = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 64.0 },
        ..base
    };
    let mut enc = ctx.encoder("stale light");
    let (bricks, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
    let other_tf = TransferFunction::constant(Vec3::ONE, 0.2);
    // Another volume of the same size: its lit density would hold the old densities.
    let other_volume = rig.cloud(24, 6);
    for (volume, tf, l2w) in [
        (&volume, &other_tf, Mat4::IDENTITY),
        (&volume, &tf, Mat4::from_translation(Vec3::X)),
        (&other_volume, &tf, Mat4::IDENTITY),
    ] {
        let e = rig
            .renderer
            .encode_march(
                &ctx.device,
                &mut enc,
                volume,
                &bricks,
                Some(&light),
                tf,
                l2w,
                &view,
                None,
                &s,
            )
            .err()
            .expect("a stale light volume should be refused")
            .to_string();
        assert!(e.contains("rebuild"), "{e}");
    }
}

/// The lit density (`volume/lit_density`) against its definition, per format: red is the
/// density texel bit for bit, green the trilinear interpolant of the light volume's nodes (node
/// i on voxel 2i) at the voxel, i.e. the node itself on even indices and the mean of its
/// neighbours along each odd axis. Odd and even sizes, so the extra node past the box is used.
#[test]
fn lit_density_is_the_density_and_the_light_nodes_interpolant() {
    let rig = Rig::new();
    let ctx = &rig.ctx;
    let dims = [9u32, 6, 5];
    let data = fbm_cloud(dims, 3);
    let tf = TransferFunction::cloud();
    let s = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 16.0 },
        ..MarchSettings::default()
    };
    use wgpu::TextureFormat::{R8Unorm, R16Float, R32Float};
    // R32Float volumes need FLOAT32_FILTERABLE (llvmpipe has it).
    assert!(
        ctx.device
            .features()
            .contains(wgpu::Features::FLOAT32_FILTERABLE),
        "the test adapter should filter R32Float"
    );
    for format in [R8Unorm, R16Float, R32Float] {
        let volume = Volume::upload(
            &ctx.device,
            &ctx.queue,
            &data,
            dims,
            format,
            Vec3::new(0.1, 0.15, 0.2),
            Vec3::splat(-0.4),
        )
        .unwrap();
        let mut enc = ctx.encoder("lit density");
        let (_, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
        ctx.submit_and_wait("lit density", enc).unwrap();
        let lit_density = light
            .lit_density
            .as_ref()
            .expect("a small volume is folded");
        let size = light.texture.size();
        assert_eq!(
            [size.width, size.height, size.depth_or_array_layers],
            [5, 4, 3],
            "nodes on every other voxel, one past an even size"
        );
        let nodes: Vec<[u16; 4]> = read_texture(ctx, &light.texture).unwrap();
        let node = |x: u32, y: u32, z: u32| {
            let i = ((z * size.height + y) * size.width + x) as usize;
            half::f16::from_bits(nodes[i][0]).to_f32()
        };
        // (density bits as the upload stored them, green) per voxel, and the green tolerance,
        // from the format's quantum and the arithmetic: R8 — Vulkan lets a store return either
        // of the two nearest levels (one level, 1/255), and the light's trilinear filter over
        // Rgba16Float nodes may be off by one f16 step near 1 (2⁻¹¹) on hardware that filters
        // half floats in reduced precision. Measured: llvmpipe within half a level; the H100
        // 0.53 levels off at (3,5,1) (251/255 stored for 0.98224). R16Float — one f16 step
        // below 1 for the store (llvmpipe's storage write rounds toward zero) and one for the
        // filter. R32Float — the filter's one f16 step (llvmpipe: within 1e-6; the H100:
        // 3.1e-5 at (1,0,0), 0.5620117 for 0.5620422).
        let (texels, tolerance): (Vec<(u32, f32)>, f32) = match format {
            R8Unorm => {
                let t: Vec<[u8; 4]> = read_texture(ctx, lit_density).unwrap();
                let texels = t
                    .iter()
                    .map(|p| (p[0] as u32, p[1] as f32 / 255.0))
                    .collect();
                (texels, 1.0 / 255.0 + 4.9e-4)
            }
            R16Float => {
                let t: Vec<[u16; 4]> = read_texture(ctx, lit_density).unwrap();
                let texels = t
                    .iter()
                    .map(|p| (p[0] as u32, half::f16::from_bits(p[1]).to_f32()))
                    .collect();
                (texels, 2.0 * 4.9e-4)
            }
            _ => {
                let t: Vec<[u32; 2]> = read_texture(ctx, lit_density).unwrap();
                (
                    t.iter().map(|p| (p[0], f32::from_bits(p[1]))).collect(),
                    4.9e-4,
                )
            }
        };
        let mut worst = 0.0f32;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let i = ((z * dims[1] + y) * dims[0] + x) as usize;
                    let stored = match format {
                        R8Unorm => (data[i].clamp(0.0, 1.0) * 255.0).round() as u32,
                        R16Float => half::f16::from_f32(data[i]).to_bits() as u32,
                        _ => data[i].to_bits(),
                    };
                    assert_eq!(texels[i].0, stored, "{format:?} density at {x},{y},{z}");
                    // Per axis the nodes at ⌊v/2⌋ and ⌈v/2⌉, weighted ½ each.
                    let mut want = 0.0;
                    for nx in [x / 2, x.div_ceil(2)] {
                        for ny in [y / 2, y.div_ceil(2)] {
                            for nz in [z / 2, z.div_ceil(2)] {
                                want += 0.125 * node(nx, ny, nz);
                            }
                        }
                    }
                    let err = (texels[i].1 - want).abs();
                    worst = worst.max(err);
                    assert!(
                        err <= tolerance,
                        "{format:?} light at {x},{y},{z}: {} against {want}",
                        texels[i].1
                    );
                }
            }
        }
        println!("{format:?}: densities exact, worst light difference {worst:.2e}");
    }
    // R16Float densities at the edges of the format survive the fold's f32 round trip: zero,
    // negatives, subnormals (the smallest, 2⁻²⁴, and one near the normal range), the largest
    // finite value.
    let edge = [0.0f32, -0.0, -0.75, 5.96e-8, 6.0e-5, 65504.0, -3.1e-6, 0.1];
    let dims = [edge.len() as u32, 1, 1];
    let volume = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &edge,
        dims,
        R16Float,
        Vec3::ONE,
        Vec3::ZERO,
    )
    .unwrap();
    let mut enc = ctx.encoder("lit density edges");
    let (_, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
    ctx.submit_and_wait("lit density edges", enc).unwrap();
    let t: Vec<[u16; 4]> = read_texture(ctx, light.lit_density.as_ref().unwrap()).unwrap();
    let got: Vec<u16> = t.iter().map(|p| p[0]).collect();
    let want: Vec<u16> = edge
        .iter()
        .map(|&v| half::f16::from_f32(v).to_bits())
        .collect();
    assert_eq!(got, want, "R16Float densities {edge:?}");
}

#[test]
fn bad_input_is_a_typed_error() {
    let rig = Rig::new();
    let ctx = &rig.ctx;
    let upload = |data: &[f32], dims: [u32; 3], format, spacing| {
        Volume::upload(
            &ctx.device,
            &ctx.queue,
            data,
            dims,
            format,
            spacing,
            Vec3::ZERO,
        )
    };
    let err = |r: Result<Volume, fieldkit::Error>| r.err().expect("should be refused").to_string();
    let max = ctx.device.limits().max_texture_dimension_3d;
    use wgpu::TextureFormat::{R8Unorm, Rgba8Unorm};
    let two = [2u32, 2, 2];
    for (data, dims, format, spacing, named) in [
        // A format the march does not sample.
        (&[0.0f32; 8][..], two, Rgba8Unorm, Vec3::ONE, "Rgba8Unorm"),
        // Sizes: zero, and past the device's 3D limit.
        (&[][..], [0, 2, 2], R8Unorm, Vec3::ONE, "volume width is 0"),
        (
            &[][..],
            [2, max + 1, 2],
            R8Unorm,
            Vec3::ONE,
            "volume height",
        ),
        // Data: the wrong count, NaN, a zero spacing.
        (&[0.0; 7][..], two, R8Unorm, Vec3::ONE, "7 densities"),
        (&[f32::NAN; 8][..], two, R8Unorm, Vec3::ONE, "NaN"),
        (
            &[0.0; 8][..],
            two,
            R8Unorm,
            Vec3::new(1.0, 0.0, 1.0),
            "spacing",
        ),
    ] {
        let e = err(upload(data, dims, format, spacing));
        assert!(e.contains(named), "{e}");
    }

    let volume = rig.volume(&[0.5; 8], [2, 2, 2], Vec3::ONE, Vec3::splat(-1.0));
    let tf = TransferFunction::constant(Vec3::ONE, 0.1);
    let mut enc = ctx.encoder("bad");
    let bricks = rig
        .renderer
        .encode_bricks(&ctx.device, &mut enc, &volume)
        .unwrap();
    let view = view_from(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 0.1);
    let mut march = |l2w: Mat4, view: &View, s: &MarchSettings, tf: &TransferFunction| {
        rig.renderer
            .encode_march(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                None,
                tf,
                l2w,
                view,
                None,
                s,
            )
            .err()
            .expect("should be refused")
            .to_string()
    };
    let ok = MarchSettings {
        shadow: Shadow::None,
        ..MarchSettings::default()
    };
    let e = march(Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)), &view, &ok, &tf);
    assert!(e.contains("invertible"), "{e}");
    for (settings, named) in [
        (
            MarchSettings {
                step: f32::NAN,
                ..ok
            },
            "step",
        ),
        (
            MarchSettings {
                light_dir: Vec3::ZERO,
                ..ok
            },
            "light_dir",
        ),
        (
            MarchSettings {
                mode: Mode::IsoSurface { iso: f32::NAN },
                ..ok
            },
            "iso",
        ),
        (
            MarchSettings {
                min_transmittance: 1.0,
                ..ok
            },
            "min_transmittance",
        ),
        // The default shadows through a light volume, and none is given.
        (MarchSettings::default(), "light volume"),
    ] {
        let e = march(Mat4::IDENTITY, &view, &settings, &tf);
        assert!(e.contains(named), "{e}");
    }
    let bad_tf = TransferFunction {
        entries: vec![[1.0, 1.0, 1.0, 1.5]; 2],
        range: [0.0, 1.0],
    };
    let e = march(Mat4::IDENTITY, &view, &ok, &bad_tf);
    assert!(e.contains("opacity"), "{e}");
    // A near plane behind the eye (near = −0.1), built by hand: glam asserts near > 0.
    let (n, f) = (-0.1f32, 60.0f32);
    let h = 1.0 / (0.45f32).tan();
    let proj = Mat4::from_cols(
        Vec4::new(h, 0.0, 0.0, 0.0),
        Vec4::new(0.0, h, 0.0, 0.0),
        Vec4::new(0.0, 0.0, f / (n - f), -1.0),
        Vec4::new(0.0, 0.0, n * f / (n - f), 0.0),
    );
    let behind = View {
        view_proj: proj
            * glam::camera::rh::view::look_at_mat4(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y),
        ..view
    };
    let e = march(Mat4::IDENTITY, &behind, &ok, &tf);
    assert!(e.contains("near plane"), "{e}");
    // R32Float needs FLOAT32_FILTERABLE: accepted where the device has it, refused by name where not.
    let r = upload(&[0.0; 8], two, wgpu::TextureFormat::R32Float, Vec3::ONE);
    if ctx
        .device
        .features()
        .contains(wgpu::Features::FLOAT32_FILTERABLE)
    {
        assert!(r.is_ok());
    } else {
        assert!(err(r).contains("FLOAT32_FILTERABLE"));
    }
}
