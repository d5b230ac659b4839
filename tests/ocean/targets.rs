//! The ocean's other outputs and inputs: the seed's depth fade (thirty centimetres, the depth
//! left as it was), every depth format with and without a stencil, the G-buffer's subsurface
//! target and material, and user height and normal maps.
//!
//! Tolerances were set on llvmpipe.

use crate::common;

use common::ocean::*;
use fieldkit::Error;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::ocean::{Look, OceanCamera, OceanRenderer, Output};
use glam::{DVec3, Vec2, Vec3, Vec4};

/// The source's water (`Look::seed`, `DepthMode::seed`): a fade over 30 cm, the depth tested
/// and not written. Against fade = 1 − saturate((scene − water) / 0.3), as the default's 3 m in
/// `depth_fade_and_depth_write_in_one_pass`.
#[test]
fn seed_fade_is_thirty_centimetres_and_leaves_the_depth() {
    use fieldkit::ocean::DepthMode;
    let ctx = Context::shared();
    let seed = Look::seed();
    assert_eq!(seed.fade_distance, 0.3);
    assert_eq!(fieldkit::ocean::LodSettings::default().size, 2560.0);
    assert!(!DepthMode::seed().write);
    let renderer = OceanRenderer::with_depth(
        &ctx.device,
        &ctx.queue,
        Output::GBuffer([RGBA32; 4]),
        false,
        DepthMode::seed(),
    )
    .unwrap();
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    // Looking steeply down from 6 m: across the image the water's view depth spans about a
    // metre, so a 30 cm fade covers many pixels.
    let eye = DVec3::new(2.0e4, 6.0, -3.5e4);
    let cam = OceanCamera::look_at(
        eye,
        eye + DVec3::new(0.0, -6.0, -0.8),
        glam::camera::rh::proj::directx::perspective(0.5, W as f32 / H as f32, 0.1, 400.0),
    );
    let scene = 6.25;
    let scene_ndc = ndc_of(&cam, scene) as f32;
    let look = Look {
        fade_distance: seed.fade_distance,
        ..calm_look()
    };
    draw_from(
        &ctx,
        &renderer,
        &calm(),
        &look,
        &targets,
        &depth,
        scene_ndc,
        true,
        cam,
    );
    let base: Vec<Vec4> = read_texture(&ctx, &targets[3]).unwrap();
    let z: Vec<f32> = read_texture(&ctx, &depth).unwrap();
    let (mut drawn, mut faded, mut worst) = (0, 0, 0f64);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            assert_eq!(z[i], scene_ndc, "depth written at ({x}, {y})");
            if let Some((d, _)) = plane_hit(&cam, x, y)
                && d < scene - 0.05
            {
                drawn += 1;
                let want = 1.0 - ((scene - d) / 0.3).clamp(0.0, 1.0);
                faded += (want > 0.0) as usize;
                worst = worst.max((base[i].x as f64 - want).abs());
            }
        }
    }
    println!("seed fade: {drawn} drawn, {faded} fading, error {worst:.2e}");
    assert!(drawn > 500 && faded > 5, "{drawn} {faded}");
    // llvmpipe: the depths come back through f32 NDC, ten times steeper than the default's.
    assert!(worst < 2e-2, "fade error {worst}");
}

