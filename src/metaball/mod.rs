//! Metaball voxels: a voxel set (centres and scales) splatted into a density grid, iso-surface
//! seeds, a signed distance field by JFA, and a raymarched surface (see [`Raymarcher`]).
//!
#![doc = include_str!("../../docs/metaball.md")]

mod bins;
pub mod cpu;
mod cubes;
mod field;
mod layout;
mod ray_settings;
mod render;

pub use bins::{BlobBins, MAX_BINS};
pub use cubes::{CubeStyle, Cubes};
pub use layout::{Animation, MAX_PACKED, animate, extent_grid, packed_grid, region_for_extent};
pub use render::{Direct, Filter, Marched, Material, Output, RayEnd, RaymarchSettings, Raymarcher};

use glam::{Vec3, Vec4};

use crate::bind::ComputePipeline;
use crate::distance::{Distance3d, Grid, MAX_POINTS, Method, Variant};
use crate::error::Error;
use crate::shaders::metaball::{bin_blobs, march_field, splat, surface_seeds};

const STAGE: &str = "metaball";

/// Fixed-point units per unit density in the splat, as the source used; lowered when many
/// instances could overflow a u32 sum (see [`fixed_scale`]).
pub const FIXED_SCALE: f32 = 10000.0;

/// The fixed-point scale for `count` instances: no voxel gets more than one contribution (≤ 1)
/// per instance, so `count × scale` must fit in a u32.
pub fn fixed_scale(count: u32) -> f32 {
    FIXED_SCALE.min((u32::MAX / count.max(1)) as f32).floor()
}

/// How the voxel set becomes a field.
///
/// [`Settings::default`] is fieldkit's choice; [`Settings::seed`] is the source's (the voxel
/// actor: support radius × 1.5, a full-volume field by 26-neighbour JFA).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(default))]
pub struct Settings {
    /// Iso-level of the surface (the source used 0.5).
    pub threshold: f32,
    /// Support radius = edge × scale × ½ × overlap × falloff_extend.
    pub overlap: f32,
    /// Extra factor on the support radius, on top of `overlap`: 1 by default, 1.5 in the
    /// source's `falloffExtend` ([`Settings::seed`]), whose blobs are 1.5 times as wide at equal
    /// overlap.
    pub falloff_extend: f32,
    /// Grid cells per voxel edge when the grid is fitted ([`Settings::fit_grid`]).
    pub cells_per_edge: f32,
    /// Distances the SDF must hold, in cells: the line passes scan this far, JFA starts at the
    /// power of two above it, and the field is clamped to ±band (what the raymarcher's steps
    /// need, no more).
    pub band: f32,
    /// How the distance stage finds each voxel's nearest seed: [`Method::Lines`] (default; 3.7×
    /// faster than JFA+2 on the H100 at 128³, same raymarched surface error) or
    /// [`Method::Jfa`] (nearer seeds away from the surface). The exact transform takes integer
    /// seeds only and is refused.
    pub method: Method,
    /// A field over the whole volume instead of the band: JFA from half the grid, no clamp, and
    /// voxels no seed reached (an empty set) at −one cell inside and [`FULL_VOLUME_FAR`] outside,
    /// as the source writes them. For users who read the SDF elsewhere; the raymarch needs only
    /// the band. Needs [`Method::Jfa`] (the line passes scan a band).
    pub full_volume: bool,
    /// When to bin the blobs with the field ([`MetaballField::bins`]) so that the SDF march
    /// decides crossings on the blobs' own field within two cells of the surface: the
    /// texture's trilinear density moves the surface by up to about a tenth of a cell at 4
    /// cells per blob edge, and a ray at a grazing angle may cross the true surface only that
    /// deep (`tests/metaball/grazing.rs`). It costs what tracing the blobs near the surface
    /// costs (`docs/metaball.md`), so by default only up to [`EXACT_SURFACE_UP_TO`] blobs;
    /// off in [`Settings::seed`] (the source marches the texture alone).
    pub exact_surface: ExactSurface,
}

/// When a metaball field keeps its blobs for an exact surface ([`Settings::exact_surface`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ExactSurface {
    /// The texture alone.
    Off,
    /// Always.
    On,
    /// For sets of at most this many blobs.
    UpTo(u32),
}

/// The blob count up to which a default field keeps its blobs for an exact surface: on the
/// H200 at 1080p the exact surface of 100 blobs seen low over the set costs 1.4 ms a frame
/// against 0.18 for the texture alone, and the viewer's island of 225 blobs 1.5 ms against
/// 0.1 (`docs/metaball.md`).
pub const EXACT_SURFACE_UP_TO: u32 = 128;

impl ExactSurface {
    /// Whether a set of `count` blobs keeps its blobs.
    pub fn applies(self, count: u32) -> bool {
        match self {
            Self::Off => false,
            Self::On => true,
            Self::UpTo(n) => count <= n,
        }
    }
}

