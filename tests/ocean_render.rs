//! The ocean's render stage (`ocean/surface`: `vs_surface` with `fs_forward` or `fs_gbuffer`):
//! depth fade against a closed form, the depth the pass writes, the G-buffer normal against the
//! f64 wave normal, snapshots of both outputs, and bad input.
//!
//! Tolerances were set on llvmpipe.

use fieldkit::Error;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::harness::Summary;
use fieldkit::ocean::{ALL_SKIRTS, Look, OceanCamera, OceanRenderer, Output, Patch};
use fieldkit::ocean::{Wave, Waves};
use glam::{DVec2, DVec3, DVec4, Vec2, Vec3, Vec4};

const W: u32 = 96;
const H: u32 = 64;
const RGBA32: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const CLEAR: f64 = -1.0;

fn wave(dx: f32, dz: f32, amplitude: f32, wavelength: f32, speed: f32) -> Wave {
    Wave {
        direction: Vec2::new(dx, dz),
        amplitude,
        wavelength,
        speed,
    }
}

fn sea() -> Waves {
    Waves::new(
        vec![
            wave(1.0, 0.15, 0.5, 31.0, 7.0),
            wave(0.4, 1.0, 0.25, 13.5, 4.6),
            wave(-0.7, 0.6, 0.08, 5.3, 2.9),
        ],
        0.6,
    )
    .unwrap()
}

/// Far from the world origin, looking down the z axis at about 17°.
fn camera() -> OceanCamera {
    let eye = DVec3::new(2.0e4, 6.0, -3.5e4);
    OceanCamera::look_at(
        eye,
        eye + DVec3::new(0.0, -6.0, -20.0),
        glam::camera::rh::proj::directx::perspective(1.0, W as f32 / H as f32, 0.1, 400.0),
    )
}

/// 6 × 6 patches of 16 m around the eye.
fn patches(cam: &OceanCamera) -> Vec<Patch> {
    let eye = cam.eye();
    let mut out = Vec::new();
    for j in 0..6 {
        for i in 0..6 {
            out.push(Patch::new(
                DVec2::new(
                    eye.x - 48.0 + 16.0 * i as f64,
                    eye.z - 80.0 + 16.0 * j as f64,
                ),
                16.0,
            ));
        }
    }
    out
}

fn target(ctx: &Context, format: wgpu::TextureFormat) -> wgpu::Texture {
    fieldkit::gpu::texture(
        &ctx.device,
        "test target",
        [W, H, 1],
        wgpu::TextureDimension::D2,
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
    )
}

/// Clear `views` to CLEAR and `depth` to `clear_depth`.
fn clear(
    enc: &mut wgpu::CommandEncoder,
    views: &[&wgpu::TextureView],
    depth: &wgpu::TextureView,
    clear_depth: f32,
) {
    let attachments: Vec<_> = views
        .iter()
        .map(|v| {
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: CLEAR,
                        g: CLEAR,
                        b: CLEAR,
                        a: CLEAR,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(clear_depth),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        ..Default::default()
    });
}

/// Clear the colour targets to CLEAR and the depth to `depth`, then draw.
#[allow(clippy::too_many_arguments)]
fn draw(
    ctx: &Context,
    renderer: &OceanRenderer,
    waves: &Waves,
    look: &Look,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
    clear_depth: f32,
    fade: bool,
) {
    draw_from(
        ctx,
        renderer,
        waves,
        look,
        targets,
        depth,
        clear_depth,
        fade,
        camera(),
    );
}

/// [`draw`] from another camera.
#[allow(clippy::too_many_arguments)]
fn draw_from(
    ctx: &Context,
    renderer: &OceanRenderer,
    waves: &Waves,
    look: &Look,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
    clear_depth: f32,
    fade: bool,
    cam: OceanCamera,
) {
    let views: Vec<wgpu::TextureView> = targets
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let depth_view = depth.create_view(&Default::default());
    let mut enc = ctx.encoder("ocean test");
    clear(
        &mut enc,
        &views.iter().collect::<Vec<_>>(),
        &depth_view,
        clear_depth,
    );
    let refs: Vec<&wgpu::TextureView> = views.iter().collect();
    renderer
        .encode(
            &ctx.device,
            &mut enc,
            waves,
            12.5,
            &cam,
            look,
            &patches(&cam),
            &refs,
            depth,
            fade,
        )
        .unwrap();
    ctx.submit_and_wait("ocean test", enc).unwrap();
}

