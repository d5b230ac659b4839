//! Sparse voxel octrees (`shaders/octree/`; OpenGL Insights ch. 22, Crassin & Green, part 2):
//! a voxelization whose memory grows with its occupied voxels, not with the grid, built on the
//! GPU level by level from the voxelizer's fragment list ([`crate::voxelize::Fragments`]).
//!
//! The tree covers a cube of 2^`log_side` voxels (the grid's largest side rounded up to a power
//! of two, at least 8). Its nodes are entries of two `u32` in one pool, breadth first:
//!
//! - an inner node is (child mask, entry of its first child): child octant `o` (x + 2y + 4z) is
//!   there when bit `o` is set, at entry `first + popcount(mask & ((1 << o) - 1))`;
//! - the nodes of the last level ([`Octree::leaf_level`]) cover 4³ voxels and are bricks of 64
//!   occupancy bits, voxel (x, y, z) of the brick at bit x + 4y + 16z.
//!
//! Level `l` is entries `starts[l] .. starts[l + 1]` (the root is entry 0); the children of a
//! level come in their parents' order, each parent's in octant order, so the layout is a
//! function of the voxels alone: two builds give the same bytes, and [`OctreeData::from_voxels`]
//! builds the same tree on the CPU.
//!
#![doc = include_str!("../../docs/octree.md")]

mod attributes;
mod cast;

pub use cast::{Casts, CellHit, Lod, OctreeCaster, OctreeImage, Ray, RenderSettings};

use std::sync::OnceLock;

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Readback, Record, readback_buffers, uniform_buffer as uniform};
use crate::shaders::octree::build::{self as stage, BuildParams};
use crate::voxelize::{Fragments, Grid, Mesh, Separation, Voxelizer};

/// Nodes one workgroup of `scan_nodes` covers (the shader's `BLOCK_NODES`).
const BLOCK_NODES: u64 = 1024;
/// Bytes per pool entry.
const ENTRY_BYTES: u64 = 8;
/// Smallest side of the tree's cube: a root above one level of bricks.
const MIN_LOG_SIDE: u32 = 3;

/// The octree build pipelines. Create once, build many times.
///
/// ```no_run
/// # async fn f(device: &wgpu::Device, queue: &wgpu::Queue, mesh: &fieldkit::voxelize::Mesh)
/// #     -> Result<(), fieldkit::Error> {
/// use fieldkit::octree::OctreeBuilder;
/// use fieldkit::voxelize::{Grid, Separation, Voxelizer};
/// let (voxelizer, builder) = (Voxelizer::new(device)?, OctreeBuilder::new(device)?); // once
/// let grid = Grid::fit(mesh, 4096)?;
/// // Finishes as the app's loop polls the device (its sizes come from counts read back).
/// let octree = builder.voxelize(device, queue, &voxelizer, mesh, &grid, Separation::Conservative).await?;
/// # let _ = octree; Ok(()) }
/// ```
pub struct OctreeBuilder {
    flag: OnceLock<ComputePipeline<stage::flag::Entry>>,
    scan_nodes: OnceLock<ComputePipeline<stage::scan_nodes::Entry>>,
    scan_blocks: OnceLock<ComputePipeline<stage::scan_blocks::Entry>>,
    link: OnceLock<ComputePipeline<stage::link::Entry>>,
    attributes: attributes::AttributePipelines,
}

/// A sparse voxel octree on the GPU (see the [module docs](self) for the layout).
pub struct Octree {
    /// Voxels per axis of the grid it was built from.
    pub size: [u32; 3],
    /// log2 of the side of the cube the tree covers.
    pub log_side: u32,
    /// The level of the 4³ bricks (`log_side − 2`); the root is level 0.
    pub leaf_level: u32,
    /// Entries `pool` holds.
    pub capacity: u32,
    /// Two `u32` per entry: inner nodes (child mask, first child), then bricks (64 bits).
    pub pool: wgpu::Buffer,
    /// `leaf_level + 3` `u32`: the first entry of each level, then the entries the tree
    /// needs (more than `capacity` when the pool was too small), then that plus the occupied
    /// voxels where the tree was built for attributes.
    pub starts: wgpu::Buffer,
    /// Colour and normal per voxel and per node, where they were built
    /// ([`OctreeBuilder::encode_attributes`], [`OctreeBuilder::voxelize_with_attributes`]).
    pub attributes: Option<OctreeAttributes>,
    /// Per brick, its first voxel among the occupied voxels (built with attributes).
    brick_voxels: Option<wgpu::Buffer>,
    /// Per fragment of each part, its brick (built with attributes).
    cursor: Option<Vec<wgpu::Buffer>>,
}

