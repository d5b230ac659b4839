//! The mesh distance field: a mesh baked into its signed distance field, drawn by the SDF march.

use super::*;

/// `mesh`'s signed distance field in a grid of `n` along its longest side (exact within 4
/// voxels), its surface drawn by the SDF march from the voxelize scene's camera, into RGBA8
/// pixels.
pub fn mesh_sdf_scene(
    ctx: &Context,
    mesh: &fieldkit::mesh_sdf::Mesh,
    n: u32,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, Error> {
    use fieldkit::mesh_sdf::{MeshSdf, Settings};
    use fieldkit::metaball::{MarchField, RaymarchSettings, Raymarcher};
    use fieldkit::view::{Targets, View};
    use glam::{Mat4, Vec3};
    let device = &ctx.device;
    let grid = fieldkit::mesh_sdf::Grid::fit(mesh, n)?;
    let settings = Settings {
        march: true,
        ..Settings::default()
    };
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [w, h], colour_format, depth_format);
    let marcher = Raymarcher::new(device, &ctx.queue, colour_format, depth_format, false)?;
    let mut enc = ctx.encoder("gallery mesh sdf");
    let field = MeshSdf::new(device)?.encode(device, &mut enc, mesh, &grid, &settings)?;
    let centre =
        (grid.origin + glam::DVec3::from(grid.size.map(f64::from)) * grid.voxel * 0.5).as_vec3();
    let radius = grid.size.into_iter().max().unwrap_or(1) as f32 * grid.voxel as f32 * 0.5;
    let eye = centre + Vec3::new(0.75, 0.45, 1.0).normalize() * radius * 3.2;
    let proj = glam::camera::rh::proj::directx::perspective(
        0.7,
        w as f32 / h as f32,
        radius * 0.1,
        radius * 10.0,
    );
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    targets.clear(
        &mut enc,
        wgpu::Color {
            r: 0.16,
            g: 0.17,
            b: 0.2,
            a: 1.0,
        },
        1.0,
    );
    let march = MarchField {
        march: field.march.as_ref().expect("asked for"),
        grid,
        band: settings.band * grid.voxel as f32,
        threshold: 0.0,
    };
    let marched = marcher.encode_march_field(
        device,
        &mut enc,
        &march,
        Mat4::IDENTITY,
        &view,
        &RaymarchSettings::default(),
    )?;
    if let Some(m) = marched {
        marcher.encode_composite(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &m,
        )?;
    }
    ctx.submit_and_wait("gallery mesh sdf", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &targets.colour)?;
    Ok(px.concat())
}
