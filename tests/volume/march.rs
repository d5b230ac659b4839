//! The volume raymarch (`shaders/volume/`) against closed forms: transmittance of a constant
//! density, a linear ramp and a one-voxel slab, with the camera outside, inside and on the
//! boundary; step-length invariance, jitter, brick skipping, the scene's depth, anisotropic
//! spacing, a box longer than any fixed step cap; bad input; per-stage snapshots.
//!
//! Tolerances were set on llvmpipe (lavapipe, Mesa 25): the march writes Rgba16Float (11-bit
//! mantissa, so about 2.5e-4 on values ≤ 1) and samples R16Float densities with the adapter's
//! trilinear filter.

use crate::common;

use common::volume::*;
use fieldkit::harness::Summary;
use fieldkit::view::View;
use fieldkit::volume::{MarchSettings, Mode, Shadow, TransferFunction, Volume};
use glam::{Mat4, Vec3, Vec4};

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
    let (_, ranges) = rig.brick_ranges(&volume);
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
    let (bricks, got) = rig.brick_ranges(&volume);
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
        let depth = crate::common::texture(
            &rig.ctx,
            [SIZE, SIZE, 1],
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let dv = depth.create_view(&Default::default());
        let mut enc = rig.ctx.encoder("clear depth");
        fieldkit::gpu::clear_depth(&mut enc, &dv, wall);
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

/// The renderer keeps its march textures: a march whose output is still held gets a texture
/// of its own, one after the output is dropped gets a kept one back, and two marches recorded
/// into one encoder (two views, both outputs held) each come out as they do alone.
#[test]
fn marches_reuse_dropped_outputs_and_keep_their_own_parameters() {
    let rig = Rig::new();
    let ctx = &rig.ctx;
    let volume = rig.cloud(16, 3);
    let tf = TransferFunction::extinction(Vec3::ONE, 6.0, 1.0 / 64.0, [0.0, 1.0], 64);
    let views = [
        view_from(Vec3::new(0.4, 0.5, 1.6), Vec3::ZERO, 0.05),
        view_from(Vec3::new(-1.2, 0.3, 0.9), Vec3::ZERO, 0.05),
    ];
    let settings = plain(1.0 / 64.0, 1.0 / 64.0);
    let alone = views.map(|v| rig.march(&volume, &tf, &v, None, &settings));
    assert_ne!(alone[0], alone[1]);
    let mut enc = ctx.encoder("two marches");
    let bricks = rig
        .renderer
        .encode_bricks(&ctx.device, &mut enc, &volume)
        .unwrap();
    let march = |enc: &mut wgpu::CommandEncoder, view: &View| {
        rig.renderer
            .encode_march(
                &ctx.device,
                enc,
                &volume,
                &bricks,
                None,
                &tf,
                Mat4::IDENTITY,
                view,
                None,
                &settings,
            )
            .unwrap()
            .expect("on screen")
    };
    let both = views.each_ref().map(|v| march(&mut enc, v));
    ctx.submit_and_wait("two marches", enc).unwrap();
    assert!(
        both[0].colour != both[1].colour,
        "a held output was marched into"
    );
    for k in 0..2 {
        assert!(read_marched(ctx, &both[k]) == alone[k], "march {k} differs");
    }
    let textures = both.each_ref().map(|m| m.colour.clone());
    drop(both);
    let mut enc = ctx.encoder("again");
    let again = march(&mut enc, &views[0]);
    ctx.submit_and_wait("again", enc).unwrap();
    assert!(
        textures.contains(&again.colour),
        "a dropped output's texture was not taken back"
    );
    assert!(read_marched(ctx, &again) == alone[0]);
}

/// The renderer keeps its march texture across a resize the viewport still fits (made with each
/// side rounded up to 128 pixels): the march at a smaller viewport after a larger one reuses the
/// texture and comes out as a fresh renderer's does, and it composites into targets of the
/// viewport's size, not of the texture's.
#[test]
fn a_smaller_march_after_a_larger_reuses_its_texture() {
    let (rig, fresh) = (Rig::new(), Rig::new());
    let ctx = &rig.ctx;
    let volume = rig.cloud(16, 3);
    let march = |rig: &Rig, viewport: [u32; 2]| {
        let view = View {
            viewport,
            ..view_from(Vec3::new(0.4, 0.5, 1.6), Vec3::ZERO, 0.05)
        };
        let tf = TransferFunction::extinction(Vec3::ONE, 6.0, 1.0 / 64.0, [0.0, 1.0], 64);
        rig.marched(&volume, &tf, &view, &plain(1.0 / 64.0, 1.0 / 64.0))
    };
    let size = |t: &wgpu::Texture| [t.width(), t.height()];
    let large = march(&rig, [150, 130]);
    let texture = large.colour.clone();
    assert_eq!(size(&texture), [256, 256]);
    drop(large);
    let small = march(&rig, [130, 120]);
    assert!(small.colour == texture, "the kept texture was not reused");
    assert_eq!(small.viewport, [130, 120]);
    let alone = march(&fresh, [130, 120]);
    assert_eq!(size(&alone.colour), [256, 128]);
    let image = read_marched(ctx, &small);
    assert_eq!(image.len(), 130 * 120);
    assert!(image.iter().filter(|p| p[3] > 0.01).count() > 1000);
    assert!(
        image == read_marched(ctx, &alone),
        "the resized march differs"
    );

    let target = |size: [u32; 2]| {
        fieldkit::gpu::texture(
            &ctx.device,
            "composite target",
            [size[0], size[1], 1],
            wgpu::TextureDimension::D2,
            wgpu::TextureFormat::Rgba8Unorm,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default())
    };
    let mut enc = ctx.encoder("composite");
    let composite = |enc: &mut wgpu::CommandEncoder, view: &wgpu::TextureView| {
        rig.renderer
            .encode_composite(&ctx.device, enc, view, &small)
    };
    composite(&mut enc, &target([130, 120])).unwrap();
    let e = composite(&mut enc, &target([256, 256]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("256×256") && e.contains("viewport 130×120"),
        "{e}"
    );
    ctx.submit_and_wait("composite", enc).unwrap();
}
