//! The ocean's render stage (`ocean/surface`: `vs_surface` with `fs_forward` or `fs_gbuffer`):
//! depth fade against a closed form, the depth the pass writes, the G-buffer normal against the
//! f64 wave normal, snapshots of both outputs, and bad input.
//!
//! Tolerances were set on llvmpipe.

use crate::common;

use common::ocean::*;
use fieldkit::Error;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::harness::Summary;
use fieldkit::ocean::Waves;
use fieldkit::ocean::{ALL_SKIRTS, Look, OceanCamera, OceanRenderer, Output, Patch};
use glam::{DVec2, DVec3, DVec4, Vec3, Vec4};

/// A calm sea (0.1 mm waves) over a scene at a constant view depth of 15 m: where the water is
/// nearer, it is drawn with fade = 1 − saturate((15 − its depth) / 3), which the base-colour
/// target shows directly (deep black, shallow white), and its depth is written; elsewhere the
/// scene's depth and the clear colour stay.
#[test]
fn depth_fade_and_depth_write_in_one_pass() {
    let ctx = Context::shared();
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap();
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    let cam = camera();
    let scene = FADE_SCENE;
    let scene_ndc = ndc_of(&cam, scene) as f32;
    draw_faded(&ctx, &renderer, &targets, &depth);
    let base: Vec<Vec4> = read_texture(&ctx, &targets[3]).unwrap();
    let z: Vec<f32> = read_texture(&ctx, &depth).unwrap();
    let (mut drawn, mut faded, mut worst_fade, mut worst_z) = (0, 0, 0f64, 0f64);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let hit = plane_hit(&cam, x, y);
            match hit {
                Some((d, ndc)) if d < scene - 0.05 => {
                    drawn += 1;
                    let want = 1.0 - ((scene - d) / 3.0).clamp(0.0, 1.0);
                    if want > 0.0 {
                        faded += 1;
                    }
                    worst_fade = worst_fade.max((base[i].x as f64 - want).abs());
                    worst_z = worst_z.max((z[i] as f64 - ndc).abs());
                }
                Some((d, _)) if d < scene + 0.05 => {} // on the boundary
                _ => {
                    assert_eq!(
                        base[i].x as f64, CLEAR,
                        "pixel ({x}, {y}) should not be drawn"
                    );
                    assert_eq!(
                        z[i], scene_ndc,
                        "pixel ({x}, {y}) depth should be the scene's"
                    );
                }
            }
        }
    }
    println!(
        "{drawn} pixels drawn, {faded} fading; fade error {worst_fade:.2e}, depth error {worst_z:.2e}"
    );
    assert!(drawn > 500 && faded > 100, "{drawn} drawn, {faded} fading");
    // llvmpipe: 1.7e-4 (the fade's depths come back through f32 NDC) and 3.5e-7.
    assert!(worst_fade < 2e-3, "fade error {worst_fade}");
    assert!(worst_z < 1e-5, "depth error {worst_z}");
}

/// The G-buffer normal at a pixel is the f64 wave normal at the point the depth says was drawn
/// (found with the CPU query), with no detail layers.
#[test]
fn gbuffer_normal_is_the_wave_normal() {
    let ctx = Context::shared();
    let waves = sea();
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap();
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    draw(
        &ctx,
        &renderer,
        &waves,
        &calm_look(),
        &targets,
        &depth,
        1.0,
        false,
    );
    let normals: Vec<Vec4> = read_texture(&ctx, &targets[1]).unwrap();
    let z: Vec<f32> = read_texture(&ctx, &depth).unwrap();
    let cam = camera();
    let inv = (cam.proj.as_dmat4() * cam.view).inverse();
    let (mut n, mut worst) = (0, 0f64);
    for y in (H / 2..H).step_by(4) {
        for x in (0..W).step_by(6) {
            let i = (y * W + x) as usize;
            if z[i] >= 1.0 {
                continue;
            }
            let ndc = DVec4::new(
                (x as f64 + 0.5) / W as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / H as f64 * 2.0,
                z[i] as f64,
                1.0,
            );
            let h = inv * ndc;
            let p = h.truncate() / h.w;
            let want = waves.sample(DVec2::new(p.x, p.z), 12.5).normal;
            let got = (normals[i].truncate().as_dvec3() * 2.0 - 1.0).normalize();
            worst = worst.max((got - want).length());
            n += 1;
        }
    }
    println!("{n} pixels, worst normal difference {worst:.4}");
    assert!(n > 50, "{n} pixels checked");
    // llvmpipe: 0.0023 (interpolation across 0.25 m triangles, f32 depth).
    assert!(worst < 0.03, "normal difference {worst}");
}