impl Default for ExactSurface {
    fn default() -> Self {
        Self::UpTo(EXACT_SURFACE_UP_TO)
    }
}

/// The distance the full-volume field gives a voxel outside that no seed reached (the source's
/// 1e6, in local units).
pub const FULL_VOLUME_FAR: f32 = 1.0e6;

impl Default for Settings {
    fn default() -> Self {
        Self {
            threshold: 0.5,
            overlap: 2.0,
            cells_per_edge: 4.0,
            band: 8.0,
            method: Method::Lines,
            falloff_extend: 1.0,
            full_volume: false,
            exact_surface: ExactSurface::default(),
        }
    }
}

impl Settings {
    /// The source's voxel actor: the support radius × `falloffExtend` = 1.5 on top of the
    /// overlap of 2, and its distance step, a full-volume field by plain 26-neighbour JFA
    /// ([`Variant::Jfa`]). fieldkit's default keeps the radius without the extra factor (the
    /// source's blobs merge into one lump at block spacing) and a band of 8 cells by the line
    /// passes: the raymarch reads the field only within the band, and on the H100 the band
    /// built by the line passes is 3.7× faster than JFA+2 over the volume (`docs/metaball.md`).
    pub fn seed() -> Self {
        Self {
            falloff_extend: 1.5,
            method: Method::Jfa(Variant::Jfa),
            full_volume: true,
            exact_surface: ExactSurface::Off,
            ..Self::default()
        }
    }

    fn check(&self) -> Result<(), Error> {
        let bad = |what: &str, v: f32| Error::Invalid {
            stage: STAGE,
            what: format!("{what} must be finite and positive, got {v}"),
        };
        if !(self.threshold.is_finite() && self.threshold > 0.0 && self.threshold < 1.0) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("threshold must be in (0, 1), got {}", self.threshold),
            });
        }
        for (what, v) in [
            ("overlap", self.overlap),
            ("falloff_extend", self.falloff_extend),
            ("cells_per_edge", self.cells_per_edge),
            ("band", self.band),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(what, v));
            }
        }
        if self.method == Method::Exact {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "method: the exact transform takes integer seeds; the surface seeds are \
                       sub-voxel (use Method::Lines or Method::Jfa)"
                    .into(),
            });
        }
        if self.full_volume && self.method == Method::Lines {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "full_volume needs Method::Jfa: the line passes scan only the band".into(),
            });
        }
        Ok(())
    }

    /// Support radius of an instance of scale `scale`: edge × scale × ½ × overlap ×
    /// falloff_extend.
    pub fn radius(&self, edge: f32, scale: f32) -> f32 {
        edge * scale * 0.5 * self.overlap * self.falloff_extend
    }

    /// A grid fitted to the instances' support (plus one cell), with cells of
    /// `edge / cells_per_edge`. `None` for an empty set or one whose scales are all zero.
    pub fn fit_grid(&self, voxels: &[Vec4], edge: f32) -> Result<Option<Grid>, Error> {
        self.check()?;
        check_voxels(voxels, edge)?;
        let cell = edge / self.cells_per_edge;
        if !(cell.is_finite() && cell >= f32::MIN_POSITIVE) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "cell size edge / cells_per_edge = {edge} / {} = {cell} is not a normal \
                     positive number",
                    self.cells_per_edge
                ),
            });
        }
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for v in voxels.iter().filter(|v| v.w > 0.0) {
            let r = self.radius(edge, v.w);
            lo = lo.min(v.truncate() - r);
            hi = hi.max(v.truncate() + r);
        }
        if lo.x > hi.x {
            return Ok(None);
        }
        let lo = lo - cell;
        let hi = hi + cell;
        // At least one cell per axis; a span that overflows f32 is infinitely many (refused below).
        let cells = ((hi - lo) / cell).ceil().max(Vec3::ONE);
        let count = |c: f32| if c.is_finite() { c as u64 } else { u64::MAX };
        let size = [count(cells.x), count(cells.y), count(cells.z)];
        let max = crate::distance::MAX_SIDE_3D;
        for (i, what) in ["grid width", "grid height", "grid depth"]
            .into_iter()
            .enumerate()
        {
            if size[i] > max[i] as u64 {
                return Err(Error::Size {
                    stage: STAGE,
                    what,
                    got: size[i],
                    max: max[i] as u64,
                });
            }
        }
        let size = [size[0] as u32, size[1] as u32, size[2] as u32];
        // Centre the grid on the support so the extra fraction of a cell is split evenly.
        let extent = Vec3::new(size[0] as f32, size[1] as f32, size[2] as f32) * cell;
        Ok(Some(Grid {
            size,
            voxel: cell as f64,
            origin: ((lo + hi) * 0.5 - extent * 0.5).as_dvec3(),
        }))
    }
}

