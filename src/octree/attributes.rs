//! An octree's attributes (`octree/attributes`): each occupied voxel's colour and normal, and
//! every node's filtered from its children's.

use std::sync::OnceLock;

use super::{ENTRY_BYTES, Octree, OctreeAttributes, OctreeBuilder};
use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::AlbedoBinding;
use crate::gpu::{Readback, Record, readback_buffer, uniform_buffer as uniform};
use crate::shaders::octree::attributes::{self as stage, AttributeParams};
use crate::voxelize::{FragmentAttributes, Fragments, SLACK};

/// `u32` sums per occupied voxel (the shader's `SUMS`).
const SUMS: u64 = 8;

#[derive(Default)]
pub(super) struct AttributePipelines {
    accumulate: OnceLock<ComputePipeline<stage::accumulate::Entry>>,
    average: OnceLock<ComputePipeline<stage::average_voxels::Entry>>,
    resolve: OnceLock<ComputePipeline<stage::resolve::Entry>>,
    filter: OnceLock<ComputePipeline<stage::filter_level::Entry>>,
    albedo: AlbedoBinding,
}

impl Octree {
    /// The occupied voxels, read back once the encoder that built the tree from fragments with
    /// attributes ([`crate::voxelize::Voxelizer::encode_fragments_with_attributes`]) has been
    /// submitted: what [`OctreeBuilder::encode_attributes`] sizes its lists by.
    pub fn voxel_count(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<u32> {
        let leaf = self.leaf_level as usize;
        let built = self.brick_voxels.is_some();
        readback_buffer(device, queue, &self.starts).then(move |bytes| {
            if !built {
                return Err(Error::Invalid {
                    stage: stage::STAGE,
                    what: "the octree was built from fragments without attributes \
                           (Voxelizer::encode_fragments_with_attributes)"
                        .into(),
                });
            }
            let starts: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
            Ok(starts[leaf + 2] - starts[leaf + 1])
        })
    }
}

impl OctreeBuilder {
    /// Record `octree`'s attributes from `fragments` (made by
    /// [`crate::voxelize::Voxelizer::encode_fragments_with_attributes`], the tree built from
    /// them by [`OctreeBuilder::encode`]) for its `voxels` occupied voxels
    /// ([`Octree::voxel_count`]): integer sums per voxel (32 bytes each while they are
    /// summed, in batches of voxels that each fit the device's storage binding), then each
    /// voxel's average and each brick's, then every level's means up to the root. Sets
    /// [`Octree::attributes`].
    pub fn encode_attributes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &mut Octree,
        fragments: &Fragments,
        voxels: u32,
    ) -> Result<(), Error> {
        self.encode_attributes_with(device, rec, octree, fragments, voxels, None)
    }

    /// [`OctreeBuilder::encode_attributes`] with an `albedo` texture: each fragment's colour
    /// is the corners' colour × the albedo at the corners' texture coordinates, as
    /// [`crate::voxelize::Voxelizer::encode_attributes_with`] samples it (the same bytes for the
    /// same voxel). The mesh the fragments came from needs texture coordinates; the texture a
    /// filterable colour format.
    pub fn encode_attributes_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &mut Octree,
        fragments: &Fragments,
        voxels: u32,
        albedo: Option<&wgpu::Texture>,
    ) -> Result<(), Error> {
        let (inputs, brick_voxels, cursors) = attribute_inputs(octree, fragments)?;
        let albedo = AlbedoBinding::check(device, stage::STAGE, albedo, inputs.textured)?;
        let (batch, sums, attributes) = attribute_buffers(device, octree, voxels, brick_voxels)?;
        let grid = |n: u64| groups(device, n);
        let params = |level, first_voxel, fragments| {
            uniform(
                device,
                "octree attribute params",
                &AttributeParams {
                    grid: octree.size.into(),
                    level,
                    leaf_level: octree.leaf_level,
                    fragments,
                    capacity: octree.capacity,
                    first_voxel,
                    batch,
                    voxels,
                    slack: SLACK,
                    textured: albedo.is_some() as u32,
                },
            )
        };
        let p = &self.attributes;
        let accumulate = ComputePipeline::cached(&p.accumulate, device, &[])?;
        let average = ComputePipeline::cached(&p.average, device, &[])?;
        let (albedo_view, sampler) = p.albedo.bind(device, albedo.as_ref());
        for first in (0..voxels).step_by(batch as usize) {
            if first > 0 {
                rec.recorder().encoder.clear_buffer(&sums, 0, None);
            }
            for (part, cursor) in fragments.parts.iter().zip(cursors) {
                let params = params(octree.leaf_level, first, part.capacity);
                let Some(ids) = &part.triangle_ids else {
                    continue;
                };
                accumulate.record(
                    device,
                    rec,
                    &stage::accumulate::Resources {
                        params: (&params).into(),
                        fragments: (&part.list).into(),
                        triangle_ids: ids.into(),
                        triangles: (&inputs.triangles).into(),
                        corners: (&inputs.corners).into(),
                        cursor: cursor.into(),
                        pool: (&octree.pool).into(),
                        brick_voxels: brick_voxels.into(),
                        sums: (&sums).into(),
                        albedo: albedo_view.into(),
                        albedo_sampler: sampler.into(),
                    },
                    grid(part.capacity as u64),
                    stage::STAGE,
                )?;
            }
            let params = params(octree.leaf_level, first, 0);
            average.record(
                device,
                rec,
                &stage::average_voxels::Resources {
                    params: (&params).into(),
                    sums: (&sums).into(),
                    voxel_attributes: (&attributes.voxel_attributes).into(),
                },
                grid(batch as u64),
                stage::STAGE,
            )?;
        }
        self.record_nodes(device, rec, octree, brick_voxels, &attributes, &params)?;
        octree.attributes = Some(attributes);
        Ok(())
    }

    /// The leaves' attributes gathered from their voxels, then each level above filtered
    /// from its children, up to the root.
    fn record_nodes(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        octree: &Octree,
        brick_voxels: &wgpu::Buffer,
        attributes: &OctreeAttributes,
        params: &dyn Fn(u32, u32, u32) -> wgpu::Buffer,
    ) -> Result<(), Error> {
        let p = &self.attributes;
        let grid = |n: u64| groups(device, n);
        let leaf = params(octree.leaf_level, 0, 0);
        // Each level's nodes are at most the pool's entries and the level's cells.
        let nodes = |l: u32| 8u64.saturating_pow(l).min(octree.capacity as u64);
        ComputePipeline::cached(&p.resolve, device, &[])?.record(
            device,
            rec,
            &stage::resolve::Resources {
                params: (&leaf).into(),
                pool: (&octree.pool).into(),
                starts: (&octree.starts).into(),
                brick_voxels: brick_voxels.into(),
                voxel_attributes: (&attributes.voxel_attributes).into(),
                node_attributes: (&attributes.node_attributes).into(),
            },
            grid(nodes(octree.leaf_level)),
            stage::STAGE,
        )?;
        let filter = ComputePipeline::cached(&p.filter, device, &[])?;
        for level in (0..octree.leaf_level).rev() {
            let params = params(level, 0, 0);
            filter.record(
                device,
                rec,
                &stage::filter_level::Resources {
                    params: (&params).into(),
                    pool: (&octree.pool).into(),
                    starts: (&octree.starts).into(),
                    node_attributes: (&attributes.node_attributes).into(),
                },
                grid(nodes(level)),
                stage::STAGE,
            )?;
        }
        Ok(())
    }
}