#[test]
fn forward_and_gbuffer_snapshots() {
    let ctx = Context::shared();
    let waves = sea();
    let forward =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(RGBA32), false).unwrap();
    let colour = target(&ctx, RGBA32);
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    draw(
        &ctx,
        &forward,
        &waves,
        &Look::default(),
        std::slice::from_ref(&colour),
        &depth,
        1.0,
        false,
    );
    let lum = |v: &[Vec4]| -> Vec<f32> { v.iter().map(|c| (c.x + c.y + c.z) / 3.0).collect() };
    let shape = [H as usize, W as usize];
    let image: Vec<Vec4> = read_texture(&ctx, &colour).unwrap();
    let gbuffer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap();
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    draw(
        &ctx,
        &gbuffer,
        &waves,
        &Look::default(),
        &targets,
        &depth,
        1.0,
        false,
    );
    let g: Vec<Vec<Vec4>> = targets
        .iter()
        .map(|t| read_texture(&ctx, t).unwrap())
        .collect();
    let normal_y: Vec<f32> = g[1].iter().map(|n| n.y).collect();
    let roughness: Vec<f32> = g[2].iter().map(|m| m.z).collect();
    fieldkit::assert_summary!(
        "forward_and_gbuffer_snapshots",
        Summary::floats(&shape, &lum(&image), 3)
            .and("scene colour", Summary::floats(&shape, &lum(&g[0]), 3))
            .and("normal y", Summary::floats(&shape, &normal_y, 3))
            .and("roughness", Summary::floats(&shape, &roughness, 3))
            .and("base colour", Summary::floats(&shape, &lum(&g[3]), 3))
            .to_string()
    );
}

