//! The ocean's patches chosen on the GPU (`OceanRenderer::encode_lod`, `ocean/lod`): the same
//! patches, quads and skirts as the CPU quadtree (`ocean::select`) for cameras near, far,
//! grazing and looking down, the same picture as drawing the CPU's list, the settings `select`
//! refuses refused, and the same buffers from frame to frame.

use crate::common;

use common::ocean::*;
use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::ocean::{
    LodSettings, Look, OceanCamera, OceanRenderer, Output, Patch, Waves, select,
};
use glam::{DVec2, DVec3};

/// Short enough for lavapipe to draw: the selection sees only the height and the projection.
const VIEW: [u32; 2] = [120, 270];

fn camera(eye: DVec3, dir: DVec3) -> OceanCamera {
    OceanCamera::look_at(
        eye,
        eye + dir,
        glam::camera::rh::proj::directx::perspective(60f32.to_radians(), 16.0 / 9.0, 0.5, 5000.0),
    )
}

/// Near the water looking 8° down (as `tests/ocean/lod.rs`), grazing far from the square's
/// centre, high up looking down, and one a patch edge away from an exact power-of-two corner.
fn cameras() -> Vec<OceanCamera> {
    vec![
        camera(
            DVec3::new(130.0, 12.0, -260.0),
            DVec3::new(0.6, -0.14, -0.79),
        ),
        camera(
            DVec3::new(-1100.0, 2.5, 900.0),
            DVec3::new(0.9, -0.02, -0.3),
        ),
        camera(DVec3::new(40.0, 300.0, 20.0), DVec3::new(0.1, -1.0, 0.3)),
        camera(DVec3::new(320.0, 6.0, 160.0), DVec3::new(-0.5, -0.2, 0.8)),
    ]
}

fn renderer(ctx: &Context) -> OceanRenderer {
    let r = OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(RGBA32), false).unwrap();
    assert!(
        r.lod_on_gpu(),
        "{} lacks INDIRECT_FIRST_INSTANCE: the GPU selection cannot be tested here",
        ctx.adapter_name()
    );
    r
}

fn targets(ctx: &Context) -> (wgpu::Texture, wgpu::Texture) {
    let colour = fieldkit::gpu::texture(
        &ctx.device,
        "colour",
        [VIEW[0], VIEW[1], 1],
        wgpu::TextureDimension::D2,
        RGBA32,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
        size: wgpu::Extent3d {
            width: VIEW[0],
            height: VIEW[1],
            depth_or_array_layers: 1,
        },
        ..depth_desc()
    });
    (colour, depth)
}

/// Clear, draw (the CPU's list where `listed`, else the GPU's choice), submit; the colour.
#[allow(clippy::too_many_arguments)]
fn draw(
    ctx: &Context,
    r: &OceanRenderer,
    waves: &Waves,
    cam: &OceanCamera,
    lod: &LodSettings,
    listed: Option<&[Patch]>,
    (colour, depth): &(wgpu::Texture, wgpu::Texture),
) -> Vec<[f32; 4]> {
    let look = Look::default();
    let view = colour.create_view(&Default::default());
    let mut enc = ctx.device.create_command_encoder(&Default::default());
    clear(
        &mut enc,
        &[&view],
        &depth.create_view(&Default::default()),
        1.0,
    );
    let d = &ctx.device;
    match listed {
        Some(p) => r.encode(
            d,
            &mut enc,
            waves,
            3.0,
            cam,
            &look,
            p,
            &[&view],
            depth,
            false,
        ),
        None => r.encode_lod(
            d,
            &mut enc,
            waves,
            3.0,
            cam,
            &look,
            lod,
            &[&view],
            depth,
            false,
        ),
    }
    .unwrap();
    ctx.queue.submit([enc.finish()]);
    read_texture(ctx, colour).unwrap()
}

fn key(p: &Patch) -> (i64, i64, i64) {
    let mm = |v: f64| (v * 100.0).round() as i64;
    (mm(p.corner.x), mm(p.corner.y), mm(p.size))
}

fn gpu_patches(ctx: &Context, r: &OceanRenderer) -> Vec<Patch> {
    let drawn = r.last_lod().expect("encode_lod ran on the GPU");
    let draws = read_buffer(ctx, &drawn.draws).unwrap();
    let instances = read_buffer(ctx, &drawn.instances).unwrap();
    let mut p = drawn.patches(&draws, &instances);
    p.sort_by_key(key);
    p
}