/// An octree's attributes: each occupied voxel's averaged colour and normal, and each node's
/// filtered from its children's.
pub struct OctreeAttributes {
    /// Occupied voxels.
    pub voxels: u32,
    /// Per occupied voxel, brick by brick in bit order, a `vec2<u32>`: RGBA8 colour and the
    /// normal as an octahedral pair of snorm16 (`0x80008000` where the normals cancel).
    pub voxel_attributes: wgpu::Buffer,
    /// Per pool entry, the node's (colour, normal) as above: a brick's the mean of its voxels',
    /// an inner node's the mean of its children's.
    pub node_attributes: wgpu::Buffer,
    /// Per pool entry, a `u32`; for a brick, the slot of its first voxel in
    /// `voxel_attributes`.
    pub brick_voxels: wgpu::Buffer,
}

/// An octree read back to the CPU ([`Octree::read`]), or built there
/// ([`OctreeData::from_voxels`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OctreeData {
    /// Voxels per axis of the grid.
    pub size: [u32; 3],
    /// log2 of the side of the cube the tree covers.
    pub log_side: u32,
    /// The level of the bricks.
    pub leaf_level: u32,
    /// The first entry of each level, then the number of entries.
    pub starts: Vec<u32>,
    /// The entries (see the [module docs](self)).
    pub pool: Vec<[u32; 2]>,
    /// Per occupied voxel, brick by brick in bit order: (RGBA8 colour, octahedral normal).
    /// Empty where the tree has no attributes.
    pub voxel_attributes: Vec<[u32; 2]>,
    /// Per entry: the node's filtered (colour, normal). Empty without attributes.
    pub node_attributes: Vec<[u32; 2]>,
    /// Per entry (bricks only), its first voxel's slot in `voxel_attributes`. Empty without
    /// attributes.
    pub brick_voxels: Vec<u32>,
}

/// log2 of the tree's cube for a grid of `size`.
pub fn log_side(size: [u32; 3]) -> u32 {
    let side = size.into_iter().max().unwrap_or(1).max(1);
    side.next_power_of_two().trailing_zeros().max(MIN_LOG_SIDE)
}

/// Octant x + 2y + 4z of the child of a level-(l − 1) node that holds voxel `v`.
fn octant(v: [u32; 3], log_side: u32, l: u32) -> u32 {
    let s = log_side - l;
    ((v[0] >> s) & 1) | (((v[1] >> s) & 1) << 1) | (((v[2] >> s) & 1) << 2)
}

fn brick_bit(v: [u32; 3]) -> u32 {
    (v[0] & 3) | ((v[1] & 3) << 2) | ((v[2] & 3) << 4)
}

