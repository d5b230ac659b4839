//! The volume march over a density function (issue 24, seed 002): seed 002's fBm cloud linked
//! into the march at build time (`volume::cloud_march`, from `shaders/shared/fbm_cloud.wesl` by
//! fieldkit-build's `density_march`). Its values against the CPU's `fbm_cloud_at`, its image
//! against a fine CPU integral of the same function along each pixel's ray, brick skipping over
//! a sampled bound, the iso-surface against the CPU's first crossing, and bad input. The user
//! crate (`tests/user-crate/tests/density.rs`) links a function of its own and checks it
//! against a closed form.
//!
//! Tolerances were set on llvmpipe (lavapipe, Mesa 22.3): the march writes Rgba16Float (about
//! 2.5e-4 on values ≤ 1); the rest is the march's midpoint rule against the fine integral.

use crate::common;

use fieldkit::gpu::{Context, read_buffer};
use fieldkit::view::View;
use fieldkit::volume::{
    CloudMarch, FunctionVolume, MarchSettings, Mode, Shadow, TransferFunction, fbm_cloud,
    fbm_cloud_at,
};
use glam::{Mat4, Vec3};

const SIZE: u32 = 32;

fn view_from(eye: Vec3, target: Vec3) -> View {
    let proj = glam::camera::rh::proj::directx::perspective(0.9, 1.0, 0.05, 60.0);
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
        viewport: [SIZE, SIZE],
        reversed_z: false,
        origin: [0, 0],
    }
}

/// Emission only, white, no light, no jitter: each pixel's alpha is 1 − transmittance.
fn plain(step: f32, skip: bool) -> MarchSettings {
    MarchSettings {
        step,
        reference_step: 1.0 / 64.0,
        mode: Mode::EmissionAbsorption,
        shadow: Shadow::None,
        light_colour: Vec3::ZERO,
        ambient: 1.0,
        jitter: false,
        skip,
        min_transmittance: 0.0,
        ..MarchSettings::default()
    }
}

fn march(
    ctx: &Context,
    cloud: &CloudMarch,
    volume: &FunctionVolume,
    tf: &TransferFunction,
    view: &View,
    settings: &MarchSettings,
) -> Vec<[f32; 4]> {
    let mut enc = ctx.encoder("density march test");
    let bricks = cloud.encode_bricks(&ctx.device, &mut enc, volume).unwrap();
    let marched = cloud
        .encode_march(
            &ctx.device,
            &mut enc,
            volume,
            &bricks,
            tf,
            Mat4::IDENTITY,
            view,
            None,
            settings,
        )
        .unwrap()
        .expect("the box is on screen");
    ctx.submit_and_wait("density march test", enc).unwrap();
    common::volume::read_marched(ctx, &marched)
}

