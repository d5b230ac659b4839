//! Averaged voxel attributes: each occupied voxel's colour and normal, averaged over the
//! triangles that touch it with integer atomic sums and a count (`voxelize/attributes`), in a
//! list compacted to the occupied voxels in voxel order (`voxelize/compact`). Integer sums do
//! not depend on the order the GPU runs threads in, so two runs give identical bytes.
//!
//! Sizing the compact list exactly needs the number of occupied voxels, which only the GPU
//! knows: [`Voxelizer::attributes`] reads it back between two submissions. Callers that keep
//! their own encoders use [`Voxelizer::encode_attributes`], [`PendingAttributes::occupied`] and
//! [`Voxelizer::encode_resolve_attributes`]; or [`Voxelizer::encode_attributes_in_one`], which
//! records everything into one encoder with the list sized by a bound the CPU knows
//! ([`occupied_bound`]) and the true count left on the GPU ([`Attributes::occupied`]), where
//! the view draws and the reads read it.

use std::sync::OnceLock;

use glam::{DVec3, Vec3};

use super::{Grid, GridMesh, HeavyWork, Mesh, SLACK, STAGE, Surface, Voxelizer, batches, run_walk};
use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{AlbedoBinding, volume_texture};
use crate::gpu::{Readback, Record, readback_buffer, uniform_buffer as uniform};
use crate::shaders::voxelize::attribute_volume::{self as volume_stage, AttributeVolumeParams};
use crate::shaders::voxelize::attributes::{self as stage, AttributeParams};
use crate::shaders::voxelize::compact::{self as compact, CompactParams};

/// Words of the bitset one workgroup of `compact::scan_words` covers (the shader's
/// `BLOCK_WORDS`).
const BLOCK_WORDS: u64 = 1024;
/// `u32` sums per occupied voxel (the shader's `SUMS`).
const SUMS: u64 = 8;
/// The packed normal of a voxel whose normals cancel (the shader's `NO_NORMAL`).
const NO_NORMAL: u32 = 0x8000_8000;

#[derive(Default)]
pub(super) struct AttributePipelines {
    scan_words: OnceLock<ComputePipeline<compact::scan_words::Entry>>,
    scan_blocks: OnceLock<ComputePipeline<compact::scan_blocks::Entry>>,
    accumulate: OnceLock<ComputePipeline<stage::accumulate::Entry>>,
    accumulate_heavy: OnceLock<ComputePipeline<stage::accumulate_heavy::Entry>>,
    accumulate_giant: OnceLock<ComputePipeline<stage::accumulate_giant::Entry>>,
    resolve: OnceLock<ComputePipeline<stage::resolve::Entry>>,
    to_volumes: OnceLock<ComputePipeline<volume_stage::to_volumes::Entry>>,
    albedo: AlbedoBinding,
}

/// Voxel attributes as dense 3D textures (`voxelize/attribute_volume`), for stages that sample
/// them: zero where no voxel is.
pub struct AttributeVolumes {
    /// `Rgba8Unorm`: each occupied voxel's averaged colour.
    pub colour: wgpu::Texture,
    /// `Rgba8Snorm`: each occupied voxel's averaged normal in xyz, 1 in w (all zero where the
    /// normals cancel but w).
    pub normal: wgpu::Texture,
}

/// The first half of an attribute pass, recorded: surface voxels, their dense indices, and the
/// triangles' attributes on the GPU. [`PendingAttributes::occupied`] reads how many voxels
/// the second half needs room for.
pub struct PendingAttributes {
    bound: u64,
    albedo: Option<wgpu::TextureView>,
    surface: Surface,
    grid: Grid,
    triangles: wgpu::Buffer,
    corners: wgpu::Buffer,
    heavy: HeavyWork,
    word_offsets: wgpu::Buffer,
    block_offsets: wgpu::Buffer,
    total: wgpu::Buffer,
    words: u32,
    count: u32,
}

impl PendingAttributes {
    /// The bound on occupied voxels ([`occupied_bound`]) that
    /// [`Voxelizer::encode_attributes_in_one`] sizes its list by.
    pub fn bound(&self) -> u64 {
        self.bound
    }