impl OctreeData {
    /// The octree of a dense voxel grid (one `bool` per voxel, x fastest), built on the CPU
    /// with the GPU's layout: the reference the GPU build is tested against.
    pub fn from_voxels(occupied: &[bool], size: [u32; 3]) -> Result<OctreeData, Error> {
        let voxels = size.iter().map(|&n| n as u64).product::<u64>();
        if occupied.len() as u64 != voxels {
            return Err(Error::Invalid {
                stage: stage::STAGE,
                what: format!(
                    "{} voxels given for a grid of {size:?} ({voxels})",
                    occupied.len()
                ),
            });
        }
        let log_side = log_side(size);
        let leaf_level = log_side - 2;
        let [nx, ny, _] = size.map(|n| n as usize);
        let list: Vec<[u32; 3]> = occupied
            .iter()
            .enumerate()
            .filter(|(_, o)| **o)
            .map(|(i, _)| {
                [
                    (i % nx) as u32,
                    ((i / nx) % ny) as u32,
                    (i / (nx * ny)) as u32,
                ]
            })
            .collect();
        // Breadth first: each level's nodes as (cell, voxels in it), in entry order.
        let mut pool = vec![[0u32; 2]];
        let mut starts = vec![0u32, 1];
        let mut level: Vec<Vec<[u32; 3]>> = vec![list];
        for l in 0..leaf_level {
            let next_start = *starts.last().unwrap();
            let mut next = Vec::new();
            for (k, voxels) in level.iter().enumerate() {
                let mut children: [Vec<[u32; 3]>; 8] = Default::default();
                for &v in voxels {
                    children[octant(v, log_side, l + 1) as usize].push(v);
                }
                let mask = (0..8)
                    .filter(|&o| !children[o].is_empty())
                    .fold(0u32, |m, o| m | (1 << o));
                let e = starts[l as usize] as usize + k;
                pool[e] = [mask, next_start + next.len() as u32];
                next.extend(children.into_iter().filter(|c| !c.is_empty()));
            }
            pool.resize(pool.len() + next.len(), [0, 0]);
            starts.push(next_start + next.len() as u32);
            level = next;
        }
        let first = starts[leaf_level as usize] as usize;
        for (k, voxels) in level.iter().enumerate() {
            for &v in voxels {
                let bit = brick_bit(v);
                pool[first + k][(bit / 32) as usize] |= 1 << (bit % 32);
            }
        }
        Ok(OctreeData {
            size,
            log_side,
            leaf_level,
            starts,
            pool,
            voxel_attributes: Vec::new(),
            node_attributes: Vec::new(),
            brick_voxels: Vec::new(),
        })
    }

    /// The entry of the brick that holds voxel `v`, if the tree has one.
    pub fn brick_of(&self, v: [u32; 3]) -> Option<usize> {
        if (0..3).any(|k| v[k] >= self.size[k]) {
            return None;
        }
        let mut node = 0usize;
        for l in 1..=self.leaf_level {
            let [mask, first] = self.pool[node];
            let o = octant(v, self.log_side, l);
            if mask & (1 << o) == 0 {
                return None;
            }
            node = (first + (mask & ((1 << o) - 1)).count_ones()) as usize;
        }
        Some(node)
    }

    /// Voxel `v`'s (colour, normal), where it is occupied and the tree has attributes.
    pub fn voxel_attribute(&self, v: [u32; 3]) -> Option<[u32; 2]> {
        let e = self.brick_of(v)?;
        let bit = brick_bit(v);
        let [lo, hi] = self.pool[e];
        let bits = lo as u64 | (hi as u64) << 32;
        if bits & (1 << bit) == 0 {
            return None;
        }
        let first = *self.brick_voxels.get(e)?;
        let slot = first as usize + (bits & ((1u64 << bit) - 1)).count_ones() as usize;
        self.voxel_attributes.get(slot).copied()
    }

    /// Whether voxel `v` is occupied: a walk from the root.
    pub fn occupied(&self, v: [u32; 3]) -> bool {
        self.brick_of(v).is_some_and(|node| {
            let bit = brick_bit(v);
            self.pool[node][(bit / 32) as usize] & (1 << (bit % 32)) != 0
        })
    }

    /// The tree as a dense grid: one `bool` per voxel, x fastest.
    pub fn voxels(&self) -> Vec<bool> {
        let [nx, ny, nz] = self.size;
        let mut out = Vec::with_capacity(nx as usize * ny as usize * nz as usize);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    out.push(self.occupied([x, y, z]));
                }
            }
        }
        out
    }

    /// Nodes at each level, root first, bricks last.
    pub fn nodes_per_level(&self) -> Vec<u32> {
        self.starts.windows(2).map(|w| w[1] - w[0]).collect()
    }

    /// Bytes the tree takes on the GPU (8 per node, bricks included).
    pub fn bytes(&self) -> u64 {
        self.pool.len() as u64 * ENTRY_BYTES
    }
}

/// The pool entries a tree over `fragments` fragments can need at most: one node per fragment
/// per level, and no more than the level has cells.
pub fn pool_bound(fragments: u64, log_side: u32) -> u64 {
    (0..=log_side - 2)
        .map(|l| 8u64.saturating_pow(l).min(fragments.max(1)))
        .fold(0u64, u64::saturating_add)
}

fn pool_error(needed: u64, capacity: u32) -> Error {
    Error::Size {
        stage: stage::STAGE,
        what: "octree pool entries (8 bytes each; `got` is what the levels built so far need)",
        got: needed,
        max: capacity as u64,
    }
}