/// Where a fine patch meets a coarse one, the coarse edge interpolates between vertices the fine
/// edge has in between: without skirts light shows through the cracks (pixels that see the
/// water's mean plane inside the patches keep the clear colour); with skirts none do.
#[test]
fn skirts_close_the_cracks_between_levels() {
    let ctx = Context::shared();
    // A short wave along the shared edge: the coarse edge is off by up to 6 cm between vertices.
    let waves = Waves::new(vec![wave(0.0, 1.0, 0.2, 1.0, 0.0)], 0.0).unwrap();
    let (w, h) = (256u32, 192u32);
    let make = |format| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            format,
            ..depth_desc()
        })
    };
    let eye = DVec3::new(5.0, 1.6, 3.0);
    let cam = OceanCamera::look_at(
        eye,
        DVec3::new(9.0, 0.0, 4.0),
        glam::camera::rh::proj::directx::perspective(1.0, w as f32 / h as f32, 0.05, 100.0),
    );
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(RGBA32), false).unwrap();
    // A fine patch (0.125 m spacing) beside a coarse one (0.25 m) sharing the edge x = 8, as a
    // quadtree level change makes them; then the same squares with quad counts that turn it
    // round (0.5 m beside 0.25 m), as `lod::select`'s choice of quads per patch can.
    // Well inside the two patches: 0.5 m from their outer edges, and 4 m from the far one, where
    // grazing rays pass over troughs and out of the patch (the coarse patch's edge x = 8 is an
    // outer edge where z < 0).
    let level_change = |p: DVec3| {
        (p.x > 0.5 && p.x < 8.0 && p.z > 0.5 && p.z < 7.5)
            || (p.x >= 8.0 && p.x < 20.0 && p.z > -7.5 && p.z < 7.5 && (p.x > 8.5 || p.z > 0.5))
    };
    // Two patches of the same size and quads share their edge's vertices bit for bit, so they
    // meet without a crack and without a skirt: `lod::select` leaves that edge bare.
    let bare = Patch {
        skirts: 0,
        ..Patch::new(DVec2::new(0.0, 0.0), 8.0)
    };
    let same = |p: DVec3| p.x > 0.5 && p.x < 12.0 && p.z > 0.5 && p.z < 7.5;
    // The level change again with the shared edge's skirts left out (bit 2: x high; bit 8: x
    // low): the renderer draws only the skirts a patch lists, so the cracks stay.
    let unskirted = [
        Patch {
            skirts: ALL_SKIRTS & !2,
            ..Patch::new(DVec2::new(0.0, 0.0), 8.0)
        },
        Patch {
            skirts: ALL_SKIRTS & !8,
            ..Patch::new(DVec2::new(8.0, -8.0), 16.0)
        },
    ];
    let layouts: [CrackLayout; 4] = [
        (
            [
                Patch::new(DVec2::new(0.0, 0.0), 8.0),
                Patch::new(DVec2::new(8.0, -8.0), 16.0),
            ],
            &level_change,
            true,
            true,
        ),
        (
            [
                Patch {
                    quads: 16,
                    ..Patch::new(DVec2::new(0.0, 0.0), 8.0)
                },
                Patch::new(DVec2::new(8.0, -8.0), 16.0),
            ],
            &level_change,
            true,
            true,
        ),
        (unskirted, &level_change, true, false),
        (
            [
                bare,
                Patch {
                    corner: DVec2::new(8.0, 0.0),
                    ..bare
                },
            ],
            &same,
            false,
            true,
        ),
    ];
    for (patches, inside, cracks, closed) in layouts {
        let mut holes = Vec::new();
        for skirt in [0.0f32, 0.5] {
            let colour = make(RGBA32);
            let depth = make(wgpu::TextureFormat::Depth32Float);
            let look = Look {
                skirt,
                height_layers: vec![],
                normal_layers: vec![],
                ..Look::default()
            };
            let (cv, dv) = (
                colour.create_view(&Default::default()),
                depth.create_view(&Default::default()),
            );
            let mut enc = ctx.encoder("cracks");
            clear(&mut enc, &[&cv], &dv, 1.0);
            renderer
                .encode(
                    &ctx.device,
                    &mut enc,
                    &waves,
                    0.3,
                    &cam,
                    &look,
                    &patches,
                    &[&cv],
                    &depth,
                    false,
                )
                .unwrap();
            ctx.submit_and_wait("cracks", enc).unwrap();
            let px: Vec<Vec4> = read_texture(&ctx, &colour).unwrap();
            let mut count = 0;
            for y in 0..h {
                for x in 0..w {
                    let Some(p) = plane_point(&cam, [w, h], x, y) else {
                        continue;
                    };
                    if inside(p) && px[(y * w + x) as usize].x as f64 == CLEAR {
                        count += 1;
                        // Cracks are at the shared edge (rays through them meet the plane a little
                        // beyond it).
                        assert!(
                            (p.x - 8.0).abs() < 1.5,
                            "a hole away from the shared edge, at {p}"
                        );
                    }
                }
            }
            holes.push(count);
        }
        println!(
            "clear pixels inside the patches: {} without skirts, {} with",
            holes[0], holes[1]
        );
        if cracks {
            assert!(
                holes[0] >= 5,
                "expected cracks without skirts, saw {}",
                holes[0]
            );
        } else {
            assert_eq!(
                holes[0], 0,
                "patches of one spacing should meet without a crack"
            );
        }
        if closed {
            assert_eq!(holes[1], 0, "skirts should close every crack");
        } else {
            assert!(
                holes[1] >= 5,
                "unskirted edges should still crack, saw {}",
                holes[1]
            );
        }
    }
}

