//! The ocean scenes: the forward and G-buffer outputs of the Gerstner surface.

use super::*;

/// The gallery's shoreline: an island of metaballs (raymarched into colour and depth) in a
/// Gerstner sea whose colour fades with the depth of the water over it. `gbuffer`: the four
/// G-buffer targets in a 2 × 2 grid (scene colour, normal; material, base colour) instead of the
/// forward-shaded image; each quarter is `w/2 × h/2`.
pub fn ocean_scene(ctx: &Context, w: u32, h: u32, gbuffer: bool) -> Result<Vec<u8>, Error> {
    ocean_scene_with(ctx, w, h, gbuffer, Preset::Fieldkit)
}

/// [`ocean_scene`] with `preset`'s look: the seed preset fades over 30 cm and tests the scene's
/// depth without writing it (the source's `bUseDepthBlend`).
pub fn ocean_scene_with(
    ctx: &Context,
    w: u32,
    h: u32,
    gbuffer: bool,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::metaball::{Metaballs, Settings, packed_grid};
    use fieldkit::metaball::{RaymarchSettings, Raymarcher};
    use fieldkit::ocean::DepthMode;
    use fieldkit::ocean::{Look, OceanCamera, OceanRenderer, Output, Patch};
    use fieldkit::ocean::{Wave, Waves};
    use fieldkit::view::{Targets, View};
    use glam::{DVec2, DVec3, Mat4, Vec2, Vec3};
    let device = &ctx.device;
    let (tw, th) = if gbuffer { (w / 2, h / 2) } else { (w, h) };
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [tw, th], colour_format, depth_format);
    // The island: a mound of blobs 3 m across on a wide shelf just under the water, so the
    // water over the shelf is shallow and fades.
    let edge = 3.0;
    let voxels: Vec<glam::Vec4> = packed_grid([13, 3, 9], edge)?
        .into_iter()
        .map(|v| v - glam::Vec4::new(0.0, 3.5, 0.0, 0.0))
        .filter(|v| {
            let r = (v.x * v.x + 1.6 * v.z * v.z).sqrt();
            r < 19.0 - 4.0 * (v.y + 3.5)
        })
        .collect();
    let balls = Metaballs::new(device)?;
    let instances = balls.upload(&ctx.device, &ctx.queue, &voxels)?;
    let settings = Settings::default();
    let eye = DVec3::new(-5.0, 8.0, 30.0);
    let proj = glam::camera::rh::proj::directx::perspective(0.8, tw as f32 / th as f32, 0.1, 500.0);
    let camera = OceanCamera::look_at(eye, DVec3::new(0.0, -1.0, 0.0), proj);
    let view = View {
        view_proj: proj * camera.view.as_mat4(),
        viewport: [tw, th],
        reversed_z: false,
        origin: [0, 0],
    };
    let mut enc = ctx.encoder("gallery ocean");
    let sky = wgpu::Color {
        r: 0.55,
        g: 0.7,
        b: 0.85,
        a: 1.0,
    };
    targets.clear(&mut enc, sky, 1.0);
    if let Some(grid) = settings.fit_grid(&voxels, edge)? {
        let field = balls.encode(device, &mut enc, &instances, &grid, edge, &settings)?;
        let marcher = Raymarcher::new(device, &ctx.queue, colour_format, depth_format, false)?;
        marcher.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &field,
            Mat4::IDENTITY,
            &view,
            &RaymarchSettings::default(),
        )?;
    }
    let waves = Waves::new(
        vec![
            Wave {
                direction: Vec2::new(1.0, 0.3),
                amplitude: 0.35,
                wavelength: 21.0,
                speed: 5.7,
            },
            Wave {
                direction: Vec2::new(0.2, 1.0),
                amplitude: 0.18,
                wavelength: 9.5,
                speed: 3.8,
            },
            Wave {
                direction: Vec2::new(-0.8, 0.5),
                amplitude: 0.06,
                wavelength: 4.1,
                speed: 2.5,
            },
        ],
        0.7,
    )?;
    let (base_look, depth_mode) = match preset {
        Preset::Fieldkit => (Look::default(), DepthMode::default()),
        Preset::Seed => (Look::seed(), DepthMode::seed()),
    };
    let look = Look {
        sun_direction: Vec3::new(-0.4, 0.5, -0.75),
        ..base_look
    };
    let patches: Vec<Patch> = (0..100)
        .map(|k| {
            Patch::new(
                DVec2::new(
                    -160.0 + 32.0 * (k % 10) as f64,
                    -160.0 + 32.0 * (k / 10) as f64,
                ),
                32.0,
            )
        })
        .collect();
    let out = if gbuffer {
        let formats = [wgpu::TextureFormat::Rgba8Unorm; 4];
        let renderer = OceanRenderer::with_depth(
            device,
            &ctx.queue,
            Output::GBuffer(formats),
            false,
            depth_mode,
        )?;
        let g: Vec<Targets> = (0..4)
            .map(|_| Targets::new(device, [tw, th], colour_format, depth_format))
            .collect();
        for t in &g {
            t.clear(&mut enc, wgpu::Color::BLACK, 1.0);
        }
        let views: Vec<&wgpu::TextureView> = g.iter().map(|t| &t.colour_view).collect();
        renderer.encode(
            device,
            &mut enc,
            &waves,
            4.0,
            &camera,
            &look,
            &patches,
            &views,
            &targets.depth,
            true,
        )?;
        ctx.submit_and_wait("gallery ocean", enc)?;
        let quarters: Vec<Vec<[u8; 4]>> = g
            .iter()
            .map(|t| read_texture(ctx, &t.colour))
            .collect::<Result<_, _>>()?;
        let mut px = vec![[0u8; 4]; (w * h) as usize];
        for (q, quarter) in quarters.iter().enumerate() {
            let (ox, oy) = ((q as u32 % 2) * tw, (q as u32 / 2) * th);
            for y in 0..th {
                for x in 0..tw {
                    // Alpha shown opaque (the material target keeps the shading model there).
                    let [r, g, b, _] = quarter[(y * tw + x) as usize];
                    px[((oy + y) * w + ox + x) as usize] = [r, g, b, 255];
                }
            }
        }
        px
    } else {
        let renderer = OceanRenderer::with_depth(
            device,
            &ctx.queue,
            Output::Forward(colour_format),
            false,
            depth_mode,
        )?;
        renderer.encode(
            device,
            &mut enc,
            &waves,
            4.0,
            &camera,
            &look,
            &patches,
            &[&targets.colour_view],
            &targets.depth,
            true,
        )?;
        ctx.submit_and_wait("gallery ocean", enc)?;
        read_texture(ctx, &targets.colour)?
    };
    Ok(out.concat())
}
