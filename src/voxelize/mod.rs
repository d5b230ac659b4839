//! Mesh voxelization (`shaders/voxelize/`): conservative surface voxels of a triangle mesh in an
//! occupancy bitset, exact against the 13-axis separating-axis test ([`cpu::conservative`]).
//!
//! Meshes come in world units and are moved into grid-local coordinates (origin 0, voxels of
//! edge 1) on the CPU in f64 before they are rounded to f32, so a mesh 100 km from the origin
//! voxelizes as well as one at it.
//!
#![doc = include_str!("../../docs/voxelize.md")]

mod attributes;
pub mod cpu;
pub mod export;
mod fragments;
mod listing;
mod mesh;
mod obj;
mod placed;
mod surface;
mod view;

pub use view::{ColourBy, Light, VoxelView};

pub use crate::grid::Grid;
pub use attributes::{
    AttributeVolumes, Attributes, PendingAttributes, VoxelAttributes, occupied_bound,
};
pub use fragments::{FragmentAttributes, Fragments, fragment_estimate};
pub use listing::{
    CHUNK, GIANT_MIN_COLUMNS, GpuListing, LIST_BUDGET, Listing, MAX_CHUNKS, MAX_GIANTS,
    heavy_chunk_bound,
};
pub use mesh::{GridMesh, Mesh};
pub use placed::GpuMesh;
pub use surface::Surface;

use glam::Vec4;
use listing::{
    GIANT_BYTES, Sorted, box_columns, giant_blocks_bound, giant_count, in_rows, listed,
    mark_giants, most_chunks,
};

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Record, uniform_buffer as uniform};
use crate::shaders::voxelize::occupancy_volume::{self as volume_stage, VolumeParams};
use crate::shaders::voxelize::raster::{self as raster_stage, RasterParams};
use crate::shaders::voxelize::solid::{self as solid_stage, SolidParams};
use crate::shaders::voxelize::surface::{self as stage, SurfaceParams};

const STAGE: &str = stage::STAGE;

/// Largest side of a voxel grid.
pub const MAX_SIDE: u32 = 4096;

/// Most voxels in a grid: the shaders index voxels with u32.
pub const MAX_VOXELS: u64 = 1 << 32;

/// Largest side of a grid that is never held densely (voxel fragments, the octree): 2¹³, as
/// fragments store a coordinate in 16 bits and the octree's levels stay within 13.
pub const MAX_SPARSE_SIDE: u32 = 8192;

/// Relative slack on the GPU's tests: a few f32 ulp, so rounding only ever adds voxels within
/// about this fraction of the coordinates' size.
pub const SLACK: f32 = 4.0 * f32::EPSILON;

/// A model matrix's determinant, once it is known to be affine, finite and invertible.
fn check_model(model: glam::DMat4) -> Result<f64, Error> {
    let det = glam::DMat3::from_mat4(model).determinant();
    let affine = model.row(3).abs_diff_eq(glam::DVec4::W, 1e-12);
    if !(model.is_finite() && det.is_finite() && det != 0.0 && affine) {
        return Err(Error::invalid(
            STAGE,
            format!(
                "model matrix must be affine, finite and invertible, got {model} (determinant \
             {det})"
            ),
        ));
    }
    Ok(det)
}

/// Refuses a GPU work list for `listing` larger than one binding of `device`.
fn check_work_list(device: &wgpu::Device, listing: &GpuListing) -> Result<(), Error> {
    let limit = device.limits().max_storage_buffer_binding_size;
    if listing.capacity.saturating_mul(8) > limit {
        return Err(Error::Size {
            stage: STAGE,
            what: "heavy-triangle work list bytes",
            got: listing.capacity.saturating_mul(8),
            max: limit,
        });
    }
    Ok(())
}

fn check_grid(grid: &Grid) -> Result<(), Error> {
    check_sides(grid, MAX_SIDE)?;
    // Voxel indices are u32 in the shaders.
    let voxels = grid.voxels();
    if voxels > MAX_VOXELS {
        return Err(Error::Size {
            stage: STAGE,
            what: "voxels in the grid",
            got: voxels,
            max: MAX_VOXELS,
        });
    }
    Ok(())
}

