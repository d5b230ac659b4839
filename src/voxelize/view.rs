//! Debug view of voxel attributes (`voxelize/voxel_view`): one lit cube per occupied voxel,
//! drawn straight from [`Attributes::voxels`] by instance index.

use std::sync::Mutex;

use glam::{Mat4, Vec3};

use super::{Attributes, Grid};
use crate::bind::{Bound, RenderPipeline, RenderTargets};
use crate::error::Error;
use crate::gpu::{KeptUniform, Record};
use crate::shaders::voxelize::voxel_view::{self as stage, ViewParams};
use crate::view::{depth_state, load_pass_recorded};

/// Bad input to the voxel view: an error of its own stage.
fn refused(what: String) -> Error {
    Error::Invalid {
        stage: stage::STAGE,
        what,
    }
}

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

/// The light over the voxel cubes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Light {
    /// Toward a light at infinity (world direction, normalised on use).
    Directional(Vec3),
    /// The source's demo scene: a point light at `position` (world), its N·L weighted by
    /// (1 − (d / range)²)² (0 past `range`), per cube corner.
    Point {
        /// World position.
        position: Vec3,
        /// Distance at which the light reaches 0.
        range: f32,
    },
}

/// A direction toward a light at infinity.
impl From<Vec3> for Light {
    fn from(toward: Vec3) -> Self {
        Light::Directional(toward)
    }
}

impl Light {
    /// Ambient 0.35 plus 0.65 × N·L × attenuation: what each cube corner gets (the shader's
    /// formula, for tests and users).
    pub fn shade(&self, normal: Vec3, world: Vec3) -> f32 {
        let (l, atten) = match *self {
            Light::Directional(d) => (d.normalize(), 1.0),
            Light::Point { position, range } => {
                let to = position - world;
                let d = to.length();
                let q = (1.0 - (d / range).powi(2)).max(0.0);
                (to / d.max(1e-6), q * q)
            }
        };
        0.35 + 0.65 * normal.dot(l).max(0.0) * atten
    }

    fn check(&self) -> Result<(), Error> {
        let ok = match *self {
            Light::Directional(d) => d.is_finite() && d.length_squared() > 0.0,
            Light::Point { position, range } => {
                position.is_finite() && range.is_finite() && range > 0.0
            }
        };
        if ok {
            Ok(())
        } else {
            Err(refused(format!(
                "light {self:?}: a direction finite and non-zero, or a point with a finite \
                 position and a range > 0"
            )))
        }
    }
}

/// Draws voxel attributes as cubes into a caller's colour and depth targets.
///
/// A redraw of the same voxels with the same camera and light makes no GPU object: the view
/// keeps its parameters' buffer while they hold, the bind group of the voxels it drew last and
/// their draw's arguments (it holds those voxels' buffer until it draws others or is dropped).
pub struct VoxelView {
    pipeline: RenderPipeline<stage::fs_view::Entry>,
    params: KeptUniform,
    /// The voxels drawn last: their list, the bind group with the parameters' buffer it was
    /// made with, and their indirect draw's arguments.
    drawn: Mutex<Option<Drawn>>,
}

/// What [`VoxelView`] keeps of the voxels it drew last.
struct Drawn {
    voxels: wgpu::Buffer,
    params: wgpu::Buffer,
    bound: Bound<stage::fs_view::Entry>,
    args: wgpu::Buffer,
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
        Ok(Self {
            pipeline,
            params: KeptUniform::default(),
            drawn: Mutex::new(None),
        })
    }

    /// Draw every occupied voxel of `voxels` (voxelized in `grid`) as a cube, loading what the
    /// targets hold, under `light`: a direction toward a light at infinity (a `Vec3`) or any
    /// [`Light`] (a point light as the source's demo scene). Made for every frame: its
    /// uniforms, bind group and indirect draw arguments are kept, and made again only when other
    /// voxels are given.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        voxels: &Attributes,
        grid: &Grid,
        view_proj: Mat4,
        light: impl Into<Light>,
        by: ColourBy,
    ) -> Result<(), Error> {
        let light = light.into();
        light.check()?;
        if voxels.surface.size != grid.size {
            return Err(refused(format!(
                "the voxels were made in a {:?} grid, not {:?}",
                voxels.surface.size, grid.size
            )));
        }
        if !view_proj.is_finite() {
            return Err(refused("view_proj must be finite".into()));
        }
        if voxels.count == 0 {
            return Ok(());
        }
        let grid_to_world = Mat4::from_translation(grid.origin.as_vec3())
            * Mat4::from_scale(Vec3::splat(grid.voxel as f32));
        let params = self.params.get(
            device,
            "voxel view params",
            &ViewParams {
                view_proj,
                grid_to_world,
                light: match light {
                    Light::Directional(d) => d.normalize().extend(0.0),
                    Light::Point { position, .. } => position.extend(1.0),
                },
                light_range: match light {
                    Light::Directional(_) => 0.0,
                    Light::Point { range, .. } => range,
                },
                grid: grid.size.into(),
                colour_by: (by == ColourBy::Colour) as u32,
            },
        );
        let mut drawn = self.drawn.lock().unwrap_or_else(|e| e.into_inner());
        let kept = drawn
            .as_ref()
            .is_some_and(|d| d.voxels == voxels.voxels && d.params == params);
        if !kept {
            let bound = self.pipeline.bind(
                device,
                &stage::fs_view::Resources {
                    params: (&params).into(),
                    voxels: (&voxels.voxels).into(),
                },
            )?;
            // One cube per occupied voxel: the count is on the GPU (a list sized by a bound has
            // room for more), so the draw is indirect, its instance count copied from it.
            let same_voxels = drawn.as_ref().is_some_and(|d| d.voxels == voxels.voxels);
            let args = match drawn.take() {
                Some(d) if same_voxels => d.args,
                _ => {
                    use wgpu::util::DeviceExt;
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("voxel view draw"),
                        contents: bytemuck::cast_slice(&[36u32, 0, 0, 0]),
                        usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                    })
                }
            };
            *drawn = Some(Drawn {
                voxels: voxels.voxels.clone(),
                params,
                bound,
                args,
            });
        }
        let d = drawn.as_ref().expect("kept or made above");
        // The count again each draw: the voxels may have been made anew in the same buffers.
        let mut rec = rec.recorder();
        rec.encoder
            .copy_buffer_to_buffer(&voxels.occupied, 0, &d.args, 4, 4);
        let mut pass = load_pass_recorded(&mut rec, stage::STAGE, colour, depth);
        pass.set_pipeline(&self.pipeline.pipeline);
        d.bound.set_render(&mut pass);
        pass.draw_indirect(&d.args, 0);
        Ok(())
    }
}
