//! Debug view of voxel attributes (`voxelize/voxel_view`): one lit cube per occupied voxel,
//! drawn straight from [`Attributes::voxels`] by instance index.

use glam::{Mat4, Vec3};

use super::{Attributes, Grid, invalid};
use crate::bind::{RenderPipeline, RenderTargets};
use crate::error::Error;
use crate::gpu::uniform_buffer as uniform;
use crate::shaders::voxelize::voxel_view::{self as stage, ViewParams};
use crate::view::{depth_state, load_pass};

/// What the cubes are coloured by.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ColourBy {
    /// The averaged normal, n · ½ + ½.
    #[default]
    Normal,
    /// The averaged vertex colour.
    Colour,
}

/// Draws voxel attributes as cubes into a caller's colour and depth targets.
pub struct VoxelView {
    pipeline: RenderPipeline<stage::fs_view::Entry>,
}

impl VoxelView {
    /// A view drawing into `colour` and `depth` targets of these formats (depth test `Less`,
    /// back faces culled).
    pub fn new(
        device: &wgpu::Device,
        colour: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
    ) -> Result<Self, Error> {
        let pipeline = RenderPipeline::new(
            device,
            &RenderTargets {
                color: &[Some(colour.into())],
                depth_stencil: Some(depth_state(
                    stage::STAGE,
                    depth,
                    wgpu::CompareFunction::Less,
                )?),
                primitive: wgpu::PrimitiveState {
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                ..Default::default()
            },
        )?;
        Ok(Self { pipeline })
    }

    /// Draw every occupied voxel of `voxels` (voxelized in `grid`) as a cube, loading what the
    /// targets hold. `light` points toward the light.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        voxels: &Attributes,
        grid: &Grid,
        view_proj: Mat4,
        light: Vec3,
        by: ColourBy,
    ) -> Result<(), Error> {
        if voxels.surface.size != grid.size {
            return Err(invalid(format!(
                "the voxels were made in a {:?} grid, not {:?}",
                voxels.surface.size, grid.size
            )));
        }
        if !(view_proj.is_finite() && light.is_finite() && light.length_squared() > 0.0) {
            return Err(invalid(format!(
                "view_proj must be finite and light ({light}) finite and non-zero"
            )));
        }
        if voxels.count == 0 {
            return Ok(());
        }
        let grid_to_world = Mat4::from_translation(grid.origin.as_vec3())
            * Mat4::from_scale(Vec3::splat(grid.voxel as f32));
        let params = uniform(
            device,
            "voxel view params",
            &ViewParams {
                view_proj,
                grid_to_world,
                light: light.normalize().extend(0.0),
                grid: grid.size.into(),
                colour_by: (by == ColourBy::Colour) as u32,
            },
        );
        let bound = self.pipeline.bind(
            device,
            &stage::fs_view::Resources {
                params: (&params).into(),
                voxels: (&voxels.voxels).into(),
            },
        )?;
        let mut pass = load_pass(encoder, stage::STAGE, colour, depth);
        pass.set_pipeline(&self.pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..36, 0..voxels.count);
        Ok(())
    }
}