    /// Occupied voxels, read back once the encoder that recorded this has been submitted.
    pub fn occupied(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<u32> {
        readback_buffer(device, queue, &self.total)
            .then(|bytes| Ok(bytemuck::pod_read_unaligned(&bytes[..4])))
    }

    /// The parameters of the attribute passes over triangles `first..first + count`.
    fn params(&self, device: &wgpu::Device, first: u32, count: u32) -> wgpu::Buffer {
        uniform(
            device,
            "voxel attribute params",
            &AttributeParams {
                grid: self.grid.size.into(),
                first,
                count,
                slack: SLACK,
                capacity: self.heavy.capacity,
                words: self.words,
                textured: self.albedo.is_some() as u32,
            },
        )
    }
}

/// Averaged attributes of every occupied voxel.
pub struct Attributes {
    /// The conservative surface voxels the list covers.
    pub surface: Surface,
    /// Entries `voxels` has room for: the occupied voxels where the count was read back
    /// ([`Voxelizer::attributes`]), a bound on them where it was not
    /// ([`Voxelizer::encode_attributes_in_one`]).
    pub count: u32,
    /// The occupied voxels, a `u32` on the GPU: entries of `voxels` that hold one. Indirect
    /// draws and dispatches read it there.
    pub occupied: wgpu::Buffer,
    /// Per occupied voxel, in voxel order, a `vec4<u32>`: the voxel index
    /// ((z · ny + y) · nx + x), the RGBA8 colour, the normal as an octahedral pair of snorm16
    /// (0x80008000 where the normals cancel) and the number of triangles. 16 bytes per
    /// occupied voxel rather than per voxel of the grid.
    pub voxels: wgpu::Buffer,
}

/// One occupied voxel's averages, as [`Attributes::read`] decodes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoxelAttributes {
    /// Its voxel coordinates.
    pub voxel: [u32; 3],
    /// Mean colour, rounded to the nearest 8-bit level.
    pub color: [u8; 4],
    /// Direction of the summed normals; `None` where they cancel.
    pub normal: Option<Vec3>,
    /// Triangles that touch the voxel.
    pub triangles: u32,
}