/// The band of a full-volume field: no distance between two voxels of `grid` is longer than its
/// diagonal (what the SDF debug view scales by; unreached voxels lie beyond it).
fn full_band(grid: &Grid) -> f32 {
    Vec3::from_array(grid.size.map(|s| s as f32)).length() * (grid.voxel as f32)
}

/// Settings, voxel edge and grid placement, checked before any stage is encoded.
fn check_inputs(
    settings: &Settings,
    edge: f32,
    grid: &Grid,
    stage: &'static str,
) -> Result<(), Error> {
    settings.check()?;
    check_voxels(&[], edge)?;
    // The stages place the field in f32.
    grid.as_f32(stage)?;
    Ok(())
}

/// A storage buffer the stages write and tests read back (at least 4 bytes: empty sets still
/// bind something).
fn storage_buffer(device: &wgpu::Device, label: &str, bytes: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes.max(4),
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn max_scale(voxels: &[Vec4]) -> f32 {
    voxels.iter().map(|v| v.w).fold(0.0, f32::max)
}

fn centre_bounds(voxels: &[Vec4]) -> [Vec3; 2] {
    if voxels.is_empty() {
        return [Vec3::ZERO; 2];
    }
    voxels.iter().fold(
        [Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)],
        |[lo, hi], v| [lo.min(v.truncate()), hi.max(v.truncate())],
    )
}

fn check_voxels(voxels: &[Vec4], edge: f32) -> Result<(), Error> {
    if !(edge.is_finite() && edge > 0.0) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("voxel edge must be finite and positive, got {edge}"),
        });
    }
    if let Some((i, v)) = voxels
        .iter()
        .enumerate()
        .find(|(_, v)| !v.is_finite() || v.w < 0.0)
    {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "voxel {i} has centre {} and scale {}: centres must be finite and scales finite and ≥ 0",
                v.truncate(),
                v.w
            ),
        });
    }
    Ok(())
}

/// Instances on the GPU: one vec4 (centre, scale) each, for the splat and the debug cubes.
#[derive(Debug)]
pub struct Instances {
    /// `vec4<f32>` per instance.
    pub buffer: wgpu::Buffer,
    /// Number of instances.
    pub count: u32,
    /// The largest scale uploaded: it sizes the bins of direct tracing.
    pub max_scale: f32,
    /// Least and greatest centre uploaded (local units; both zero for an empty set): the debug
    /// cubes' frustum culling.
    pub centres: [Vec3; 2],
}

/// Everything a metaball field keeps on the GPU.
#[derive(Debug)]
pub struct MetaballField {
    /// The grid the field lives on.
    pub grid: Grid,
    /// Fixed-point density sums (u32 per voxel) and the scale they use.
    pub density_fixed: wgpu::Buffer,
    /// Density = fixed / `fixed_scale`.
    pub fixed_scale: f32,
    /// Density as `R32Float`.
    pub density: wgpu::Texture,
    /// Seed points (voxel coordinates, w = 1 for a seed), indexed by voxel.
    pub points: wgpu::Buffer,
    /// Nearest seed key per voxel after JFA.
    pub nearest: wgpu::Buffer,
    /// Signed distance (`R32Float`, local units, negative inside, clamped to ±band).
    pub sdf: wgpu::Texture,
    /// The clamp of `sdf`, local units.
    pub band: f32,
    /// The iso-level of the surface.
    pub threshold: f32,
    /// What the raymarch reads: distance in cells (r) and density (g) as `Rgba16Float`, one
    /// filtered fetch for both.
    pub march: wgpu::Texture,
    /// The blobs in bins, which the SDF march reads near the surface
    /// ([`Settings::exact_surface`]); `None` when the setting is off.
    pub bins: Option<BlobBins>,
    /// The hold on these: [`Metaballs`] takes them back for a later field once dropped.
    _lease: crate::gpu::Lease,
}

impl MetaballField {
    /// What the SDF march reads of this field.
    pub fn march_field(&self) -> MarchField<'_> {
        MarchField {
            march: &self.march,
            grid: self.grid,
            band: self.band,
            threshold: self.threshold,
            blobs: self.bins.as_ref(),
        }
    }
}

/// A signed distance field as [`Raymarcher::encode_march_field`] reads it: any field, not only
/// a metaball one, in the march's own format.
#[derive(Clone, Copy, Debug)]
pub struct MarchField<'a> {
    /// `Rgba16Float` 3D texture over `grid`, filterable: red the signed distance in cells
    /// (negative inside), green a density that is at or above `threshold` exactly inside
    /// (`-distance` with threshold 0 serves); the march steps by red and finds the surface,
    /// its normal and its crossings from green.
    pub march: &'a wgpu::Texture,
    /// Where the texels sit (local units: the march's `local_to_world` places them).
    pub grid: Grid,
    /// The clamp of the distances, local units: where red reaches it the march may step that far.
    pub band: f32,
    /// The density of the surface.
    pub threshold: f32,
    /// The blobs whose field `march` samples, for an exact surface: within two cells of the
    /// texture's surface the march steps through their own field (segment tracing) and finds
    /// the crossing and the normal on it. `None` marches the texture alone.
    pub blobs: Option<&'a BlobBins>,
}