/// A pixel's ray as the shader builds it: near-plane point, unit direction, length to the far
/// plane (world space = local space here).
fn pixel_ray(view: &View, x: u32, y: u32) -> (Vec3, Vec3, f32) {
    let inv = view.view_proj.inverse();
    let ndc_x = (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0;
    let ndc_y = 1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0;
    let near = inv.project_point3(Vec3::new(ndc_x, ndc_y, 0.0));
    let far = inv.project_point3(Vec3::new(ndc_x, ndc_y, 1.0));
    (near, (far - near).normalize(), (far - near).length())
}

/// Entry and exit of a ray through the unit box [0, 1]³.
fn unit_box(o: Vec3, d: Vec3) -> (f32, f32) {
    let (mut t0, mut t1) = (f32::NEG_INFINITY, f32::INFINITY);
    for a in 0..3 {
        let (p, q) = ((0.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
        t0 = t0.max(p.min(q));
        t1 = t1.min(p.max(q));
    }
    (t0.max(0.0), t1)
}

#[test]
fn the_baked_function_is_the_cpu_cloud() {
    let ctx = Context::shared();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let dims = [24, 20, 16];
    let volume = FunctionVolume {
        min: Vec3::ZERO,
        max: Vec3::ONE,
        dims,
    };
    let mut enc = ctx.encoder("bake");
    let baked = cloud.encode_bake(&ctx.device, &mut enc, &volume).unwrap();
    ctx.submit_and_wait("bake", enc).unwrap();
    let gpu: Vec<f32> = bytemuck::cast_slice(&read_buffer(&ctx, &baked).unwrap()).to_vec();
    let cpu = fbm_cloud(dims, 0);
    assert_eq!(gpu.len(), cpu.len());
    let worst = gpu
        .iter()
        .zip(&cpu)
        .map(|(g, c)| (g - c).abs())
        .fold(0.0f32, f32::max);
    let inside = cpu.iter().filter(|&&c| c > 0.0).count();
    println!(
        "bake: {inside} of {} cells inside, worst |Δ| {worst:.2e}",
        cpu.len()
    );
    assert!(
        inside > cpu.len() / 20,
        "the cloud is nearly empty: {inside}"
    );
    // The same f32 operations in the same order; a GPU may fuse a multiply-add, a few ulp of 1.
    assert!(worst <= 1e-5, "worst |Δ| {worst}");
}

/// The march's image against 1 − exp(−σ ∫ d) along each ray, the integral taken on the CPU
/// with 16 times the march's segments: only the midpoint rule's error and the Rgba16Float
/// output separate them.
#[test]
fn the_march_integrates_the_function() {
    let ctx = Context::shared();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let volume = FunctionVolume::unit(32);
    let sigma = 4.0f32;
    let reference = 1.0 / 64.0;
    let tf = TransferFunction::extinction(Vec3::ONE, sigma, reference, [0.0, 1.0], 256);
    let step = 1.0 / 128.0;
    for (name, eye, target) in [
        ("outside", Vec3::new(1.6, 1.1, 2.0), Vec3::splat(0.5)),
        (
            "inside",
            Vec3::new(0.45, 0.5, 0.55),
            Vec3::new(1.5, 0.2, -0.4),
        ),
    ] {
        let view = view_from(eye, target);
        let px = march(&ctx, &cloud, &volume, &tf, &view, &plain(step, false));
        let (mut covered, mut worst) = (0, 0.0f32);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let (o, d, len) = pixel_ray(&view, x, y);
                let (t0, t1) = unit_box(o, d);
                let t1 = t1.min(len);
                let mut optical = 0.0f64;
                if t0 < t1 {
                    let n = (((t1 - t0) / step) * 16.0).ceil() as usize;
                    let h = (t1 - t0) / n as f32;
                    for k in 0..n {
                        let t = t0 + (k as f32 + 0.5) * h;
                        optical += (fbm_cloud_at(o + t * d, 0) * h) as f64;
                    }
                }
                let want = 1.0 - (-(sigma as f64) * optical).exp() as f32;
                let got = px[(y * SIZE + x) as usize][3];
                if want > 0.01 {
                    covered += 1;
                }
                worst = worst.max((got - want).abs());
            }
        }
        println!("{name}: {covered} pixels covered, worst |Δα| {worst:.2e}");
        assert!(covered > 100, "{name}: {covered}");
        // llvmpipe: 3e-3 (the midpoint rule on a function with features a few segments
        // wide, the 256-entry transfer function, and f16 output).
        assert!(worst < 1e-2, "{name}: worst |Δα| {worst}");
    }
}

/// Bricks over a function are bounded by its values at cell centres (dilated by one cell), not
/// by a true bound: this shows what skipping does to the cloud, whose top octave varies within
/// a cell. With a transfer function clear below 0.05 and 64³ cells (8³ bricks, the corners
/// empty) nothing visible is lost.
#[test]
fn skipping_over_sampled_bricks() {
    let ctx = Context::shared();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let volume = FunctionVolume::unit(64);
    let mut tf = TransferFunction::extinction(Vec3::ONE, 4.0, 1.0 / 64.0, [0.0, 1.0], 64);
    for e in tf.entries.iter_mut().take(4) {
        e[3] = 0.0;
    }
    assert!(tf.clear_below() > 0.04);
    let view = view_from(Vec3::new(1.6, 1.1, 2.0), Vec3::splat(0.5));
    let all = march(
        &ctx,
        &cloud,
        &volume,
        &tf,
        &view,
        &plain(1.0 / 128.0, false),
    );
    let skipped = march(&ctx, &cloud, &volume, &tf, &view, &plain(1.0 / 128.0, true));
    let worst = all
        .iter()
        .zip(&skipped)
        .map(|(a, b)| (a[3] - b[3]).abs())
        .fold(0.0f32, f32::max);
    let lit = all.iter().filter(|p| p[3] > 0.01).count();
    println!("skipping: {lit} pixels lit, worst |Δα| {worst:.2e}");
    assert!(lit > 100);
    assert!(worst <= 1e-3, "worst |Δα| {worst}");
    // The skip really skips: fewer samples with it than without.
    let count = |skip| {
        let s = MarchSettings {
            count_samples: true,
            ..plain(1.0 / 128.0, skip)
        };
        march(&ctx, &cloud, &volume, &tf, &view, &s)
            .iter()
            .map(|p| p[0] as f64)
            .sum::<f64>()
    };
    let (with, without) = (count(true), count(false));
    println!("samples: {with} skipping, {without} not");
    assert!(with < 0.8 * without, "{with} vs {without}");
}

/// The iso-surface hits where the CPU's fine walk along the ray first reaches the iso value.
#[test]
fn the_iso_surface_is_the_first_crossing() {
    let ctx = Context::shared();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let volume = FunctionVolume::unit(32);
    let iso = 0.3;
    let tf = TransferFunction::constant(Vec3::ONE, 1.0);
    let view = view_from(Vec3::new(1.6, 1.1, 2.0), Vec3::splat(0.5));
    let settings = MarchSettings {
        mode: Mode::IsoSurface { iso },
        ..plain(1.0 / 256.0, true)
    };
    let px = march(&ctx, &cloud, &volume, &tf, &view, &settings);
    let (mut hits, mut disagree) = (0, 0);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let (o, d, len) = pixel_ray(&view, x, y);
            let (t0, t1) = unit_box(o, d);
            let n = (((t1.min(len) - t0) * 2048.0).ceil()).max(0.0) as usize;
            let hit = (0..n).any(|k| fbm_cloud_at(o + (t0 + k as f32 / 2048.0) * d, 0) >= iso);
            let got = px[(y * SIZE + x) as usize][3] > 0.5;
            hits += hit as usize;
            disagree += (hit != got) as usize;
        }
    }
    println!("iso: {hits} pixels hit, {disagree} disagree");
    assert!(hits > 50);
    // A ray that grazes a blob thinner than the march's step can miss it (or the fine walk
    // can): at most 2% of the image.
    assert!(disagree * 50 <= (SIZE * SIZE) as usize, "{disagree}");
}