/// The octahedral pair of snorm16 the shader writes, back to a unit vector.
fn decode_normal(packed: u32) -> Option<Vec3> {
    if packed == NO_NORMAL {
        return None;
    }
    let s = |v: u32| ((v & 0xffff) as u16 as i16 as f32 / 32767.0).max(-1.0);
    let (x, y) = (s(packed), s(packed >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    Some(Vec3::new(x, y, z).normalize())
}

impl Attributes {
    /// Every occupied voxel's averages, in voxel order.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Readback<Vec<VoxelAttributes>> {
        let [nx, ny, _] = self.surface.size;
        let room = self.count as usize;
        let list_bytes = self.voxels.size() as usize;
        crate::gpu::readback_buffers(device, queue, &[&self.occupied, &self.voxels]).then(
            move |bytes| {
                // The occupied count's buffer comes first, whole.
                let head = bytes.len() - list_bytes;
                let occupied: u32 = bytemuck::pod_read_unaligned(&bytes[..4]);
                let count = (occupied as usize).min(room);
                let words: &[[u32; 4]] = bytemuck::cast_slice(&bytes[head..]);
                Ok(words[..count]
                    .iter()
                    .map(|&[i, colour, normal, triangles]| VoxelAttributes {
                        voxel: [i % nx, i / nx % ny, i / (nx * ny)],
                        color: colour.to_le_bytes(),
                        normal: decode_normal(normal),
                        triangles,
                    })
                    .collect())
            },
        )
    }
}

/// A bound on the occupied voxels of `local` (a grid of `size`) that the CPU knows before the GPU
/// runs: a triangle's conservative voxels lie in its bounding box (widened by the GPU tests'
/// slack), and the grid holds no more voxels than it has. Sizes the list of
/// [`Voxelizer::encode_attributes_in_one`]: 48 bytes per bound voxel on the GPU.
pub fn occupied_bound(local: &GridMesh, size: [u32; 3]) -> u64 {
    let total = size.iter().map(|&n| n as u64).product::<u64>();
    let mut sum = 0u64;
    for t in local.vertices.chunks_exact(3) {
        let lo = t[0].min(t[1]).min(t[2]).truncate();
        let hi = t[0].max(t[1]).max(t[2]).truncate();
        let mut n = 1u64;
        for k in 0..3 {
            let eps = 0.01 + 16.0 * f32::EPSILON * lo[k].abs().max(hi[k].abs());
            let a = ((lo[k] - eps).floor().max(0.0) as u64).min(size[k] as u64);
            let b = ((hi[k] + eps).floor().max(-1.0) as i64).min(size[k] as i64 - 1);
            n *= (b - a as i64 + 1).max(0) as u64;
        }
        sum = sum.saturating_add(n);
        if sum >= total {
            return total;
        }
    }
    sum.min(total)
}

/// Per triangle corner of `local`, two words of four: the RGBA8 colour and the normal's f32
/// bits (the vertex normal, or the triangle's own where the mesh has none), then the texture
/// coordinates' f32 bits ((0, 0) where the mesh has none).
pub(super) fn corners(mesh: &Mesh, local: &GridMesh) -> Result<Vec<[u32; 4]>, Error> {
    let n = mesh.positions.len();
    for (what, len) in [
        ("colors", mesh.colors.len()),
        ("normals", mesh.normals.len()),
    ] {
        if len != 0 && len != n {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the mesh has {n} positions but {len} {what} (give one per vertex, or none)"
                ),
            ));
        }
    }
    let t = mesh.triangles.len();
    if !mesh.texcoords.is_empty() && mesh.texcoords.len() != t {
        return Err(Error::invalid(
            STAGE,
            format!(
                "the mesh has {t} triangles but {} texcoords (give one [uv; 3] per triangle, or none)",
                mesh.texcoords.len()
            ),
        ));
    }
    if let Some(i) = mesh.normals.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            STAGE,
            format!("normal {i} is not finite: {}", mesh.normals[i]),
        ));
    }
    if let Some(i) = mesh
        .texcoords
        .iter()
        .position(|c| c.iter().any(|uv| !uv.is_finite()))
    {
        return Err(Error::invalid(
            STAGE,
            format!(
                "texcoords of triangle {i} are not finite: {:?}",
                mesh.texcoords[i]
            ),
        ));
    }
    let mut out = Vec::with_capacity(2 * local.vertices.len());
    for &t in &local.source {
        let tri = mesh.triangles[t as usize];
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        let face = (b - a).cross(c - a).normalize_or_zero();
        let uvs = mesh
            .texcoords
            .get(t as usize)
            .copied()
            .unwrap_or([glam::Vec2::ZERO; 3]);
        for (k, i) in tri.into_iter().enumerate() {
            let colour = mesh.colors.get(i as usize).copied().unwrap_or([255; 4]);
            let normal: DVec3 = mesh.normals.get(i as usize).copied().unwrap_or(face);
            let normal = normal.as_vec3();
            out.push([
                u32::from_le_bytes(colour),
                normal.x.to_bits(),
                normal.y.to_bits(),
                normal.z.to_bits(),
            ]);
            out.push([uvs[k].x.to_bits(), uvs[k].y.to_bits(), 0, 0]);
        }
    }
    Ok(out)
}

