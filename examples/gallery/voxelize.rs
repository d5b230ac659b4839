//! The voxelization scenes: surface, raster, solid and attributes, and a distance slice.

use super::*;

/// `mesh` voxelized in a grid of `n` along its longest side, drawn as cubes coloured by each
/// voxel's averaged normal, into RGBA8 pixels.
pub fn voxelize_scene(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, Error> {
    voxelize_scene_with(ctx, mesh, n, w, h, Preset::Fieldkit)
}

/// The mesh scenes' background.
pub const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.16,
    g: 0.17,
    b: 0.2,
    a: 1.0,
};

/// A camera over `grid` from the front, above and to the right, its box in view of a `w` × `h`
/// frame: the view-projection matrix, the box's centre and its half longest side.
pub fn grid_camera(grid: &fieldkit::Grid, w: u32, h: u32) -> (glam::Mat4, glam::Vec3, f32) {
    use glam::Vec3;
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
    let view_proj = proj * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y);
    (view_proj, centre, radius)
}

/// [`voxelize_scene`] with `preset`'s light: the seed preset is the source's demo scene, a
/// point light near the mesh's top front corner.
pub fn voxelize_scene_with(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    w: u32,
    h: u32,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::view::Targets;
    use fieldkit::voxelize::Voxelizer;
    use fieldkit::voxelize::{ColourBy, Light, VoxelView};
    use glam::Vec3;
    let device = &ctx.device;
    let grid = fieldkit::voxelize::Grid::fit(mesh, n)?;
    let voxels =
        ctx.block_on(Voxelizer::new(device)?.attributes(device, &ctx.queue, mesh, &grid))?;
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [w, h], colour_format, depth_format);
    let (view_proj, centre, radius) = grid_camera(&grid, w, h);
    let view = VoxelView::new(device, colour_format, depth_format)?;
    let mut enc = ctx.encoder("gallery voxelize");
    targets.clear(&mut enc, BACKGROUND, 1.0);
    let light = match preset {
        Preset::Fieldkit => Light::Directional(Vec3::new(0.4, 0.8, 0.5)),
        Preset::Seed => Light::Point {
            position: centre + Vec3::new(0.6, 1.2, 1.0) * radius,
            range: radius * 3.5,
        },
    };
    view.encode(
        device,
        &mut enc,
        &targets.colour_view,
        &targets.depth_view,
        &voxels,
        &grid,
        view_proj,
        light,
        ColourBy::Normal,
    )?;
    ctx.submit_and_wait("gallery voxelize", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &targets.colour)?;
    Ok(px.concat())
}

/// The signed distance field of a closed `mesh` (solid voxels, then the exact 3D transform),
/// in a grid of `n` along its longest side: the slice through the middle of z, +y up, colour
/// mapped with iso-lines every 4 voxels and scaled up `zoom` times. Returns pixels, width and
/// height.
pub fn voxelize_distance_slice(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    zoom: u32,
) -> Result<(Vec<u8>, u32, u32), Error> {
    use fieldkit::distance::{Distance3d, Settings3d};
    use fieldkit::voxelize::Voxelizer;
    let device = &ctx.device;
    let grid = fieldkit::voxelize::Grid::fit(mesh, n)?;
    let v = Voxelizer::new(device)?;
    let mut enc = ctx.encoder("gallery mesh distance");
    let solid = v.encode_solid(&ctx.device, &mut enc, mesh, &grid, false)?;
    let volume = v.encode_volume(device, &mut enc, &solid)?;
    let field =
        Distance3d::new(device)?.encode(device, &mut enc, &volume, &Settings3d::signed())?;
    ctx.submit_and_wait("gallery mesh distance", enc)?;
    let d: Vec<f32> = read_texture(ctx, &field.distance)?;
    let [nx, ny, nz] = grid.size;
    let z = nz / 2;
    let slice: Vec<f32> = (0..ny)
        .rev()
        .flat_map(|y| {
            let row = ((z * ny + y) * nx) as usize;
            d[row..row + nx as usize].to_vec()
        })
        .collect();
    use wgpu::util::DeviceExt;
    let texture = device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("gallery distance slice"),
            size: wgpu::Extent3d {
                width: nx,
                height: ny,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&slice),
    );
    let small = visualize_distance(ctx, &texture, 4.0, n as f32 * 0.4)?;
    let (w, h) = (nx * zoom, ny * zoom);
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let i = (((y / zoom) * nx + x / zoom) * 4) as usize;
            out.extend_from_slice(&small[i..i + 4]);
        }
    }
    Ok((out, w, h))
}
