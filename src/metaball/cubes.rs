//! The debug view of a metaball set: one instanced cube per voxel, into the caller's colour and
//! depth targets.

use glam::{Mat4, Vec4};

use super::Instances;
use crate::bind::{KeptBound, RenderPipeline, RenderTargets};
use crate::error::Error;
use crate::gpu::{Record, Uploads};
use crate::shaders::metaball::voxel_cubes;
use crate::view::{box_visible, depth_state, load_pass_recorded};

/// How the debug cubes are drawn.
///
/// [`CubeStyle::default`] draws solid cubes that hide each other; [`CubeStyle::seed`] is the
/// source's debug draw (both faces, depth test `Always`, no depth write).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct CubeStyle {
    /// Faces culled; `None` (the source's choice) draws both sides.
    pub cull: Option<wgpu::Face>,
    /// `Always` (the source's choice, to be sure the cubes show) or a normal test (`Less`).
    pub depth_compare: wgpu::CompareFunction,
    /// Write depth (default); the source reads depth only, so its cubes never hide the scene
    /// drawn after them.
    pub depth_write: bool,
    /// Skip the draw when the voxel set's box is outside the view's frustum (default on, as the
    /// source culls each volume).
    pub frustum_cull: bool,
    /// Edges only: with the adapter's `POLYGON_MODE_LINE` the cubes' triangles are drawn as
    /// lines; without it, 12 edges per cube as a line list (no diagonals, same picture).
    pub wireframe: bool,
    /// Cube colour (RGBA, linear).
    pub colour: Vec4,
    /// Cube edge × the voxel's scale; off draws every cube one edge long.
    pub scale_size: bool,
}

impl Default for CubeStyle {
    fn default() -> Self {
        Self {
            cull: Some(wgpu::Face::Back),
            depth_compare: wgpu::CompareFunction::Less,
            depth_write: true,
            frustum_cull: true,
            wireframe: false,
            colour: Vec4::new(0.35, 0.7, 0.45, 1.0),
            scale_size: true,
        }
    }
}

impl CubeStyle {
    /// The source's debug cubes: both faces, depth compare `Always`, depth read only.
    pub fn seed() -> Self {
        Self {
            cull: None,
            depth_compare: wgpu::CompareFunction::Always,
            depth_write: false,
            ..Self::default()
        }
    }
}

/// Instanced debug cubes: one draw of 36 vertices (24 for line-list edges) × the voxel count.
/// A frame's draw makes no GPU object: its parameters go through an upload ring into a kept
/// uniform, bound by a kept bind group (see [`RING_UPLOADS`](crate::gpu::RING_UPLOADS) for how
/// many draws one encoder may hold).
pub struct Cubes {
    pipeline: RenderPipeline<voxel_cubes::fs_main::Entry>,
    style: CubeStyle,
    /// Edges drawn as a line list (wireframe without `POLYGON_MODE_LINE`).
    edges: bool,
    uploads: Uploads,
    params: std::sync::Mutex<Option<wgpu::Buffer>>,
    bound: KeptBound<voxel_cubes::fs_main::Entry>,
}