impl Voxelizer {
    /// Conservative surface voxels of `mesh` with each voxel's colour and normal averaged
    /// over the triangles that touch it. Submits twice: the number of occupied voxels is read
    /// back in between to size the compact list, so the future finishes only as the device is
    /// polled (a frame loop's `device.poll`, or `fieldkit::gpu::Context::block_on` with the `context` feature).
    /// To keep the read-back out of a frame, record the two halves yourself
    /// ([`Voxelizer::encode_attributes`], [`Voxelizer::encode_resolve_attributes`]).
    ///
    /// ```
    /// # async fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
    /// use fieldkit::glam::DVec3;
    /// let mut mesh = Mesh::uv_sphere(DVec3::ZERO, 1.0, 24, 12);
    /// mesh.colors = vec![[200, 40, 90, 255]; mesh.positions.len()];
    /// let grid = Grid { origin: DVec3::splat(-1.25), voxel: 2.5 / 32.0, size: [32, 32, 32] };
    /// let voxelizer = Voxelizer::new(device)?;
    /// let attributes = voxelizer.attributes(device, queue, &mesh, &grid).await?;
    /// let voxels = attributes.read(device, queue).await?;
    /// assert!(voxels.iter().all(|v| v.color == [200, 40, 90, 255]));
    /// # Ok(()) }
    /// ```
    pub async fn attributes(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Attributes, Error> {
        let encoder = |label| {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
        };
        let mut first = encoder("voxelize attributes");
        let pending = self.encode_attributes(device, &mut first, mesh, grid)?;
        queue.submit([first.finish()]);
        let occupied = pending.occupied(device, queue).await?;
        let mut second = encoder("voxelize attributes resolve");
        let attributes = self.encode_resolve_attributes(device, &mut second, pending, occupied)?;
        queue.submit([second.finish()]);
        Ok(attributes)
    }

    /// Scatter `attributes` into dense colour and normal 3D textures of the grid's size. The
    /// grid must fit the device's 3D texture limit (2048 per side by default).
    pub fn encode_attribute_volumes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        attributes: &Attributes,
    ) -> Result<AttributeVolumes, Error> {
        let [w, h, d] = attributes.surface.size;
        let max = device.limits().max_texture_dimension_3d;
        if w.max(h).max(d) > max {
            return Err(Error::Size {
                stage: volume_stage::STAGE,
                what: "largest grid side (3D texture side)",
                got: w.max(h).max(d) as u64,
                max: max as u64,
            });
        }
        let texture = |label, format| volume_texture(device, label, [w, h, d], format);
        let volumes = AttributeVolumes {
            colour: texture("voxel colour volume", wgpu::TextureFormat::Rgba8Unorm),
            normal: texture("voxel normal volume", wgpu::TextureFormat::Rgba8Snorm),
        };
        if attributes.count == 0 {
            return Ok(volumes);
        }
        let params = uniform(
            device,
            "voxel attribute volume params",
            &AttributeVolumeParams {
                grid: attributes.surface.size.into(),
                count: attributes.count,
            },
        );
        let (colour, normal) = (
            volumes.colour.create_view(&Default::default()),
            volumes.normal.create_view(&Default::default()),
        );
        let pipeline = ComputePipeline::cached(&self.attribute_pipelines.to_volumes, device, &[])?;
        let groups = attributes.count.div_ceil(64);
        let row = device.limits().max_compute_workgroups_per_dimension;
        pipeline.record(
            device,
            rec,
            &volume_stage::to_volumes::Resources {
                params: (&params).into(),
                voxels: (&attributes.voxels).into(),
                occupied: (&attributes.occupied).into(),
                colour: (&colour).into(),
                normal: (&normal).into(),
            },
            [groups.min(row), groups.div_ceil(row), 1],
            volume_stage::STAGE,
        )?;
        Ok(volumes)
    }

    /// Record the first half of [`Voxelizer::attributes`]: the conservative surface and the
    /// dense index of every occupied voxel.
    pub fn encode_attributes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<PendingAttributes, Error> {
        self.encode_attributes_with(device, rec, mesh, grid, None)
    }

