//! What the metaball raymarcher writes and where: a viewport at an origin, the G-buffer a
//! scene's lighting reads, depth compositing with the scene (standard and reversed Z), two
//! marches in one encoder, and a smaller frame after a larger one.

use crate::common;

use common::metaball::*;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::metaball::cpu;
use fieldkit::metaball::{Material, RaymarchSettings, Raymarcher};
use fieldkit::view::{Targets, View};

use glam::{Mat4, Vec3};

/// The source's `ViewportMin`: a view drawn at an origin inside a larger target puts every
/// pixel where the whole-target view has it, shifted by the origin, and touches nothing
/// outside its rectangle.
#[test]
fn viewport_origin_shifts_the_picture() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let view = camera(Vec3::new(0.3, 0.4, 2.5), Vec3::ZERO, false);
    let whole = shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0);
    let (ox, oy) = (10u32, 6u32);
    let (tw, th) = (W + ox + 3, H + oy + 2);
    let targets = Targets::new(
        &ctx.device,
        [tw, th],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let marcher = raymarcher(&ctx, wgpu::TextureFormat::Rgba32Float, false);
    let placed = View {
        origin: [ox, oy],
        ..view
    };
    let mut enc = ctx.encoder("origin");
    targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
    let drawn = marcher
        .encode(
            &ctx.device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &field,
            Mat4::IDENTITY,
            &placed,
            &normals(),
        )
        .unwrap();
    ctx.submit_and_wait("origin", enc).unwrap();
    assert!(drawn);
    let colour: Vec<[f32; 4]> = read_texture(&ctx, &targets.colour).unwrap();
    let mut hits = 0;
    for y in 0..th {
        for x in 0..tw {
            let got = colour[(y * tw + x) as usize];
            let inside = (ox..ox + W).contains(&x) && (oy..oy + H).contains(&y);
            if !inside {
                assert_eq!(got[3], 0.0, "pixel {x},{y} outside the viewport was drawn");
                continue;
            }
            let want = whole.colour[((y - oy) * W + (x - ox)) as usize];
            // The same rays, the same march: equal to the last bit.
            assert_eq!(got, want, "pixel {x},{y}");
            hits += (got[3] != 0.0) as usize;
        }
    }
    assert!(hits > 100, "{hits}");
    // A target smaller than origin + viewport is refused.
    let small = Targets::new(
        &ctx.device,
        [W, H],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let mut enc = ctx.encoder("origin, small target");
    let e = marcher
        .encode(
            &ctx.device,
            &mut enc,
            &small.colour_view,
            &small.depth_view,
            &field,
            Mat4::IDENTITY,
            &placed,
            &normals(),
        )
        .unwrap_err();
    assert!(
        e.to_string().contains("smaller than the march's viewport"),
        "{e}"
    );
}

/// The G-buffer output (the source's stated limitation lifted): the same march writes depth
/// to the bit, the world normal, the material given and the base colour, in the ocean's target
/// order; pixels the surface misses keep what the targets held. In half floats at the
/// adapter's limits, and in `GBUFFER_FORMATS` on a device with WebGPU's default limits (32
/// bytes a sample), where 64 bytes of `Rgba32Float` targets are a typed error.
#[test]
fn gbuffer_holds_the_surface_for_the_scene_lighting() {
    let shared = Context::shared();
    gbuffer_on(&shared, [wgpu::TextureFormat::Rgba16Float; 4]);
    let defaults = common::default_limits(&shared);
    gbuffer_on(&defaults, fieldkit::gpu::GBUFFER_FORMATS);
    let e = Raymarcher::gbuffer(
        &defaults.device,
        &defaults.queue,
        [wgpu::TextureFormat::Rgba32Float; 4],
        wgpu::TextureFormat::Depth32Float,
        false,
    )
    .err()
    .expect("64 bytes a sample on a 32-byte device");
    assert!(matches!(e, fieldkit::Error::Unsupported { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("max_color_attachment_bytes_per_sample ≥ 64"),
        "{e}"
    );
}

fn gbuffer_on(ctx: &Context, formats: [wgpu::TextureFormat; 4]) {
    let (_, field) = one_blob(ctx);
    let view = camera(Vec3::new(0.3, 0.4, 2.5), Vec3::ZERO, false);
    let forward = shoot(ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0);
    let f16 = wgpu::TextureFormat::Rgba16Float;
    let marcher = Raymarcher::gbuffer(
        &ctx.device,
        &ctx.queue,
        formats,
        wgpu::TextureFormat::Depth32Float,
        false,
    )
    .unwrap();
    let make = |format| {
        crate::common::texture(
            ctx,
            [W, H, 1],
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        )
    };
    let gb: Vec<wgpu::Texture> = formats.iter().map(|f| make(*f)).collect();
    let depth = make(wgpu::TextureFormat::Depth32Float);
    let views: Vec<wgpu::TextureView> = gb
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let dv = depth.create_view(&Default::default());
    let mut enc = ctx.encoder("gbuffer");
    for v in &views {
        enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: None,
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 0.25,
                        g: 0.25,
                        b: 0.25,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
    }
    fieldkit::gpu::clear_depth(&mut enc, &dv, 1.0);
    let base = Vec3::new(0.8, 0.4, 0.2);
    let settings = RaymarchSettings {
        base_colour: base,
        // The pile moves the base toward itself: the base colour stays as given.
        pile_colour: Some(base),
        ..RaymarchSettings::default()
    };
    let material = Material {
        metallic: 0.25,
        specular: 0.5,
        roughness: 0.75,
        shading_model: 3,
    };
    let refs = [&views[0], &views[1], &views[2], &views[3]];
    // The G-buffer of the blob with `material`, drawn by `marcher` into `refs` and `dv`.
    let draw = |marcher: &Raymarcher, enc: &mut wgpu::CommandEncoder, material: &Material| {
        let (place, dv) = (Mat4::IDENTITY, &dv);
        marcher.encode_gbuffer(
            &ctx.device,
            enc,
            refs,
            dv,
            &field,
            place,
            &view,
            &settings,
            material,
        )
    };
    let drawn = draw(&marcher, &mut enc, &material).unwrap();
    ctx.submit_and_wait("gbuffer", enc).unwrap();
    assert!(drawn);
    let [scene, normal, mat, base_out] = [0, 1, 2, 3].map(|i| common::read_rgba(ctx, &gb[i]));
    // Each target's rounding: its format's step (set on llvmpipe; the formats' own steps, so
    // they hold on any adapter), plus 1e-3 of the march's own.
    let [_, normal_step, mat_step, base_step] = formats.map(common::format_step);
    let close = |a: [f32; 4], b: [f32; 4], tol: f32| (0..4).all(|k| (a[k] - b[k]).abs() <= tol);
    let depth: Vec<f32> = read_texture(ctx, &depth).unwrap();
    let mut hits = 0;
    for i in 0..(W * H) as usize {
        match forward.hits[i] {
            Some((n, _)) => {
                hits += 1;
                // The same march: the same depth, to the bit.
                assert_eq!(depth[i], forward.depth[i], "depth at {i}");
                let got = Vec3::new(normal[i][0], normal[i][1], normal[i][2]) * 2.0 - 1.0;
                let tol = 2.0 * (normal_step + 1e-3);
                assert!(got.abs_diff_eq(n, tol), "normal at {i}: {got} vs {n}");
                assert_eq!(scene[i], [0.0, 0.0, 0.0, 1.0]);
                let m = [0.25, 0.5, 0.75, 3.0 / 255.0];
                assert!(close(mat[i], m, mat_step + 1e-3), "{:?}", mat[i]);
                // 8 bits in the march's packing, then the target's format.
                let b = Vec3::new(base_out[i][0], base_out[i][1], base_out[i][2]);
                let tol = 0.5 / 255.0 + base_step + 1e-3;
                assert!(b.abs_diff_eq(base, tol), "base at {i}: {b}");
            }
            None => {
                assert_eq!(depth[i], 1.0, "depth written at a miss, {i}");
                let clear = [0.25, 0.25, 0.25, 0.0];
                let tol = normal_step + 1e-6;
                assert!(close(normal[i], clear, tol), "normal written at a miss");
            }
        }
    }
    assert!(hits > 200, "{hits}");
    // Each raymarcher draws its own kind of target; materials are checked.
    let mut enc = ctx.encoder("gbuffer errors");
    let e = marcher
        .encode(
            &ctx.device,
            &mut enc,
            &views[0],
            &dv,
            &field,
            Mat4::IDENTITY,
            &view,
            &settings,
        )
        .unwrap_err();
    assert!(e.to_string().contains("encode_gbuffer"), "{e}");
    let bad = Material {
        roughness: f32::NAN,
        ..material
    };
    let e = draw(&marcher, &mut enc, &bad).unwrap_err();
    assert!(e.to_string().contains("roughness"), "{e}");
    let forward_marcher = raymarcher(ctx, f16, false);
    let e = draw(&forward_marcher, &mut enc, &material).unwrap_err();
    assert!(e.to_string().contains("Raymarcher::gbuffer"), "{e}");
}

/// The surface writes depth and is tested against the caller's: a wall at a depth in front of
/// the blob hides it, one behind it does not; the same with reversed Z.
#[test]
fn depth_composites_with_the_scene_standard_and_reversed() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    for reversed in [false, true] {
        let view = camera(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, reversed);
        let depth_at = |z: f32| view.view_proj.project_point3(Vec3::new(0.0, 0.0, z)).z;
        let far = if reversed { 0.0 } else { 1.0 };
        let open = shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), far);
        let n = count(&open);
        assert!(n > 100, "reversed {reversed}: {n}");
        // Written depth: the centre pixel's depth, unprojected, is the front of the sphere.
        let r = cpu::blob_iso_radius(blob_settings().radius(1.0, 1.0) as f64, 0.5) as f32;
        let centre = open.depth[(H / 2 * W + W / 2) as usize];
        let ndc = Vec3::new(1.0 / W as f32, -1.0 / H as f32, centre);
        let front = view.view_proj.inverse().project_point3(ndc);
        let cell = field.grid.voxel as f32;
        assert!(
            (front.z - r).abs() < 0.2 * cell,
            "reversed {reversed}: depth {centre} puts the front at z = {}, the sphere's is {r}",
            front.z
        );
        // A wall at z = 0.9 (in front of the blob): nothing passes.
        let hidden = shoot(
            &ctx,
            &field,
            &view,
            Mat4::IDENTITY,
            &normals(),
            depth_at(0.9),
        );
        assert_eq!(count(&hidden), 0, "reversed {reversed}");
        // A wall at z = -0.9 (behind): all of it passes.
        let shown = shoot(
            &ctx,
            &field,
            &view,
            Mat4::IDENTITY,
            &normals(),
            depth_at(-0.9),
        );
        assert_eq!(count(&shown), n, "reversed {reversed}");
    }
}