/// Where the ray through the centre of pixel (x, y) of a `w` × `h` image meets the plane y = 0,
/// if it does between the near and far planes.
fn plane_point(cam: &OceanCamera, [w, h]: [u32; 2], x: u32, y: u32) -> Option<DVec3> {
    let inv = (cam.proj.as_dmat4() * cam.view).inverse();
    let ndc = DVec2::new(
        (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
        1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
    );
    let un = |z: f64| {
        let q = inv * DVec4::new(ndc.x, ndc.y, z, 1.0);
        q.truncate() / q.w
    };
    let (a, b) = (un(0.0), un(1.0));
    let t = a.y / (a.y - b.y);
    (t > 0.0 && t < 1.0).then(|| a + (b - a) * t)
}

/// The pixel centre's ray hitting y = 0: view depth and NDC depth, if it hits ahead.
fn plane_hit(cam: &OceanCamera, x: u32, y: u32) -> Option<(f64, f64)> {
    let proj = cam.proj.as_dmat4();
    let p = plane_point(cam, [W, H], x, y)?;
    let v = cam.view * p.extend(1.0);
    let clip = proj * v;
    Some((-v.z, clip.z / clip.w))
}

/// NDC depth of view depth `d`.
fn ndc_of(cam: &OceanCamera, d: f64) -> f64 {
    let clip = cam.proj.as_dmat4() * DVec4::new(0.0, 0.0, -d, 1.0);
    clip.z / clip.w
}

fn calm_look() -> Look {
    Look {
        height_layers: vec![],
        normal_layers: vec![],
        deep_colour: Vec3::ZERO,
        shallow_colour: Vec3::ONE,
        fade_distance: 3.0,
        skirt: 0.0,
        ..Look::default()
    }
}

/// A calm sea (0.1 mm waves) over a scene at a constant view depth of 15 m: where the water is
/// nearer, it is drawn with fade = 1 − saturate((15 − its depth) / 3), which the base-colour
/// target shows directly (deep black, shallow white), and its depth is written; elsewhere the
/// scene's depth and the clear colour stay.
#[test]
fn depth_fade_and_depth_write_in_one_pass() {
    let ctx = Context::shared();
    let calm = Waves::new(vec![wave(1.0, 0.0, 1e-4, 50.0, 0.0)], 0.0).unwrap();
    let renderer =
        OceanRenderer::new(&ctx.device, &ctx.queue, Output::GBuffer([RGBA32; 4]), false).unwrap();
    let targets: Vec<_> = (0..4).map(|_| target(&ctx, RGBA32)).collect();
    let depth = target(&ctx, wgpu::TextureFormat::Depth32Float);
    let cam = camera();
    let scene = 15.0;
    let scene_ndc = ndc_of(&cam, scene) as f32;
    draw(
        &ctx,
        &renderer,
        &calm,
        &calm_look(),
        &targets,
        &depth,
        scene_ndc,
        true,
    );
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

fn depth_desc() -> wgpu::TextureDescriptor<'static> {
    wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    }
}

/// Where the ray through the centre of pixel (x, y) meets the plane y = `level`: view depth
/// and NDC depth, if ahead.
fn level_hit(cam: &OceanCamera, x: u32, y: u32, level: f64) -> Option<(f64, f64)> {
    let proj = cam.proj.as_dmat4();
    let inv = (proj * cam.view).inverse();
    let ndc = DVec2::new(
        (x as f64 + 0.5) / W as f64 * 2.0 - 1.0,
        1.0 - (y as f64 + 0.5) / H as f64 * 2.0,
    );
    let un = |z: f64| {
        let q = inv * DVec4::new(ndc.x, ndc.y, z, 1.0);
        q.truncate() / q.w
    };
    let (a, b) = (un(0.0), un(1.0));
    let t = (a.y - level) / (a.y - b.y);
    if !(t > 0.0 && t < 1.0) {
        return None;
    }
    let v = cam.view * (a + (b - a) * t).extend(1.0);
    let clip = proj * v;
    Some((-v.z, clip.z / clip.w))
}

fn calm() -> Waves {
    Waves::new(vec![wave(1.0, 0.0, 1e-4, 50.0, 0.0)], 0.0).unwrap()
}

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
    let cam = camera();
    let views: Vec<_> = targets
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let refs: Vec<&wgpu::TextureView> = views.iter().collect();
    let mut enc = ctx.encoder("bad");
    let e = renderer
        .encode(
            &ctx.device,
            &mut enc,
            &calm(),
            0.0,
            &cam,
            &bad,
            &patches(&cam),
            &refs,
            &depth,
            false,
        )
        .unwrap_err();
    assert!(e.to_string().contains("metallic"), "{e}");
    let e = renderer
        .encode(
            &ctx.device,
            &mut enc,
            &calm(),
            0.0,
            &cam,
            &look,
            &patches(&cam),
            &refs[..4],
            &depth,
            false,
        )
        .unwrap_err();
    assert!(e.to_string().contains("takes 5"), "{e}");
}

/// A texture array of `layers` constant layers.
fn constant_maps(
    ctx: &Context,
    format: wgpu::TextureFormat,
    layers: &[[u8; 4]],
    channels: usize,
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    let side = 8u32;
    let texels: Vec<u8> = layers
        .iter()
        .flat_map(|c| std::iter::repeat_n(c[..channels].to_vec(), (side * side) as usize).flatten())
        .collect();
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("test maps"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: layers.len() as u32,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &texels,
    )
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
    let volume = fieldkit::gpu::texture(
        &ctx.device,
        "test texture",
        [4, 4, 4],
        wgpu::TextureDimension::D3,
        wgpu::TextureFormat::R8Unorm,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
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
    let views: Vec<_> = targets
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let refs: Vec<&wgpu::TextureView> = views.iter().collect();
    let mut enc = ctx.encoder("bad maps");
    let e = renderer
        .encode(
            &ctx.device,
            &mut enc,
            &calm(),
            0.0,
            &cam,
            &past,
            &patches(&cam),
            &refs,
            &depth,
            false,
        )
        .unwrap_err();
    assert!(e.to_string().contains("samples map 2"), "{e}");
}
