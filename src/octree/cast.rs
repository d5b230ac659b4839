//! Ray casts through an [`Octree`] (`octree/cast`): a first-hit render at a level of detail,
//! rays for other stages and tests, and occupancy lookups.

use std::sync::OnceLock;

use glam::{Mat4, Vec3};

use super::Octree;
use crate::bind::{ComputePipeline, Variants};
use crate::error::Error;
use crate::gpu::{Readback, Record, readback_buffer, uniform_buffer as uniform};
use crate::shaders::octree::cast::{self as stage, CastParams};
use crate::view::View;
use crate::voxelize::Grid;

/// The shader's `LOD_BY_FOOTPRINT`.
const LOD_BY_FOOTPRINT: u32 = u32::MAX;
/// The shader's `MISS`.
const MISS: i32 = 3;

/// Which level of the tree a render casts at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lod {
    /// One level for every pixel: 0 is the root, [`Octree::log_side`] the voxels.
    Level(u32),
    /// Per pixel, the finest level whose cells are at least this many pixels wide where the ray
    /// enters the grid (1.0: a voxel no smaller than a pixel).
    Footprint(f32),
}

/// How [`OctreeCaster::encode_render`] draws.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// The level of detail.
    pub lod: Lod,
    /// Linear RGB of the cells.
    pub colour: Vec3,
    /// Towards the light, world space.
    pub light: Vec3,
    /// Shade each hit cell's filtered colour and normal where the octree has attributes
    /// ([`super::OctreeBuilder::voxelize_with_attributes`]); otherwise, or with `false`, the
    /// hit face in `colour`.
    pub attributes: bool,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            lod: Lod::Footprint(1.0),
            colour: Vec3::new(0.85, 0.8, 0.72),
            light: Vec3::new(0.4, 0.8, 0.45),
            attributes: true,
        }
    }
}

/// A render's output, the viewport's size: `Rgba8Unorm` colour (alpha 0 where no cell was hit)
/// and `R32Float` depth (NDC, the far plane where none was).
pub struct OctreeImage {
    /// Shaded hit cells.
    pub colour: wgpu::Texture,
    /// The hits' depth.
    pub depth: wgpu::Texture,
}

/// One ray for [`OctreeCaster::encode_cast`], in the grid's local coordinates (voxels of edge
/// 1, the grid's corner at the origin).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where it starts, inside the grid.
    pub start: Vec3,
    /// Its direction (any length; not zero).
    pub dir: Vec3,
    /// The level whose cells it walks.
    pub level: u32,
}

/// The first occupied cell a ray met.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellHit {
    /// The cell, in cells of its level.
    pub cell: [i32; 3],
    /// The axis crossed into it; `None` for the cell the ray started in.
    pub axis: Option<u32>,
}

/// Rays cast on the GPU ([`OctreeCaster::encode_cast`]).
pub struct Casts {
    /// Per ray, a `vec4<i32>`: the hit cell and the axis crossed into it (−1 for the start
    /// cell), or (−1, −1, −1, 3) for a miss.
    pub hits: wgpu::Buffer,
    count: usize,
}

impl Casts {
    /// The hits, read back once the encoder has been submitted: `None` for a miss.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Readback<Vec<Option<CellHit>>> {
        let count = self.count;
        readback_buffer(device, queue, &self.hits).then(move |bytes| {
            let hits: Vec<[i32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..count * 16]);
            Ok(hits
                .into_iter()
                .map(|[x, y, z, axis]| {
                    (axis != MISS).then_some(CellHit {
                        cell: [x, y, z],
                        axis: u32::try_from(axis).ok(),
                    })
                })
                .collect())
        })
    }

    /// Per point of [`OctreeCaster::encode_lookup`], whether its cell is occupied.
    pub fn read_occupied(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<bool>> {
        let count = self.count;
        readback_buffer(device, queue, &self.hits).then(move |bytes| {
            let hits: Vec<[i32; 4]> = bytemuck::pod_collect_to_vec(&bytes[..count * 16]);
            Ok(hits.into_iter().map(|h| h[0] != 0).collect())
        })
    }
}

