//! The metaball raymarcher's failure modes, each shown: cameras inside the volume and inside a
//! blob, a volume behind the near plane, the step cap, culling and bad views, empty and
//! degenerate sets, and a stale march or wrong target handed to the composite.

use crate::common;

use common::metaball::*;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::metaball::{Output, RaymarchSettings, Raymarcher};
use fieldkit::view::{Targets, View, box_visible};

use glam::{Mat4, Vec3, Vec4};

/// Cameras inside the box, inside the blob, and a box cut by the near plane.
#[test]
fn cameras_inside_and_the_near_plane() {
    let ctx = Context::shared();
    let (voxels, field) = one_blob(&ctx);
    let s = blob_settings();
    // Inside the box, outside the blob: rays start at the near plane, inside the box.
    let eye = Vec3::new(0.0, 0.0, 0.8);
    assert!(field.grid.origin.z + field.grid.size[2] as f64 * field.grid.voxel > 0.8);
    let view = camera(eye, Vec3::ZERO, false);
    let shot = shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0);
    let a = against_analytic(&shot, &view, &voxels, &s, field.grid.voxel);
    println!(
        "camera in the box: {} hits, {} silhouette off",
        a.hits, a.silhouette_off
    );
    assert!(a.hits > 500 && a.silhouette_off <= 6);
    // Inside the blob: every pixel is inside from its first sample, so the surface is drawn at
    // the near plane over the whole screen (distance 0), not lost.
    let view = camera(Vec3::new(0.05, 0.0, 0.1), Vec3::new(0.05, 0.0, -1.0), false);
    let shot = shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0);
    assert_eq!(count(&shot), (W * H) as usize);
    assert!(shot.hits.iter().all(|h| h.unwrap().1 < 1e-3));
    // The near plane cuts the sphere: pixels whose near-plane point is inside show the cut at
    // distance 0; the rest see the sphere behind it.
    // Near plane at z = 0.4 cuts the sphere (r ≈ 0.454) in a disc of radius 0.21; the screen
    // spans ±0.40 there.
    let view = camera_near(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO, false, 1.1);
    let shot = shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0);
    let cut = shot
        .hits
        .iter()
        .filter(|h| h.is_some_and(|h| h.1 < 1e-3))
        .count();
    let beyond = shot
        .hits
        .iter()
        .filter(|h| h.is_some_and(|h| h.1 >= 1e-3))
        .count();
    println!("near plane through the blob: {cut} cut pixels, {beyond} beyond");
    assert!(cut > 50 && beyond > 50);
}

/// The step cap: with one step nothing far from the surface converges, and those pixels are
/// left as they were (not drawn at a wrong depth). The Steps view shows the count.
#[test]
fn step_cap_leaves_pixels_undrawn() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let view = camera(Vec3::new(0.0, 0.0, 2.5), Vec3::ZERO, false);
    let full = count(&shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0));
    let capped = RaymarchSettings {
        max_steps: 2,
        ..normals()
    };
    let few = count(&shoot(&ctx, &field, &view, Mat4::IDENTITY, &capped, 1.0));
    println!("step cap 2: {few} of {full} pixels drawn");
    assert!(few < full / 4, "{few} of {full}");
    let steps = shoot(
        &ctx,
        &field,
        &view,
        Mat4::IDENTITY,
        &RaymarchSettings {
            output: Output::Steps,
            ..RaymarchSettings::default()
        },
        1.0,
    );
    // Steps view covers the box's footprint, blob or not.
    let box_px = steps.colour.iter().filter(|c| c[3] != 0.0).count();
    assert!(box_px > full, "{box_px} box pixels, {full} blob pixels");
}