impl Octree {
    /// The first entry of each level and the entries the tree needs, read back once the
    /// encoder that built it has been submitted; [`Error::Size`] where the pool was too small
    /// (the levels past the one that ran out were not built, so the size it names is a lower
    /// bound; [`OctreeBuilder::voxelize`] retries until the tree fits).
    pub fn starts(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<u32>> {
        let (capacity, levels) = (self.capacity, self.leaf_level as usize + 2);
        readback_buffers(device, queue, &[&self.starts]).then(move |bytes| {
            let mut starts: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
            starts.truncate(levels);
            let needed = starts[levels - 1];
            if needed > capacity {
                return Err(pool_error(needed as u64, capacity));
            }
            Ok(starts)
        })
    }

    /// The whole tree, read back (checked as [`Octree::starts`] checks it).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<OctreeData> {
        let (capacity, size, log_side, leaf_level) =
            (self.capacity, self.size, self.log_side, self.leaf_level);
        let levels = (leaf_level + 2) as usize;
        let mut buffers = vec![&self.starts, &self.pool];
        if let Some(a) = &self.attributes {
            buffers.extend([&a.voxel_attributes, &a.node_attributes, &a.brick_voxels]);
        }
        let sizes: Vec<usize> = buffers.iter().map(|b| b.size() as usize).collect();
        let voxels = self.attributes.as_ref().map(|a| a.voxels as usize);
        readback_buffers(device, queue, &buffers).then(move |bytes| {
            let mut parts = Vec::new();
            let mut at = 0;
            for n in sizes {
                parts.push(&bytes[at..at + n]);
                at += n;
            }
            let mut starts: Vec<u32> = bytemuck::pod_collect_to_vec(parts[0]);
            starts.truncate(levels);
            let needed = starts[levels - 1] as usize;
            if needed > capacity as usize {
                return Err(pool_error(needed as u64, capacity));
            }
            let pairs = |b: &[u8], n: usize| -> Vec<[u32; 2]> {
                bytemuck::pod_collect_to_vec(&b[..n * ENTRY_BYTES as usize])
            };
            let pool = pairs(parts[1], needed);
            let (voxel_attributes, node_attributes, brick_voxels) = match voxels {
                Some(v) => (
                    pairs(parts[2], v),
                    pairs(parts[3], needed),
                    bytemuck::pod_collect_to_vec(&parts[4][..needed * 4]),
                ),
                None => Default::default(),
            };
            Ok(OctreeData {
                size,
                log_side,
                leaf_level,
                starts,
                pool,
                voxel_attributes,
                node_attributes,
                brick_voxels,
            })
        })
    }
}