/// Patches, where to look for holes, whether there are cracks to close, whether the patches'
/// skirts close them.
type CrackLayout<'a> = ([Patch; 2], &'a dyn Fn(DVec3) -> bool, bool, bool);

/// Name, time, look, patches, targets, depth target, fade.
type Case<'a> = (
    &'a str,
    f64,
    &'a Look,
    &'a [Patch],
    Vec<&'a wgpu::TextureView>,
    &'a wgpu::Texture,
    bool,
);

#[test]
fn bad_input_gets_typed_errors() {
    let ctx = Context::shared();
    let waves = sea();
    let cam = camera();
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(RGBA32), false).unwrap();
    let colour = target(&ctx, RGBA32);
    let view = colour.create_view(&Default::default());
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    let other = target(&ctx, wgpu::TextureFormat::Depth24Plus);
    let no_binding = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: depth.size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let small = ctx.device.create_texture(&wgpu::TextureDescriptor {
        size: wgpu::Extent3d {
            width: 8,
            height: 8,
            depth_or_array_layers: 1,
        },
        ..depth_desc()
    });
    let good = Look::default();
    let many = Look {
        normal_layers: vec![good.normal_layers[0]; 5],
        ..Look::default()
    };
    let no_fade = Look {
        fade_distance: 0.0,
        ..Look::default()
    };
    let nan_sun = Look {
        sun_direction: Vec3::NAN,
        ..Look::default()
    };
    let bad_patch = [Patch::new(DVec2::ZERO, 0.0)];
    let ok_patches = patches(&cam);
    let cases: Vec<Case> = vec![
        (
            "NaN time",
            f64::NAN,
            &good,
            &ok_patches,
            vec![&view],
            &depth,
            true,
        ),
        (
            "two targets for forward",
            0.0,
            &good,
            &ok_patches,
            vec![&view, &view],
            &depth,
            true,
        ),
        (
            "Depth24Plus",
            0.0,
            &good,
            &ok_patches,
            vec![&view],
            &other,
            true,
        ),
        (
            "depth without TEXTURE_BINDING, fade on",
            0.0,
            &good,
            &ok_patches,
            vec![&view],
            &no_binding,
            true,
        ),
        (
            "depth of another size",
            0.0,
            &good,
            &ok_patches,
            vec![&view],
            &small,
            true,
        ),
        (
            "five normal layers",
            0.0,
            &many,
            &ok_patches,
            vec![&view],
            &depth,
            true,
        ),
        (
            "zero fade distance",
            0.0,
            &no_fade,
            &ok_patches,
            vec![&view],
            &depth,
            true,
        ),
        (
            "NaN sun",
            0.0,
            &nan_sun,
            &ok_patches,
            vec![&view],
            &depth,
            true,
        ),
        (
            "zero-size patch",
            0.0,
            &good,
            &bad_patch,
            vec![&view],
            &depth,
            true,
        ),
    ];
    for (name, time, look, patches, targets, depth, fade) in cases {
        let mut enc = ctx.encoder("bad");
        let err = renderer
            .encode(
                &ctx.device,
                &mut enc,
                &waves,
                time,
                &cam,
                look,
                patches,
                &targets,
                depth,
                fade,
            )
            .err()
            .unwrap_or_else(|| panic!("{name}: accepted"));
        assert!(
            matches!(
                err,
                Error::Invalid { .. } | Error::Size { .. } | Error::Format { .. }
            ),
            "{name}: {err:?}"
        );
    }
    // Without fade no copy is made, so TEXTURE_BINDING is not needed.
    let mut enc = ctx.encoder("no fade");
    renderer
        .encode(
            &ctx.device,
            &mut enc,
            &waves,
            0.0,
            &cam,
            &good,
            &ok_patches,
            &[&view],
            &no_binding,
            false,
        )
        .unwrap();
}