/// A rigid placement moves the surface with it; culling skips a box outside the frustum;
/// a singular or projective placement is refused (scale is placed: see
/// `scaled_placement_matches_the_analytic_field`).
#[test]
fn placement_culling_and_bad_views() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let view = camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, false);
    let place = Mat4::from_rotation_y(0.7) * Mat4::from_translation(Vec3::new(0.6, 0.0, 0.0));
    let moved = shoot(&ctx, &field, &view, place, &normals(), 1.0);
    // Centre of mass of the hit pixels follows the blob's projected centre.
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for y in 0..H {
        for x in 0..W {
            if moved.hits[(y * W + x) as usize].is_some() {
                sx += x as f32 + 0.5;
                sy += y as f32 + 0.5;
                n += 1.0;
            }
        }
    }
    let c = view
        .view_proj
        .project_point3(place.transform_point3(Vec3::ZERO));
    let px = ((c.x + 1.0) * 0.5 * W as f32, (1.0 - c.y) * 0.5 * H as f32);
    assert!(n > 50.0);
    assert!(
        (sx / n - px.0).abs() < 1.0 && (sy / n - px.1).abs() < 1.0,
        "{:?} vs {px:?}",
        (sx / n, sy / n)
    );
    let g = field.grid;
    let hi = g.origin.as_vec3()
        + Vec3::new(g.size[0] as f32, g.size[1] as f32, g.size[2] as f32) * g.voxel as f32;
    assert!(box_visible(
        view.view_proj,
        Mat4::IDENTITY,
        g.origin.as_vec3(),
        hi
    ));
    let away = Mat4::from_translation(Vec3::new(0.0, 0.0, 10.0));
    assert!(!box_visible(view.view_proj, away, g.origin.as_vec3(), hi));
    let marcher = raymarcher(&ctx, wgpu::TextureFormat::Rgba8Unorm, false);
    let tex = |format| {
        crate::common::texture(
            &ctx,
            [W, H, 1],
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default())
    };
    let cv = tex(wgpu::TextureFormat::Rgba8Unorm);
    let dv = tex(wgpu::TextureFormat::Depth32Float);
    let mut enc = ctx.encoder("cull");
    let mut march = |place: Mat4, view: &View, settings: &RaymarchSettings| {
        marcher.encode(
            &ctx.device,
            &mut enc,
            &cv,
            &dv,
            &field,
            place,
            view,
            settings,
        )
    };
    let drawn = march(away, &view, &RaymarchSettings::default()).unwrap();
    assert!(!drawn, "a box behind the camera is culled on the host");
    let flat = Mat4::from_scale(Vec3::new(2.0, 0.0, 1.0));
    let mut projective = Mat4::IDENTITY;
    projective.x_axis.w = 0.5;
    for bad in [flat, projective, Mat4::from_scale(Vec3::splat(f32::NAN))] {
        let e = march(bad, &view, &RaymarchSettings::default()).unwrap_err();
        assert!(e.to_string().contains("affine and invertible"), "{e}");
    }
    let nan = RaymarchSettings {
        safety: f32::NAN,
        ..RaymarchSettings::default()
    };
    let e = march(Mat4::IDENTITY, &view, &nan).unwrap_err();
    assert!(e.to_string().contains("safety"), "{e}");
    let rev = View {
        reversed_z: true,
        ..view
    };
    let e = march(Mat4::IDENTITY, &rev, &RaymarchSettings::default()).unwrap_err();
    assert!(e.to_string().contains("reversed_z"), "{e}");
    let e = Raymarcher::new(
        &ctx.device,
        &ctx.queue,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureFormat::Rgba8Unorm,
        false,
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("depth format"), "{e}");
}

/// Degenerate sets: an instance of scale zero adds nothing; an empty set gives a field of +band
/// everywhere (no seeds), which the raymarcher crosses without drawing.
#[test]
fn empty_and_zero_scale_sets() {
    let ctx = Context::shared();
    let s = blob_settings();
    let balls = fieldkit::metaball::Metaballs::new(&ctx.device).unwrap();
    let grid = fieldkit::distance::Grid {
        size: [16, 16, 16],
        voxel: 1.0 / 12.0,
        origin: glam::DVec3::splat(-8.0 / 12.0),
    };
    for voxels in [vec![], vec![Vec4::new(0.0, 0.0, 0.0, 0.0)]] {
        let inst = balls.upload(&ctx.device, &ctx.queue, &voxels).unwrap();
        let mut enc = ctx.encoder("empty");
        let field = balls
            .encode(&ctx.device, &mut enc, &inst, &grid, 1.0, &s)
            .unwrap();
        ctx.submit_and_wait("empty", enc).unwrap();
        let sdf: Vec<f32> = read_texture(&ctx, &field.sdf).unwrap();
        assert!(
            sdf.iter().all(|&d| d == field.band),
            "{} voxels: no seed, +band",
            voxels.len()
        );
        let view = camera(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, false);
        assert_eq!(
            count(&shoot(&ctx, &field, &view, Mat4::IDENTITY, &normals(), 1.0)),
            0
        );
    }
}

/// The split march/composite API cannot draw garbage: a march whose images a later march reused
/// is refused, and so is a target of another size than the march's viewport. The latest march
/// still composites.
#[test]
fn composite_refuses_a_stale_march_and_a_wrong_target() {
    let ctx = Context::shared();
    let (_, field) = one_blob(&ctx);
    let view = camera(Vec3::new(0.3, 0.4, 2.5), Vec3::ZERO, false);
    let marcher = raymarcher(&ctx, wgpu::TextureFormat::Rgba32Float, false);
    let rs = normals();
    let mut enc = ctx.encoder("split");
    let first = marcher
        .encode_march(&ctx.device, &mut enc, &field, Mat4::IDENTITY, &view, &rs)
        .unwrap()
        .expect("on screen");
    let second = marcher
        .encode_march(&ctx.device, &mut enc, &field, Mat4::IDENTITY, &view, &rs)
        .unwrap()
        .expect("on screen");
    let targets = Targets::new(
        &ctx.device,
        [W, H],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    let stale = marcher
        .encode_composite(&ctx.device, &mut enc, cv, dv, &first)
        .unwrap_err()
        .to_string();
    assert!(stale.contains("overwritten"), "{stale}");
    let small = Targets::new(
        &ctx.device,
        [W / 2, H],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let size = marcher
        .encode_composite(
            &ctx.device,
            &mut enc,
            &small.colour_view,
            &small.depth_view,
            &second,
        )
        .unwrap_err()
        .to_string();
    assert!(size.contains("viewport"), "{size}");
    targets.clear(&mut enc, wgpu::Color::TRANSPARENT, 1.0);
    marcher
        .encode_composite(&ctx.device, &mut enc, cv, dv, &second)
        .unwrap();
    ctx.submit_and_wait("split", enc).unwrap();
    let px: Vec<[f32; 4]> = read_texture(&ctx, &targets.colour).unwrap();
    assert!(px.iter().filter(|p| p[3] != 0.0).count() > 200);
}
