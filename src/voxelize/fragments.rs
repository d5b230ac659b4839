//! Voxel fragments (`voxelize/fragments`): every voxel each triangle touches, as a list of
//! coordinates instead of a dense bitset, for grids too large to hold densely (up to
//! [`super::MAX_SPARSE_SIDE`] per side). The sparse voxel octree ([`crate::octree`]) is built from it.

use std::sync::OnceLock;

use super::{Grid, GridMesh, Listed, Mesh, SLACK, Separation, Voxelizer, box_columns};
use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Readback, Record, readback_buffer, uniform_buffer as uniform};
use crate::shaders::voxelize::fragments::{self as stage, FragmentParams};

/// Bytes per fragment: (x | y << 16, z).
const FRAGMENT_BYTES: u64 = 8;

/// Per separation (conservative, six), without and with triangle ids.
#[derive(Default)]
pub(super) struct FragmentPipelines {
    variants: [OnceLock<ComputePipeline<stage::fragments_listed::Entry>>; 4],
}

/// The voxels of a mesh's surface as a list on the GPU, one entry per (triangle, voxel) it
/// touches: a voxel several triangles touch is listed once for each.
pub struct Fragments {
    /// Voxels per axis of the grid.
    pub size: [u32; 3],
    /// Entries `list` holds.
    pub capacity: u32,
    /// A `vec2<u32>` per fragment: voxel (x, y, z) as (x | y << 16, z), in no particular order.
    pub list: wgpu::Buffer,
    /// A `u32`: the fragments the mesh has, also those past `capacity`, which are not in
    /// `list`. [`Fragments::count`] reads it.
    pub total: wgpu::Buffer,
    /// Triangles left out for having no area.
    pub degenerate: usize,
    /// With [`Voxelizer::encode_fragments_with_attributes`]: what the octree's attributes need.
    pub attributes: Option<FragmentAttributes>,
}

/// Each fragment's triangle and the triangles' corner attributes
/// ([`Voxelizer::encode_fragments_with_attributes`]).
pub struct FragmentAttributes {
    /// A `u32` per fragment of [`Fragments::list`]: its triangle in `triangles`.
    pub triangle_ids: wgpu::Buffer,
    /// Three grid-local `vec4<f32>` vertices per triangle, in the order the ids count.
    pub triangles: wgpu::Buffer,
    /// Six `vec4<u32>` per triangle: per corner (RGBA8 colour, the normal's f32 bits), then
    /// (u, v, 0, 0), as the dense attribute pass reads them.
    pub corners: wgpu::Buffer,
}

impl Fragments {
    /// The number of fragments, read back once the encoder that recorded them has been
    /// submitted: [`Error::Size`] when it is past [`Fragments::capacity`] (the list lost some;
    /// the error says how many there are, the capacity to ask for).
    pub fn count(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<u32> {
        let capacity = self.capacity;
        readback_buffer(device, queue, &self.total).then(move |bytes| {
            let total: u32 = bytemuck::pod_read_unaligned(&bytes[..4]);
            check_total(total, capacity)?;
            Ok(total)
        })
    }

    /// The fragments' voxels, as [`Fragments::count`] checks them.
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<[u32; 3]>> {
        let capacity = self.capacity;
        crate::gpu::readback_buffers(device, queue, &[&self.total, &self.list]).then(move |bytes| {
            let total: u32 = bytemuck::pod_read_unaligned(&bytes[..4]);
            check_total(total, capacity)?;
            let list: &[[u32; 2]] =
                bytemuck::cast_slice(&bytes[4..4 + total as usize * FRAGMENT_BYTES as usize]);
            Ok(list
                .iter()
                .map(|&[xy, z]| [xy & 0xffff, xy >> 16, z])
                .collect())
        })
    }
}

fn check_total(total: u32, capacity: u32) -> Result<(), Error> {
    if total > capacity {
        return Err(Error::Size {
            stage: stage::STAGE,
            what: "voxel fragments (the list's capacity)",
            got: total as u64,
            max: capacity as u64,
        });
    }
    Ok(())
}

/// An estimate of the fragments of `local` in a grid of `size`: four per column of each
/// triangle's box along its dominant axis. A triangle's plane crosses at most four voxels of
/// a column along the axis its normal leans on most, so this holds but where the box's face
/// is much larger than the triangle's shadow on it, where it is generous.
pub fn fragment_estimate(local: &GridMesh, size: [u32; 3]) -> u64 {
    local
        .vertices
        .chunks(3)
        .map(|t| 4 * box_columns(t, size))
        .fold(0u64, u64::saturating_add)
}

impl Voxelizer {
    /// Record the surface voxels of `mesh` in `grid` as a list of fragments (see
    /// [`Fragments`]), as thick as `separation` says: the same voxels as
    /// [`Voxelizer::encode_surface_with`], with no dense grid, so sides up to
    /// [`super::MAX_SPARSE_SIDE`]. The list holds `capacity` fragments, by default
    /// [`fragment_estimate`] (at most the device's storage binding); [`Fragments::count`] says
    /// whether that was enough.
    ///
    /// ```
    /// # fn f(ctx: &fieldkit::gpu::Context) -> Result<(), fieldkit::Error> {
    /// use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
    /// use glam::DVec3;
    /// let mesh = Mesh::uv_sphere(DVec3::splat(8.0), 5.0, 16, 8);
    /// let grid = Grid { origin: DVec3::ZERO, voxel: 1.0, size: [16, 16, 16] };
    /// let v = Voxelizer::new(&ctx.device)?;
    /// let mut encoder = ctx.encoder("fragments");
    /// let fragments =
    ///     v.encode_fragments(&ctx.device, &mut encoder, &mesh, &grid, Separation::Conservative, None)?;
    /// ctx.submit_and_wait("fragments", encoder)?;
    /// let voxels = fragments.read(&ctx.device, &ctx.queue).wait(ctx)?;
    /// assert!(voxels.iter().all(|v| v.iter().all(|&c| c < 16)));
    /// # Ok(()) }
    /// ```
    pub fn encode_fragments(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
        capacity: Option<u32>,
    ) -> Result<Fragments, Error> {
        self.fragments(device, rec, mesh, grid, separation, capacity, false)
    }

