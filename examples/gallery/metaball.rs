//! The metaball scenes: the animated actor, its presets and its views.

use super::*;

/// What the metaball scene draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetaballView {
    /// The debug cubes, one per voxel.
    Cubes,
    /// The raymarched surface, in one of the raymarcher's outputs.
    Surface(fieldkit::metaball::Output),
    /// The field traced directly from blob bins (no SDF texture).
    Direct(fieldkit::metaball::Direct),
}

/// Whose settings a scene uses: fieldkit's defaults, or the source's (`seed()` presets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// `Default::default()` everywhere.
    Fieldkit,
    /// Each technique's `seed()` preset: the system the source describes.
    Seed,
}

/// The gallery's metaball scene: a packed 5×4×3 voxel set, animated to time `t` (seconds), seen
/// from a fixed camera over a grey floor-coloured background, into RGBA8 pixels.
pub fn metaball_scene(
    ctx: &Context,
    width: u32,
    height: u32,
    t: f32,
    what: MetaballView,
) -> Result<Vec<u8>, Error> {
    metaball_scene_with(ctx, width, height, t, what, Preset::Fieldkit)
}

/// [`metaball_scene`] with `preset`'s settings: the seed preset builds the set from an extent
/// and a block size, animates it with the source's ratios, widens the falloff, builds the
/// full-volume field by plain JFA, marches and shades as the source does and draws its debug
/// cubes as wireframes with depth read only.
pub fn metaball_scene_with(
    ctx: &Context,
    width: u32,
    height: u32,
    t: f32,
    what: MetaballView,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::metaball::{Animation, Metaballs, Settings, animate, extent_grid, packed_grid};
    use fieldkit::metaball::{CubeStyle, Cubes, RaymarchSettings, Raymarcher};
    use fieldkit::view::{Targets, View};
    use glam::{Mat4, Vec3};
    let device = &ctx.device;
    let edge = 1.0;
    let (voxels, settings, march, cube_style) = match preset {
        Preset::Fieldkit => (
            animate(&packed_grid([5, 4, 3], edge)?, edge, t, 0.5, 0.15),
            Settings::default(),
            RaymarchSettings::default(),
            CubeStyle::default(),
        ),
        Preset::Seed => (
            // Extent 5 × 4 × 3 in blocks of 1: the same 60 voxels, built the source's way.
            Animation::seed().apply(&extent_grid(Vec3::new(5.0, 4.0, 3.0), edge)?, edge, t)?,
            Settings::seed(),
            RaymarchSettings::seed(),
            CubeStyle {
                wireframe: true,
                ..CubeStyle::seed()
            },
        ),
    };
    let balls = Metaballs::new(device)?;
    let instances = balls.upload(&ctx.device, &ctx.queue, &voxels)?;
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [width, height], colour_format, depth_format);
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    let proj = glam::camera::rh::proj::directx::perspective(
        0.75,
        width as f32 / height as f32,
        0.1,
        100.0,
    );
    let eye = Vec3::new(4.5, 3.5, 7.5);
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y),
        viewport: [width, height],
        reversed_z: false,
        origin: [0, 0],
    };
    let mut enc = ctx.encoder("gallery metaballs");
    let background = wgpu::Color {
        r: 0.09,
        g: 0.1,
        b: 0.12,
        a: 1.0,
    };
    targets.clear(&mut enc, background, 1.0);
    match what {
        MetaballView::Cubes => {
            let cubes = Cubes::new(device, &ctx.queue, colour_format, depth_format, cube_style)?;
            cubes.encode(
                device,
                &mut enc,
                cv,
                dv,
                &instances,
                edge,
                Mat4::IDENTITY,
                view.view_proj,
            )?;
        }
        MetaballView::Surface(output) => {
            let Some(grid) = settings.fit_grid(&voxels, edge)? else {
                return Err(Error::Invalid {
                    stage: "gallery",
                    what: "the scene's voxel set is empty".into(),
                });
            };
            let field = balls.encode(device, &mut enc, &instances, &grid, edge, &settings)?;
            let marcher = Raymarcher::new(device, &ctx.queue, colour_format, depth_format, false)?;
            let rs = RaymarchSettings { output, ..march };
            marcher.encode(device, &mut enc, cv, dv, &field, Mat4::IDENTITY, &view, &rs)?;
        }
        MetaballView::Direct(method) => {
            let Some(grid) = settings.fit_grid(&voxels, edge)? else {
                return Err(Error::Invalid {
                    stage: "gallery",
                    what: "the scene's voxel set is empty".into(),
                });
            };
            let bins = balls.encode_bins(device, &mut enc, &instances, &grid, edge, &settings)?;
            let marcher = Raymarcher::new(device, &ctx.queue, colour_format, depth_format, false)?;
            let rs = RaymarchSettings {
                max_steps: 4096,
                ..RaymarchSettings::default()
            };
            marcher.encode_direct(
                device,
                &mut enc,
                cv,
                dv,
                &bins,
                method,
                Mat4::IDENTITY,
                &view,
                &rs,
            )?;
        }
    }
    ctx.submit_and_wait("gallery metaballs", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &targets.colour)?;
    Ok(px.concat())
}