/// A finite origin, a voxel edge > 0 and sides from 1 to `max_side`.
fn check_sides(grid: &Grid, max_side: u32) -> Result<(), Error> {
    grid.check_sides(STAGE, max_side)
}

/// An empty occupancy bitset for `grid`: a new buffer, which wgpu hands over zeroed (it clears
/// new buffers before their first use, outside the passes that fill them), so no clear is
/// recorded here.
fn zeroed_bitset(device: &wgpu::Device, grid: &Grid) -> Result<wgpu::Buffer, Error> {
    let voxels = grid.voxels();
    let words = voxels.div_ceil(32).max(1);
    let limit = device.limits().max_storage_buffer_binding_size;
    if words * 4 > limit {
        return Err(Error::Size {
            stage: STAGE,
            what: "occupancy bitset bytes",
            got: words * 4,
            max: limit,
        });
    }
    let occupancy = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("voxel occupancy"),
        size: words * 4,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    Ok(occupancy)
}

/// How thick a surface voxelization is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Separation {
    /// Every voxel a triangle touches (closed boxes): no 26-connected path crosses it.
    #[default]
    Conservative,
    /// Thinner: voxels whose inner cross the triangle's plane crosses and whose centre
    /// projects within half a voxel of the triangle: no 6-connected path crosses it.
    Six,
}

/// The entries of one surface variant: triangles (listing the heavy ones' chunks and sizing
/// their indirect dispatch), the heavy triangles' chunks, and both in one pass where the host
/// listed the chunks.
struct SurfacePipelines {
    light: ComputePipeline<stage::surface::Entry>,
    heavy: ComputePipeline<stage::surface_heavy::Entry>,
    giant: ComputePipeline<stage::surface_giant::Entry>,
    listed: ComputePipeline<stage::surface_listed::Entry>,
}

impl SurfacePipelines {
    fn new(device: &wgpu::Device, six: bool) -> Result<Self, Error> {
        let o = stage::Overrides {
            six_separating: six,
            ..Default::default()
        };
        Ok(Self {
            light: ComputePipeline::with_constants(device, &o)?,
            heavy: ComputePipeline::with_constants(device, &o)?,
            giant: ComputePipeline::with_constants(device, &o)?,
            listed: ComputePipeline::with_constants(device, &o)?,
        })
    }
}

/// Most columns a triangle walks in its own thread; heavier ones go through the work list (the
/// shader's `LIGHT`).
pub const LIGHT: u32 = 16;

/// The voxelization pipelines. Create once, encode many times.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
/// use fieldkit::glam::DVec3;
/// use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
/// let voxelizer = Voxelizer::new(device)?; // once
/// let mesh = Mesh::cuboid(DVec3::ZERO, DVec3::ONE);
/// let grid = Grid::fit(&mesh, 64)?;
/// let mut encoder = device.create_command_encoder(&Default::default());
/// let surface = voxelizer.encode_surface(device, &mut encoder, &mesh, &grid)?; // a bitset
/// queue.submit([encoder.finish()]);
/// let voxels = surface.read(device, queue); // a `Readback<Vec<bool>>`, x fastest
/// # let _ = voxels; Ok(()) }
/// ```
pub struct Voxelizer {
    surface: SurfacePipelines,
    surface_six: SurfacePipelines,
    solid: ComputePipeline<solid_stage::solid::Entry>,
    to_volume: ComputePipeline<volume_stage::to_volume::Entry>,
    attribute_pipelines: attributes::AttributePipelines,
    fragment_pipelines: fragments::FragmentPipelines,
    raster: std::sync::OnceLock<crate::bind::RenderPipeline<raster_stage::fs_raster::Entry>>,
    listing: Option<Listing>,
}

/// Most workgroups a walk of the GPU's list is dispatched with directly, the host's bound on
/// them, instead of through the arguments the surface pass counted: an indirect dispatch
/// costs the H100 several microseconds more (wgpu validates indirect arguments by default,
/// `InstanceFlags::VALIDATION_INDIRECT_CALL`), and a bound dispatched directly may launch
/// many workgroups that find nothing. Measured on the H100 (docs/voxelize.md, "Giant triangles on the GPU's list"): the
/// resident bunny's heavy pass, bounded by 0.43 M / 0.73 M / 1.6 M / 4.4 M entries at 128³ /
/// 256³ / 512³ / 1024³, took 0.0091 / 0.0121 / 0.0466 / 0.1965 ms direct against 0.0120 /
/// 0.0204 / 0.0491 / 0.1468 indirect; so bounds up to 2^21 invocations go direct.
const DIRECT_GROUPS: u64 = 1 << 15;