/// The cast pipelines. Create once, cast many times.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, octree: &fieldkit::octree::Octree,
/// #      grid: &fieldkit::voxelize::Grid, view: &fieldkit::view::View) -> Result<(), fieldkit::Error> {
/// use fieldkit::octree::{Lod, OctreeCaster, RenderSettings};
/// let caster = OctreeCaster::new(); // once
/// let settings = RenderSettings { lod: Lod::Footprint(1.0), ..Default::default() };
/// let image = caster.encode_render(device, encoder, octree, grid, view, &settings)?; // first hits
/// # let _ = image; Ok(()) }
/// ```
#[derive(Default)]
pub struct OctreeCaster {
    /// Without and with attributes.
    render: Variants<stage::render::Entry, stage::Overrides>,
    cast_rays: OnceLock<ComputePipeline<stage::cast_rays::Entry>>,
    lookup: OnceLock<ComputePipeline<stage::lookup::Entry>>,
    expand: OnceLock<ComputePipeline<stage::expand::Entry>>,
}

fn storage(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | usage,
        mapped_at_creation: false,
    })
}

impl OctreeCaster {
    /// The caster (pipelines are made on first use).
    pub fn new() -> Self {
        Self::default()
    }

    fn params(&self, octree: &Octree, count: u32) -> CastParams {
        CastParams {
            inv_view_proj: Mat4::IDENTITY,
            view_proj: Mat4::IDENTITY,
            world_to_local: Mat4::IDENTITY,
            local_to_world: Mat4::IDENTITY,
            size: octree.size.into(),
            log_side: octree.log_side,
            light: Vec3::Z,
            level: 0,
            colour: Vec3::ONE,
            footprint: 1.0,
            viewport: glam::Vec2::ONE,
            near_z: 0.0,
            far_z: 1.0,
            count,
        }
    }

