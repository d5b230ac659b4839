//! Blobs sorted into bins one support radius wide: what the direct tracer steps through and
//! what the SDF march reads near the surface (`shaders/shared/blobs.wesl`). [`Metaballs`]
//! keeps the bins' buffers, uniforms and bind groups from call to call (taken back once the
//! [`BlobBins`] holding them is dropped), so a frame that bins again makes no GPU object.

use glam::Vec3;

use super::{Instances, Metaballs, Settings, check_inputs, storage_buffer};
use crate::bind::{Group, KeptBound};
use crate::distance::Grid;
use crate::error::Error;
use crate::gpu::{KeptUniform, Lease, Leased, Record};
use crate::shaders::groups::blobs;
use crate::shaders::metaball::bin_blobs;
use crate::shaders::shared::blobs::BlobGrid;

/// Blobs sorted into a uniform grid of bins for tracing the field directly
/// ([`super::Raymarcher::encode_direct`]) and for the SDF march's exact shell (a
/// [`super::MetaballField`] built with [`Settings::exact_surface`]): each bin lists every blob
/// whose support overlaps it.
#[derive(Debug)]
pub struct BlobBins {
    /// Local-space corner of the bins' box, and the bin edge (at least the largest support
    /// radius).
    pub origin: Vec3,
    /// Edge of a bin, local units.
    pub bin_size: f32,
    /// Bins per axis.
    pub bins: [u32; 3],
    /// Per bin, its first entry in `items`, and the total at the end (`u32`).
    pub starts: wgpu::Buffer,
    /// Blobs in bin order: centre, support radius (`vec4<f32>`).
    pub items: wgpu::Buffer,
    /// The most blobs in a bin (`u32`), then the global Lipschitz bound (`f32`).
    pub stats: wgpu::Buffer,
    /// The cell of the grid the bins were fitted to: tolerances are in these units.
    pub cell: f32,
    /// The iso-level of the surface.
    pub threshold: f32,
    /// The bind group of `shared/blobs` over these bins, as the tracers bind it.
    pub group: Group<blobs::Entry>,
    /// The hold on the buffers: [`Metaballs`] takes them back for later bins once dropped.
    _lease: Lease,
}

impl BlobBins {
    /// The box's far corner.
    pub fn box_max(&self) -> Vec3 {
        self.origin + Vec3::from_array(self.bins.map(|b| b as f32)) * self.bin_size
    }
}

/// Most bins a [`BlobBins`] holds; beyond it bins grow wider.
pub const MAX_BINS: u32 = 1 << 21;

/// The buffers of one set of bins, kept and handed out again.
#[derive(Clone)]
struct BinSet {
    bins: [u32; 3],
    capacity: u64,
    counts: wgpu::Buffer,
    starts: wgpu::Buffer,
    items: wgpu::Buffer,
    stats: wgpu::Buffer,
    /// The shared group, with the grid uniform it was made with.
    group: Option<(wgpu::Buffer, Group<blobs::Entry>)>,
}

impl BinSet {
    fn new(device: &wgpu::Device, bins: [u32; 3], capacity: u64) -> Self {
        let bin_total = bins.iter().map(|&b| b as u64).product::<u64>();
        let storage = |label: &str, bytes: u64| storage_buffer(device, label, bytes);
        Self {
            bins,
            capacity,
            counts: storage("blob bin counts", bin_total * 4),
            starts: storage("blob bin starts", (bin_total + 1) * 4),
            items: storage("blob bin items", capacity.max(1) * 16),
            stats: storage("blob bin stats", 8),
            group: None,
        }
    }
}

/// What [`Metaballs::encode_bins`] keeps from call to call.
#[derive(Default)]
pub(super) struct BinsKept {
    sets: Leased<BinSet>,
    params: KeptUniform,
    grid: KeptUniform,
    count: KeptBound<bin_blobs::bin_count::Entry>,
    scan: KeptBound<bin_blobs::bin_scan::Entry>,
    fill: KeptBound<bin_blobs::bin_fill::Entry>,
    bound: KeptBound<bin_blobs::bin_bound::Entry>,
}

/// Bins per axis and their edge for blobs of support radius up to `r_max` over `extent`.
fn bin_layout(extent: Vec3, r_max: f32) -> ([u32; 3], f32) {
    let mut bin_size = if r_max > 0.0 {
        r_max
    } else {
        extent.max_element()
    };
    let count_bins = |size: f32| (extent / size).ceil().max(Vec3::ONE);
    let n = count_bins(bin_size);
    let total = n.x as f64 * n.y as f64 * n.z as f64;
    if total > MAX_BINS as f64 {
        bin_size *= ((total / MAX_BINS as f64).cbrt() * 1.001) as f32;
    }
    let n = count_bins(bin_size);
    ([n.x as u32, n.y as u32, n.z as u32], bin_size)
}

/// A stand-in for the `shared/blobs` group where a march has no blobs to read (`present` 0).
pub(crate) fn absent_group(device: &wgpu::Device) -> Result<Group<blobs::Entry>, Error> {
    let grid = crate::gpu::uniform_buffer(
        device,
        "no blobs",
        &BlobGrid {
            origin: Vec3::ZERO,
            bin_size: 1.0,
            bins: glam::UVec3::ONE,
            present: 0,
        },
    );
    let empty = storage_buffer(device, "no blobs", 16);
    Group::new(
        device,
        &blobs::Resources {
            blob_grid: (&grid).into(),
            blob_starts: (&empty).into(),
            blob_items: (&empty).into(),
            blob_stats: (&empty).into(),
        },
    )
}

