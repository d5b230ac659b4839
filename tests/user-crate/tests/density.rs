//! A density function of the user's own (`shaders/shared/ramp.wesl`, d = x + ½ over the box
//! [−½, ½]³) linked into fieldkit's volume march by `Builder::density_march` and run through
//! `fieldkit::volume::DensityMarch`: every pixel's transmittance against the closed form
//! exp(−σ ∫ d), which the march's midpoint rule meets exactly on a linear density.
//!
//! Tolerance set on llvmpipe (lavapipe): the march writes Rgba16Float (about 2.5e-4 on values
//! ≤ 1) and the extinction transfer function is 256 linear pieces of 1 − exp(−σ·d·Δ₀).

use fieldkit::gpu::{read_texture, Context};
use fieldkit::view::View;
use fieldkit::volume::{FunctionVolume, MarchSettings, Mode, Shadow, TransferFunction};
use glam::{Mat4, Vec3};

type Ramp = fieldkit::density_march!(fieldkit_user_crate::shaders::scene::ramp_march);

const SIZE: u32 = 32;

#[test]
fn the_users_function_is_marched_to_its_closed_form() {
    let ctx = Context::shared();
    let march = Ramp::new(&ctx.device, &ctx.queue).expect("the user's density march");
    let volume = FunctionVolume {
        min: Vec3::splat(-0.5),
        max: Vec3::splat(0.5),
        dims: [16, 16, 16],
    };
    let sigma = 3.0f64;
    let reference = 1.0 / 64.0;
    let tf = TransferFunction::extinction(Vec3::ONE, sigma as f32, reference, [0.0, 1.0], 256);
    let settings = MarchSettings {
        step: 1.0 / 40.0,
        reference_step: reference,
        mode: Mode::EmissionAbsorption,
        shadow: Shadow::None,
        light_colour: Vec3::ZERO,
        ambient: 1.0,
        jitter: false,
        min_transmittance: 0.0,
        ..MarchSettings::default()
    };
    for (name, eye, target) in [
        ("outside", Vec3::new(1.5, 0.6, 1.4), Vec3::ZERO),
        (
            "inside",
            Vec3::new(-0.2, 0.1, 0.1),
            Vec3::new(2.0, 0.4, -0.9),
        ),
    ] {
        let proj = glam::camera::rh::proj::directx::perspective(0.9, 1.0, 0.05, 60.0);
        let view = View {
            view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
            viewport: [SIZE, SIZE],
            reversed_z: false,
            origin: [0, 0],
        };
        let mut enc = ctx.encoder("ramp");
        let bricks = march.encode_bricks(&ctx.device, &mut enc, &volume).unwrap();
        let marched = march
            .encode_march(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                &tf,
                Mat4::IDENTITY,
                &view,
                None,
                &settings,
            )
            .unwrap()
            .expect("on screen");
        ctx.submit_and_wait("ramp", enc).unwrap();
        let px: Vec<[u16; 4]> = read_texture(&ctx, &marched.colour).unwrap();
        // The march's image may be larger than the viewport (kept across resizes): its rows.
        let width = marched.colour.width();
        let inv = view.view_proj.inverse();
        let (mut covered, mut worst) = (0, 0.0f64);
        for y in 0..SIZE {
            for x in 0..SIZE {
                let ndc = |z: f32| {
                    Vec3::new(
                        (x as f32 + 0.5) / SIZE as f32 * 2.0 - 1.0,
                        1.0 - (y as f32 + 0.5) / SIZE as f32 * 2.0,
                        z,
                    )
                };
                let (near, far) = (inv.project_point3(ndc(0.0)), inv.project_point3(ndc(1.0)));
                let d = (far - near).normalize().as_dvec3();
                let o = near.as_dvec3();
                let (mut t0, mut t1) = (0.0f64, (far - near).length() as f64);
                for a in 0..3 {
                    let (p, q) = ((-0.5 - o[a]) / d[a], (0.5 - o[a]) / d[a]);
                    t0 = t0.max(p.min(q));
                    t1 = t1.min(p.max(q));
                }
                // ∫ (o.x + t·d.x + ½) dt over [t0, t1].
                let optical = if t1 > t0 {
                    (o.x + 0.5) * (t1 - t0) + d.x * (t1 * t1 - t0 * t0) / 2.0
                } else {
                    0.0
                };
                let want = 1.0 - (-sigma * optical).exp();
                let got = half::f16::from_bits(px[(y * width + x) as usize][3]).to_f64();
                covered += (want > 0.01) as usize;
                worst = worst.max((got - want).abs());
            }
        }
        println!("{name}: {covered} pixels covered, worst |Δα| {worst:.2e}");
        assert!(covered > 100, "{name}: {covered}");
        assert!(worst < 3e-3, "{name}: worst |Δα| {worst}");
    }
}