    /// Record a first-hit render of `octree`, placed in the world by `grid` (the grid it was
    /// built in), into new colour and depth textures of the view's size.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_render(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        grid: &Grid,
        view: &View,
        settings: &RenderSettings,
    ) -> Result<OctreeImage, Error> {
        let (level, footprint) = check_render(octree, grid, view, settings)?;
        let local_to_world = Mat4::from_translation(grid.origin.as_vec3())
            * Mat4::from_scale(Vec3::splat(grid.voxel as f32));
        let (near_z, far_z) = if view.reversed_z {
            (1.0, 0.0)
        } else {
            (0.0, 1.0)
        };
        let params = uniform(
            device,
            "octree render params",
            &CastParams {
                inv_view_proj: view.view_proj.inverse(),
                view_proj: view.view_proj,
                world_to_local: local_to_world.inverse(),
                local_to_world,
                light: settings.light.normalize(),
                level,
                colour: settings.colour,
                footprint,
                viewport: glam::UVec2::from(view.viewport).as_vec2(),
                near_z,
                far_z,
                ..self.params(octree, 0)
            },
        );
        let size = [view.viewport[0], view.viewport[1], 1];
        let texture = |label, format| {
            crate::gpu::texture(
                device,
                label,
                size,
                wgpu::TextureDimension::D2,
                format,
                wgpu::TextureUsages::STORAGE_BINDING
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
            )
        };
        let image = OctreeImage {
            colour: texture("octree colour", wgpu::TextureFormat::Rgba8Unorm),
            depth: texture("octree depth", wgpu::TextureFormat::R32Float),
        };
        let (cv, dv) = (
            image.colour.create_view(&Default::default()),
            image.depth.create_view(&Default::default()),
        );
        let attributes = octree.attributes.as_ref().filter(|_| settings.attributes);
        let pipeline = self.render.get(
            device,
            &stage::Overrides {
                attributes: attributes.is_some(),
            },
            true,
        )?;
        let none = storage(
            device,
            "no octree attributes",
            16,
            wgpu::BufferUsages::empty(),
        );
        pipeline.record(
            device,
            rec,
            &stage::render::Resources {
                params: (&params).into(),
                pool: (&octree.pool).into(),
                colour_out: (&cv).into(),
                depth_out: (&dv).into(),
                node_attributes: attributes.map_or(&none, |a| &a.node_attributes).into(),
                voxel_attributes: attributes.map_or(&none, |a| &a.voxel_attributes).into(),
                brick_voxels: attributes.map_or(&none, |a| &a.brick_voxels).into(),
            },
            [
                view.viewport[0].div_ceil(8),
                view.viewport[1].div_ceil(8),
                1,
            ],
            stage::STAGE,
        )?;
        Ok(image)
    }

    /// Record `rays` cast through `octree`, each at its own level.
    pub fn encode_cast(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        rays: &[Ray],
    ) -> Result<Casts, Error> {
        let mut data = Vec::with_capacity(rays.len() * 2);
        let size = glam::UVec3::from(octree.size).as_vec3();
        for (i, r) in rays.iter().enumerate() {
            if !(r.start.is_finite() && r.dir.is_finite()) || r.dir == Vec3::ZERO {
                return Err(Error::invalid(
                    stage::STAGE,
                    format!("ray {i}: {r:?} is not finite or has no direction"),
                ));
            }
            if r.start.cmplt(Vec3::ZERO).any() || r.start.cmpgt(size).any() {
                return Err(Error::invalid(
                    stage::STAGE,
                    format!("ray {i} starts outside the grid: {}", r.start),
                ));
            }
            if r.level > octree.log_side {
                return Err(Error::Size {
                    stage: stage::STAGE,
                    what: "ray level (0 the root, log_side the voxels)",
                    got: r.level as u64,
                    max: octree.log_side as u64,
                });
            }
            data.push(r.start.extend(f32::from_bits(r.level)));
            data.push(r.dir.recip().extend(0.0));
        }
        self.run(
            device,
            rec,
            octree,
            bytemuck::cast_slice(&data),
            rays.len(),
            true,
        )
    }

    /// Record occupancy lookups: per point, whether the cell of `level` that holds voxel `p` is
    /// occupied (at [`Octree::log_side`], the voxel itself). [`Casts::read_occupied`] reads them.
    pub fn encode_lookup(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        points: &[[u32; 3]],
        level: u32,
    ) -> Result<Casts, Error> {
        if level > octree.log_side {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "lookup level (0 the root, log_side the voxels)",
                got: level as u64,
                max: octree.log_side as u64,
            });
        }
        let data: Vec<[u32; 4]> = points.iter().map(|p| [p[0], p[1], p[2], level]).collect();
        self.run(
            device,
            rec,
            octree,
            bytemuck::cast_slice(&data),
            points.len(),
            false,
        )
    }

    /// Record level `level` of `octree` as a dense bitset of its cells (cells of
    /// 2^(log_side − level) voxels; at [`Octree::log_side`], the voxels): a
    /// [`crate::voxelize::Surface`], so what takes a voxelization takes a tree's level —
    /// [`crate::voxelize::Voxelizer::encode_volume`] makes it the 3D mask the distance stages
    /// read. The grid of cells must fit a dense grid (at most 2³² cells and one storage
    /// binding of bits).
    pub fn encode_dense(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        level: u32,
    ) -> Result<crate::voxelize::Surface, Error> {
        if level > octree.log_side {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "dense level (0 the root, log_side the voxels)",
                got: level as u64,
                max: octree.log_side as u64,
            });
        }
        let shift = octree.log_side - level;
        let size = octree.size.map(|n| n.div_ceil(1 << shift));
        let cells = size.iter().map(|&n| n as u64).product::<u64>();
        let words = cells.div_ceil(32);
        let limit = device.limits().max_storage_buffer_binding_size;
        if cells > crate::voxelize::MAX_VOXELS || words * 4 > limit {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "cells of the dense level (a bit each, one binding)",
                got: cells,
                max: (limit * 8).min(crate::voxelize::MAX_VOXELS),
            });
        }
        let occupancy = storage(
            device,
            "octree dense level",
            words * 4,
            wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let params = uniform(
            device,
            "octree dense params",
            &CastParams {
                level,
                ..self.params(octree, words as u32)
            },
        );
        let groups = words.div_ceil(64);
        let row = device.limits().max_compute_workgroups_per_dimension as u64;
        ComputePipeline::cached(&self.expand, device, &[])?.record(
            device,
            rec,
            &stage::expand::Resources {
                params: (&params).into(),
                pool: (&octree.pool).into(),
                dense: (&occupancy).into(),
            },
            [groups.min(row) as u32, groups.div_ceil(row) as u32, 1],
            stage::STAGE,
        )?;
        crate::voxelize::Surface::from_bits(size, occupancy)
    }

    fn run(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        input: &[u8],
        count: usize,
        rays: bool,
    ) -> Result<Casts, Error> {
        let limit = device.limits().max_storage_buffer_binding_size;
        let groups = count.div_ceil(64) as u64;
        if count as u64 * 32 > limit
            || groups > device.limits().max_compute_workgroups_per_dimension as u64
        {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "rays or points in one call",
                got: count as u64,
                max: (limit / 32)
                    .min(device.limits().max_compute_workgroups_per_dimension as u64 * 64),
            });
        }
        use wgpu::util::DeviceExt;
        let mut padded = input.to_vec();
        padded.resize(padded.len().max(32), 0);
        let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("octree cast input"),
            contents: &padded,
            usage: wgpu::BufferUsages::STORAGE,
        });
        let casts = Casts {
            hits: storage(
                device,
                "octree hits",
                count as u64 * 16,
                wgpu::BufferUsages::COPY_SRC,
            ),
            count,
        };
        if count == 0 {
            return Ok(casts);
        }
        let params = uniform(
            device,
            "octree cast params",
            &self.params(octree, count as u32),
        );
        let groups = [groups as u32, 1, 1];
        if rays {
            ComputePipeline::cached(&self.cast_rays, device, &[])?.record(
                device,
                rec,
                &stage::cast_rays::Resources {
                    params: (&params).into(),
                    pool: (&octree.pool).into(),
                    rays: (&input).into(),
                    hits: (&casts.hits).into(),
                },
                groups,
                stage::STAGE,
            )?;
        } else {
            ComputePipeline::cached(&self.lookup, device, &[])?.record(
                device,
                rec,
                &stage::lookup::Resources {
                    params: (&params).into(),
                    pool: (&octree.pool).into(),
                    hits: (&casts.hits).into(),
                    points: (&input).into(),
                },
                groups,
                stage::STAGE,
            )?;
        }
        Ok(casts)
    }
}

