//! Voxel fragments (`voxelize/fragments`): every voxel each triangle touches, as a list of
//! coordinates instead of a dense bitset, for grids too large to hold densely (up to
//! [`super::MAX_SPARSE_SIDE`] per side). The sparse voxel octree ([`crate::octree`]) is built from it.

use super::{Grid, GridMesh, Listed, Mesh, SLACK, Separation, Voxelizer, box_columns};
use crate::bind::Variants;
use crate::error::Error;
use crate::gpu::{Readback, Record, storage_buffer as storage, uniform_buffer as uniform};
use crate::shaders::voxelize::fragments::{self as stage, FragmentParams};

/// Bytes per fragment: (x | y << 16, z).
const FRAGMENT_BYTES: u64 = 8;

/// Per separation (conservative, six), without and with triangle ids.
#[derive(Default)]
pub(super) struct FragmentPipelines {
    variants: Variants<stage::fragments_listed::Entry, stage::Overrides>,
}

/// The voxels of a mesh's surface as lists on the GPU, one entry per (triangle, voxel) it
/// touches: a voxel several triangles touch is listed once for each. The triangles are split
/// into parts whose lists each fit one storage binding (one part unless the surface is large
/// for the device), so the whole list may exceed what one buffer holds.
pub struct Fragments {
    /// Voxels per axis of the grid.
    pub size: [u32; 3],
    /// The lists, each of a run of the triangles.
    pub parts: Vec<FragmentPart>,
    /// Triangles left out for having no area.
    pub degenerate: usize,
    /// With [`Voxelizer::encode_fragments_with_attributes`]: the triangles and their corner
    /// attributes, which each part's `triangle_ids` index.
    pub attributes: Option<FragmentAttributes>,
}

/// One part of [`Fragments`].
pub struct FragmentPart {
    /// Entries `list` holds.
    pub capacity: u32,
    /// A `vec2<u32>` per fragment: voxel (x, y, z) as (x | y << 16, z), in no particular order.
    pub list: wgpu::Buffer,
    /// A `u32`: the part's fragments, also those past `capacity`, which are not in `list`.
    pub total: wgpu::Buffer,
    /// With attributes, a `u32` per fragment: its triangle in [`FragmentAttributes::triangles`].
    pub triangle_ids: Option<wgpu::Buffer>,
}

/// The triangles and their corner attributes
/// ([`Voxelizer::encode_fragments_with_attributes`]).
pub struct FragmentAttributes {
    /// Three grid-local `vec4<f32>` vertices per triangle, in the order the ids count.
    pub triangles: wgpu::Buffer,
    /// Six `vec4<u32>` per triangle: per corner (RGBA8 colour, the normal's f32 bits), then
    /// (u, v, 0, 0), as the dense attribute pass reads them.
    pub corners: wgpu::Buffer,
    /// Whether the mesh had texture coordinates (an albedo can be sampled).
    pub textured: bool,
}

impl Fragments {
    /// Entries the parts' lists hold in all.
    pub fn capacity(&self) -> u64 {
        self.parts.iter().map(|p| p.capacity as u64).sum()
    }