/// One raymarcher marching and compositing twice into one encoder (two views into two sets
/// of targets) draws each as a raymarcher of its own does alone: it keeps its parameters'
/// buffer and bind groups from call to call, and each march still reads its own view.
#[test]
fn two_marches_in_one_encoder_keep_their_own_parameters() {
    use fieldkit::view::Targets;
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let views = [
        camera(Vec3::new(0.3, 0.4, 2.5), Vec3::ZERO, false),
        camera(Vec3::new(-1.9, 0.8, 1.4), Vec3::ZERO, false),
    ];
    let settings = normals();
    let alone = views
        .each_ref()
        .map(|v| shoot(&ctx, &field, v, Mat4::IDENTITY, &settings, 1.0).colour);
    assert_ne!(alone[0], alone[1]);
    let (colour, depth) = (
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let marcher = Raymarcher::new(&ctx.device, &ctx.queue, colour, depth, false).unwrap();
    let targets = [0, 1].map(|_| Targets::new(&ctx.device, [W, H], colour, depth));
    let mut enc = ctx.encoder("two marches");
    for (t, v) in targets.iter().zip(&views) {
        t.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
        let drawn = marcher
            .encode(
                &ctx.device,
                &mut enc,
                &t.colour_view,
                &t.depth_view,
                &field,
                Mat4::IDENTITY,
                v,
                &settings,
            )
            .unwrap();
        assert!(drawn);
    }
    ctx.submit_and_wait("two marches", enc).unwrap();
    for (k, t) in targets.iter().enumerate() {
        let together: Vec<[f32; 4]> = read_texture(&ctx, &t.colour).unwrap();
        assert!(
            together == alone[k],
            "march {k} differs when marched with the other"
        );
    }
}

/// A raymarcher keeps its march images across a resize the target still fits: the frame it
/// draws at the smaller size after a larger one (its images now 256 × 256 for a 130 × 120
/// target) is, to the bit, the frame one that never drew larger draws (images 256 × 128).
#[test]
fn a_smaller_frame_after_a_larger_is_the_frame_alone() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let (colour, depth) = (
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let make = || Raymarcher::new(&ctx.device, &ctx.queue, colour, depth, false).unwrap();
    let draw = |marcher: &Raymarcher, size: [u32; 2]| -> Vec<[f32; 4]> {
        let view = View {
            viewport: size,
            ..camera(Vec3::new(0.3, 0.4, 2.5), Vec3::ZERO, false)
        };
        let targets = Targets::new(&ctx.device, size, colour, depth);
        let mut enc = ctx.encoder("resize");
        targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
        let (cv, dv) = (&targets.colour_view, &targets.depth_view);
        let drawn = marcher
            .encode(
                &ctx.device,
                &mut enc,
                cv,
                dv,
                &field,
                Mat4::IDENTITY,
                &view,
                &normals(),
            )
            .unwrap();
        assert!(drawn, "{size:?}: the blob is on screen");
        ctx.submit_and_wait("resize", enc).unwrap();
        read_texture(&ctx, &targets.colour).unwrap()
    };
    let kept = make();
    let large = draw(&kept, [150, 130]);
    let small = [130, 120];
    let after = draw(&kept, small);
    let alone = draw(&make(), small);
    assert!(large.iter().filter(|p| p[3] != 0.0).count() > 500);
    assert!(after.iter().filter(|p| p[3] != 0.0).count() > 500);
    assert!(after == alone, "the smaller frame after the larger differs");
}