/// What [`OctreeCaster::encode_render`] refuses, else the level it renders at and the
/// footprint (pixels a node may cover) it picks levels by.
fn check_render(
    octree: &Octree,
    grid: &Grid,
    view: &View,
    settings: &RenderSettings,
) -> Result<(u32, f32), Error> {
    view.check(stage::STAGE)?;
    if view.origin != [0, 0] {
        return Err(Error::invalid(
            stage::STAGE,
            format!(
                "origin {:?}: the octree render draws whole targets (origin [0, 0])",
                view.origin
            ),
        ));
    }
    if grid.size != octree.size {
        return Err(Error::invalid(
            stage::STAGE,
            format!(
                "the grid is {:?}, the octree was built in one of {:?}",
                grid.size, octree.size
            ),
        ));
    }
    grid.check(stage::STAGE)?;
    let (level, footprint) = match settings.lod {
        Lod::Level(l) if l <= octree.log_side => (l, 1.0),
        Lod::Level(l) => {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "octree level (0 the root, log_side the voxels)",
                got: l as u64,
                max: octree.log_side as u64,
            });
        }
        Lod::Footprint(p) if p.is_finite() && p > 0.0 => (LOD_BY_FOOTPRINT, p),
        Lod::Footprint(p) => {
            return Err(Error::invalid(
                stage::STAGE,
                format!("the footprint must be finite and > 0, got {p}"),
            ));
        }
    };
    if !(settings.colour.is_finite() && settings.light.is_finite())
        || settings.light.length_squared() == 0.0
    {
        return Err(Error::invalid(
            stage::STAGE,
            format!(
                "colour {} and light {} must be finite, the light not zero",
                settings.colour, settings.light
            ),
        ));
    }
    Ok((level, footprint))
}