#[test]
fn the_gpu_chooses_the_cpu_patches() {
    let ctx = Context::shared();
    let r = renderer(&ctx);
    let t = targets(&ctx);
    let waves = Waves::open_sea();
    let settings = [
        LodSettings::default(),
        LodSettings {
            patch_quads: 8,
            max_error_px: 2.0,
            ..Default::default()
        },
        LodSettings {
            centre: DVec2::new(-700.0, 450.0),
            patch_quads: 13,
            max_depth: 9,
            ..Default::default()
        },
    ];
    let mut compared = 0;
    for (c, cam) in cameras().iter().enumerate() {
        for (s, lod) in settings.iter().enumerate() {
            draw(&ctx, &r, &waves, cam, lod, None, &t);
            let got = gpu_patches(&ctx, &r);
            let mut want = select(&waves, &Look::default(), cam, VIEW[1], lod)
                .unwrap()
                .patches;
            want.sort_by_key(key);
            assert_eq!(got.len(), want.len(), "camera {c}, settings {s}: patches");
            for (g, w) in got.iter().zip(&want) {
                assert_eq!(key(g), key(w), "camera {c}, settings {s}: {g:?} vs {w:?}");
                // f32 corners relative to the eye, within a millimetre of the f64 ones.
                assert!(
                    (g.corner - w.corner).abs().max_element() < 1e-3,
                    "{g:?} vs {w:?}"
                );
                assert_eq!(
                    (g.quads, g.skirts),
                    (w.quads, w.skirts),
                    "camera {c}, settings {s}: {w:?}"
                );
            }
            compared += want.len();
        }
    }
    // Enough patches that a wrong fate, quad count or skirt somewhere would show.
    assert!(compared > 500, "{compared} patches compared");
}

#[test]
fn encode_lod_draws_the_picture_encode_draws() {
    let ctx = Context::shared();
    let r = renderer(&ctx);
    let t = targets(&ctx);
    let waves = Waves::open_sea();
    let lod = LodSettings::default();
    for cam in cameras() {
        let patches = select(&waves, &Look::default(), &cam, VIEW[1], &lod)
            .unwrap()
            .patches;
        let listed = draw(&ctx, &r, &waves, &cam, &lod, Some(&patches), &t);
        let chosen = draw(&ctx, &r, &waves, &cam, &lod, None, &t);
        let water = listed.iter().filter(|p| p[3] != CLEAR as f32).count();
        let differ = listed
            .iter()
            .zip(&chosen)
            .filter(|(a, b)| (0..4).any(|i| (a[i] - b[i]).abs() > 1e-3))
            .count();
        // The same patches from corners rounded another way (f32 relative to the eye against f64
        // then rounded) and in another order: a pixel may differ where two triangles' edges
        // meet at it. lavapipe: 0 differ of 32 400.
        assert!(
            water > VIEW[0] as usize * VIEW[1] as usize / 4,
            "{water} water pixels"
        );
        assert!(
            differ * 1000 <= water,
            "{differ} of {water} water pixels differ"
        );
    }
}

#[test]
fn settings_select_refuses_are_refused() {
    let ctx = Context::shared();
    let r = renderer(&ctx);
    let t = targets(&ctx);
    let (waves, look) = (Waves::open_sea(), Look::default());
    let cam = cameras()[0];
    let view = t.0.create_view(&Default::default());
    for lod in [
        LodSettings {
            max_error_px: 0.0,
            ..Default::default()
        },
        LodSettings {
            patch_quads: 1,
            ..Default::default()
        },
        LodSettings {
            max_depth: 25,
            ..Default::default()
        },
        LodSettings {
            size: f64::NAN,
            ..Default::default()
        },
        // Every node of 24 levels would be looked at.
        LodSettings {
            max_error_px: 1e-9,
            max_depth: 24,
            ..Default::default()
        },
    ] {
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        let d = &ctx.device;
        let got = r.encode_lod(
            d,
            &mut enc,
            &waves,
            0.0,
            &cam,
            &look,
            &lod,
            &[&view],
            &t.1,
            false,
        );
        assert!(got.is_err(), "{lod:?} accepted");
        assert!(
            select(&waves, &look, &cam, VIEW[1], &lod).is_err(),
            "{lod:?}"
        );
    }
}

#[test]
fn frames_reuse_the_selection_buffers() {
    let ctx = Context::shared();
    let r = renderer(&ctx);
    let t = targets(&ctx);
    let waves = Waves::open_sea();
    let lod = LodSettings::default();
    let cams = cameras();
    draw(&ctx, &r, &waves, &cams[0], &lod, None, &t);
    let first = r.last_lod().unwrap();
    // Another camera, fewer candidates: the same buffers.
    draw(&ctx, &r, &waves, &cams[2], &lod, None, &t);
    let second = r.last_lod().unwrap();
    assert_eq!(first.instances, second.instances);
    assert_eq!(first.draws, second.draws);
}

/// Without depth writes the order of the patches decides what is seen where the water overlaps
/// itself, and the GPU lists them in no fixed order: such a renderer chooses on the CPU, and
/// `encode_lod` draws exactly what `encode` draws with `select`'s list.
#[test]
fn without_depth_writes_the_cpu_chooses() {
    let ctx = Context::shared();
    let r = OceanRenderer::with_depth(
        &ctx.device,
        &ctx.queue,
        Output::Forward(RGBA32),
        false,
        fieldkit::ocean::DepthMode::seed(),
    )
    .unwrap();
    assert!(!r.lod_on_gpu());
    let t = targets(&ctx);
    let (waves, lod, cam) = (Waves::open_sea(), LodSettings::default(), cameras()[1]);
    let patches = select(&waves, &Look::default(), &cam, VIEW[1], &lod)
        .unwrap()
        .patches;
    let listed = draw(&ctx, &r, &waves, &cam, &lod, Some(&patches), &t);
    let chosen = draw(&ctx, &r, &waves, &cam, &lod, None, &t);
    assert!(r.last_lod().is_none());
    assert!(listed == chosen, "encode_lod drew another picture");
}