    /// [`Voxelizer::encode_attributes`] with an `albedo` texture: each voxel's colour is the
    /// corners' colour × the albedo at the corners' texture coordinates ([`Mesh::texcoords`]),
    /// both interpolated at the voxel centre's closest point on the triangle, as the source's
    /// vertex stage passes texture coordinates on. The mesh needs texture coordinates; the
    /// texture a filterable colour format. A bake, made when the mesh or the grid changes: the
    /// mesh's upload and the outputs are new each call, and the caller keeps them.
    pub fn encode_attributes_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        albedo: Option<&wgpu::Texture>,
    ) -> Result<PendingAttributes, Error> {
        let albedo_view =
            AlbedoBinding::check(device, stage::STAGE, albedo, !mesh.texcoords.is_empty())?;
        let local = mesh.to_grid(grid)?;
        let bound = occupied_bound(&local, grid.size);
        let corner_data = corners(mesh, &local)?;
        let (listing, giants) = super::GpuListing::exact(&local, grid.size);
        let (occupancy, triangles) = self.bitset(device, &local, grid, &giants)?;
        let heavy = self.surface_into(
            device,
            rec,
            &self.surface,
            &occupancy,
            &triangles,
            (local.vertices.len() / 3) as u32,
            listing,
            grid,
        )?;
        let voxels = grid.voxels();
        let words = voxels.div_ceil(32);
        let blocks = words.div_ceil(BLOCK_WORDS);
        if blocks > device.limits().max_compute_workgroups_per_dimension as u64 {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "bitset blocks of 1024 words (voxels / 32768)",
                got: blocks,
                max: device.limits().max_compute_workgroups_per_dimension as u64,
            });
        }
        let storage = |label, size: u64, extra| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::STORAGE | extra,
                mapped_at_creation: false,
            })
        };
        let word_offsets = storage("voxel word offsets", words * 4, wgpu::BufferUsages::empty());
        let block_offsets = storage(
            "voxel block offsets",
            blocks * 4,
            wgpu::BufferUsages::empty(),
        );
        let total = storage("occupied voxels", 4, wgpu::BufferUsages::COPY_SRC);
        let params = uniform(
            device,
            "voxel compact params",
            &CompactParams {
                words: words as u32,
            },
        );
        let resources = |_| compact::scan_words::Resources {
            params: (&params).into(),
            occupancy: (&occupancy).into(),
            word_offsets: (&word_offsets).into(),
            block_offsets: (&block_offsets).into(),
        };
        let p = &self.attribute_pipelines;
        let scan_words = ComputePipeline::cached(&p.scan_words, device, &[])?;
        scan_words.record(
            device,
            rec,
            &resources(()),
            [blocks as u32, 1, 1],
            compact::STAGE,
        )?;
        let scan_blocks = ComputePipeline::cached(&p.scan_blocks, device, &[])?;

        scan_blocks.record(
            device,
            rec,
            &compact::scan_blocks::Resources {
                params: (&params).into(),
                block_offsets: (&block_offsets).into(),
                total: (&total).into(),
            },
            [1, 1, 1],
            compact::STAGE,
        )?;
        use wgpu::util::DeviceExt;
        let mut corner_data = corner_data;
        if corner_data.is_empty() {
            corner_data.push([0; 4]);
        }
        let corners = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize corner attributes"),
            contents: bytemuck::cast_slice(&corner_data),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Ok(PendingAttributes {
            bound,
            albedo: albedo_view,
            surface: Surface::new(grid.size, occupancy, local.degenerate),
            grid: *grid,
            triangles,
            corners,
            heavy,
            word_offsets,
            block_offsets,
            total,
            words: words as u32,
            count: (local.vertices.len() / 3) as u32,
        })
    }

    /// Record the second half of [`Voxelizer::attributes`] for `occupied` voxels (what
    /// [`PendingAttributes::occupied`] read): the sums, then the averages.
    pub fn encode_resolve_attributes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pending: PendingAttributes,
        occupied: u32,
    ) -> Result<Attributes, Error> {
        let limit = device.limits().max_storage_buffer_binding_size;
        let sum_bytes = occupied as u64 * SUMS * 4;
        if sum_bytes > limit {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "attribute sum bytes (32 per occupied voxel)",
                got: sum_bytes,
                max: limit,
            });
        }
        let buffer = |label, size: u64, usage| {
            crate::gpu::storage_buffer(device, label, size.max(16), usage)
        };
        let sums = buffer(
            "voxel attribute sums",
            sum_bytes,
            wgpu::BufferUsages::COPY_DST,
        );
        let voxels = buffer(
            "voxel attributes",
            occupied as u64 * 16,
            wgpu::BufferUsages::COPY_SRC,
        );
        rec.recorder().encoder.clear_buffer(&sums, 0, None);
        let params = pending.params(device, 0, pending.count);
        self.record_sums(device, rec, &pending, &params, &sums)?;
        self.record_averages(device, rec, &pending, &params, &sums, &voxels)?;
        Ok(Attributes {
            surface: pending.surface,
            count: occupied,
            occupied: pending.total,
            voxels,
        })
    }

    /// Every triangle's attributes added into the `sums` of the voxels it covers: light
    /// triangles in batches, then the giant and heavy ones walked by blocks.
    fn record_sums(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pending: &PendingAttributes,
        params: &wgpu::Buffer,
        sums: &wgpu::Buffer,
    ) -> Result<(), Error> {
        let PendingAttributes {
            surface,
            triangles,
            corners,
            heavy,
            word_offsets,
            block_offsets,
            count,
            albedo,
            ..
        } = pending;
        let p = &self.attribute_pipelines;
        let (albedo_view, sampler) = p.albedo.bind(device, albedo.as_ref());
        let accumulate = ComputePipeline::cached(&p.accumulate, device, &[])?;
        for (first, n) in batches(*count) {
            let params = pending.params(device, first, n);
            accumulate.record(
                device,
                rec,
                &stage::accumulate::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    corners: corners.into(),
                    occupancy: (&surface.occupancy).into(),
                    word_offsets: word_offsets.into(),
                    block_offsets: block_offsets.into(),
                    sums: sums.into(),
                    albedo: albedo_view.into(),
                    albedo_sampler: sampler.into(),
                },
                [n.div_ceil(64), 1, 1],
                stage::STAGE,
            )?;
        }
        if heavy.giant_blocks > 0 {
            let pipeline = ComputePipeline::cached(&p.accumulate_giant, device, &[])?;
            let bound = pipeline.bind(
                device,
                &stage::accumulate_giant::Resources {
                    params: params.into(),
                    triangles: triangles.into(),
                    corners: corners.into(),
                    occupancy: (&surface.occupancy).into(),
                    word_offsets: word_offsets.into(),
                    block_offsets: block_offsets.into(),
                    giants: (&heavy.giant_records).into(),
                    sums: sums.into(),
                    albedo: albedo_view.into(),
                    albedo_sampler: sampler.into(),
                },
            )?;
            run_walk(
                rec,
                "voxel attributes of giant triangles",
                pipeline,
                &bound,
                &heavy.giant_records,
                heavy.giant_blocks,
            );
        }
        if heavy.capacity > 0 {
            let pipeline = ComputePipeline::cached(&p.accumulate_heavy, device, &[])?;
            let bound = pipeline.bind(
                device,
                &stage::accumulate_heavy::Resources {
                    params: params.into(),
                    triangles: triangles.into(),
                    corners: corners.into(),
                    occupancy: (&surface.occupancy).into(),
                    word_offsets: word_offsets.into(),
                    block_offsets: block_offsets.into(),
                    work: (&heavy.work).into(),
                    work_count: (&heavy.work_count).into(),
                    sums: sums.into(),
                    albedo: albedo_view.into(),
                    albedo_sampler: sampler.into(),
                },
            )?;
            run_walk(
                rec,
                "voxel attributes of heavy triangles",
                pipeline,
                &bound,
                &heavy.dispatch,
                (heavy.capacity as u64).div_ceil(64),
            );
        }
        Ok(())
    }

    /// Each occupied voxel's sums divided into its averaged attributes, written to `voxels`.
    fn record_averages(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pending: &PendingAttributes,
        params: &wgpu::Buffer,
        sums: &wgpu::Buffer,
        voxels: &wgpu::Buffer,
    ) -> Result<(), Error> {
        let resolve = ComputePipeline::cached(&self.attribute_pipelines.resolve, device, &[])?;
        let groups = pending.words.div_ceil(64);
        let row = device.limits().max_compute_workgroups_per_dimension;
        resolve.record(
            device,
            rec,
            &stage::resolve::Resources {
                params: params.into(),
                occupancy: (&pending.surface.occupancy).into(),
                word_offsets: (&pending.word_offsets).into(),
                block_offsets: (&pending.block_offsets).into(),
                sums: sums.into(),
                voxels: voxels.into(),
            },
            [groups.min(row), groups.div_ceil(row), 1],
            stage::STAGE,
        )
    }

    /// Every stage of [`Voxelizer::attributes`] recorded into `rec` alone, no read-back in
    /// between: the list is sized by [`occupied_bound`] and [`Attributes::occupied`] holds
    /// the true count on the GPU, which [`super::view::VoxelView`], [`Attributes::read`] and
    /// [`Voxelizer::encode_attribute_volumes`] read. A bound past the device's storage binding
    /// (large triangles in a large grid) is [`Error::Size`]; use [`Voxelizer::attributes`]
    /// there.
    pub fn encode_attributes_in_one(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Attributes, Error> {
        self.encode_attributes_in_one_with(device, rec, mesh, grid, None)
    }

    /// [`Voxelizer::encode_attributes_in_one`] with an albedo texture
    /// ([`Voxelizer::encode_attributes_with`]).
    pub fn encode_attributes_in_one_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        albedo: Option<&wgpu::Texture>,
    ) -> Result<Attributes, Error> {
        let pending = self.encode_attributes_with(device, rec, mesh, grid, albedo)?;
        let bound = u32::try_from(pending.bound).map_err(|_| Error::Size {
            stage: stage::STAGE,
            what: "bound on occupied voxels (one list entry each)",
            got: pending.bound,
            max: u32::MAX as u64,
        })?;
        self.encode_resolve_attributes(device, rec, pending, bound)
    }
}
