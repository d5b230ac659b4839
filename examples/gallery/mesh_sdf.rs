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
    use glam::Mat4;
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
    let (view_proj, _, _) = grid_camera(&grid, w, h);
    let view = View {
        view_proj,
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    targets.clear(&mut enc, BACKGROUND, 1.0);
    let march = MarchField {
        march: field.march.as_ref().expect("asked for"),
        grid,
        band: settings.band * grid.voxel as f32,
        threshold: 0.0,
        blobs: None,
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