/// What the attribute passes read of `octree` and `fragments`, or why they cannot run.
fn attribute_inputs<'a>(
    octree: &'a Octree,
    fragments: &'a Fragments,
) -> Result<(&'a FragmentAttributes, &'a wgpu::Buffer, &'a [wgpu::Buffer]), Error> {
    let (Some(inputs), Some(brick_voxels), Some(cursors)) =
        (&fragments.attributes, &octree.brick_voxels, &octree.cursor)
    else {
        return Err(Error::Invalid {
            stage: stage::STAGE,
            what: "attributes need fragments with attributes \
                   (Voxelizer::encode_fragments_with_attributes) and the tree built from them"
                .into(),
        });
    };
    if fragments.size != octree.size {
        return Err(Error::Invalid {
            stage: stage::STAGE,
            what: format!(
                "the fragments are of a {:?} grid, the octree of {:?}",
                fragments.size, octree.size
            ),
        });
    }
    if cursors.len() != fragments.parts.len()
        || fragments.parts.iter().any(|p| p.triangle_ids.is_none())
    {
        return Err(Error::Invalid {
            stage: stage::STAGE,
            what: "the octree was built from other fragments than these".into(),
        });
    }
    Ok((inputs, brick_voxels, cursors))
}

/// Workgroups of 64 threads for `n` items, rows of the device's most per dimension.
fn groups(device: &wgpu::Device, n: u64) -> [u32; 3] {
    let row = device.limits().max_compute_workgroups_per_dimension as u64;
    let groups = n.div_ceil(64).max(1);
    [groups.min(row) as u32, groups.div_ceil(row) as u32, 1]
}

/// The attribute passes' buffers: the sums of one batch of voxels (as many as one binding
/// holds), and the voxels' and nodes' attributes; [`Error::Size`] where the voxels' attributes
/// pass one binding.
fn attribute_buffers(
    device: &wgpu::Device,
    octree: &Octree,
    voxels: u32,
    brick_voxels: &wgpu::Buffer,
) -> Result<(u32, wgpu::Buffer, OctreeAttributes), Error> {
    let limit = device.limits().max_storage_buffer_binding_size;
    // Voxels whose sums one binding holds: the batches.
    let batch = (limit / (SUMS * 4)).min(voxels.max(1) as u64) as u32;
    if voxels as u64 * ENTRY_BYTES > limit {
        return Err(Error::Size {
            stage: stage::STAGE,
            what: "octree voxel attribute bytes (8 per occupied voxel)",
            got: voxels as u64 * ENTRY_BYTES,
            max: limit,
        });
    }
    let buffer =
        |label, size: u64, usage| crate::gpu::storage_buffer(device, label, size.max(16), usage);
    let sums = buffer(
        "octree attribute sums",
        batch as u64 * SUMS * 4,
        wgpu::BufferUsages::COPY_DST,
    );
    let attributes = OctreeAttributes {
        voxels,
        voxel_attributes: buffer(
            "octree voxel attributes",
            voxels as u64 * ENTRY_BYTES,
            wgpu::BufferUsages::COPY_SRC,
        ),
        node_attributes: buffer(
            "octree node attributes",
            octree.capacity as u64 * ENTRY_BYTES,
            wgpu::BufferUsages::COPY_SRC,
        ),
        brick_voxels: brick_voxels.clone(),
    };
    Ok((batch, sums, attributes))
}
