//! The octree scenes: the bunny built into a sparse voxel octree, cast at each level.

use super::*;

/// The sparse voxel octree of `mesh`'s surface in a grid of `n` along its longest side; with
/// `attributes`, each voxel's averaged colour and normal filtered up the tree.
pub fn octree_of(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    attributes: bool,
) -> Result<(fieldkit::octree::Octree, fieldkit::voxelize::Grid), Error> {
    use fieldkit::octree::OctreeBuilder;
    use fieldkit::voxelize::{Grid, Separation, Voxelizer};
    let grid = Grid::fit(mesh, n)?;
    let (builder, voxelizer) = (
        OctreeBuilder::new(&ctx.device)?,
        Voxelizer::new(&ctx.device)?,
    );
    let (device, queue) = (&ctx.device, &ctx.queue);
    let octree = if attributes {
        ctx.block_on(builder.voxelize_with_attributes(device, queue, &voxelizer, mesh, &grid))?
    } else {
        ctx.block_on(builder.voxelize(
            device,
            queue,
            &voxelizer,
            mesh,
            &grid,
            Separation::Conservative,
        ))?
    };
    Ok((octree, grid))
}

/// A first-hit render of `octree` at `lod` over a dark background, into RGBA8 pixels.
pub fn octree_scene(
    ctx: &Context,
    octree: &fieldkit::octree::Octree,
    grid: &fieldkit::voxelize::Grid,
    lod: fieldkit::octree::Lod,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, Error> {
    use fieldkit::octree::{OctreeCaster, RenderSettings};
    use glam::Vec3;
    let centre =
        (grid.origin + glam::DVec3::from(grid.size.map(f64::from)) * grid.voxel * 0.5).as_vec3();
    let radius = grid.size.into_iter().max().unwrap_or(1) as f32 * grid.voxel as f32 * 0.5;
    let eye = centre + Vec3::new(0.75, 0.45, 1.0).normalize() * radius * 3.4;
    let view = fieldkit::view::View {
        view_proj: glam::camera::rh::proj::directx::perspective(
            0.7,
            w as f32 / h as f32,
            radius * 0.1,
            radius * 10.0,
        ) * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    let settings = RenderSettings {
        lod,
        ..Default::default()
    };
    let mut enc = ctx.encoder("gallery octree");
    let image =
        OctreeCaster::new().encode_render(&ctx.device, &mut enc, octree, grid, &view, &settings)?;
    ctx.submit_and_wait("gallery octree", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &image.colour)?;
    Ok(px
        .into_iter()
        .flat_map(|p| if p[3] == 0 { [41, 43, 51, 255] } else { p })
        .collect())
}