    /// [`Voxelizer::encode_fragments`] (conservative) with each fragment's triangle and the
    /// triangles' vertex colours and normals, for the octree's attributes
    /// ([`crate::octree::OctreeBuilder::encode_attributes`]); 4 more bytes per fragment.
    pub fn encode_fragments_with_attributes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        capacity: Option<u32>,
    ) -> Result<Fragments, Error> {
        self.fragments(
            device,
            rec,
            mesh,
            grid,
            Separation::Conservative,
            capacity,
            true,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn fragments(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
        capacity: Option<u32>,
        ids: bool,
    ) -> Result<Fragments, Error> {
        let local = mesh.to_sparse_grid(grid)?;
        // Checked before anything runs: corners for every triangle kept.
        let corner_data = if ids {
            Some(super::attributes::corners(mesh, &local)?)
        } else {
            None
        };
        let limit = device.limits().max_storage_buffer_binding_size;
        let most = (limit / FRAGMENT_BYTES).min(u32::MAX as u64);
        let capacity = match capacity {
            Some(0) => {
                return Err(Error::Size {
                    stage: stage::STAGE,
                    what: "voxel fragment capacity",
                    got: 0,
                    max: most,
                });
            }
            Some(c) if c as u64 > most => {
                return Err(Error::Size {
                    stage: stage::STAGE,
                    what: "voxel fragment capacity (8 bytes each, the storage binding limit)",
                    got: c as u64,
                    max: most,
                });
            }
            Some(c) => c,
            None => fragment_estimate(&local, grid.size).clamp(1, most) as u32,
        };
        let listed = Listed::new(device, &local, grid)?;
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        // New buffers: zeroed by wgpu (the total starts at 0).
        let attributes = corner_data.map(|corners| {
            use wgpu::util::DeviceExt;
            // The corners in the order the triangles were sorted in.
            let mut sorted: Vec<[u32; 4]> = listed
                .order
                .iter()
                .flat_map(|&t| corners[6 * t as usize..6 * t as usize + 6].iter().copied())
                .collect();
            if sorted.is_empty() {
                sorted.push([0; 4]);
            }
            FragmentAttributes {
                triangle_ids: buffer(
                    "voxel fragment triangles",
                    capacity as u64 * 4,
                    wgpu::BufferUsages::empty(),
                ),
                triangles: listed.triangles.clone(),
                corners: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("voxel fragment corners"),
                    contents: bytemuck::cast_slice(&sorted),
                    usage: wgpu::BufferUsages::STORAGE,
                }),
            }
        });
        let fragments = Fragments {
            size: grid.size,
            capacity,
            list: buffer(
                "voxel fragments",
                capacity as u64 * FRAGMENT_BYTES,
                wgpu::BufferUsages::COPY_SRC,
            ),
            total: buffer("voxel fragment count", 4, wgpu::BufferUsages::COPY_SRC),
            degenerate: local.degenerate,
            attributes,
        };
        let threads = listed.light as u64 + listed.chunk_count as u64;
        if threads == 0 {
            return Ok(fragments);
        }
        let groups = threads.div_ceil(64);
        let (wide, rows) = (groups.min(65535), groups.div_ceil(65535));
        if rows > 65535 {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "fragment threads (triangles and heavy chunks)",
                got: threads,
                max: 65535 * 65535 * 64,
            });
        }
        let six = separation == Separation::Six;
        let pipeline = ComputePipeline::cached(
            &self.fragment_pipelines.variants[six as usize * 2 + ids as usize],
            device,
            &[
                ("SIX_SEPARATING", six as u32 as f64),
                ("TRIANGLE_IDS", ids as u32 as f64),
            ],
        )?;
        let no_ids;
        let triangle_ids = match &fragments.attributes {
            Some(a) => &a.triangle_ids,
            None => {
                no_ids = buffer("no fragment triangles", 4, wgpu::BufferUsages::empty());
                &no_ids
            }
        };
        let params = uniform(
            device,
            "voxel fragment params",
            &FragmentParams {
                grid: grid.size.into(),
                count: listed.light,
                slack: SLACK,
                chunks: listed.chunk_count,
                capacity,
            },
        );
        pipeline.record(
            device,
            rec,
            &stage::fragments_listed::Resources {
                params: (&params).into(),
                triangles: (&listed.triangles).into(),
                listed: (&listed.chunks).into(),
                fragments: (&fragments.list).into(),
                total: (&fragments.total).into(),
                triangle_ids: triangle_ids.into(),
            },
            [wide as u32, rows as u32, 1],
            stage::STAGE,
        )?;
        Ok(fragments)
    }
}