    /// Each part's fragments, read back once the encoder that recorded them has been
    /// submitted, as they were counted (also past a part's capacity).
    pub fn totals(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<u32>> {
        let totals: Vec<&wgpu::Buffer> = self.parts.iter().map(|p| &p.total).collect();
        crate::gpu::readback_buffers(device, queue, &totals)
            .then(|bytes| Ok(bytemuck::pod_collect_to_vec(&bytes)))
    }

    /// The number of fragments, read back once the encoder that recorded them has been
    /// submitted: [`Error::Size`] when a part counted more than its capacity (its list lost
    /// some; the error names the part's count, the capacity to ask for).
    pub fn count(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<u64> {
        let capacities: Vec<u32> = self.parts.iter().map(|p| p.capacity).collect();
        self.totals(device, queue).then(move |totals| {
            for (&t, &c) in totals.iter().zip(&capacities) {
                check_total(t, c)?;
            }
            Ok(totals.iter().map(|&t| t as u64).sum())
        })
    }

    /// The fragments' voxels, part after part, as [`Fragments::count`] checks them.
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<[u32; 3]>> {
        let capacities: Vec<u32> = self.parts.iter().map(|p| p.capacity).collect();
        let mut buffers: Vec<&wgpu::Buffer> = self.parts.iter().map(|p| &p.total).collect();
        buffers.extend(self.parts.iter().map(|p| &p.list));
        let sizes: Vec<usize> = self.parts.iter().map(|p| p.list.size() as usize).collect();
        crate::gpu::readback_buffers(device, queue, &buffers).then(move |bytes| {
            let n = capacities.len();
            let totals: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..n * 4]);
            let mut at = n * 4;
            let mut out = Vec::new();
            for ((&total, &capacity), size) in totals.iter().zip(&capacities).zip(sizes) {
                check_total(total, capacity)?;
                let list: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(
                    &bytes[at..at + total as usize * FRAGMENT_BYTES as usize],
                );
                out.extend(list.iter().map(|&[xy, z]| [xy & 0xffff, xy >> 16, z]));
                at += size;
            }
            Ok(out)
        })
    }
}

fn check_total(total: u32, capacity: u32) -> Result<(), Error> {
    if total > capacity {
        return Err(Error::Size {
            stage: stage::STAGE,
            what: "voxel fragments of a part (its list's capacity)",
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
    /// [`super::MAX_SPARSE_SIDE`]. The triangles are cut into parts whose estimated fragments
    /// ([`fragment_estimate`]'s four per column) fit `capacity`, or one storage binding by
    /// default; each part's list holds `capacity`, or by default its estimate.
    /// [`Fragments::count`] says whether that was enough, [`Fragments::totals`] what each part
    /// needs.
    ///
    /// ```
    /// # async fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
    /// use fieldkit::glam::DVec3;
    /// let mesh = Mesh::uv_sphere(DVec3::splat(8.0), 5.0, 16, 8);
    /// let grid = Grid { origin: DVec3::ZERO, voxel: 1.0, size: [16, 16, 16] };
    /// let v = Voxelizer::new(device)?;
    /// let mut encoder = device.create_command_encoder(&Default::default());
    /// let fragments =
    ///     v.encode_fragments(device, &mut encoder, &mesh, &grid, Separation::Conservative, None)?;
    /// queue.submit([encoder.finish()]);
    /// let voxels = fragments.read(device, queue).await?;
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
        if let Some(c) = capacity
            && (c == 0 || c as u64 > most)
        {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "voxel fragment capacity of a part (8 bytes each, one storage binding)",
                got: c as u64,
                max: most,
            });
        }
        let listed = Listed::new(device, &local, grid, super::Listing::default())?;
        let threads = listed.light as u64 + listed.chunk_count as u64;
        let parts = parts(&listed, &local, grid, capacity.map_or(most, |c| c as u64));
        let attributes =
            corner_data.map(|corners| FragmentAttributes::sorted(device, mesh, &listed, &corners));
        let groups = threads.div_ceil(64);
        if groups.div_ceil(65535) > 65535 {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "fragment threads (triangles and heavy chunks)",
                got: threads,
                max: 65535 * 65535 * 64,
            });
        }
        let six = separation == Separation::Six;
        let pipeline = self.fragment_pipelines.variants.get(
            device,
            &stage::Overrides {
                six_separating: six,
                triangle_ids: ids,
            },
            true,
        )?;
        let no_ids = storage(
            device,
            "no fragment triangles",
            4,
            wgpu::BufferUsages::empty(),
        );
        let mut fragments = Fragments {
            size: grid.size,
            parts: Vec::with_capacity(parts.len()),
            degenerate: local.degenerate,
            attributes,
        };
        for (first_thread, count, estimate) in parts {
            // Exactly the capacity asked for, else the estimate (within one binding).
            let part_capacity = capacity.unwrap_or(estimate.clamp(1, most) as u32);
            let part = FragmentPart::new(device, part_capacity, ids);
            if count > 0 {
                let params = uniform(
                    device,
                    "voxel fragment params",
                    &FragmentParams {
                        grid: grid.size.into(),
                        count: listed.light,
                        slack: SLACK,
                        chunks: listed.chunk_count,
                        capacity: part_capacity,
                        first_thread,
                        threads: count,
                    },
                );
                let groups = (count as u64).div_ceil(64);
                pipeline.record(
                    device,
                    rec,
                    &stage::fragments_listed::Resources {
                        params: (&params).into(),
                        triangles: (&listed.triangles).into(),
                        listed: (&listed.chunks).into(),
                        fragments: (&part.list).into(),
                        total: (&part.total).into(),
                        triangle_ids: part.triangle_ids.as_ref().unwrap_or(&no_ids).into(),
                    },
                    [groups.min(65535) as u32, groups.div_ceil(65535) as u32, 1],
                    stage::STAGE,
                )?;
            }
            fragments.parts.push(part);
        }
        Ok(fragments)
    }
}