/// Depth formats beyond Depth32Float: Depth24Plus draws the same fade, and a stencil is left as
/// it was.
#[test]
fn depth_formats_and_the_stencil() {
    use fieldkit::ocean::DepthMode;
    let ctx = Context::shared();
    let cam = camera();
    let scene = 15.0;
    let scene_ndc = ndc_of(&cam, scene) as f32;
    let look = calm_look();
    let mut bases = Vec::new();
    for format in [
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureFormat::Depth24Plus,
        wgpu::TextureFormat::Depth24PlusStencil8,
    ] {
        let renderer = OceanRenderer::with_depth(
            &ctx.device,
            &ctx.queue,
            Output::GBuffer([RGBA32; 4]),
            false,
            DepthMode {
                format,
                write: true,
            },
        )
        .unwrap();
        let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
        let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
            format,
            ..depth_desc()
        });
        let views: Vec<wgpu::TextureView> = targets
            .iter()
            .map(|t| t.create_view(&Default::default()))
            .collect();
        let dv = depth.create_view(&Default::default());
        let mut enc = ctx.encoder("depth formats");
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("clear"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &dv,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(scene_ndc),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: format.has_stencil_aspect().then_some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(7),
                    store: wgpu::StoreOp::Store,
                }),
            }),
            ..Default::default()
        });
        let refs: Vec<&wgpu::TextureView> = views.iter().collect();
        renderer
            .encode(
                &ctx.device,
                &mut enc,
                &calm(),
                12.5,
                &cam,
                &look,
                &patches(&cam),
                &refs,
                &depth,
                true,
            )
            .unwrap();
        // The stencil aspect, copied out where there is one.
        let stencil = format.has_stencil_aspect().then(|| {
            let row = (W as u64).next_multiple_of(256);
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: row * H as u64,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            enc.copy_texture_to_buffer(
                wgpu::TexelCopyTextureInfo {
                    texture: &depth,
                    mip_level: 0,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::StencilOnly,
                },
                wgpu::TexelCopyBufferInfo {
                    buffer: &buf,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row as u32),
                        rows_per_image: None,
                    },
                },
                depth.size(),
            );
            (buf, row)
        });
        ctx.submit_and_wait("depth formats", enc).unwrap();
        if let Some((buf, row)) = stencil {
            let bytes = fieldkit::gpu::read_buffer(&ctx, &buf).unwrap();
            for y in 0..H as u64 {
                for x in 0..W as u64 {
                    assert_eq!(bytes[(y * row + x) as usize], 7, "stencil at ({x}, {y})");
                }
            }
        }
        bases.push(read_texture::<Vec4>(&ctx, &targets[3]).unwrap());
    }
    let drawn = bases[0].iter().filter(|c| c.x as f64 != CLEAR).count();
    assert!(drawn > 500, "{drawn}");
    for (k, other) in bases.iter().enumerate().skip(1) {
        let worst = bases[0]
            .iter()
            .zip(other)
            .map(|(a, b)| (a.x - b.x).abs())
            .fold(0.0f32, f32::max);
        // Depth24Plus keeps 24 bits of NDC depth: the fade's depths differ by millimetres.
        assert!(worst < 5e-3, "format {k}: fade differs by {worst}");
    }
    // Depth32FloatStencil8 where the device has its feature; a typed error where not.
    let f32s8 = OceanRenderer::with_depth(
        &ctx.device,
        &ctx.queue,
        Output::Forward(RGBA32),
        false,
        DepthMode {
            format: wgpu::TextureFormat::Depth32FloatStencil8,
            write: true,
        },
    );
    let has = ctx
        .device
        .features()
        .contains(wgpu::Features::DEPTH32FLOAT_STENCIL8);
    assert_eq!(f32s8.is_ok(), has);
    if !has {
        assert!(matches!(f32s8, Err(Error::Unsupported { .. })));
    }
    // A format the ocean does not draw into.
    assert!(
        OceanRenderer::with_depth(
            &ctx.device,
            &ctx.queue,
            Output::Forward(RGBA32),
            false,
            DepthMode {
                format: wgpu::TextureFormat::R32Float,
                write: true,
            },
        )
        .is_err()
    );
}

/// The source's fifth target (subsurface colour) and the material parameters.
#[test]
fn gbuffer_subsurface_target_and_material() {
    let ctx = Context::shared();
    let renderer = OceanRenderer::new(
        &ctx.device,
        &ctx.queue,
        Output::GBufferSubsurface([RGBA32; 5]),
        false,
    )
    .unwrap();
    let targets: Vec<_> = (0..5).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    let look = Look {
        metallic: 0.25,
        specular: 0.75,
        subsurface_colour: Vec3::new(0.2, 0.5, 0.1),
        ..calm_look()
    };
    draw(
        &ctx,
        &renderer,
        &calm(),
        &look,
        &targets,
        &depth,
        1.0,
        false,
    );
    let material: Vec<Vec4> = read_texture(&ctx, &targets[2]).unwrap();
    let sss: Vec<Vec4> = read_texture(&ctx, &targets[4]).unwrap();
    let mut drawn = 0;
    for i in 0..(W * H) as usize {
        if sss[i].x as f64 == CLEAR {
            continue;
        }
        drawn += 1;
        assert_eq!(sss[i], Vec4::new(0.2, 0.5, 0.1, 1.0));
        assert_eq!(
            material[i],
            Vec4::new(
                0.25,
                0.75,
                look.roughness,
                look.shading_model as f32 / 255.0
            )
        );
    }
    assert!(drawn > 500, "{drawn}");
    let bad = Look {
        metallic: 1.5,
        ..look.clone()
    };
    let e = refusal(&ctx, &renderer, &bad, &targets, &depth);
    assert!(e.to_string().contains("metallic"), "{e}");
    let e = refusal(&ctx, &renderer, &look, &targets[..4], &depth);
    assert!(e.to_string().contains("takes 5"), "{e}");
}