impl Metaballs {
    /// Sort `instances` into bins over `grid`'s box for direct tracing: count, scan, fill, and
    /// the global Lipschitz bound. Bins are one largest support radius wide, and at least a
    /// unit-scale blob's (wider if there would be more than [`MAX_BINS`]), so a blob lands in at
    /// most 27. The bins' buffers come back to
    /// this `Metaballs` once the [`BlobBins`] is dropped, for the next call of the same layout.
    pub fn encode_bins(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        instances: &Instances,
        grid: &Grid,
        edge: f32,
        settings: &Settings,
    ) -> Result<BlobBins, Error> {
        check_inputs(settings, edge, grid, bin_blobs::STAGE)?;
        let extent = Vec3::from_array(grid.size.map(|s| s as f32)) * (grid.voxel as f32);
        // At least a unit-scale blob's radius: an animation whose scales pulse below 1 keeps
        // one layout (and so its uniforms and bind groups) from frame to frame.
        let widest = settings.radius(edge, instances.max_scale.max(1.0));
        let (bins, bin_size) = bin_layout(extent, widest);
        let bin_total = bins.iter().product::<u32>();
        let capacity = instances.count as u64 * 27;
        let max_binding = device.limits().max_storage_buffer_binding_size;
        if capacity.max(1) * 16 > max_binding {
            return Err(Error::Size {
                stage: bin_blobs::STAGE,
                what: "bin entries (27 per instance, 16 bytes each)",
                got: capacity,
                max: max_binding / 16,
            });
        }
        let kept = &self.bins;
        let (set, lease) = kept.sets.take(
            |s| s.bins == bins && s.capacity == capacity,
            || BinSet::new(device, bins, capacity),
        );
        let origin = grid.origin.as_vec3();
        let params = kept.params.get(
            device,
            "blob bin params",
            &bin_blobs::BinParams {
                bins: bins.into(),
                count: instances.count,
                origin,
                bin_size,
                radius_per_scale: settings.radius(edge, 1.0),
                capacity: capacity as u32,
            },
        );
        let mut rec = rec.recorder();
        rec.encoder.clear_buffer(&set.counts, 0, None);
        rec.encoder.clear_buffer(&set.stats, 0, None);
        let per_instance = [instances.count.div_ceil(64).max(1), 1, 1];
        let count = self.bin_count.bind_kept(
            device,
            &kept.count,
            &bin_blobs::bin_count::Resources {
                params: (&params).into(),
                instances: (&instances.buffer).into(),
                counts: (&set.counts).into(),
            },
        )?;
        let scan = self.bin_scan.bind_kept(
            device,
            &kept.scan,
            &bin_blobs::bin_scan::Resources {
                params: (&params).into(),
                counts: (&set.counts).into(),
                starts: (&set.starts).into(),
                stats: (&set.stats).into(),
            },
        )?;
        let fill = self.bin_fill.bind_kept(
            device,
            &kept.fill,
            &bin_blobs::bin_fill::Resources {
                params: (&params).into(),
                instances: (&instances.buffer).into(),
                counts: (&set.counts).into(),
                starts: (&set.starts).into(),
                items: (&set.items).into(),
            },
        )?;
        let bound = self.bin_bound.bind_kept(
            device,
            &kept.bound,
            &bin_blobs::bin_bound::Resources {
                params: (&params).into(),
                starts: (&set.starts).into(),
                items: (&set.items).into(),
                stats: (&set.stats).into(),
            },
        )?;
        let mut pass = rec.compute_pass(bin_blobs::STAGE, "bins");
        if instances.count > 0 {
            self.bin_count.dispatch(&mut pass, &count, per_instance);
        }
        self.bin_scan.dispatch(&mut pass, &scan, [1, 1, 1]);
        if instances.count > 0 {
            self.bin_fill.dispatch(&mut pass, &fill, per_instance);
        }
        self.bin_bound
            .dispatch(&mut pass, &bound, [bin_total.div_ceil(64), 1, 1]);
        drop(pass);
        let group = self.bins_group(device, &set, &lease, origin, bin_size)?;
        Ok(BlobBins {
            origin,
            bin_size,
            bins,
            starts: set.starts,
            items: set.items,
            stats: set.stats,
            cell: (grid.voxel as f32),
            threshold: settings.threshold,
            group,
            _lease: lease,
        })
    }

    /// The `shared/blobs` group over `set`, kept with it while its grid stays.
    fn bins_group(
        &self,
        device: &wgpu::Device,
        set: &BinSet,
        lease: &Lease,
        origin: Vec3,
        bin_size: f32,
    ) -> Result<Group<blobs::Entry>, Error> {
        let grid = self.bins.grid.get(
            device,
            "blob grid",
            &BlobGrid {
                origin,
                bin_size,
                bins: set.bins.into(),
                present: 1,
            },
        );
        if let Some((held, group)) = &set.group
            && *held == grid
        {
            return Ok(group.clone());
        }
        let group = Group::new(
            device,
            &blobs::Resources {
                blob_grid: (&grid).into(),
                blob_starts: (&set.starts).into(),
                blob_items: (&set.items).into(),
                blob_stats: (&set.stats).into(),
            },
        )?;
        let made = (grid, group.clone());
        self.bins.sets.update(lease, |s| s.group = Some(made));
        Ok(group)
    }
}