/// One compute pass of `pipeline` over at most `most` workgroups: exactly that many, in rows
/// of 65535, up to [`DIRECT_GROUPS`], else as many as `args` (three u32 the surface pass
/// wrote) say.
fn run_walk<E: crate::bind::Entry>(
    rec: &mut impl Record,
    label: &str,
    pipeline: &ComputePipeline<E>,
    bound: &crate::bind::Bound<E>,
    args: &wgpu::Buffer,
    most: u64,
) {
    let mut rec = rec.recorder();
    let mut pass = rec.compute_pass(label, label);
    if most <= DIRECT_GROUPS {
        pipeline.dispatch(&mut pass, bound, in_rows(most));
    } else {
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_compute(&mut pass);
        pass.dispatch_workgroups_indirect(args, 0);
    }
}

/// Triangles per dispatch: at most 65535 workgroups of 64.
const PER_DISPATCH: u32 = 65535 * 64;

/// `count` triangles as (first, count) runs of at most [`PER_DISPATCH`].
fn batches(count: u32) -> impl Iterator<Item = (u32, u32)> {
    (0..count)
        .step_by(PER_DISPATCH as usize)
        .map(move |first| (first, (count - first).min(PER_DISPATCH)))
}

/// The triangles of one surface pass: a buffer of `count` triangles (three `vec4<f32>` each),
/// the work-list entries their heavy triangles can need, the move into grid-local coordinates
/// and how far its f32 rounding can move a vertex (voxels).
struct SurfaceRun<'a> {
    triangles: &'a wgpu::Buffer,
    count: u32,
    listing: GpuListing,
    to_grid: glam::Mat4,
    moved: f32,
}

/// Triangles sorted on the host for `surface_listed` (see [`listed`]): light ones first, then
/// heavy ones, and the heavy ones' chunks.
struct Listed {
    triangles: wgpu::Buffer,
    chunks: wgpu::Buffer,
    light: u32,
    chunk_count: u32,
    /// Per heavy triangle (in the sorted order): its chunks and their columns.
    runs: Vec<(u32, u32)>,
    /// Per sorted triangle, its index in the [`GridMesh`].
    order: Vec<u32>,
}

impl Listed {
    fn new(
        device: &wgpu::Device,
        local: &GridMesh,
        grid: &Grid,
        listing: Listing,
    ) -> Result<Listed, Error> {
        use wgpu::util::DeviceExt;
        let limit = device.limits().max_storage_buffer_binding_size;
        let Sorted {
            mut vertices,
            light,
            mut chunks,
            runs,
            order,
        } = listed(local, grid.size, limit, listing)?;
        let chunk_count = chunks.len() as u32;
        // Padding keeps the buffers non-empty.
        if vertices.is_empty() {
            vertices.push(Vec4::ZERO);
        }
        if chunks.is_empty() {
            chunks.push([0, 0]);
        }
        let buffer = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Ok(Listed {
            triangles: buffer("voxelize triangles", bytemuck::cast_slice(&vertices)),
            chunks: buffer("voxelize heavy chunks", bytemuck::cast_slice(&chunks)),
            light,
            chunk_count,
            runs,
            order,
        })
    }
}

/// The heavy triangles' chunks a surface pass listed and the indirect dispatch that walks
/// them, and its giant triangles' records with a bound on their blocks (0: no giants).
struct HeavyWork {
    work: wgpu::Buffer,
    work_count: wgpu::Buffer,
    dispatch: wgpu::Buffer,
    capacity: u32,
    giant_records: wgpu::Buffer,
    giant_blocks: u64,
}