#[test]
fn bad_input_is_a_typed_error() {
    use fieldkit::Error;
    let ctx = Context::shared();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let volume = FunctionVolume::unit(16);
    let tf = TransferFunction::cloud();
    let view = view_from(Vec3::new(1.6, 1.1, 2.0), Vec3::splat(0.5));
    let mut enc = ctx.encoder("errors");
    let bricks = cloud.encode_bricks(&ctx.device, &mut enc, &volume).unwrap();
    let run = |enc: &mut wgpu::CommandEncoder, v: &FunctionVolume, s: &MarchSettings| {
        cloud
            .encode_march(
                &ctx.device,
                enc,
                v,
                &bricks,
                &tf,
                Mat4::IDENTITY,
                &view,
                None,
                s,
            )
            .map(|_| ())
    };
    let light = MarchSettings {
        shadow: Shadow::LightVolume { step: 0.01 },
        ..MarchSettings::default()
    };
    assert!(matches!(
        run(&mut enc, &volume, &light),
        Err(Error::Invalid { .. })
    ));
    let flat = FunctionVolume {
        max: Vec3::new(1.0, 0.0, 1.0),
        ..volume
    };
    assert!(matches!(
        run(&mut enc, &flat, &MarchSettings::default()),
        Err(Error::Invalid { .. })
    ));
    let other = FunctionVolume::unit(40);
    assert!(matches!(
        run(&mut enc, &other, &MarchSettings::default()),
        Err(Error::Invalid { .. })
    ));
    assert!(matches!(
        cloud.encode_bake(&ctx.device, &mut enc, &FunctionVolume::unit(0)),
        Err(Error::Size { .. })
    ));
    let nan = MarchSettings {
        step: f32::NAN,
        ..MarchSettings::default()
    };
    assert!(run(&mut enc, &volume, &nan).is_err());
    run(
        &mut enc,
        &volume,
        &MarchSettings {
            shadow: Shadow::Rays { step: 1.0 / 32.0 },
            ..MarchSettings::default()
        },
    )
    .unwrap();
    ctx.submit_and_wait("errors", enc).unwrap();
}