impl Cubes {
    /// The cube pipeline for the given targets; `style` fixes culling, depth and wireframe
    /// ([`Self::restyle`] changes the rest in place).
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::metaball::{CubeStyle, Cubes};
    /// let rgba = wgpu::TextureFormat::Rgba8Unorm;
    /// let depth = wgpu::TextureFormat::Depth32Float;
    /// let mut cubes = Cubes::new(device, queue, rgba, depth, CubeStyle::default())?;
    /// // A new colour needs no new pipeline.
    /// let red = CubeStyle { colour: glam::Vec4::new(1.0, 0.0, 0.0, 1.0), ..CubeStyle::default() };
    /// assert!(cubes.restyle(red)?);
    /// # Ok(()) }
    /// ```
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        colour: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
        style: CubeStyle,
    ) -> Result<Self, Error> {
        let polygon_lines = device
            .features()
            .contains(wgpu::Features::POLYGON_MODE_LINE);
        Self::with_edges(
            device,
            queue,
            colour,
            depth,
            style,
            style.wireframe && !polygon_lines,
        )
    }

    /// [`Cubes::new`], with the wireframe as line-list edges even where the device has
    /// `POLYGON_MODE_LINE` (`edges`, for tests and to draw the same picture everywhere).
    pub fn with_edges(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        colour: wgpu::TextureFormat,
        depth: wgpu::TextureFormat,
        style: CubeStyle,
        edges: bool,
    ) -> Result<Self, Error> {
        let stage = voxel_cubes::STAGE;
        if edges && !style.wireframe {
            return Err(Error::Invalid {
                stage,
                what: "line-list edges draw the wireframe; set style.wireframe".into(),
            });
        }
        check_colour(style)?;
        let mut depth_stencil = depth_state(stage, depth, style.depth_compare)?;
        depth_stencil.depth_write_enabled = Some(style.depth_write);
        let pipeline = RenderPipeline::new(
            device,
            &RenderTargets {
                color: &[Some(colour.into())],
                depth_stencil: Some(depth_stencil),
                primitive: wgpu::PrimitiveState {
                    topology: if edges {
                        wgpu::PrimitiveTopology::LineList
                    } else {
                        wgpu::PrimitiveTopology::TriangleList
                    },
                    // Lines have no faces to cull.
                    cull_mode: if edges { None } else { style.cull },
                    polygon_mode: if style.wireframe && !edges {
                        wgpu::PolygonMode::Line
                    } else {
                        wgpu::PolygonMode::Fill
                    },
                    ..Default::default()
                },
                ..Default::default()
            },
        )?;
        Ok(Self {
            pipeline,
            style,
            edges,
            uploads: Uploads::new(queue),
            params: Default::default(),
            bound: KeptBound::default(),
        })
    }

    /// Whether the wireframe is drawn as line-list edges.
    pub fn edges(&self) -> bool {
        self.edges
    }

    /// The style drawn.
    pub fn style(&self) -> CubeStyle {
        self.style
    }

    /// Take `style`'s colour, size scaling and frustum culling, which the pipeline does not
    /// fix, for the draws recorded from now on. `Ok(false)`, nothing changed, where `style`
    /// differs in what the pipeline fixes (culling, depth, wireframe): that takes a new
    /// [`Cubes`], which an app makes ahead (on another thread) and swaps in.
    pub fn restyle(&mut self, style: CubeStyle) -> Result<bool, Error> {
        check_colour(style)?;
        let fixed = |s: CubeStyle| (s.cull, s.depth_compare, s.depth_write, s.wireframe);
        if fixed(style) != fixed(self.style) {
            return Ok(false);
        }
        self.style = style;
        Ok(true)
    }

    /// Draw every instance as a cube of edge `edge` (× scale) into `colour` and `depth`,
    /// loading what they hold. Returns false, drawing nothing, for an empty set or, with
    /// `frustum_cull`, when the set's box is outside the frustum of `view_proj`.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        instances: &Instances,
        edge: f32,
        local_to_world: Mat4,
        view_proj: Mat4,
    ) -> Result<bool, Error> {
        let stage = voxel_cubes::STAGE;
        if !(edge.is_finite() && edge > 0.0 && local_to_world.is_finite() && view_proj.is_finite())
        {
            return Err(Error::Invalid {
                stage,
                what: format!("edge ({edge}) must be finite and positive, matrices finite"),
            });
        }
        if instances.count == 0 {
            return Ok(false);
        }
        if self.style.frustum_cull {
            let size = edge
                * if self.style.scale_size {
                    instances.max_scale
                } else {
                    1.0
                };
            let [lo, hi] = instances.centres;
            if !box_visible(view_proj, local_to_world, lo - 0.5 * size, hi + 0.5 * size) {
                return Ok(false);
            }
        }
        let mut rec = rec.recorder();
        let params = self.uploads.uniform(
            device,
            rec.encoder,
            &self.params,
            "cube params",
            &voxel_cubes::CubeParams {
                view_proj,
                local_to_world,
                colour: self.style.colour,
                edge,
                scale_size: self.style.scale_size as u32,
                edges: self.edges as u32,
            },
        );
        let bound = self.pipeline.bind_kept(
            device,
            &self.bound,
            &voxel_cubes::fs_main::Resources {
                params: (&params).into(),
            },
        )?;
        let mut pass = load_pass_recorded(&mut rec, stage, colour, depth);
        pass.set_pipeline(&self.pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.set_vertex_buffer(0, instances.buffer.slice(..instances.count as u64 * 16));
        pass.draw(0..if self.edges { 24 } else { 36 }, 0..instances.count);
        Ok(true)
    }
}

/// A typed error unless the cubes' colour is finite.
fn check_colour(style: CubeStyle) -> Result<(), Error> {
    if style.colour.is_finite() {
        return Ok(());
    }
    Err(Error::Invalid {
        stage: voxel_cubes::STAGE,
        what: format!("colour {} must be finite", style.colour),
    })
}
