//! The voxel debug view (`voxelize/voxel_view`): one occupied voxel drawn face-on under an
//! orthographic camera covers exactly its square of pixels, in the colour of its averaged normal
//! (or of its averaged colour), lit head-on.

use fieldkit::gpu::Context;
use fieldkit::view::Targets;
use fieldkit::voxelize::{Attributes, Grid, Mesh, Voxelizer};
use fieldkit::voxelize::{ColourBy, VoxelView};
use glam::{DVec3, Vec3};

/// A triangle facing +z strictly inside voxel (1, 1, 1) of a 3³ grid (that voxel alone, in the
/// triangle's colour), its attributes, and a camera looking down −z at it: x and y in
/// [-0.5, 3.5] fill a 32 × 32 target, so the voxel's face spans pixels 12..20 on both axes.
fn one_voxel(ctx: &Context) -> (Grid, Attributes, glam::Mat4) {
    let mesh = Mesh {
        positions: vec![
            DVec3::new(1.2, 1.2, 1.5),
            DVec3::new(1.8, 1.3, 1.5),
            DVec3::new(1.4, 1.8, 1.5),
        ],
        triangles: vec![[0, 1, 2]],
        colors: vec![[200, 30, 90, 255]; 3],
        ..Mesh::default()
    };
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [3, 3, 3],
    };
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let voxels = ctx
        .block_on(voxelizer.attributes(&ctx.device, &ctx.queue, &mesh, &grid))
        .unwrap();
    let proj = glam::camera::rh::proj::directx::orthographic(-2.0, 2.0, -2.0, 2.0, 0.1, 20.0);
    let view_proj = proj
        * glam::camera::rh::view::look_at_mat4(
            Vec3::new(1.5, 1.5, 10.0),
            Vec3::new(1.5, 1.5, 0.0),
            Vec3::Y,
        );
    (grid, voxels, view_proj)
}

#[test]
fn one_voxel_covers_its_square_in_its_colour() {
    let ctx = Context::shared();
    let device = &ctx.device;
    let (grid, voxels, view_proj) = one_voxel(&ctx);
    assert_eq!(voxels.count, 1);
    let (colour_format, depth_format) = (
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureFormat::Depth32Float,
    );
    let view = VoxelView::new(device, colour_format, depth_format).unwrap();
    for (by, want) in [
        // Normal (0, 0, 1) → (½, ½, 1), lit head-on (factor 1).
        (ColourBy::Normal, [128, 128, 255]),
        (ColourBy::Colour, [200, 30, 90]),
    ] {
        let targets = Targets::new(device, [32, 32], colour_format, depth_format);
        let mut enc = ctx.encoder("view");
        targets.clear(&mut enc, wgpu::Color::BLACK, 1.0);
        view.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &voxels,
            &grid,
            view_proj,
            Vec3::Z,
            by,
        )
        .unwrap();
        ctx.submit_and_wait("view", enc).unwrap();
        let px: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, &targets.colour).unwrap();
        let mut lit = 0;
        for (i, p) in px.iter().enumerate() {
            let (x, y) = (i % 32, i / 32);
            let inside = (12..20).contains(&x) && (12..20).contains(&y);
            if inside {
                // Unorm rounding of ½ (llvmpipe writes 128; 127 would be as right).
                for c in 0..3 {
                    assert!(
                        (p[c] as i32 - want[c]).abs() <= 1,
                        "{by:?}: pixel ({x}, {y}) is {p:?}, want {want:?}"
                    );
                }
                lit += 1;
            } else {
                assert_eq!(
                    *p,
                    [0, 0, 0, 255],
                    "{by:?}: pixel ({x}, {y}) outside the voxel"
                );
            }
        }
        assert_eq!(lit, 64);
    }
    // Voxels from another grid are refused.
    let other = Grid {
        size: [4, 3, 3],
        ..grid
    };
    let targets = Targets::new(device, [8, 8], colour_format, depth_format);
    let mut enc = ctx.encoder("view");
    assert!(
        view.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &voxels,
            &other,
            view_proj,
            Vec3::Z,
            ColourBy::Normal,
        )
        .is_err()
    );
}

/// The source's demo scene lights its voxels with a point light: each cube corner gets
/// 0.35 + 0.65 · N·L · (1 − (d / range)²)². A light straight above the voxel's top face is as
/// far from its four corners, so the face is one colour, written out here; out of range, only
/// the ambient is left.
#[test]
fn a_point_light_shades_by_distance() {
    use fieldkit::voxelize::Light;
    let ctx = Context::shared();
    let device = &ctx.device;
    let (grid, voxels, view_proj) = one_voxel(&ctx);
    let format = wgpu::TextureFormat::Rgba32Float;
    let view = VoxelView::new(device, format, wgpu::TextureFormat::Depth32Float).unwrap();
    // The top face's corners are (1 or 2, 1 or 2, 2); the light is 1 above its centre.
    let position = Vec3::new(1.5, 1.5, 3.0);
    let d2: f32 = 0.5 * 0.5 + 0.5 * 0.5 + 1.0;
    let base = Vec3::new(200.0, 30.0, 90.0) / 255.0;
    for (range, want) in [
        (4.0f32, {
            let q = 1.0 - d2 / 16.0;
            0.35 + 0.65 * (1.0 / d2.sqrt()) * q * q
        }),
        // Out of range: the ambient alone.
        (1.0, 0.35),
    ] {
        let targets = Targets::new(device, [32, 32], format, wgpu::TextureFormat::Depth32Float);
        let mut enc = ctx.encoder("point light");
        targets.clear(&mut enc, wgpu::Color::BLACK, 1.0);
        view.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &voxels,
            &grid,
            view_proj,
            Light::Point { position, range },
            ColourBy::Colour,
        )
        .unwrap();
        ctx.submit_and_wait("point light", enc).unwrap();
        let px: Vec<[f32; 4]> = fieldkit::gpu::read_texture(&ctx, &targets.colour).unwrap();
        for y in 12..20 {
            for x in 12..20 {
                let got = Vec3::from_slice(&px[y * 32 + x][..3]);
                // The colour went through Rgba8 in the attribute list; the shade in f32.
                assert!(
                    got.abs_diff_eq(base * want, 1e-4),
                    "({x}, {y}): {got} vs {}",
                    base * want
                );
            }
        }
        assert_eq!(
            Light::Point { position, range }.shade(Vec3::Z, Vec3::new(1.0, 1.0, 2.0)),
            want
        );
    }
    // Bad lights are typed errors.
    let targets = Targets::new(device, [8, 8], format, wgpu::TextureFormat::Depth32Float);
    let mut enc = ctx.encoder("bad light");
    for bad in [
        Light::Point {
            position: Vec3::ZERO,
            range: 0.0,
        },
        Light::Directional(Vec3::ZERO),
        Light::Point {
            position: Vec3::NAN,
            range: 1.0,
        },
    ] {
        let err = view
            .encode(
                device,
                &mut enc,
                &targets.colour_view,
                &targets.depth_view,
                &voxels,
                &grid,
                view_proj,
                bad,
                ColourBy::Colour,
            )
            .expect_err("a bad light was accepted");
        // The view's own stage refuses it, not the voxelizer's.
        assert!(
            matches!(&err, fieldkit::Error::Invalid { stage: "voxelize::voxel_view", what } if what.contains("light")),
            "{err}"
        );
    }
}