/// A stage not made from the density march template is refused before anything is made: the
/// texture march's `march` has the entry point's name but other bindings, and the cloud's
/// `bricks` in the march's place has another entry point.
#[test]
fn a_stage_not_from_the_template_is_refused() {
    use fieldkit::shaders::volume::{cloud_march, volume_march};
    use fieldkit::volume::DensityMarch;
    let ctx = Context::shared();
    type Bricks = cloud_march::bricks::Entry;
    type Bake = cloud_march::bake::Entry;
    let refusal = |made: Result<(), fieldkit::Error>| match made {
        Err(fieldkit::Error::Invalid { what, .. }) => what,
        other => panic!("expected a refusal, got {other:?}"),
    };
    let texture_march = refusal(
        DensityMarch::<volume_march::march::Entry, Bricks, Bake>::new(&ctx.device, &ctx.queue)
            .map(|_| ()),
    );
    assert!(
        texture_march.contains("not a density march stage")
            && texture_march.contains("binds `density` at @group(0) @binding(1)"),
        "{texture_march}"
    );
    let bricks_as_march =
        refusal(DensityMarch::<Bricks, Bricks, Bake>::new(&ctx.device, &ctx.queue).map(|_| ()));
    assert!(
        bricks_as_march.contains("expected the entry point `march`, got `bricks`"),
        "{bricks_as_march}"
    );
}

/// `prepare` makes the march pipelines settings need ahead (on any thread), `prepared` says
/// so, and the march that follows makes none — for the texture march (both light-volume
/// layouts under `Shadow::LightVolume`) and the function's; `reserve` makes the march's image
/// ahead, and the march makes no texture. Counted by wgpu's own pipeline
/// counter on a device of the test's own. A march marches the same image prepared or not.
#[test]
fn prepare_makes_the_march_pipelines_ahead() {
    let ctx = Context::new().expect("a GPU adapter (apt-get install mesa-vulkan-drivers)");
    let pipelines = || common::compute_pipelines(&ctx.device);
    let renderer = fieldkit::volume::VolumeRenderer::new(
        &ctx.device,
        &ctx.queue,
        wgpu::TextureFormat::Rgba8Unorm,
    )
    .unwrap();
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).unwrap();
    let mip = MarchSettings {
        mode: Mode::MaximumIntensity,
        ..plain(1.0 / 32.0, true)
    };
    let lit = MarchSettings {
        shadow: Shadow::LightVolume { step: 0.05 },
        ..MarchSettings::default()
    };
    for s in [&mip, &lit] {
        assert!(!renderer.prepared(s), "{s:?}");
    }
    assert!(!cloud.prepared(&mip));
    let before = pipelines();
    // Made on another thread, as an app makes them while its frames draw.
    std::thread::scope(|scope| {
        scope.spawn(|| renderer.prepare(&ctx.device, &mip).unwrap());
        scope.spawn(|| renderer.prepare(&ctx.device, &lit).unwrap());
        scope.spawn(|| cloud.prepare(&ctx.device, &mip).unwrap());
    });
    // One for the maximum intensity, two light-volume layouts, one density march.
    assert_eq!(pipelines(), before + 4);
    assert!(renderer.prepared(&mip) && renderer.prepared(&lit) && cloud.prepared(&mip));
    // A density march has no light volume: never prepared, a typed error to prepare.
    assert!(!cloud.prepared(&lit));
    assert!(cloud.prepare(&ctx.device, &lit).is_err());
    let made = pipelines();
    let volume = FunctionVolume {
        min: Vec3::ZERO,
        max: Vec3::ONE,
        dims: [16; 3],
    };
    let tf = TransferFunction::constant(Vec3::ONE, 1.0);
    let view = view_from(Vec3::new(0.5, 0.6, 2.5), Vec3::splat(0.5));
    // Its image made ahead too: the march makes no texture (wgpu counts texture memory; its
    // texture count misses textures made through the device).
    let textures = || ctx.device.get_internal_counters().hal.texture_memory.read();
    cloud.reserve(&ctx.device, view.viewport).unwrap();
    // A viewport with a zero side, or wider than the device's 2D textures, is refused.
    let widest = ctx.device.limits().max_texture_dimension_2d + 1;
    for bad in [[0, 8], [widest, 8]] {
        let refused = cloud.reserve(&ctx.device, bad);
        assert!(
            matches!(refused, Err(fieldkit::Error::Size { .. })),
            "{bad:?}: {refused:?}"
        );
        let refused = renderer.reserve(&ctx.device, bad);
        assert!(
            matches!(refused, Err(fieldkit::Error::Size { .. })),
            "{bad:?}: {refused:?}"
        );
    }
    let reserved = textures();
    let image = march(&ctx, &cloud, &volume, &tf, &view, &mip);
    assert_eq!(pipelines(), made, "the march made a pipeline");
    assert_eq!(textures(), reserved, "the march made a texture");
    assert!(image.iter().any(|p| p[3] > 0.05), "nothing marched");
}