/// Every G-buffer output within WebGPU's default 32 bytes a sample: the four targets in
/// `Output::gbuffer()` and the five packed ones of `Output::gbuffer_subsurface()` (material and
/// subsurface colour as `pack4x8unorm` words), drawn on a default-limits device, hold what the
/// wide `Rgba32Float` targets hold at the adapter's limits, to the formats' own rounding; the
/// wide outputs there are a typed error naming the limit.
#[test]
fn gbuffers_fit_webgpu_default_limits() {
    let shared = Context::shared();
    let ctx = common::default_limits(&shared);
    assert_eq!(
        ctx.device.limits().max_color_attachment_bytes_per_sample,
        32
    );
    for output in [
        Output::GBuffer([RGBA32; 4]),
        Output::GBufferSubsurface([wgpu::TextureFormat::Rgba8Unorm; 5]),
    ] {
        let e = OceanRenderer::new(&ctx.device, &ctx.queue, output, false)
            .err()
            .expect("past 32 bytes a sample");
        assert!(matches!(e, Error::Unsupported { .. }), "{e}");
        assert!(
            e.to_string()
                .contains("max_color_attachment_bytes_per_sample"),
            "{e}"
        );
    }
    let look = Look {
        metallic: 0.25,
        specular: 0.75,
        subsurface_colour: Vec3::new(0.2, 0.6, 0.1),
        ..calm_look()
    };
    let depth_of = |ctx: &Context| target(ctx, wgpu::TextureFormat::Depth32Float);
    let wide = OceanRenderer::new(
        &shared.device,
        &shared.queue,
        Output::GBufferSubsurface([RGBA32; 5]),
        false,
    )
    .unwrap();
    let wide_targets: Vec<_> = (0..5).map(|_| target(&shared, RGBA32)).collect();
    draw(
        &shared,
        &wide,
        &calm(),
        &look,
        &wide_targets,
        &depth_of(&shared),
        1.0,
        false,
    );
    let want: Vec<Vec<[f32; 4]>> = wide_targets
        .iter()
        .map(|t| common::read_rgba(&shared, t))
        .collect();
    for output in [Output::gbuffer(), Output::gbuffer_subsurface()] {
        let formats = output.formats();
        assert!(
            fieldkit::gpu::target_bytes_per_sample(&formats) <= Some(32),
            "{formats:?}"
        );
        let renderer = OceanRenderer::new(&ctx.device, &ctx.queue, output, false).unwrap();
        let targets: Vec<_> = formats.iter().map(|f| target(&ctx, *f)).collect();
        draw(
            &ctx,
            &renderer,
            &calm(),
            &look,
            &targets,
            &depth_of(&ctx),
            1.0,
            false,
        );
        let mut drawn = 0;
        for (k, (t, f)) in targets.iter().zip(&formats).enumerate() {
            let got = common::read_rgba(&ctx, t);
            // The format's own rounding (a step; half floats relative to the value), set on
            // llvmpipe and bound by the formats, so it holds on any adapter. The packed words
            // are integers: WGSL defines pack4x8unorm as ⌊0.5 + 255 v⌋, so they compare exactly.
            let step = common::format_step(*f);
            for (i, (g, w)) in got.iter().zip(&want[k]).enumerate() {
                if w[0] as f64 == CLEAR {
                    continue;
                }
                drawn += 1;
                for c in 0..4 {
                    let ok = if *f == wgpu::TextureFormat::R32Uint {
                        (g[c] * 255.0).round() == (0.5 + 255.0 * w[c]).floor()
                    } else {
                        (g[c] - w[c]).abs() <= step * w[c].abs().max(1.0) + 1e-6
                    };
                    assert!(
                        ok,
                        "{output:?} target {k} channel {c} at {i}: {g:?} vs {w:?}"
                    );
                }
            }
        }
        assert!(drawn > 500 * formats.len(), "{drawn}");
    }
}