/// Output of the splat and surface-seed stages.
#[derive(Debug)]
pub struct SurfaceSeeds {
    /// Fixed-point density sums, `u32` per voxel.
    pub density_fixed: wgpu::Buffer,
    /// Density = fixed / `fixed_scale`.
    pub fixed_scale: f32,
    /// The density as an `R32Float` 3D texture.
    pub density: wgpu::Texture,
    /// Seed key per voxel: `point_key(voxel index, offset)`, 0 for none.
    pub keys: wgpu::Buffer,
    /// Seed point per voxel (voxel coordinates, w = 1 for a seed, zero elsewhere).
    pub points: wgpu::Buffer,
}

/// The field pipelines. Create once, encode many times.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
/// use fieldkit::metaball::{packed_grid, Metaballs, Settings};
/// let balls = Metaballs::new(device)?; // once
/// let voxels = packed_grid([6, 4, 3], 1.0)?; // centres and scales
/// let settings = Settings::default();
/// let instances = balls.upload(device, queue, &voxels)?;
/// if let Some(grid) = settings.fit_grid(&voxels, 1.0)? {
///     let mut encoder = device.create_command_encoder(&Default::default());
///     let field = balls.encode(device, &mut encoder, &instances, &grid, 1.0, &settings)?;
///     queue.submit([encoder.finish()]); // field: the SDF a `Raymarcher` draws
///     # let _ = field;
/// }
/// # Ok(()) }
/// ```
pub struct Metaballs {
    splat: ComputePipeline<splat::splat::Entry>,
    seeds: ComputePipeline<surface_seeds::surface_seeds::Entry>,
    pack: ComputePipeline<march_field::march_field::Entry>,
    bin_count: ComputePipeline<bin_blobs::bin_count::Entry>,
    bin_scan: ComputePipeline<bin_blobs::bin_scan::Entry>,
    bin_fill: ComputePipeline<bin_blobs::bin_fill::Entry>,
    bin_bound: ComputePipeline<bin_blobs::bin_bound::Entry>,
    distance: Distance3d,
    /// What `encode` keeps from call to call.
    field: field::FieldKept,
    /// What `encode_bins` keeps from call to call.
    bins: bins::BinsKept,
}

impl Metaballs {
    /// Create every metaball pipeline.
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            splat: ComputePipeline::new(device)?,
            seeds: ComputePipeline::new(device)?,
            pack: ComputePipeline::new(device)?,
            bin_count: ComputePipeline::new(device)?,
            bin_scan: ComputePipeline::new(device)?,
            bin_fill: ComputePipeline::new(device)?,
            bin_bound: ComputePipeline::new(device)?,
            distance: Distance3d::new(device)?,
            field: Default::default(),
            bins: Default::default(),
        })
    }

    /// Upload a voxel set (xyz: centre, w: scale). NaN or infinite centres, and negative or
    /// non-finite scales, are refused.
    pub fn upload(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        voxels: &[Vec4],
    ) -> Result<Instances, Error> {
        check_voxels(voxels, 1.0)?;
        // 16 bytes an instance, bound whole as storage.
        let limits = device.limits();
        let max = (limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 16)
            .min(u32::MAX as u64);
        if voxels.len() as u64 > max {
            return Err(Error::Size {
                stage: STAGE,
                what: "voxel count (16 bytes each, one storage binding)",
                got: voxels.len() as u64,
                max,
            });
        }
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("metaball instances"),
            size: (voxels.len().max(1) * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::VERTEX
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&buffer, 0, bytemuck::cast_slice(voxels));
        Ok(Instances {
            buffer,
            count: voxels.len() as u32,
            max_scale: max_scale(voxels),
            centres: centre_bounds(voxels),
        })
    }

    /// Re-upload changed voxels in place (same count): the per-frame path of an animation.
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        instances: &mut Instances,
        voxels: &[Vec4],
    ) -> Result<(), Error> {
        check_voxels(voxels, 1.0)?;
        if voxels.len() != instances.count as usize {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "{} voxels given for a buffer of {}; upload a new set instead",
                    voxels.len(),
                    instances.count
                ),
            });
        }
        queue.write_buffer(&instances.buffer, 0, bytemuck::cast_slice(voxels));
        instances.max_scale = max_scale(voxels);
        instances.centres = centre_bounds(voxels);
        Ok(())
    }
}