impl HeavyWork {
    /// New buffers for a list of `capacity` entries (at least one): the count zero, both
    /// dispatches' arguments (0, 1, 1) (`surface` raises the count, and the rows of 65535, as
    /// it lists chunks), the giants' counts zero.
    fn new(device: &wgpu::Device, capacity: u32, giant_blocks: u64) -> Self {
        let buffer =
            |label, size: u64, usage| crate::gpu::storage_buffer(device, label, size, usage);
        let arguments = |label, bytes: u64| {
            wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(&initial_arguments(bytes)),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::INDIRECT
                        | wgpu::BufferUsages::COPY_DST,
                },
            )
        };
        HeavyWork {
            work: buffer(
                "voxelize work list",
                capacity.max(1) as u64 * 8,
                wgpu::BufferUsages::empty(),
            ),
            work_count: buffer("voxelize work count", 4, wgpu::BufferUsages::COPY_DST),
            dispatch: arguments("voxelize heavy dispatch", 12),
            capacity,
            // The giant pass's arguments (0, 1, 1), then zeros.
            giant_records: arguments("voxelize giant triangles", GIANT_BYTES),
            giant_blocks,
        }
    }
}

/// Words of `bytes` of indirect dispatch arguments before any work is listed: (0, 1, 1), then
/// zeros.
fn initial_arguments(bytes: u64) -> Vec<u32> {
    let mut words = vec![0u32; bytes as usize / 4];
    words[1..3].copy_from_slice(&[1, 1]);
    words
}

/// A [`HeavyWork`] kept with a refilled [`Surface`] (`encode_surface_placed_into`), and the
/// arguments it starts from, copied over it before each pass that uses it.
struct KeptWork {
    heavy: HeavyWork,
    initial: wgpu::Buffer,
}

impl KeptWork {
    /// Kept buffers for a list of at least `capacity` entries (a quarter more, so that a
    /// listing that grows a little from frame to frame does not make new ones each time).
    fn new(device: &wgpu::Device, capacity: u32) -> Self {
        let initial = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("voxelize initial arguments"),
                contents: bytemuck::cast_slice(&initial_arguments(GIANT_BYTES)),
                usage: wgpu::BufferUsages::COPY_SRC,
            },
        );
        let most = device.limits().max_storage_buffer_binding_size / 8;
        let room = (capacity as u64 + capacity as u64 / 4).min(most) as u32;
        KeptWork {
            heavy: HeavyWork::new(device, room, 0),
            initial,
        }
    }

    /// Record the count's and the arguments' reset, so the next pass lists from nothing.
    fn reset(&self, rec: &mut impl Record) {
        let rec = rec.recorder();
        let h = &self.heavy;
        rec.encoder.clear_buffer(&h.work_count, 0, None);
        rec.encoder
            .copy_buffer_to_buffer(&self.initial, 0, &h.dispatch, 0, 12);
        rec.encoder
            .copy_buffer_to_buffer(&self.initial, 0, &h.giant_records, 0, GIANT_BYTES);
    }
}