impl OctreeBuilder {
    /// The builder (pipelines are made on first use).
    pub fn new(_device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            flag: OnceLock::new(),
            scan_nodes: OnceLock::new(),
            scan_blocks: OnceLock::new(),
            link: OnceLock::new(),
            attributes: Default::default(),
        })
    }

    /// Record the octree of `fragments` into `rec`, in a pool of `capacity` entries (8 bytes
    /// each): per level a pass over the fragments and three over the level's nodes, nothing
    /// read back. [`Octree::starts`] says afterwards whether the pool was large enough;
    /// [`OctreeBuilder::voxelize`] sizes it for you.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        fragments: &Fragments,
        capacity: u32,
    ) -> Result<Octree, Error> {
        let plan = BuildPlan::new(&device.limits(), fragments, capacity)?;
        let BuildPlan {
            log_side,
            leaf_level,
            widest,
            row,
            with_attributes,
            ..
        } = plan;
        let (octree, scratch) = plan.buffers(device, fragments);
        let BuildScratch {
            cursors,
            node_offsets,
            block_offsets,
            brick_slot,
        } = &scratch;
        let flag = ComputePipeline::cached(&self.flag, device, &[])?;
        let scan_nodes = ComputePipeline::cached(&self.scan_nodes, device, &[])?;
        let scan_blocks = ComputePipeline::cached(&self.scan_blocks, device, &[])?;
        let link = ComputePipeline::cached(&self.link, device, &[])?;
        let grid = |n: u64| [n.min(row) as u32, n.div_ceil(row) as u32, 1];
        let params_for = |level, fragments| {
            uniform(
                device,
                "octree build params",
                &BuildParams {
                    log_side,
                    level,
                    leaf_level,
                    fragments,
                    capacity,
                },
            )
        };
        for level in 0..=leaf_level {
            for (part, cursor) in fragments.parts.iter().zip(cursors) {
                let params = params_for(level, part.capacity);
                flag.record(
                    device,
                    rec,
                    &stage::flag::Resources {
                        params: (&params).into(),
                        fragments: (&part.list).into(),
                        fragment_count: (&part.total).into(),
                        cursor: cursor.into(),
                        pool: (&octree.pool).into(),
                    },
                    grid((part.capacity as u64).div_ceil(64).max(1)),
                    stage::STAGE,
                )?;
            }
            let params = params_for(level, 0);
            if level == leaf_level && !with_attributes {
                break;
            }
            let nodes = 8u64.saturating_pow(level).min(widest);
            scan_nodes.record(
                device,
                rec,
                &stage::scan_nodes::Resources {
                    params: (&params).into(),
                    pool: (&octree.pool).into(),
                    starts: (&octree.starts).into(),
                    node_offsets: node_offsets.into(),
                    block_offsets: block_offsets.into(),
                },
                grid(nodes.div_ceil(BLOCK_NODES)),
                stage::STAGE,
            )?;
            scan_blocks.record(
                device,
                rec,
                &stage::scan_blocks::Resources {
                    params: (&params).into(),
                    starts: (&octree.starts).into(),
                    block_offsets: block_offsets.into(),
                },
                [1, 1, 1],
                stage::STAGE,
            )?;
            link.record(
                device,
                rec,
                &stage::link::Resources {
                    params: (&params).into(),
                    pool: (&octree.pool).into(),
                    starts: (&octree.starts).into(),
                    node_offsets: node_offsets.into(),
                    block_offsets: block_offsets.into(),
                    brick_voxels: brick_slot.into(),
                },
                grid(nodes.div_ceil(64)),
                stage::STAGE,
            )?;
        }
        Ok(Octree {
            cursor: with_attributes.then_some(scratch.cursors),
            ..octree
        })
    }

    /// `octree` in a pool of the `needed` entries it uses (the estimate it was built in is
    /// larger): one copy, submitted.
    fn shrunk(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        octree: Octree,
        needed: u32,
    ) -> Octree {
        if needed >= octree.capacity {
            return octree;
        }
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("octree shrink"),
        });
        let mut copy = |from: &wgpu::Buffer, label, bytes| {
            let to = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: from.usage() | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_buffer_to_buffer(from, 0, &to, 0, bytes);
            to
        };
        let pool = copy(&octree.pool, "octree pool", needed as u64 * ENTRY_BYTES);
        // The bricks' first voxels, one u32 per entry, for attributes.
        let brick_voxels = octree
            .brick_voxels
            .as_ref()
            .map(|b| copy(b, "octree brick voxels", needed as u64 * 4));
        queue.submit([encoder.finish()]);
        Octree {
            pool,
            capacity: needed,
            brick_voxels,
            ..octree
        }
    }

    /// The octree of `mesh`'s surface voxels in `grid` (sides up to
    /// [`crate::voxelize::MAX_SPARSE_SIDE`]), its fragment list and pool sized for it: built
    /// with estimates, read back, and built again with the sizes the GPU counted where an
    /// estimate was short (the fragment count is exact; the pool grows at least a level per
    /// try); the pool is then copied into one of the entries the tree uses, so what stays
    /// allocated is 8 bytes per node. Submits its own work and waits for the counts, so the
    /// future finishes only as the device is polled.
    pub async fn voxelize(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxelizer: &Voxelizer,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
    ) -> Result<Octree, Error> {
        self.voxelize_inner(device, queue, voxelizer, mesh, grid, separation, None)
            .await
    }

    /// [`OctreeBuilder::voxelize`] (conservative) with attributes: each occupied voxel's
    /// colour and normal averaged over the triangles that touch it (the mesh's vertex colours
    /// and normals, as [`Voxelizer::attributes`] averages them: the same bytes for the same
    /// voxel), and every node's filtered from its children's ([`Octree::attributes`]).
    pub async fn voxelize_with_attributes(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxelizer: &Voxelizer,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Octree, Error> {
        self.voxelize_inner(
            device,
            queue,
            voxelizer,
            mesh,
            grid,
            Separation::Conservative,
            Some(None),
        )
        .await
    }

    /// [`OctreeBuilder::voxelize_with_attributes`] with an `albedo` texture: each voxel's
    /// colour is the corners' colour × the albedo at the corners' texture coordinates
    /// ([`Mesh::texcoords`](crate::voxelize::Mesh::texcoords)), averaged over the triangles
    /// that touch it, as [`Voxelizer::encode_attributes_with`] gives it (the same bytes for the
    /// same voxel). The mesh needs texture coordinates; the texture a filterable colour format.
    pub async fn voxelize_with_albedo(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxelizer: &Voxelizer,
        mesh: &Mesh,
        grid: &Grid,
        albedo: &wgpu::Texture,
    ) -> Result<Octree, Error> {
        // Refused before anything is built.
        crate::gpu::AlbedoBinding::check(
            device,
            crate::shaders::octree::attributes::STAGE,
            Some(albedo),
            !mesh.texcoords.is_empty(),
        )?;
        self.voxelize_inner(
            device,
            queue,
            voxelizer,
            mesh,
            grid,
            Separation::Conservative,
            Some(Some(albedo)),
        )
        .await
    }

    #[allow(clippy::too_many_arguments)]
    async fn voxelize_inner(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxelizer: &Voxelizer,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
        // With attributes: Some(the albedo, if any).
        attributes: Option<Option<&wgpu::Texture>>,
    ) -> Result<Octree, Error> {
        let mut fragment_capacity = None;
        let mut pool_capacity = None;
        let most = (device.limits().max_storage_buffer_binding_size / ENTRY_BYTES)
            .min(u32::MAX as u64) as u32;
        let log_side = log_side(grid.size);
        let leaf_level = log_side - 2;
        // A try builds at least one more level than the last, and the fragment list is sized
        // exactly after one: the levels and two more tries.
        for _ in 0..log_side + 2 {
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("octree voxelize"),
            });
            let fragments = if attributes.is_some() {
                voxelizer.encode_fragments_with_attributes(
                    device,
                    &mut encoder,
                    mesh,
                    grid,
                    fragment_capacity,
                )?
            } else {
                voxelizer.encode_fragments(
                    device,
                    &mut encoder,
                    mesh,
                    grid,
                    separation,
                    fragment_capacity,
                )?
            };
            let capacity = pool_capacity.unwrap_or_else(|| {
                let f = fragments.capacity();
                pool_bound(f, log_side).min(f / 8 + 4096).min(most as u64) as u32
            });
            let octree = self.encode(device, &mut encoder, &fragments, capacity)?;
            queue.submit([encoder.finish()]);
            let mut buffers: Vec<&wgpu::Buffer> =
                fragments.parts.iter().map(|p| &p.total).collect();
            buffers.push(&octree.starts);
            let bytes = readback_buffers(device, queue, &buffers).await?;
            let counts: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
            let (totals, starts) = counts.split_at(fragments.parts.len());
            let needed = starts[leaf_level as usize + 1];
            let short = fragments
                .parts
                .iter()
                .zip(totals)
                .filter(|(p, t)| **t > p.capacity)
                .map(|(_, &t)| t)
                .max();
            if let Some(total) = short {
                // Every part's list as long as the longest count (within one binding, where
                // the parts are cut again by the estimates).
                let most_fragments = (device.limits().max_storage_buffer_binding_size / 8)
                    .min(u32::MAX as u64) as u32;
                fragment_capacity = Some(total.min(most_fragments));
                pool_capacity = None;
                continue;
            }
            if needed > capacity {
                if capacity == most {
                    return Err(pool_error(needed as u64, capacity));
                }
                pool_capacity = Some((needed as u64 * 2).min(most as u64) as u32);
                continue;
            }
            let mut octree = self.shrunk(device, queue, octree, needed);
            if let Some(albedo) = attributes {
                let voxels = starts[leaf_level as usize + 2] - needed;
                let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some("octree attributes"),
                });
                self.encode_attributes_with(
                    device,
                    &mut encoder,
                    &mut octree,
                    &fragments,
                    voxels,
                    albedo,
                )?;
                queue.submit([encoder.finish()]);
            }
            return Ok(octree);
        }
        Err(Error::Invalid {
            stage: stage::STAGE,
            what: "the octree's sizes did not settle (a bug: please report it)".into(),
        })
    }
}

