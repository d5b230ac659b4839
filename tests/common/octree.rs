//! What the octree tests share: grids of unit voxels, a tree built and read back, the dense
//! voxelization it is held to, a painted mesh, and a read-back render.

use fieldkit::gpu::Context;
use fieldkit::octree::{Octree, OctreeBuilder, OctreeData};
use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
use glam::DVec3;

pub fn unit_grid(size: [u32; 3]) -> Grid {
    Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size,
    }
}

pub fn build(
    ctx: &Context,
    mesh: &Mesh,
    grid: &Grid,
    separation: Separation,
) -> (Octree, OctreeData) {
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let octree = ctx
        .block_on(builder.voxelize(&ctx.device, &ctx.queue, &voxelizer, mesh, grid, separation))
        .unwrap();
    let data = octree.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    (octree, data)
}

pub fn dense(ctx: &Context, mesh: &Mesh, grid: &Grid, separation: Separation) -> Vec<bool> {
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("dense");
    let s = voxelizer
        .encode_surface_with(&ctx.device, &mut enc, mesh, grid, separation)
        .unwrap();
    ctx.submit_and_wait("dense", enc).unwrap();
    s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()
}

/// Cells of level `m` of a tree over `log_side`: occupied where any voxel in them is.
pub fn coarse(voxels: &[bool], size: [u32; 3], log_side: u32, m: u32) -> (Vec<bool>, [i32; 3]) {
    let shift = log_side - m;
    let extent = size.map(|n| n.div_ceil(1 << shift) as i32);
    let [ex, ey, ez] = extent.map(|e| e as usize);
    let mut out = vec![false; ex * ey * ez];
    let [nx, ny, _] = size.map(|n| n as usize);
    for (i, &o) in voxels.iter().enumerate() {
        if o {
            let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
            out[((z >> shift) * ey + (y >> shift)) * ex + (x >> shift)] = true;
        }
    }
    (out, extent)
}

/// A mesh with a colour and a normal per vertex that vary over it.
pub fn painted_torus() -> Mesh {
    let mut torus = Mesh::torus(DVec3::new(24.5, 23.2, 20.9), 14.0, 5.3, 48, 16);
    torus.colors = torus
        .positions
        .iter()
        .map(|p| {
            [
                (p.x * 9.0) as u8,
                (p.y * 7.0) as u8,
                (p.z * 11.0) as u8,
                200 + (p.x as u8 % 50),
            ]
        })
        .collect();
    torus.normals = torus
        .positions
        .iter()
        .map(|p| (*p - DVec3::new(24.5, 23.2, 20.9)).normalize())
        .collect();
    torus
}

/// A first-hit render of `octree`, read back: colour and depth per pixel.
pub fn render_image(
    ctx: &Context,
    caster: &fieldkit::octree::OctreeCaster,
    octree: &Octree,
    grid: &Grid,
    view: &fieldkit::view::View,
    settings: &fieldkit::octree::RenderSettings,
) -> (Vec<[u8; 4]>, Vec<f32>) {
    let mut enc = ctx.encoder("octree render");
    let image = caster
        .encode_render(&ctx.device, &mut enc, octree, grid, view, settings)
        .unwrap();
    ctx.submit_and_wait("octree render", enc).unwrap();
    let colour = fieldkit::gpu::readback_texture(&ctx.device, &ctx.queue, &image.colour)
        .wait(ctx)
        .unwrap();
    let depth = fieldkit::gpu::readback_texture(&ctx.device, &ctx.queue, &image.depth)
        .wait(ctx)
        .unwrap();
    (colour, depth)
}