impl Voxelizer {
    /// Create the surface, solid and volume pipelines (the rest on first use).
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            surface: SurfacePipelines::new(device, false)?,
            surface_six: SurfacePipelines::new(device, true)?,
            solid: ComputePipeline::new(device)?,
            to_volume: ComputePipeline::new(device)?,
            attribute_pipelines: Default::default(),
            fragment_pipelines: Default::default(),
            raster: Default::default(),
            listing: None,
        })
    }

    /// Bench knob: how the surface pass cuts triangles into threads (see [`Listing`]; `None`:
    /// [`Listing::auto`] per mesh).
    #[doc(hidden)]
    pub fn set_listing(
        &mut self,
        device: &wgpu::Device,
        listing: Option<Listing>,
    ) -> Result<(), Error> {
        let workgroup = listing.map_or(64, |l| l.workgroup);
        if listing.is_some_and(|l| l.chunk == 0) || !workgroup.is_power_of_two() || workgroup > 256
        {
            return Err(Error::invalid(STAGE, format!("listing {listing:?}")));
        }
        for (pipelines, six) in [(&mut self.surface, false), (&mut self.surface_six, true)] {
            pipelines.listed = ComputePipeline::with_constants(
                device,
                &stage::Overrides {
                    six_separating: six,
                    listed_workgroup: workgroup,
                },
            )?;
        }
        self.listing = listing;
        Ok(())
    }

    fn listing_for(&self, local: &GridMesh) -> Listing {
        self.listing
            .unwrap_or_else(|| Listing::auto(local.vertices.len() / 3))
    }

    /// Solid voxels of a closed mesh: every voxel whose centre is inside, by parity along x
    /// (`voxelize/solid`), ORed with the conservative surface so parts thinner than a voxel
    /// survive. A mesh with an open or inconsistently oriented edge is refused (its inside is
    /// not defined). `with_surface: false` gives the parity fill alone.
    pub fn encode_solid(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        with_surface: bool,
    ) -> Result<Surface, Error> {
        if let Some([a, b]) = mesh.open_edge() {
            return Err(Error::Invalid {
                stage: solid_stage::STAGE,
                what: format!(
                    "solid voxelization needs a closed, consistently oriented mesh: the edge \
                     between vertices {a} and {b} is not shared by exactly two triangles running \
                     opposite ways"
                ),
            });
        }
        let local = mesh.to_grid(grid)?;
        let occupancy = zeroed_bitset(device, grid)?;
        // The parity fill takes the triangles in any order: the surface pass's sorted ones.
        let listed = Listed::new(device, &local, grid, self.listing_for(&local))?;
        let triangles = &listed.triangles;
        let count = (local.vertices.len() / 3) as u32;
        for (first, n) in batches(count) {
            let params = uniform(
                device,
                "voxelize solid params",
                &SolidParams {
                    grid: grid.size.into(),
                    first,
                    count: n,
                },
            );
            self.solid.record(
                device,
                rec,
                &solid_stage::solid::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: (&occupancy).into(),
                },
                [n.div_ceil(64), 1, 1],
                solid_stage::STAGE,
            )?;
        }
        if with_surface {
            self.listed_pass(device, rec, &self.surface, &occupancy, &listed, grid)?;
        }
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }

    /// `voxels` as an `R32Float` 3D texture (1 occupied, 0 empty) that the distance stages
    /// read: `Distance3d::encode` with `Inside::Mask` gives the mesh's distance field.
    pub fn encode_volume(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        voxels: &Surface,
    ) -> Result<wgpu::Texture, Error> {
        let volume = crate::gpu::volume_texture(
            device,
            "voxel occupancy volume",
            voxels.size,
            wgpu::TextureFormat::R32Float,
        );
        let view = volume.create_view(&Default::default());
        let params = uniform(
            device,
            "voxel volume params",
            &VolumeParams {
                grid: voxels.size.into(),
            },
        );
        self.to_volume.record(
            device,
            rec,
            &volume_stage::to_volume::Resources {
                params: (&params).into(),
                occupancy: (&voxels.occupancy).into(),
                volume: (&view).into(),
            },
            ComputePipeline::<volume_stage::to_volume::Entry>::groups_for(voxels.size),
            volume_stage::STAGE,
        )?;
        Ok(volume)
    }

    /// A cleared bitset for `grid` and the triangle buffer of `local`, its `giants` marked
    /// ([`mark_giants`]).
    fn bitset(
        &self,
        device: &wgpu::Device,
        local: &GridMesh,
        grid: &Grid,
        giants: &[u32],
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), Error> {
        let occupancy = zeroed_bitset(device, grid)?;
        use wgpu::util::DeviceExt;
        let mut vertices = local.vertices.clone();
        mark_giants(&mut vertices, giants);
        // One padding vertex keeps the buffer non-empty when every triangle was degenerate.
        if vertices.is_empty() {
            vertices.push(Vec4::ZERO);
        }
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize triangles"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Ok((occupancy, triangles))
    }

    /// A surface pass (`pipelines`: conservative or six-separating) over the `count` triangles
    /// of `triangles` (marked for `listing`), ORed into `occupancy`: light triangles one per
    /// thread, heavy ones (more than [`LIGHT`] columns) in chunks of [`CHUNK`] through a work
    /// list and an indirect dispatch, giant ones by blocks. Returns the work list, which the
    /// attribute pass walks again.
    #[allow(clippy::too_many_arguments)]
    fn surface_into(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        triangles: &wgpu::Buffer,
        count: u32,
        listing: GpuListing,
        grid: &Grid,
    ) -> Result<HeavyWork, Error> {
        self.surface_pass(
            device,
            rec,
            pipelines,
            occupancy,
            &SurfaceRun {
                triangles,
                count,
                listing,
                to_grid: glam::Mat4::IDENTITY,
                moved: 0.0,
            },
            grid,
        )
    }

    /// The surface of `listed`'s triangles in one pass (`surface_listed`), ORed into
    /// `occupancy`: a light triangle per thread, then a heavy triangle's chunk per thread.
    fn listed_pass(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        listed: &Listed,
        grid: &Grid,
    ) -> Result<(), Error> {
        let threads = listed.light as u64 + listed.chunk_count as u64;
        if threads == 0 {
            return Ok(());
        }
        let params = uniform(
            device,
            "voxelize params",
            &SurfaceParams {
                to_grid: glam::Mat4::IDENTITY,
                grid: grid.size.into(),
                first: 0,
                count: listed.light,
                slack: SLACK,
                moved: 0.0,
                capacity: listed.chunk_count,
                giants: 0,
            },
        );
        // More than 65535 workgroups: rows of 65535 (the shader reads `num_workgroups`).
        let wg = self.listing.map_or(64, |l| l.workgroup) as u64;
        let groups = threads.div_ceil(wg);
        let rows = groups.div_ceil(65535);
        let wide = groups.min(65535);
        if rows > 65535 {
            return Err(Error::Size {
                stage: STAGE,
                what: "surface threads (triangles and heavy chunks)",
                got: threads,
                max: 65535 * 65535 * wg,
            });
        }
        pipelines.listed.record(
            device,
            rec,
            &stage::surface_listed::Resources {
                params: (&params).into(),
                triangles: (&listed.triangles).into(),
                occupancy: occupancy.into(),
                listed: (&listed.chunks).into(),
            },
            [wide as u32, rows as u32, 1],
            STAGE,
        )
    }

    /// The surface pipelines for `separation`.
    fn pipelines(&self, separation: Separation) -> &SurfacePipelines {
        match separation {
            Separation::Conservative => &self.surface,
            Separation::Six => &self.surface_six,
        }
    }

    /// One surface pass of `run`'s triangles into `occupancy` (see [`Self::surface_into`]),
    /// with a work list of its own.
    fn surface_pass(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        run: &SurfaceRun,
        grid: &Grid,
    ) -> Result<HeavyWork, Error> {
        check_work_list(device, &run.listing)?;
        // Within a binding: a u32 count. New buffers: zeroed by wgpu (the count starts at 0).
        let heavy = HeavyWork::new(device, run.listing.capacity as u32, run.listing.blocks);
        self.surface_pass_with(device, rec, pipelines, occupancy, run, grid, &heavy)?;
        Ok(heavy)
    }

    /// [`Self::surface_pass`] with the work list `heavy`, whose count must be zero and whose
    /// arguments (0, 1, 1) when the pass is recorded, and which holds at least the run's
    /// listing's entries (the pass uses as many as the listing asks for).
    #[allow(clippy::too_many_arguments)]
    fn surface_pass_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        run: &SurfaceRun,
        grid: &Grid,
        heavy_work: &HeavyWork,
    ) -> Result<(), Error> {
        let &SurfaceRun {
            triangles,
            count,
            listing,
            to_grid,
            moved,
        } = run;
        debug_assert!(heavy_work.capacity as u64 >= listing.capacity);
        let capacity = listing.capacity as u32;
        let HeavyWork {
            work,
            work_count,
            dispatch,
            giant_records,
            ..
        } = heavy_work;
        if count == 0 {
            return Ok(());
        }
        let params_for = |first, n| {
            uniform(
                device,
                "voxelize params",
                &SurfaceParams {
                    to_grid,
                    grid: grid.size.into(),
                    first,
                    count: n,
                    slack: SLACK,
                    moved,
                    capacity,
                    giants: listing.giants,
                },
            )
        };
        for (first, n) in batches(count) {
            let params = params_for(first, n);
            pipelines.light.record(
                device,
                rec,
                &stage::surface::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: occupancy.into(),
                    work: work.into(),
                    work_count: work_count.into(),
                    heavy_dispatch: dispatch.into(),
                    giants: giant_records.into(),
                },
                [n.div_ceil(64), 1, 1],
                STAGE,
            )?;
        }
        let params = params_for(0, count);
        if listing.giants > 0 {
            let giant = pipelines.giant.bind(
                device,
                &stage::surface_giant::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: occupancy.into(),
                    giant_list: giant_records.into(),
                },
            )?;
            run_walk(
                rec,
                "voxelize giant triangles",
                &pipelines.giant,
                &giant,
                giant_records,
                listing.blocks,
            );
        }
        if capacity == 0 {
            return Ok(());
        }
        let heavy = pipelines.heavy.bind(
            device,
            &stage::surface_heavy::Resources {
                params: (&params).into(),
                triangles: triangles.into(),
                occupancy: occupancy.into(),
                work: work.into(),
                work_count: work_count.into(),
            },
        )?;
        run_walk(
            rec,
            "voxelize heavy triangles",
            &pipelines.heavy,
            &heavy,
            dispatch,
            (capacity as u64).div_ceil(64),
        );
        Ok(())
    }

    /// The conservative surface voxels of [`Voxelizer::encode_surface`], found through the
    /// rasterizer as the write-up did (`voxelize/raster`): each triangle drawn on the plane of
    /// its dominant axis into a square target of the grid's largest side, enlarged by half a
    /// pixel's diagonal so every column it touches gets a fragment, which runs the exact tests.
    /// Kept to compare with the compute path; the voxels are the same. Its target and buffers
    /// are new each call (a bake, not a per-frame path).
    pub fn encode_surface_raster(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Surface, Error> {
        let side = grid.size.into_iter().max().unwrap_or(1);
        let max = device.limits().max_texture_dimension_2d;
        if side > max {
            return Err(Error::Size {
                stage: raster_stage::STAGE,
                what: "largest grid side (the raster target's side)",
                got: side as u64,
                max: max as u64,
            });
        }
        let local = mesh.to_grid(grid)?;
        let (occupancy, triangles) = self.bitset(device, &local, grid, &[])?;
        let format = wgpu::TextureFormat::R8Unorm;
        let pipeline = if let Some(p) = self.raster.get() {
            p
        } else {
            let p = crate::bind::RenderPipeline::new(
                device,
                &crate::bind::RenderTargets {
                    color: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                    ..Default::default()
                },
            )?;
            let _ = self.raster.set(p);
            self.raster.get().expect("set above")
        };
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("voxelize raster target"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = target.create_view(&Default::default());
        let params = uniform(
            device,
            "voxelize raster params",
            &RasterParams {
                grid: grid.size.into(),
                side,
                slack: SLACK,
                // Rasterizers snap to 1/256 pixel or finer; 1/64 covers that with room.
                margin: 1.0 / 64.0,
            },
        );
        let bound = pipeline.bind(
            device,
            &raster_stage::fs_raster::Resources {
                params: (&params).into(),
                triangles: (&triangles).into(),
                occupancy: (&occupancy).into(),
            },
        )?;
        let count = (local.vertices.len() / 3) as u32;
        let mut pass = rec
            .recorder()
            .encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(raster_stage::STAGE),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                ..Default::default()
            });
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..count * 3, 0..1);
        drop(pass);
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }

    /// Conservative surface voxels of `mesh` in `grid`: every voxel (a closed box) a triangle
    /// touches.
    pub fn encode_surface(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Surface, Error> {
        self.encode_surface_with(device, rec, mesh, grid, Separation::Conservative)
    }

    /// Surface voxels of `mesh` in `grid`, as thick as `separation` says, recorded into `rec`
    /// (a command encoder, or [`crate::gpu::Profiler::record`] to time each pass).
    pub fn encode_surface_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
    ) -> Result<Surface, Error> {
        let local = mesh.to_grid(grid)?;
        let occupancy = zeroed_bitset(device, grid)?;
        let pipelines = self.pipelines(separation);
        let listed = Listed::new(device, &local, grid, self.listing_for(&local))?;
        self.listed_pass(device, rec, pipelines, &occupancy, &listed, grid)?;
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }
}

#[cfg(test)]
mod tests;