/// One renderer drawn twice into one encoder (two looks, two cameras, two sets of targets)
/// draws each as it draws alone: the renderer keeps its buffers and bind groups from call to
/// call, and each call still reads its own patches and parameters. Same adapter, same inputs:
/// the images compare to the bit.
#[test]
fn two_draws_in_one_encoder_keep_their_own_parameters() {
    let ctx = Context::shared();
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(RGBA32), false).unwrap();
    let looks = [
        calm_look(),
        Look {
            deep_colour: Vec3::new(0.9, 0.1, 0.1),
            sun_direction: Vec3::new(0.3, 0.5, -0.8),
            ..calm_look()
        },
    ];
    let eye = DVec3::new(2.0e4 + 7.0, 9.0, -3.5e4 + 3.0);
    let cams = [
        camera(),
        OceanCamera::look_at(
            eye,
            eye + DVec3::new(2.0, -6.0, -20.0),
            glam::camera::rh::proj::directx::perspective(0.8, W as f32 / H as f32, 0.1, 400.0),
        ),
    ];
    let depth = || target(&ctx, wgpu::TextureFormat::Depth32Float);
    let alone: Vec<Vec<Vec4>> = (0..2)
        .map(|k| {
            let t = [target(&ctx, RGBA32)];
            draw_from(
                &ctx,
                &renderer,
                &sea(),
                &looks[k],
                &t,
                &depth(),
                1.0,
                false,
                cams[k],
            );
            read_texture(&ctx, &t[0]).unwrap()
        })
        .collect();
    assert_ne!(alone[0], alone[1]);
    let colour = [target(&ctx, RGBA32), target(&ctx, RGBA32)];
    let depths = [depth(), depth()];
    let mut enc = ctx.encoder("two draws");
    for k in 0..2 {
        let view = colour[k].create_view(&Default::default());
        clear(
            &mut enc,
            &[&view],
            &depths[k].create_view(&Default::default()),
            1.0,
        );
        renderer
            .encode(
                &ctx.device,
                &mut enc,
                &sea(),
                12.5,
                &cams[k],
                &looks[k],
                &patches(&cams[k]),
                &[&view],
                &depths[k],
                false,
            )
            .unwrap();
    }
    ctx.submit_and_wait("two draws", enc).unwrap();
    for k in 0..2 {
        let together: Vec<Vec4> = read_texture(&ctx, &colour[k]).unwrap();
        assert!(
            together == alone[k],
            "draw {k} differs when drawn with the other"
        );
    }
}

/// The copy of the scene's depth the fade reads is kept across a resize the targets still fit
/// (made with each side rounded up to 128 pixels): a faded frame drawn after a larger one, its
/// copy 256 × 128 for 96 × 64 targets, comes out to the bit as a fresh renderer's (copy
/// 128 × 128).
#[test]
fn a_faded_frame_after_a_larger_is_the_frame_alone() {
    let ctx = Context::shared();
    let make = || {
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap()
    };
    let draw_at = |renderer: &OceanRenderer, [w, h]: [u32; 2]| -> Vec<Vec4> {
        let sized = |format| {
            common::texture(
                &ctx,
                [w, h, 1],
                format,
                wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
            )
        };
        let targets: Vec<_> = (0..4).map(|_| sized(RGBA32)).collect();
        let depth = sized(wgpu::TextureFormat::Depth32Float);
        draw_faded(&ctx, renderer, &targets, &depth);
        read_texture(&ctx, &targets[3]).unwrap()
    };
    let kept = make();
    draw_at(&kept, [W + 40, H + 30]);
    let after = draw_at(&kept, [W, H]);
    let alone = draw_at(&make(), [W, H]);
    let fading = after.iter().filter(|p| p.x > 0.01 && p.x < 0.99).count();
    assert!(fading > 100, "{fading} pixels fading");
    assert!(after == alone, "the faded frame after a larger one differs");
}