/// The user's maps: a height layer lifts the calm sea by strength × its map's height (the
/// second layer of the array, as `Layer::map` picks it), and a normal layer tilts the normal by
/// its map's (−n.x/n.z, −n.y/n.z) × strength.
#[test]
fn user_height_and_normal_maps() {
    use fieldkit::ocean::Layer;
    let ctx = Context::shared();
    let mut renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap();
    let heights = constant_maps(
        &ctx,
        wgpu::TextureFormat::R8Unorm,
        &[[0; 4], [128, 0, 0, 0]],
        1,
    );
    // Tangent-space (0.3, 0, 1) normalised, × ½ + ½, in bytes.
    let tilt = glam::Vec3::new(0.3, 0.0, 1.0).normalize() * 0.5 + 0.5;
    let byte = |v: f32| (v * 255.0).round() as u8;
    let normal_bytes = [byte(tilt.x), byte(tilt.y), byte(tilt.z), 255];
    let normals = constant_maps(&ctx, wgpu::TextureFormat::Rgba8Unorm, &[normal_bytes], 4);
    renderer
        .set_maps(&ctx.device, Some(&heights), Some(&normals))
        .unwrap();
    let look = Look {
        height_layers: vec![Layer {
            tile: 10.0,
            velocity: Vec2::new(0.3, 0.0),
            strength: 2.0,
            map: Some(1),
        }],
        normal_layers: vec![Layer {
            tile: 3.0,
            velocity: Vec2::ZERO,
            strength: 1.0,
            map: Some(0),
        }],
        ..calm_look()
    };
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    draw(
        &ctx,
        &renderer,
        &calm(),
        &look,
        &targets,
        &depth,
        1.0,
        false,
    );
    let z: Vec<f32> = read_texture(&ctx, &depth).unwrap();
    let normal: Vec<Vec4> = read_texture(&ctx, &targets[1]).unwrap();
    let cam = camera();
    let level = 2.0 * 128.0 / 255.0;
    let n = Vec3::new(
        normal_bytes[0] as f32,
        normal_bytes[1] as f32,
        normal_bytes[2] as f32,
    )
    .map(|b| b / 255.0 * 2.0 - 1.0);
    let want_n = Vec3::new(n.x / n.z, 1.0, n.y / n.z).normalize();
    let (mut drawn, mut worst_z, mut worst_n) = (0, 0f64, 0f32);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let Some((_, ndc)) = level_hit(&cam, x, y, level) else {
                continue;
            };
            if z[i] >= 1.0 {
                continue;
            }
            drawn += 1;
            worst_z = worst_z.max((z[i] as f64 - ndc).abs());
            let got = (normal[i].truncate() * 2.0 - 1.0).normalize();
            worst_n = worst_n.max((got - want_n).length());
        }
    }
    println!("user maps: {drawn} pixels, depth error {worst_z:.2e}, normal error {worst_n:.4}");
    assert!(drawn > 500, "{drawn}");
    // llvmpipe: as the calm sea's depth (3.5e-7) and the G-buffer's f32 normal.
    assert!(worst_z < 1e-5, "depth error {worst_z}");
    assert!(worst_n < 2e-3, "normal error {worst_n}");
    // Map 0 (height 0) leaves the sea at the waves' level: the depth changes.
    let flat = Look {
        height_layers: vec![Layer {
            map: Some(0),
            ..look.height_layers[0]
        }],
        ..look.clone()
    };
    draw(
        &ctx,
        &renderer,
        &calm(),
        &flat,
        &targets,
        &depth,
        1.0,
        false,
    );
    let z0: Vec<f32> = read_texture(&ctx, &depth).unwrap();
    assert_ne!(z0, z);

    // Bad maps: typed errors.
    let r32 = constant_maps(&ctx, wgpu::TextureFormat::R32Float, &[[0; 4]], 4);
    assert!(matches!(
        renderer.set_maps(&ctx.device, Some(&r32), None),
        Err(Error::Format { .. })
    ));
    assert!(matches!(
        renderer.set_maps(&ctx.device, None, Some(&heights)),
        Err(Error::Format { .. })
    ));
    let volume = crate::common::sampled(&ctx, [4, 4, 4], wgpu::TextureFormat::R8Unorm);
    let e = renderer
        .set_maps(&ctx.device, Some(&volume), None)
        .unwrap_err();
    assert!(e.to_string().contains("2D"), "{e}");
    // A layer past the maps set.
    let past = Look {
        height_layers: vec![Layer {
            map: Some(2),
            ..look.height_layers[0]
        }],
        ..look.clone()
    };
    let e = refusal(&ctx, &renderer, &past, &targets, &depth);
    assert!(e.to_string().contains("samples map 2"), "{e}");
}