/// Parts of consecutive threads whose estimated fragments fit a list of `budget`: a light
/// triangle's estimate is 4 per column of its box, a heavy chunk's 4 per column. Each part
/// is `(first thread, threads, estimate)`; there is always at least one.
fn parts(listed: &Listed, local: &GridMesh, grid: &Grid, budget: u64) -> Vec<(u32, u32, u64)> {
    let threads = listed.light + listed.chunk_count;
    let mut parts: Vec<(u32, u32, u64)> = Vec::new();
    let (mut first, mut sum) = (0u32, 0u64);
    let light = listed.order[..listed.light as usize].iter().map(|&t| {
        let t = t as usize;
        4 * box_columns(&local.vertices[3 * t..3 * t + 3], grid.size)
    });
    let heavy = listed
        .runs
        .iter()
        .flat_map(|&(chunks, columns)| std::iter::repeat_n(4 * columns as u64, chunks as usize));
    for (i, estimate) in (0u32..).zip(light.chain(heavy)) {
        if i > first && sum + estimate > budget {
            parts.push((first, i - first, sum));
            (first, sum) = (i, 0);
        }
        sum += estimate;
    }
    if threads > first || parts.is_empty() {
        parts.push((first, threads - first, sum));
    }
    parts
}

impl FragmentPart {
    /// A new, empty part of `capacity` fragments (wgpu zeroes new buffers: the total starts
    /// at 0), with room for each fragment's triangle where `ids`.
    fn new(device: &wgpu::Device, capacity: u32, ids: bool) -> Self {
        let buffer = |label, size: u64, usage| storage(device, label, size.max(4), usage);
        FragmentPart {
            capacity,
            list: buffer(
                "voxel fragments",
                capacity as u64 * FRAGMENT_BYTES,
                wgpu::BufferUsages::COPY_SRC,
            ),
            total: buffer("voxel fragment count", 4, wgpu::BufferUsages::COPY_SRC),
            triangle_ids: ids.then(|| {
                buffer(
                    "voxel fragment triangles",
                    capacity as u64 * 4,
                    wgpu::BufferUsages::empty(),
                )
            }),
        }
    }
}

impl FragmentAttributes {
    /// The triangles' `corners` in the order `listed` sorted the triangles in.
    fn sorted(device: &wgpu::Device, mesh: &Mesh, listed: &Listed, corners: &[[u32; 4]]) -> Self {
        use wgpu::util::DeviceExt;
        let mut sorted: Vec<[u32; 4]> = listed
            .order
            .iter()
            .flat_map(|&t| corners[6 * t as usize..6 * t as usize + 6].iter().copied())
            .collect();
        if sorted.is_empty() {
            sorted.push([0; 4]);
        }
        FragmentAttributes {
            triangles: listed.triangles.clone(),
            corners: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("voxel fragment corners"),
                contents: bytemuck::cast_slice(&sorted),
                usage: wgpu::BufferUsages::STORAGE,
            }),
            textured: !mesh.texcoords.is_empty(),
        }
    }
}