/// The sizes an octree build over a fragment list is planned for, checked against the device.
#[derive(Clone, Copy)]
struct BuildPlan {
    log_side: u32,
    leaf_level: u32,
    capacity: u32,
    /// The most nodes any level can have, which the scans are sized and dispatched for.
    widest: u64,
    blocks: u64,
    /// Workgroups per row of a dispatch (the device's limit per dimension).
    row: u64,
    with_attributes: bool,
}

/// The build's scratch: a cursor per fragment part, the scans' offsets, and the bricks'
/// voxel counts (a stand-in without attributes).
struct BuildScratch {
    cursors: Vec<wgpu::Buffer>,
    node_offsets: wgpu::Buffer,
    block_offsets: wgpu::Buffer,
    brick_slot: wgpu::Buffer,
}

impl BuildPlan {
    /// The plan for `fragments` in a pool of `capacity` entries; [`Error::Size`] where the pool
    /// or the build's threads pass the device's limits.
    fn new(limits: &wgpu::Limits, fragments: &Fragments, capacity: u32) -> Result<Self, Error> {
        let log_side = log_side(fragments.size);
        let leaf_level = log_side - 2;
        let most = (limits.max_storage_buffer_binding_size / ENTRY_BYTES).min(u32::MAX as u64);
        if capacity == 0 || capacity as u64 > most {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "octree pool entries (8 bytes each, the storage binding limit)",
                got: capacity as u64,
                max: most,
            });
        }
        let count = fragments.capacity();
        // The most nodes any level can have, which the scans are sized and dispatched for.
        // With attributes, the bricks' voxels are counted too: one more level of scans.
        let with_attributes = fragments.attributes.is_some();
        let scanned = leaf_level + with_attributes as u32;
        let widest = (0..scanned)
            .map(|l| 8u64.saturating_pow(l).min(count).min(capacity as u64))
            .max()
            .unwrap_or(1)
            .max(1);
        let blocks = widest.div_ceil(BLOCK_NODES);
        let row = limits.max_compute_workgroups_per_dimension as u64;
        let threads = count.max(widest);
        if threads.div_ceil(64) > row * row || blocks > row * row {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "octree build threads (fragments)",
                got: threads,
                max: row * row * 64,
            });
        }
        Ok(Self {
            log_side,
            leaf_level,
            capacity,
            widest,
            blocks,
            row,
            with_attributes,
        })
    }

    /// The tree's buffers (pool and level starts) and the build's scratch.
    fn buffers(&self, device: &wgpu::Device, fragments: &Fragments) -> (Octree, BuildScratch) {
        let Self {
            log_side,
            leaf_level,
            capacity,
            widest,
            blocks,
            with_attributes,
            ..
        } = *self;
        let buffer =
            |label, size: u64, usage| crate::gpu::storage_buffer(device, label, size.max(4), usage);
        let none = wgpu::BufferUsages::empty();
        let pool = buffer(
            "octree pool",
            capacity as u64 * ENTRY_BYTES,
            wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        );
        let starts = {
            use wgpu::util::DeviceExt;
            let mut init = vec![0u32; leaf_level as usize + 3];
            init[1] = 1;
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("octree level starts"),
                contents: bytemuck::cast_slice(&init),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            })
        };
        let cursors: Vec<wgpu::Buffer> = fragments
            .parts
            .iter()
            .map(|p| buffer("octree fragment cursors", p.capacity as u64 * 4, none))
            .collect();
        let node_offsets = buffer("octree node offsets", widest * 4, none);
        let block_offsets = buffer("octree block offsets", blocks * 4, none);
        let brick_voxels = with_attributes.then(|| {
            buffer(
                "octree brick voxels",
                capacity as u64 * 4,
                wgpu::BufferUsages::COPY_SRC,
            )
        });
        let brick_slot = brick_voxels
            .clone()
            .unwrap_or_else(|| buffer("no octree brick voxels", 4, none));
        let octree = Octree {
            size: fragments.size,
            log_side,
            leaf_level,
            capacity,
            pool,
            starts,
            attributes: None,
            brick_voxels: brick_voxels.clone(),
            cursor: None,
        };
        (
            octree,
            BuildScratch {
                cursors,
                node_offsets,
                block_offsets,
                brick_slot,
            },
        )
    }
}
