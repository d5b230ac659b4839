//! 3D distance fields (and the exact transform in 2D, which [`super::Distance2d`] runs): an exact Euclidean distance transform,
//! the JFA family, sub-voxel seeds, and resolve to unsigned or signed distance in world units.
//!
//! Seeds and nearest-seed fields are storage buffers, x fastest, one `u32` per voxel: a packed
//! integer seed (11/11/10 bits, [`pack_seed3`]; the exact transform packs grids past 2048 ×
//! 2048 × 1024 with the bits their sides need, [`SeedPacking`]) or, for sub-voxel seeds, a key
//! into a table of points. Distances are written to an `R32Float` 3D texture for sampling.
//!
//! ```no_run
//! # fn main() -> Result<(), fieldkit::Error> {
//! use fieldkit::distance::{Distance3d, Method, Options3d, upload_volume};
//! let ctx = fieldkit::gpu::Context::new()?;
//! let distance = Distance3d::new(&ctx.device)?;
//! // A 32×24×16 occupancy volume with one occupied voxel.
//! let size = [32, 24, 16];
//! let mut mask = vec![0u8; 32 * 24 * 16];
//! mask[(8 * 24 + 12) * 32 + 5] = 255;
//! let volume = upload_volume(&ctx.device, &ctx.queue, &mask, size)?;
//! let mut encoder = ctx.encoder("distance");
//! let options = Options3d { method: Method::Exact, signed: true, ..Options3d::default() };
//! let field = distance.encode(&ctx.device, &mut encoder, &volume, &options)?;
//! ctx.submit_and_wait("distance", encoder)?;
//! let sdf: Vec<f32> = fieldkit::gpu::read_texture(&ctx, &field.distance)?;
//! # Ok(()) }
//! ```

use glam::Vec3;

use super::Variant;
use crate::bind::{ComputePipeline, Variants};
use crate::error::Error;
use crate::gpu::{Record, Recorder, uniform_buffer as uniform};
use crate::shaders::distance::{
    edt_columns, edt_rows, edt_tile, field_resolve, jfa3_seed, jfa3_seed_points, jfa3_step,
    point_lines,
};

const STAGE: &str = "distance::d3";

/// Largest sides the standard 3D packing can name: x and y in 11 bits, z in 10
/// ([`pack_seed3`]); JFA and the point seeds take these. The one grid at all three (2048 × 2048
/// × 1024, whose last voxel's code + 1 would wrap to 0) is refused too. The exact transform
/// takes more ([`SeedPacking::for_size`], [`MAX_SIDE_EXACT_3D`]).
pub const MAX_SIDE_3D: [u32; 3] = [2048, 2048, 1024];
/// Largest side of a 2D exact transform: keeps the integer separators inside i32.
pub const MAX_SIDE_2D_EXACT: u32 = 16384;
/// Bands per column in the exact column passes in global memory (`edt_columns.wgsl`): enough
/// that columns × bands reaches about `TARGET_THREADS_3D` threads in 3D, and never fewer than
/// `MIN_BANDS_3D`; about `TARGET_THREADS_2D` in 2D; 32 at most. In 3D that is 8 bands from
/// 16 384 columns up (the target was 2^19 until 2026-11-27). On the H100 (`bench distance
/// --shapes ... --column-bands B`, 1% seeds, command 38 of `docs/bench/distance_scan.csv`) the y
/// pass over 16 384 to 32 768 columns took, with 8 / 16 / 32 bands: 128 × 512 × 128 0.112 /
/// 0.117 / 0.130 ms, 64 × 1024 × 256 0.195 / 0.201 / 0.219, 128 × 1024 × 128 0.218 / 0.217 /
/// 0.233, 256 × 512 × 128 0.200 / 0.213 (16 was its old count). (The resolving z pass takes 8
/// wherever it sweeps: `encode_exact_fused`.) Measured on the H100 in one
/// command per setting (`cargo xtask bench distance --exact-only --column-bands B`, 1% seeds,
/// clocks held, 2026-11-26): 512³ took 4.51, 3.96 and 4.47 ms with 4, 8 and 16 bands; z +
/// resolve at 256³ 0.327, 0.284 and 0.271 ms, y 0.198, 0.200 and 0.238; 1024³ (split, every
/// pass in global memory) 41.5, 39.1 and 44.3 ms; 16384² 8.44, 6.82 and 5.67 ms with 32, 16 and
/// 8 bands, 8192² 1.86, 1.47 and 1.77, 4096² 0.443 and 0.533 with 32 and 16.
const TARGET_THREADS_3D: u32 = 1 << 17;
const MIN_BANDS_3D: u32 = 8;
const TARGET_THREADS_2D: u32 = 1 << 17;
const BAND_CHOICES: [u32; 6] = [1, 2, 4, 8, 16, 32];
/// The sweep (`edt_columns.wgsl`'s SCAN) runs where the resolving global pass (z; y of a field
/// split across bindings) takes this many bands (32 columns per workgroup; the pass takes it
/// whatever the automatic count, unless `set_column_bands` says otherwise), in a ring of
/// SWEEP_RING rows (24 either side of a step's 8, rounded up to a power of two: 8 KiB).
const SWEEP_BANDS: u32 = 8;
const SWEEP_RING: u32 = 64;

/// Which dispatch of a resolving pass that sweeps (`edt_columns.wgsl`'s SCAN, AFTER_SCAN) a
/// dispatch is: the sweep, the rest (the workgroups it left to the envelopes), or neither.
#[derive(Clone, Copy, PartialEq, Eq)]
enum SweepPart {
    No,
    Sweep,
    Rest,
}

fn bands_for(columns: u32, flat: bool) -> usize {
    let want = if flat {
        TARGET_THREADS_2D.div_ceil(columns.max(1))
    } else {
        TARGET_THREADS_3D.div_ceil(columns.max(1)).max(MIN_BANDS_3D)
    }
    .next_power_of_two()
    .min(32);
    BAND_CHOICES.iter().position(|&b| b == want).unwrap()
}

/// Rows per workgroup in the exact row pass (`edt_rows.wgsl`, `ROWS`): a power of two up to 32,
/// as many rows of `width` as its 2048 cells of workgroup memory hold while each thread still
/// sweeps at most 8 cells, and no more than there are rows. Short rows then share the scan's
/// barriers: at 512³ four rows share a workgroup.
fn rows_per_group(width: u32, rows: u32) -> u32 {
    let mut r = 32u32;
    while r > 1 && (r * width > 2048 || width.div_ceil(256 / r) > 8 || r / 2 >= rows) {
        r /= 2;
    }
    r
}

/// Where the exact transform's column passes hold a column while they build its envelopes.
///
/// Both give the exact distance; on a tie between two seeds, which one is named may differ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum ColumnPasses {
    /// Workgroup memory for columns up to [`AUTO_TILE_MAX_LENGTH_Y`] long along y and
    /// [`AUTO_TILE_MAX_LENGTH`] along z (where it was measured faster), global memory for longer
    /// ones (see [`tile_columns`]).
    #[default]
    Auto,
    /// Workgroup memory at every length: `256 · 8 / n` columns per tile (bands of 8 positions,
    /// 16 columns at most) where they fit, fewer where workgroup memory is short;
    /// [`Error::Size`] where one column does not fit.
    Workgroup,
    /// Global memory (`edt_columns.wgsl`): the envelopes are stacks in a buffer beside the field.
    Global,
}

/// Fewest adjacent columns per workgroup-memory tile [`ColumnPasses::Auto`] takes: fewer reads
/// too little of each 32-byte sector the tile's loads touch.
pub const MIN_TILE_COLUMNS: u32 = 4;
/// Most columns per tile (256 threads: 16 bands per column at 16 columns).
pub const MAX_TILE_COLUMNS: u32 = 16;
/// Longest column of a 3D field along z (the last pass, which also resolves the distance)
/// [`ColumnPasses::Auto`] holds in workgroup memory. Measured on the H100 (`cargo xtask bench
/// distance --exact-only`, 1% seeds, clocks held, 2026-11-26), z + resolve: 0.266 ms at 256³ in
/// workgroup memory against 0.284 in global memory (8 bands), 2.24 against 1.88 at 512³.
/// (With 16 columns per tile 512³ took 4.48 ms for y: bands of 8 positions
/// ([`AUTO_TILE_BAND`]) were fastest at every length measured, and 512 or 1024 threads per
/// workgroup instead of 256 gave nothing.)
pub const AUTO_TILE_MAX_LENGTH: u32 = 256;
/// Longest column of a 3D field along y [`ColumnPasses::Auto`] holds in workgroup memory
/// (in either memory the y pass makes its sites from the row words). Measured as above, row
/// words and y pass together: 0.049 ms at 128³ in workgroup memory against 0.069 in global
/// memory, 0.315 against 0.277 at 256³, 2.53 against 1.92 at 512³.
pub const AUTO_TILE_MAX_LENGTH_Y: u32 = 128;
/// Fewest columns of a 3D field's y pass (x · z) that [`ColumnPasses::Auto`] runs in global
/// memory whatever their length. The tile wins at 128³ (16 384 columns; above) and at 128 ×
/// 128 × 256 (32 768: 0.158 ms against 0.169 with the global pass at 16 bands), the global
/// pass from 65 536 columns. Measured on the H100 (`cargo xtask bench distance --exact-only
/// --shapes ...`, clocks held, 2026-11-27, the z pass in global memory sweeping at 8 bands),
/// the transform with y in workgroup memory against global memory: 128 × 128 × 1024 0.502
/// against 0.450 ms at 1% seeds, 0.635 against 0.450 at 1e-5 and 0.415 for both at 30%;
/// 128 × 128 × 512 0.277 / 0.257, 0.344 / 0.260 and 0.238 / 0.241; 256 × 128 × 512 0.515 /
/// 0.471, 0.626 / 0.447 and 0.438 / 0.442.
pub const AUTO_TILE_MAX_COLUMNS_Y: u32 = 1 << 16;
/// Longest column of a 2D field [`ColumnPasses::Auto`] holds in workgroup memory: 2048² took
/// 0.323 ms with 4 columns per tile against 0.257 in global memory; lengths from 257 to 512
/// were not measured, so they stay in global memory.
pub const AUTO_TILE_MAX_LENGTH_2D: u32 = 256;
/// Band length [`ColumnPasses::Auto`] aims for: at most `256 · 8 / n` columns per tile.
pub const AUTO_TILE_BAND: u32 = 8;

/// How a column of length `n` is laid out in a workgroup-memory tile (`edt_tile.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct TileGeometry {
    lg_columns: u32,
    lg_band: u32,
    bands: u32,
    column_cells: u32,
}

impl TileGeometry {
    /// The most columns (a power of two from `min_columns` to `max_columns`) whose tile fits
    /// `storage` bytes of workgroup memory, with the envelope sizes beside it.
    fn fit(n: u32, storage: u32, min_columns: u32, max_columns: u32) -> Option<Self> {
        let mut columns = max_columns.clamp(1, MAX_TILE_COLUMNS).next_power_of_two();
        if columns > max_columns.max(1) {
            columns /= 2;
        }
        while columns >= min_columns.max(1) {
            let band_len = n.div_ceil(256 / columns).next_power_of_two();
            let bands = n.div_ceil(band_len);
            // One pad cell per band, then rounded up to 32 / columns (mod 32): a warp holds
            // 32 / columns positions of each column when it loads the tile and 32 / columns
            // bands of each when it sweeps them, and with that stride between columns neither
            // puts two of its threads in one bank (with an odd stride, as before, the load met
            // 4-way conflicts: the row pass's sweep went from 0.93 to 0.65 ms at 512³ when its
            // 4-way conflicts went).
            let need = n + bands;
            let column_cells = if columns == 1 {
                need
            } else {
                need + (32 / columns + 32 - need % 32) % 32
            };
            // The tile, the 256 envelope sizes and the resolving entries' `far_sites` flag.
            let bytes = (column_cells as u64 * columns as u64 + 257) * 4;
            // A band's envelope size is 8 bits in the shader's `envelope_size`.
            if bytes <= storage as u64 && band_len <= 128 {
                return Some(Self {
                    lg_columns: columns.trailing_zeros(),
                    lg_band: band_len.trailing_zeros(),
                    bands,
                    column_cells,
                });
            }
            columns /= 2;
        }
        None
    }

    /// The longest column a tile of one column holds in `storage` bytes (0 if none). A tile's
    /// size does not grow monotonically with n (its pad cells fall where the band length
    /// doubles), so every length is tried, longest first; this runs only to word an error.
    fn longest(storage: u32) -> u32 {
        (1..=storage / 4)
            .rev()
            .find(|&n| Self::fit(n, storage, 1, 1).is_some())
            .unwrap_or(0)
    }

    /// What [`ColumnPasses::Auto`] takes for `columns` columns of length `n` along `axis` (1:
    /// y, 2: z) of a 3D field, or along y of a 2D field where `flat`.
    fn auto(n: u32, columns: u32, storage: u32, axis: u32, flat: bool) -> Option<Self> {
        let longest = match (flat, axis) {
            (true, _) => AUTO_TILE_MAX_LENGTH_2D,
            (false, 1) => AUTO_TILE_MAX_LENGTH_Y,
            (false, _) => AUTO_TILE_MAX_LENGTH,
        };
        if n > longest || (!flat && axis == 1 && columns >= AUTO_TILE_MAX_COLUMNS_Y) {
            return None;
        }
        Self::fit(n, storage, MIN_TILE_COLUMNS, Self::banded_columns(n))
    }

    /// [`Self::auto`] for the pass along `axis` of a field of `size` ([w, h, 1] where `flat`):
    /// its columns are x times the third axis.
    fn auto_for(size: [u32; 3], storage: u32, axis: u32, flat: bool) -> Option<Self> {
        let columns = size[0] * size[3 - axis as usize];
        Self::auto(size[axis as usize], columns, storage, axis, flat)
    }

    /// The tile [`ColumnPasses::Workgroup`] takes at any length: bands of 8 where they fit (16
    /// columns of 512 took 4.48 ms for y at 512³, 4 columns 2.70), fewer columns where the
    /// storage is short; [`Error::Size`] where not even one column fits.
    fn forced(n: u32, storage: u32) -> Result<Self, Error> {
        Self::fit(n, storage, 1, Self::banded_columns(n)).ok_or(Error::Size {
            stage: edt_tile::STAGE,
            what: "column length for one column in workgroup memory \
                   (max_compute_workgroup_storage_size)",
            got: n as u64,
            max: Self::longest(storage) as u64,
        })
    }

    /// The tile of a field split across bindings (`Distance3d::split_for`) for columns of
    /// length `n`: as [`Self::forced`], but at least `least` columns where they fit (at 1024,
    /// bands of 8 would leave 2, and a warp would read 8 bytes of each row).
    fn split(n: u32, storage: u32, least: u32) -> Result<Self, Error> {
        let columns = least.max(Self::banded_columns(n));
        match Self::fit(n, storage, least, columns) {
            Some(tile) => Ok(tile),
            None => Self::forced(n, storage),
        }
    }

    /// Columns per tile for bands of [`AUTO_TILE_BAND`] positions: `256 · 8 / n`, 1 to 16.
    fn banded_columns(n: u32) -> u32 {
        (256 * AUTO_TILE_BAND / n.max(1)).clamp(1, MAX_TILE_COLUMNS)
    }

    /// The pass's parameters and override constants, for the columns `span` names, reading
    /// a buffer apart from the one it writes where `source_apart`.
    #[allow(clippy::too_many_arguments)]
    fn bind(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        axis: u32,
        pack_2d: bool,
        fuse: Option<&Fuse>,
        span: &Span,
        source_apart: bool,
    ) -> (wgpu::Buffer, [(&'static str, f64); 7]) {
        let params = uniform(
            device,
            "edt tile params",
            &edt_tile::TileParams {
                size: size.into(),
                voxel_size: fuse.map_or(1.0, |f| f.voxel_size),
                band: fuse.map_or(f32::MAX, |f| f.band),
                lg_columns: self.lg_columns,
                lg_band: self.lg_band,
                bands: self.bands,
                column_cells: self.column_cells,
                first: span.first.into(),
                x_end: span.x_end,
                src: span.src,
                dst: span.dst,
            },
        );
        let [x_bits, y_bits] = packing_of(size).overrides();
        let overrides = [
            ("PACK_2D", pack_2d as u32 as f64),
            ("AXIS", axis as f64),
            ("CELLS", (self.column_cells << self.lg_columns) as f64),
            ("Y_AFTER_Z", span.y_after_z as u32 as f64),
            ("SOURCE_APART", source_apart as u32 as f64),
            x_bits,
            y_bits,
        ];
        (params, overrides)
    }

    /// Workgroups for a pass over the span's columns × `others`.
    fn groups(&self, span: &Span, others: u32) -> [u32; 3] {
        [
            (span.x_end - span.first[0]).div_ceil(1 << self.lg_columns),
            others,
            1,
        ]
    }
}

/// The columns one dispatch of a workgroup column pass answers, and where it reads and writes
/// them: a whole field in place, or, for a field too large for one binding, a part of it.
#[derive(Debug, Clone)]
struct Span {
    /// The first column's x, and the other coordinate (z for y columns, y for z columns) of the
    /// first row of workgroups.
    first: [u32; 2],
    /// The x where the span's columns end.
    x_end: u32,
    /// A y pass after the z pass: its sites are off the column's plane in z too.
    y_after_z: bool,
    src: edt_tile::Placement,
    dst: edt_tile::Placement,
}

/// How the exact transform splits a field too large for one binding (`Distance3d::split_for`).
#[derive(Debug, Clone, Copy)]
struct Split {
    /// Columns (x) per part held apart between the z and the y pass: a multiple of both
    /// tiles' columns.
    part_width: u32,
    /// Planes (z) of the field per binding of the y pass.
    slab_depth: u32,
    /// The y and z passes' tiles, or `None` for a pass in global memory.
    y: Option<TileGeometry>,
    z: Option<TileGeometry>,
}

/// A buffer holding the voxels from `origin` on, `row` elements per row, `plane` per plane.
fn placement(origin: [u32; 3], row: u32, plane: u32) -> edt_tile::Placement {
    edt_tile::Placement {
        origin: origin.into(),
        row,
        plane,
    }
}

/// What one dispatch of a workgroup column pass reads (`source`, or, `None`, `nearest` itself)
/// and writes (`nearest`, and slab `slab` of a signed pass's inside field), with the columns
/// `span` names.
struct TileIo<'a> {
    source: Option<&'a wgpu::Buffer>,
    nearest: &'a wgpu::Buffer,
    slab: usize,
    span: Span,
}

/// What one dispatch of a global-memory column pass reads and writes, as [`TileIo`] says it
/// for a workgroup pass, plus the envelope stack (in `span.src`'s layout) and, for the z pass
/// of a split field, the row words it makes its sites from.
struct ColumnsIo<'a> {
    source: Option<&'a wgpu::Buffer>,
    words: Option<&'a wgpu::Buffer>,
    nearest: &'a wgpu::Buffer,
    stack: &'a wgpu::Buffer,
    slab: usize,
    span: Span,
    /// The resolving pass sweeps the workgroups whose every voxel has a site near it and
    /// leaves the others to a pass of their own (`edt_columns.wgsl`'s SCAN, AFTER_SCAN), with
    /// its record of which it swept. It reads its sites from `source` where given (a split
    /// field's part), else from `stack` (IN_STACK).
    sweep: Option<&'a wgpu::Buffer>,
}

/// The same placement as `edt_columns.wgsl` declares it.
fn columns_placement(p: &edt_tile::Placement) -> edt_columns::Placement {
    edt_columns::Placement {
        origin: p.origin,
        row: p.row,
        plane: p.plane,
    }
}

impl<'a> TileIo<'a> {
    /// Every column of `nearest` (a field of `size`), in place.
    fn in_place(nearest: &'a wgpu::Buffer, size: [u32; 3]) -> Self {
        Self {
            source: None,
            nearest,
            slab: 0,
            span: Span::whole(size),
        }
    }
}

impl Span {
    /// Every column of a field of `size`, read and written in place.
    fn whole(size: [u32; 3]) -> Self {
        let p = placement([0; 3], size[0], size[0] * size[1]);
        Self {
            first: [0, 0],
            x_end: size[0],
            y_after_z: false,
            src: p,
            dst: p,
        }
    }
}

/// Columns per workgroup-memory tile that [`ColumnPasses::Auto`] takes for the last column
/// pass (along z in 3D, along y in 2D) over columns of length `n` of a field of `dims`
/// dimensions (2 or 3) on a device with `storage` bytes of workgroup memory
/// (`max_compute_workgroup_storage_size`), or `None` where it takes the global-memory pass:
/// 3D columns up to [`AUTO_TILE_MAX_LENGTH`] long, 2D columns up to
/// [`AUTO_TILE_MAX_LENGTH_2D`], with up to `256 · 8 / n` columns per tile (bands of 8
/// positions), 16 at most, 4 at least. The 3D y pass takes the same tile up to
/// [`AUTO_TILE_MAX_LENGTH_Y`], over fewer than [`AUTO_TILE_MAX_COLUMNS_Y`] columns. WebGPU's
/// default 16 KiB holds every tile this takes.
///
/// ```
/// use fieldkit::distance::tile_columns;
/// assert_eq!(tile_columns(16 << 10, 128, 3), Some(16));
/// assert_eq!(tile_columns(16 << 10, 256, 3), Some(8));
/// assert_eq!(tile_columns(48 << 10, 257, 3), None);
/// assert_eq!(tile_columns(48 << 10, 512, 3), None);
/// assert_eq!(tile_columns(48 << 10, 512, 2), None);
/// ```
pub fn tile_columns(storage: u32, n: u32, dims: u32) -> Option<u32> {
    TileGeometry::auto(n, 0, storage, 2, dims == 2).map(|g| 1 << g.lg_columns)
}

/// Columns per workgroup-memory tile that [`ColumnPasses::Auto`] takes for the column pass
/// along `axis` (1: y, 2: z) of a 3D field of `size`, or `None` where that pass runs in global
/// memory: [`tile_columns`] for z; for y the same up to [`AUTO_TILE_MAX_LENGTH_Y`] long over
/// fewer than [`AUTO_TILE_MAX_COLUMNS_Y`] columns (x · z).
///
/// ```
/// use fieldkit::distance::tile_columns_3d;
/// assert_eq!(tile_columns_3d(48 << 10, [128, 128, 128], 1), Some(16));
/// assert_eq!(tile_columns_3d(48 << 10, [128, 128, 1024], 1), None);
/// assert_eq!(tile_columns_3d(48 << 10, [128, 128, 1024], 2), None);
/// assert_eq!(tile_columns_3d(48 << 10, [512, 128, 256], 2), Some(8));
/// ```
pub fn tile_columns_3d(storage: u32, size: [u32; 3], axis: u32) -> Option<u32> {
    TileGeometry::auto_for(size, storage, axis, false).map(|g| 1 << g.lg_columns)
}

/// Where the last exact column pass writes distances (`columns_resolve*` in `edt_columns.wgsl`).
#[derive(Clone, Copy)]
struct Fuse<'a> {
    /// `R32Float` storage view: 3D, or 2D where `flat`.
    distance: &'a wgpu::TextureView,
    flat: bool,
    voxel_size: f32,
    /// World units; `f32::MAX` for none.
    band: f32,
    /// Signed: the inside seeds' field (the pass runs in the outside seeds' field); its slabs
    /// where the field is split, else one buffer.
    inside_field: Option<&'a [wgpu::Buffer]>,
}

/// Which entry point of a column-pass family a pass takes, and what its resolve writes.
enum Resolve<'a> {
    /// The nearest seeds alone (`columns`, `tile_columns`).
    No,
    /// Unsigned distances into a 2D (`*_resolve_2d`) or 3D (`*_resolve`) view.
    Flat(&'a wgpu::TextureView),
    Volume(&'a wgpu::TextureView),
    /// Signed (`*_resolve_signed_2d`, `*_resolve_signed`): the inside seeds' field beside it.
    SignedFlat(&'a wgpu::Buffer, &'a wgpu::TextureView),
    SignedVolume(&'a wgpu::Buffer, &'a wgpu::TextureView),
}

impl<'a> Fuse<'a> {
    /// The entry point a column pass writing slab `slab` takes for `fuse`.
    fn resolve(fuse: Option<&Fuse<'a>>, slab: usize) -> Resolve<'a> {
        match fuse {
            None => Resolve::No,
            Some(f) => match (f.flat, f.inside_field) {
                (true, None) => Resolve::Flat(f.distance),
                (false, None) => Resolve::Volume(f.distance),
                (true, Some(inside)) => Resolve::SignedFlat(&inside[slab], f.distance),
                (false, Some(inside)) => Resolve::SignedVolume(&inside[slab], f.distance),
            },
        }
    }
}

/// Records the entry point of a column-pass family that `$resolve` (a [`Resolve`]) names,
/// through the caller's `$record!(cache, entry { extra resources })`: the five entries in the
/// order No, Flat, SignedFlat, Volume, SignedVolume, each `cache => entry`.
macro_rules! record_resolved {
    ($record:ident, $resolve:expr, $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, {}, $($cache => $entry),*)
    };
    // The volume entries bind more (`edt_columns.wgsl`'s `swept`).
    ($record:ident, $resolve:expr, volume { $($field:ident: $value:expr),* },
        $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, { $($field: $value),* }, $($cache => $entry),*)
    };
    (@arms $record:ident, $resolve:expr, { $($field:ident: $value:expr),* },
        $c0:expr => $e0:ident, $c1:expr => $e1:ident, $c2:expr => $e2:ident,
        $c3:expr => $e3:ident, $c4:expr => $e4:ident) => {
        match $resolve {
            Resolve::No => $record!($c0, $e0 {}),
            Resolve::Flat(d) => $record!($c1, $e1 { distance_2d: d }),
            Resolve::SignedFlat(i, d) => $record!($c2, $e2 { nearest_inside: i, distance_2d: d }),
            Resolve::Volume(d) => $record!($c3, $e3 { distance: d $(, $field: $value)* }),
            Resolve::SignedVolume(i, d) => {
                $record!($c4, $e4 { nearest_inside: i, distance: d $(, $field: $value)* })
            }
        }
    };
}

/// The buffer kept in `slot` where it holds `bytes` (exactly `bytes` where `exact`, for
/// buffers that passes check to be their field's size), else a new one from `make`, kept for
/// the next call.
fn kept_buffer(
    slot: &std::sync::Mutex<Option<wgpu::Buffer>>,
    bytes: u64,
    exact: bool,
    make: impl FnOnce() -> wgpu::Buffer,
) -> wgpu::Buffer {
    let mut kept = slot.lock().unwrap_or_else(|e| e.into_inner());
    match kept.as_ref() {
        Some(b) if b.size() == bytes || (!exact && b.size() > bytes) => b.clone(),
        _ => {
            let b = make();
            *kept = Some(b.clone());
            b
        }
    }
}

/// Parts (columns along x) and slabs (planes along z) of a field of `size` that the exact
/// transform splits across bindings of `binding` bytes, buffers of `max_buffer_size` (each slab
/// is one), with parts whole tiles of `columns` wide: `(part_width, slab_depth)`, as few and as
/// even as fit, parts on 128-byte row boundaries where a binding holds that much.
fn split_layout(
    size: [u32; 3],
    binding: u64,
    max_buffer_size: u64,
    columns: u64,
) -> Result<(u32, u32), Error> {
    let column_bytes = size[1] as u64 * size[2] as u64 * 4;
    let columns_fit = binding / column_bytes;
    // Parts start on a 128-byte boundary of a row (32 columns) wherever a binding holds 32
    // columns: at 1024³ on the H100 (2026-11-26, parts of 342 columns) the y pass of the
    // parts starting at x = 342 and 684 took 2.79–2.90 ms per slab against 2.11–2.13 for
    // the part at 0, which writes its rows from an aligned start.
    let aligned = columns.max(ALIGNED_COLUMNS);
    let columns = if columns_fit >= aligned {
        aligned
    } else {
        columns
    };
    let widest = columns_fit / columns * columns;
    if widest == 0 {
        return Err(Error::Size {
            stage: STAGE,
            what: "one tile of columns (bytes) of a field split across bindings",
            got: column_bytes * columns,
            max: binding,
        });
    }
    // Each slab is a buffer of its own.
    let plane = size[0] as u64 * size[1] as u64 * 4;
    let deepest = binding.min(max_buffer_size) / plane;
    if deepest == 0 {
        return Err(Error::Size {
            stage: STAGE,
            what: "one plane (bytes) of a field split across bindings",
            got: plane,
            max: binding,
        });
    }
    // As few parts and slabs as fit, of even sizes (no last dispatch of a few columns).
    let even = |total: u64, most: u64, unit: u64| {
        total
            .div_ceil(total.div_ceil(most))
            .next_multiple_of(unit)
            .min(most) as u32
    };
    Ok((
        even(size[0] as u64, widest, columns),
        even(size[2] as u64, deepest, 1),
    ))
}

/// Columns (x) per 128 bytes of a field's row: where the exact transform splits a field into
/// parts, each part starts on a multiple of this where a binding holds that many.
const ALIGNED_COLUMNS: u64 = 32;

/// Most sub-voxel seeds one table may hold (24-bit index in the key).
pub const MAX_POINTS: u32 = 0xfffffe;

/// Volume texture formats the seed and exact stages read (red channel).
pub const VOLUME_FORMATS: &[wgpu::TextureFormat] = &[
    wgpu::TextureFormat::R8Unorm,
    wgpu::TextureFormat::R16Float,
    wgpu::TextureFormat::R32Float,
];

/// Pack a 3D seed as the shaders do: x in 11 bits, y in 11, z in 10, and the whole code + 1 so
/// that 0 is [`super::NO_SEED`].
pub fn pack_seed3(x: u32, y: u32, z: u32) -> u32 {
    (x | (y << 11) | (z << 22)) + 1
}

/// Unpack a 3D seed; `None` for [`super::NO_SEED`].
pub fn unpack_seed3(s: u32) -> Option<[u32; 3]> {
    (s != super::NO_SEED).then(|| {
        let c = s - 1;
        [c & 0x7ff, (c >> 11) & 0x7ff, c >> 22]
    })
}

/// Longest side of any axis of a 3D exact transform: the separators' arithmetic stays exact in
/// f32 and i32 up to 2048 (squared distances below 2^24).
pub const MAX_SIDE_EXACT_3D: u32 = 2048;

/// How a 3D field names a voxel's nearest seed: x in the low `x_bits` bits of a code, y in the
/// next `y_bits`, z in the rest, and the whole code + 1, so that 0 is [`super::NO_SEED`].
/// [`SeedPacking::STANDARD`] (11/11/10, [`pack_seed3`]) for every grid up to 2048 × 2048 × 1024
/// and every method; the exact transform also takes grids past that — any side up to
/// [`MAX_SIDE_EXACT_3D`], as long as the voxels' codes fit 32 bits (64 × 64 × 2048 takes
/// 6/6/20) — with as many bits per axis as its sides need ([`SeedPacking::for_size`]).
///
/// ```
/// use fieldkit::distance::SeedPacking;
/// let tall = SeedPacking::for_size([64, 64, 2048]).unwrap();
/// assert_eq!((tall.x_bits, tall.y_bits), (6, 6));
/// assert_eq!(tall.unpack(tall.pack(63, 5, 2047)), Some([63, 5, 2047]));
/// assert_eq!(SeedPacking::for_size([512, 512, 512]), Some(SeedPacking::STANDARD));
/// assert_eq!(SeedPacking::for_size([2048, 2048, 2048]), None); // 33 bits
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SeedPacking {
    /// Bits of x, the lowest.
    pub x_bits: u32,
    /// Bits of y, above x's; z takes the rest of 32.
    pub y_bits: u32,
}

impl SeedPacking {
    /// 11 bits for x and y, 10 for z: [`pack_seed3`].
    pub const STANDARD: Self = Self {
        x_bits: 11,
        y_bits: 11,
    };

    /// The packing the exact transform gives a grid of `size`: [`Self::STANDARD`] where it
    /// holds every voxel, otherwise the fewest bits for x and y; `None` where a side is 0 or
    /// past [`MAX_SIDE_EXACT_3D`], or the voxels' codes do not fit 32 bits.
    pub fn for_size(size: [u32; 3]) -> Option<Self> {
        if size.iter().any(|&n| n == 0 || n > MAX_SIDE_EXACT_3D) {
            return None;
        }
        if Self::STANDARD.holds(size) {
            return Some(Self::STANDARD);
        }
        let bits = |n: u32| 32 - (n - 1).leading_zeros();
        let tight = Self {
            x_bits: bits(size[0]),
            y_bits: bits(size[1]),
        };
        tight.holds(size).then_some(tight)
    }

    /// Whether every voxel of a grid of `size` gets a code of its own, none of them wrapping to
    /// [`super::NO_SEED`].
    pub fn holds(&self, size: [u32; 3]) -> bool {
        if self.x_bits + self.y_bits > 31 || size.contains(&0) {
            return false;
        }
        let z_bits = 32 - self.x_bits - self.y_bits;
        size[0] as u64 <= 1 << self.x_bits
            && size[1] as u64 <= 1 << self.y_bits
            && size[2] as u64 <= 1 << z_bits
            && self.code(size[0] - 1, size[1] - 1, size[2] - 1) < u32::MAX as u64
    }

    fn code(&self, x: u32, y: u32, z: u32) -> u64 {
        x as u64 | (y as u64) << self.x_bits | (z as u64) << (self.x_bits + self.y_bits)
    }

    /// The seed at voxel (x, y, z) (the coordinates within the grid the packing holds).
    pub fn pack(&self, x: u32, y: u32, z: u32) -> u32 {
        (self.code(x, y, z) + 1) as u32
    }

    /// The voxel a seed names; `None` for [`super::NO_SEED`].
    pub fn unpack(&self, s: u32) -> Option<[u32; 3]> {
        (s != super::NO_SEED).then(|| {
            let c = s - 1;
            [
                c & ((1u32 << self.x_bits) - 1),
                (c >> self.x_bits) & ((1u32 << self.y_bits) - 1),
                c >> (self.x_bits + self.y_bits),
            ]
        })
    }

    /// The shaders' `SEED_X_BITS` and `SEED_Y_BITS` (`edt_rows`, `edt_tile`, `edt_columns`).
    fn overrides(&self) -> [(&'static str, f64); 2] {
        [
            ("SEED_X_BITS", self.x_bits as f64),
            ("SEED_Y_BITS", self.y_bits as f64),
        ]
    }
}

/// The packing of a grid the exact transform runs on (`size` passed [`exact_volume_size`] or
/// [`check_size_3d`]), [`SeedPacking::STANDARD`] for 2D fields (which do not read it).
fn packing_of(size: [u32; 3]) -> SeedPacking {
    SeedPacking::for_size(size).unwrap_or(SeedPacking::STANDARD)
}

/// Table index named by a sub-voxel seed key; `None` for no seed.
pub fn key_index(key: u32) -> Option<u32> {
    (key != super::NO_SEED).then(|| 0xffffff - (key & 0xffffff))
}

/// Where a volume sits in the world: voxel `(i, j, k)` has its centre at
/// `origin + (i + ½, j + ½, k + ½) · voxel_size`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Grid3 {
    /// Voxels per axis.
    pub size: [u32; 3],
    /// World units per voxel.
    pub voxel_size: f32,
    /// The volume's minimum corner.
    pub origin: Vec3,
}

impl Grid3 {
    /// A grid of `size` unit voxels at the origin.
    pub fn new(size: [u32; 3]) -> Self {
        Self {
            size,
            voxel_size: 1.0,
            origin: Vec3::ZERO,
        }
    }

    /// World position → voxel coordinates (voxel centres at integers).
    pub fn to_voxel(&self, p: Vec3) -> Vec3 {
        (p - self.origin) / self.voxel_size - Vec3::splat(0.5)
    }

    /// Centre of voxel `v` in the world.
    pub fn voxel_centre(&self, v: [u32; 3]) -> Vec3 {
        self.origin + (Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) + 0.5) * self.voxel_size
    }
}

/// Which voxels of the input volume are marked (seeds; for a signed field, inside).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Inside {
    /// Any positive value.
    Mask,
    /// Value ≥ the threshold (a density's iso-level).
    Threshold(f32),
}

impl Inside {
    fn threshold(self) -> f32 {
        match self {
            Inside::Mask => f32::MIN_POSITIVE,
            Inside::Threshold(t) => t,
        }
    }
}

/// How the field is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Method {
    /// The exact transform: zero wrong voxels, and the fastest at every size measured (README).
    #[default]
    Exact,
    /// Jump flooding with the given variant.
    Jfa(Variant),
    /// Sub-voxel seeds within a band: three line passes (x, y, z), each scanning ±band voxels
    /// (`point_lines.wgsl`); the cost grows with the band. Needs [`Options3d::band`], and each
    /// point within one voxel of the voxel its key is held in (as surface seeds and
    /// [`Distance3d::encode_points`] without homes place them). Integer seeds take
    /// [`Method::Exact`]. Not exact for sub-voxel seeds: it can keep one up to about half a voxel
    /// farther than the nearest, where JFA+2 keeps one at most a tenth farther (`tests/distance_3d_points.rs` measures
    /// it against brute force and JFA+2).
    Lines,
}

impl Method {
    /// The method's name as the benchmark tables write it.
    pub fn name(self) -> String {
        match self {
            Method::Exact => "exact".into(),
            Method::Jfa(v) => v.name().into(),
            Method::Lines => "lines".into(),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
/// What [`Distance3d`] computes.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Options3d {
    /// Exact (default), JFA or the line passes.
    pub method: Method,
    /// Signed distance, negative inside (marked voxels).
    pub signed: bool,
    /// Which voxels are marked.
    pub inside: Inside,
    /// World units per voxel.
    pub voxel_size: f32,
    /// Narrow band, in voxels: distances are only needed up to this far. JFA then starts at the
    /// power of two at or above it instead of half the grid; every method clamps to it.
    pub band: Option<f32>,
    /// What a voxel that no seed reached holds (an empty seed set; or, with a band, a voxel
    /// farther than it): by default ±band, or `f32::MAX` without one. JFA only (the pass that
    /// writes these is its resolve); other methods refuse it.
    pub unreached: Option<Unreached>,
}

/// Distances for voxels no seed reached, world units: `-inside` inside and `outside` outside
/// (the metaball source's full-volume field writes −one voxel and 1e6).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Unreached {
    /// Magnitude given inside (the value written is its negation).
    pub inside: f32,
    /// Value given outside.
    pub outside: f32,
}

impl Default for Options3d {
    fn default() -> Self {
        Self {
            method: Method::Exact,
            signed: false,
            inside: Inside::Mask,
            voxel_size: 1.0,
            band: None,
            unreached: None,
        }
    }
}

impl Options3d {
    /// The band in world units distances are clamped to; `f32::MAX` for none.
    fn world_band(&self) -> f32 {
        self.band.map_or(f32::MAX, |b| b * self.voxel_size)
    }

    fn check(&self) -> Result<(), Error> {
        if !(self.voxel_size.is_finite() && self.voxel_size > 0.0) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "voxel_size must be finite and positive, got {}",
                    self.voxel_size
                ),
            });
        }
        if let Some(b) = self.band
            && !(b.is_finite() && b > 0.0)
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("band must be finite and positive, got {b}"),
            });
        }
        if let Some(u) = self.unreached {
            if !(u.inside.is_finite()
                && u.inside >= 0.0
                && u.outside.is_finite()
                && u.outside >= 0.0)
            {
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: format!(
                        "unreached inside ({}) and outside ({}) must be finite and ≥ 0",
                        u.inside, u.outside
                    ),
                });
            }
            if !matches!(self.method, Method::Jfa(_)) {
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: format!(
                        "unreached values are written by JFA's resolve; method {} does not take them",
                        self.method.name()
                    ),
                });
            }
        }
        if let Inside::Threshold(t) = self.inside
            && !t.is_finite()
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("threshold must be finite, got {t}"),
            });
        }
        Ok(())
    }

    /// The methods that take sub-voxel seeds: JFA, and the line passes with a band.
    fn check_points(&self) -> Result<(), Error> {
        match (self.method, self.band) {
            (Method::Jfa(_), _) | (Method::Lines, Some(_)) => Ok(()),
            (Method::Lines, None) => Err(Error::Invalid {
                stage: STAGE,
                what: "Method::Lines scans ±band voxels per axis and needs a band".into(),
            }),
            (Method::Exact, _) => Err(Error::Invalid {
                stage: STAGE,
                what: "sub-voxel seeds need JFA or the line passes; the exact transform takes \
                       integer seeds"
                    .into(),
            }),
        }
    }

    /// JFA step lengths for a grid whose largest side is `max_side`.
    pub fn steps(&self, variant: Variant, max_side: u32) -> Vec<u32> {
        let steps = variant.steps(max_side);
        let Some(band) = self.band else { return steps };
        // Steps p, p/2, …, 1 reach any seed up to 2p − 1 ≥ band voxels away along each axis.
        let full = max_side.max(1).next_power_of_two() / 2;
        // A band as wide as the grid (or wider, up to f32::MAX) keeps every step; compare in f32
        // before converting so a huge band cannot overflow.
        if band.is_nan() || band.ceil() >= full as f32 {
            return steps;
        }
        let first = (band.ceil() as u32).max(1).next_power_of_two();
        if first >= full {
            return steps;
        }
        let skip = (full / first).trailing_zeros() as usize;
        // Drop the long steps at the start of the JFA run (after a leading step-1 pass, if any).
        let lead = usize::from(matches!(
            variant,
            Variant::OnePlusJfa | Variant::OnePlusJfaPlus2
        ));
        let mut s = steps;
        s.drain(lead..lead + skip);
        s
    }
}

/// Sub-voxel seeds on the GPU: `count` points (`vec4<f32>`, xyz in voxel coordinates) and,
/// optionally, each point's home voxel (`u32`, packed as [`pack_seed3`]).
#[derive(Debug)]
pub struct PointSeeds {
    /// `vec4<f32>` per point, xyz in voxel coordinates.
    pub buffer: wgpu::Buffer,
    /// Each point's home voxel, packed, if given.
    pub homes: Option<wgpu::Buffer>,
    /// Number of points.
    pub count: u32,
}

/// A `u32` per voxel (x fastest, then y, then z) in one buffer, or, for a field larger than one
/// buffer or binding may be (the exact transform at 1024³: 4 GiB, where wgpu binds at most
/// 2 GiB − 1 and NVIDIA's `max_buffer_size` is 2 MiB short of 4 GiB), in slabs of whole z
/// planes, one buffer each.
#[derive(Debug)]
pub struct Slabs {
    /// The buffers, in z order: planes `k · depth ..` in buffer `k`.
    pub buffers: Vec<wgpu::Buffer>,
    /// Planes per buffer (the last may hold fewer).
    pub depth: u32,
    /// Planes in all (the field's depth).
    pub planes: u32,
}

impl Slabs {
    fn one(buffer: wgpu::Buffer, depth: u32) -> Self {
        Self {
            buffers: vec![buffer],
            depth,
            planes: depth,
        }
    }

    /// The field's buffer where one holds it; `None` where it is split.
    pub fn whole(&self) -> Option<&wgpu::Buffer> {
        match self.buffers.as_slice() {
            [one] => Some(one),
            _ => None,
        }
    }

    /// Every voxel's word, slab after slab (x fastest, then y, then z): one submission, and a
    /// [`Readback`](crate::gpu::Readback) that completes when every slab is mapped.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> crate::gpu::Readback<Vec<u32>> {
        let buffers: Vec<&wgpu::Buffer> = self.buffers.iter().collect();
        crate::gpu::readback_buffers(device, queue, &buffers)
            .then(|bytes| Ok(bytemuck::cast_slice::<u8, u32>(&bytes).to_vec()))
    }

    /// The buffer holding plane `z`, and the plane's index in it; `None` past the field.
    pub fn plane(&self, z: u32) -> Option<(&wgpu::Buffer, u32)> {
        if z >= self.planes {
            return None;
        }
        let k = (z / self.depth.max(1)) as usize;
        self.buffers.get(k).map(|b| (b, z - k as u32 * self.depth))
    }
}

/// A 3D distance field on the GPU.
#[derive(Debug)]
pub struct Field3d {
    /// Voxels per axis.
    pub size: [u32; 3],
    /// How `nearest` names integer seeds: [`SeedPacking::STANDARD`] ([`unpack_seed3`]) for
    /// every grid up to 2048 × 2048 × 1024, wider per axis where the exact transform took a
    /// grid past that (`packing.unpack(s)` decodes either).
    pub packing: SeedPacking,
    /// Nearest seed per voxel: packed (`packing`), or a key into `points` ([`key_index`]).
    /// For a signed field of integer seeds, the nearest *inside* voxel. One buffer
    /// ([`Slabs::whole`]) except where the exact transform split a field too large for one.
    pub nearest: Slabs,
    /// For a signed field of integer seeds, the nearest *outside* voxel.
    pub nearest_outside: Option<Slabs>,
    /// `R32Float`: distance in world units (signed: negative inside), clamped to the band.
    /// `±f32::MAX` where no seed exists.
    pub distance: wgpu::Texture,
}

/// A 2D field from the exact transform (nearest seeds in a buffer, packed 16/16 bits).
#[derive(Debug)]
pub struct FieldBuf2d {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Nearest seed per texel, packed 16/16 bits ([`super::pack_seed`]), x fastest.
    pub nearest: wgpu::Buffer,
    /// Signed fields: nearest outside texel.
    pub nearest_outside: Option<wgpu::Buffer>,
    /// `R32Float` 2D texture.
    pub distance: wgpu::Texture,
}

/// All 3D distance pipelines. Create once, encode many times.
///
/// Besides its pipelines it keeps one buffer between calls: the envelope stack of the exact
/// transform's column passes in global memory (4 bytes per voxel of the largest field whose
/// columns ran there; 512 MiB after a 512³ field), so that a transform run every frame does
/// not allocate, and have wgpu zero, a buffer that size each time. Drop the `Distance3d` to
/// free it.
pub struct Distance3d {
    seed: ComputePipeline<jfa3_seed::seed::Entry>,
    seed_points: ComputePipeline<jfa3_seed_points::seed_points::Entry>,
    jump: ComputePipeline<jfa3_step::jump::Entry>,
    jump_points: ComputePipeline<jfa3_step::jump_points::Entry>,
    lines_x: ComputePipeline<point_lines::lines_x::Entry>,
    lines_y: ComputePipeline<point_lines::lines_y::Entry>,
    lines_z: ComputePipeline<point_lines::lines_z::Entry>,
    lines_z_signed: ComputePipeline<point_lines::lines_z_signed::Entry>,
    /// By rows per workgroup (`rows_per_group`) and seed widths.
    rows: Variants<edt_rows::rows::Entry>,
    rows_2d: ComputePipeline<edt_rows::rows_2d::Entry>,
    /// The 3D row pass as words of marks, per rows per workgroup (`ROWS`).
    row_words: Variants<edt_rows::row_words::Entry>,
    /// Column pass per band count, packing and seed widths, made on first use.
    columns: Variants<edt_columns::columns::Entry>,
    columns_copy: Variants<edt_columns::columns_copy::Entry>,
    columns_copy_resolve: Variants<edt_columns::columns_copy_resolve::Entry>,
    /// The last 3D column pass with the resolve folded in.
    columns_resolve: Variants<edt_columns::columns_resolve::Entry>,
    columns_resolve_signed: Variants<edt_columns::columns_resolve_signed::Entry>,
    /// The same for the column pass of a 2D field.
    columns_resolve_2d: Variants<edt_columns::columns_resolve_2d::Entry>,
    columns_resolve_signed_2d: Variants<edt_columns::columns_resolve_signed_2d::Entry>,
    /// Bands per column chosen by the caller; `None` picks by grid size.
    column_bands: Option<u32>,
    /// The column passes in workgroup memory (`edt_tile.wgsl`), per tile size.
    tile_columns: Variants<edt_tile::tile_columns::Entry>,
    tile_columns_words: Variants<edt_tile::tile_columns_words::Entry>,
    tile_columns_resolve: Variants<edt_tile::tile_columns_resolve::Entry>,
    tile_columns_resolve_signed: Variants<edt_tile::tile_columns_resolve_signed::Entry>,
    tile_columns_resolve_2d: Variants<edt_tile::tile_columns_resolve_2d::Entry>,
    tile_columns_resolve_signed_2d: Variants<edt_tile::tile_columns_resolve_signed_2d::Entry>,
    tile_copy: Variants<edt_tile::tile_copy::Entry>,
    tile_copy_resolve: Variants<edt_tile::tile_copy_resolve::Entry>,
    column_passes: ColumnPasses,
    /// Fold the 3D row pass into the y pass (its sites made from the row words) where y is
    /// not the last pass.
    fold_rows: bool,
    /// The largest field the exact transform binds whole (below the device's limit: for tests).
    split_bytes: Option<u64>,
    /// Fewest columns per tile of a split field's passes.
    split_columns: u32,
    /// The global-memory column passes' envelope stack, kept from call to call (the largest
    /// made so far): a new one each call would be allocated, and zeroed by wgpu, every frame.
    stack: std::sync::Mutex<Option<wgpu::Buffer>>,
    /// The sweep's record of the workgroups it answered, kept the same way.
    swept: std::sync::Mutex<Option<wgpu::Buffer>>,
    /// The row words of the exact transform's own calls, kept the same way (every word is
    /// written before it is read).
    words: std::sync::Mutex<Option<wgpu::Buffer>>,
    /// A split field's part (the z pass's output, the y pass's input), kept the same way.
    part: std::sync::Mutex<Option<wgpu::Buffer>>,
    /// The buffers and textures of fields handed back with [`Self::recycle`], for the next
    /// calls to take instead of allocating.
    recycled: std::sync::Mutex<Recycled>,
    /// The resolving global pass (z; y of a split field) sweeps the workgroups whose every
    /// voxel has a site near it.
    sweep: bool,
    /// Bound as `edt_tile.wgsl`'s `source` where a pass reads the buffer it writes (a binding
    /// must be there; the shader does not read it then).
    no_source: wgpu::Buffer,
    /// Bound as `edt_columns.wgsl`'s `swept` where there is no sweep (not `no_source`: a
    /// dispatch may not bind one buffer both read-only and read-write).
    no_swept: wgpu::Buffer,
    resolve_unsigned: ComputePipeline<field_resolve::resolve_unsigned::Entry>,
    resolve_signed: ComputePipeline<field_resolve::resolve_signed::Entry>,
    resolve_points: ComputePipeline<field_resolve::resolve_points::Entry>,
    resolve_points_signed: ComputePipeline<field_resolve::resolve_points_signed::Entry>,
    resolve_unsigned_2d: ComputePipeline<field_resolve::resolve_unsigned_2d::Entry>,
    resolve_signed_2d: ComputePipeline<field_resolve::resolve_signed_2d::Entry>,
}

fn voxels(size: [u32; 3]) -> u64 {
    size.iter().map(|&s| s as u64).product()
}

/// What [`Distance3d::recycle`] was handed: nearest-seed buffers (all made by `field_buffer`,
/// so of one usage) and distance textures (all made by `distance_texture`).
#[derive(Default)]
struct Recycled {
    buffers: Vec<wgpu::Buffer>,
    textures: Vec<wgpu::Texture>,
}

fn field_buffer(device: &wgpu::Device, label: &str, size: [u32; 3]) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: voxels(size) * 4,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn distance_texture(
    device: &wgpu::Device,
    size: [u32; 3],
    dimension: wgpu::TextureDimension,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("distance"),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: size[2],
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

/// The parameters of the 3D row passes (`rows`, `row_words`).
fn row_params(device: &wgpu::Device, size: [u32; 3], inside: Inside, invert: bool) -> wgpu::Buffer {
    uniform(
        device,
        "edt rows params",
        &edt_rows::RowParams {
            size: size.into(),
            threshold: inside.threshold(),
            invert: invert as u32,
            channels: glam::Vec4::X,
        },
    )
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

/// Check a 3D grid size against the packing and the device: its sides, and its field (a `u32`
/// per voxel) against one storage binding. The exact transform ([`Method::Exact`]) takes larger
/// fields too, split across bindings, up to the device's `max_buffer_size`.
pub fn check_size_3d(device: &wgpu::Device, size: [u32; 3]) -> Result<(), Error> {
    check_sides_3d(device, size)?;
    check_bytes(&device.limits(), voxels(size) * 4)
}

/// Check a 3D grid's sides against the packing and the device's 3D textures.
fn check_sides_3d(device: &wgpu::Device, size: [u32; 3]) -> Result<(), Error> {
    check_sides(device, size, MAX_SIDE_3D)?;
    if size == MAX_SIDE_3D {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "a {}×{}×{} grid: its last voxel's packed seed would wrap to \"no seed\"; \
                 take one voxel off any side",
                size[0], size[1], size[2]
            ),
        });
    }
    Ok(())
}

/// Each side of `size` from 1 to its entry of `max` and the device's 3D textures.
fn check_sides(device: &wgpu::Device, size: [u32; 3], max: [u32; 3]) -> Result<(), Error> {
    let tex = device.limits().max_texture_dimension_3d;
    for (i, what) in ["width", "height", "depth"].into_iter().enumerate() {
        let max = max[i].min(tex) as u64;
        if size[i] == 0 || size[i] as u64 > max {
            return Err(Error::Size {
                stage: STAGE,
                what,
                got: size[i] as u64,
                max,
            });
        }
    }
    Ok(())
}

/// [`Error::Invalid`] from `stage` unless the `what` buffer holds exactly `bytes` (what a field
/// of `size` needs).
fn check_len(
    stage: &'static str,
    what: &str,
    buffer: &wgpu::Buffer,
    bytes: u64,
    size: [u32; 3],
) -> Result<(), Error> {
    if buffer.size() == bytes {
        return Ok(());
    }
    Err(Error::Invalid {
        stage,
        what: format!(
            "{what} buffer has {} bytes, {size:?} needs {bytes}",
            buffer.size()
        ),
    })
}

/// The checks of the benchmarks' copies (`encode_global_copy`, `encode_tile_copy`): a grid the
/// transform takes, axis 1 or 2, and buffers of the size the grid needs.
fn check_copy(
    device: &wgpu::Device,
    stage: &'static str,
    nearest: &wgpu::Buffer,
    words: Option<&wgpu::Buffer>,
    size: [u32; 3],
    axis: u32,
) -> Result<(), Error> {
    check_column_axis(device, stage, size, axis)?;
    check_len(stage, "nearest", nearest, voxels(size) * 4, size)?;
    if let Some(w) = words {
        check_len(stage, "words", w, row_words_bytes(size), size)?;
    }
    Ok(())
}

/// The distance texture a benchmark copy stores into (`encode_tile_copy`, `encode_global_copy`
/// with `distance`): a 3D `R32Float` storage texture of the grid's size, for a copy along z (the
/// resolving pass's); its view.
fn copy_distance_view(
    stage: &'static str,
    distance: &wgpu::Texture,
    size: [u32; 3],
    axis: u32,
) -> Result<wgpu::TextureView, Error> {
    let extent = distance.size();
    let got = [extent.width, extent.height, extent.depth_or_array_layers];
    let problem = if axis != 2 {
        Some(format!(
            "a distance texture is stored only by the copy along z (2), not {axis}"
        ))
    } else if distance.dimension() != wgpu::TextureDimension::D3
        || distance.format() != wgpu::TextureFormat::R32Float
        || !distance
            .usage()
            .contains(wgpu::TextureUsages::STORAGE_BINDING)
    {
        Some(format!(
            "the distance texture must be a 3D R32Float storage texture, got {:?} {:?} ({:?})",
            distance.dimension(),
            distance.format(),
            distance.usage()
        ))
    } else if got != size {
        Some(format!(
            "the distance texture is {got:?}, the grid {size:?}"
        ))
    } else {
        None
    };
    match problem {
        Some(what) => Err(Error::Invalid { stage, what }),
        None => Ok(distance.create_view(&wgpu::TextureViewDescriptor::default())),
    }
}

/// A grid the exact transform takes and a column axis: 1 (y) or 2 (z).
fn check_column_axis(
    device: &wgpu::Device,
    stage: &'static str,
    size: [u32; 3],
    axis: u32,
) -> Result<(), Error> {
    check_size_3d(device, size)?;
    if !(axis == 1 || axis == 2) {
        return Err(Error::Invalid {
            stage,
            what: format!("axis must be 1 (y) or 2 (z), got {axis}"),
        });
    }
    Ok(())
}

/// Bytes of the row words (`edt_rows.wgsl`'s `row_words`) of a field of `size`: 8 per 32 voxels
/// of a row, rows rounded up.
/// A new buffer for the row words of a field of `size`.
fn row_words_buffer(device: &wgpu::Device, size: [u32; 3]) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("edt row words"),
        size: row_words_bytes(size),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

fn row_words_bytes(size: [u32; 3]) -> u64 {
    size[0].div_ceil(32) as u64 * size[1] as u64 * size[2] as u64 * 8
}

/// [`Error::Invalid`] unless the `inside` volume (where given) is a volume of `size`.
fn check_inside(
    device: &wgpu::Device,
    inside: Option<&wgpu::Texture>,
    size: [u32; 3],
) -> Result<(), Error> {
    if let Some(v) = inside {
        let vs = check_volume(device, v)?;
        if vs != size {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("inside volume is {vs:?}, the field {size:?}"),
            });
        }
    }
    Ok(())
}

fn check_bytes(limits: &wgpu::Limits, bytes: u64) -> Result<(), Error> {
    let max = limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size);
    if bytes > max {
        return Err(Error::Size {
            stage: STAGE,
            what: "field buffer (bytes)",
            got: bytes,
            max,
        });
    }
    Ok(())
}

/// Check a 2D grid for the exact transform.
pub fn check_size_2d_exact(device: &wgpu::Device, w: u32, h: u32) -> Result<(), Error> {
    let limits = device.limits();
    let max = MAX_SIDE_2D_EXACT.min(limits.max_texture_dimension_2d) as u64;
    for (what, got) in [("width", w), ("height", h)] {
        if got == 0 || got as u64 > max {
            return Err(Error::Size {
                stage: STAGE,
                what,
                got: got as u64,
                max,
            });
        }
    }
    check_bytes(&limits, w as u64 * h as u64 * 4)
}

fn check_volume(device: &wgpu::Device, volume: &wgpu::Texture) -> Result<[u32; 3], Error> {
    let size = volume_size(device, volume)?;
    check_bytes(&device.limits(), voxels(size) * 4)?;
    Ok(size)
}

/// A volume's size for the exact transform: as [`volume_size`], but its sides checked against
/// [`SeedPacking::for_size`] (any side up to [`MAX_SIDE_EXACT_3D`] where the codes fit) and the
/// device's 3D textures.
fn exact_volume_size(device: &wgpu::Device, volume: &wgpu::Texture) -> Result<[u32; 3], Error> {
    if volume.dimension() != wgpu::TextureDimension::D3
        || !VOLUME_FORMATS.contains(&volume.format())
    {
        return volume_size(device, volume);
    }
    let size = [
        volume.width(),
        volume.height(),
        volume.depth_or_array_layers(),
    ];
    check_sides(device, size, [MAX_SIDE_EXACT_3D; 3])?;
    if SeedPacking::for_size(size).is_none() {
        let bits = size.map(|n| 32 - (n - 1).leading_zeros());
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "a {}×{}×{} grid: its sides need {}, {} and {} bits, and a seed's code + 1 \
                 (0 is \"no seed\") must fit the field's 32; take voxels off a side",
                size[0], size[1], size[2], bits[0], bits[1], bits[2]
            ),
        });
    }
    Ok(size)
}

/// A volume's size, its dimension, format and sides checked (not its field's bytes).
fn volume_size(device: &wgpu::Device, volume: &wgpu::Texture) -> Result<[u32; 3], Error> {
    if volume.dimension() != wgpu::TextureDimension::D3 {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "the volume must be a 3D texture, got {:?}",
                volume.dimension()
            ),
        });
    }
    if !VOLUME_FORMATS.contains(&volume.format()) {
        return Err(Error::Format {
            stage: STAGE,
            format: volume.format(),
            supported: "R8Unorm, R16Float, R32Float",
        });
    }
    let size = [
        volume.width(),
        volume.height(),
        volume.depth_or_array_layers(),
    ];
    check_sides_3d(device, size)?;
    Ok(size)
}

/// Upload a CPU volume (`x` fastest, then `y`, then `z`; one byte per voxel) as an `R8Unorm`
/// 3D texture. Non-zero bytes are marked under [`Inside::Mask`]. Sides up to
/// [`MAX_SIDE_EXACT_3D`] (and the device's 3D textures): the method checks its own range when it
/// runs.
pub fn upload_volume(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    data: &[u8],
    size: [u32; 3],
) -> Result<wgpu::Texture, Error> {
    // Any side a method takes: the exact transform's (the others refuse past theirs when
    // they run).
    check_sides(device, size, [MAX_SIDE_EXACT_3D; 3])?;
    if data.len() as u64 != voxels(size) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "volume has {} bytes, {size:?} needs {}",
                data.len(),
                voxels(size)
            ),
        });
    }
    crate::gpu::scoped(device, STAGE, || {
        let t = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("volume"),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: size[2],
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::R8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_DST
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        queue.write_texture(
            t.as_image_copy(),
            data,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(size[0]),
                rows_per_image: Some(size[1]),
            },
            t.size(),
        );
        t
    })
}

/// Upload sub-voxel seeds given in world coordinates; each seeds the voxel it lies in. Every
/// point must be finite and inside the grid's box; at most [`MAX_POINTS`]. Where several points
/// share a voxel only the one nearest its centre is kept: give homes
/// ([`upload_points_with_homes`]) when points come one per voxel, as from surface extraction.
pub fn upload_points(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid3,
    points: &[Vec3],
) -> Result<PointSeeds, Error> {
    upload_points_inner(device, queue, grid, points, None)
}

/// Upload sub-voxel seeds with the voxel each one seeds (typically the voxel that produced it,
/// holding the closest surface point to its centre). Homes must lie inside the grid.
pub fn upload_points_with_homes(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid3,
    points: &[Vec3],
    homes: &[[u32; 3]],
) -> Result<PointSeeds, Error> {
    if homes.len() != points.len() {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("{} homes for {} points", homes.len(), points.len()),
        });
    }
    upload_points_inner(device, queue, grid, points, Some(homes))
}

fn upload_points_inner(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    grid: &Grid3,
    points: &[Vec3],
    homes: Option<&[[u32; 3]]>,
) -> Result<PointSeeds, Error> {
    check_size_3d(device, grid.size)?;
    if !(grid.voxel_size.is_finite() && grid.voxel_size > 0.0 && grid.origin.is_finite()) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "grid voxel_size {} / origin {} must be finite (size positive)",
                grid.voxel_size, grid.origin
            ),
        });
    }
    if points.is_empty() || points.len() as u64 > MAX_POINTS as u64 {
        return Err(Error::Size {
            stage: STAGE,
            what: "number of seed points",
            got: points.len() as u64,
            max: MAX_POINTS as u64,
        });
    }
    let hi = Vec3::new(
        grid.size[0] as f32,
        grid.size[1] as f32,
        grid.size[2] as f32,
    ) - 0.5;
    let mut data = Vec::with_capacity(points.len());
    for (i, &p) in points.iter().enumerate() {
        let v = grid.to_voxel(p);
        if !p.is_finite() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("seed point {i} is not finite: {p}"),
            });
        }
        if v.cmplt(Vec3::splat(-0.5)).any() || v.cmpgt(hi).any() {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "seed point {i} at {p} lies outside the volume (voxel coordinates {v})"
                ),
            });
        }
        data.push([v.x, v.y, v.z, 0.0]);
    }
    let packed_homes = match homes {
        None => None,
        Some(h) => {
            let mut packed = Vec::with_capacity(h.len());
            for (i, v) in h.iter().enumerate() {
                if (0..3).any(|a| v[a] >= grid.size[a]) {
                    return Err(Error::Invalid {
                        stage: STAGE,
                        what: format!(
                            "home voxel {v:?} of point {i} lies outside the grid {:?}",
                            grid.size
                        ),
                    });
                }
                packed.push(pack_seed3(v[0], v[1], v[2]));
            }
            Some(packed)
        }
    };
    let storage = |label: &str, contents: &[u8]| {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: contents.len() as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        queue.write_buffer(&buffer, 0, contents);
        buffer
    };
    let buffer = storage("seed points", bytemuck::cast_slice(&data));
    let homes = packed_homes.map(|h| storage("seed point homes", bytemuck::cast_slice(&h)));
    Ok(PointSeeds {
        buffer,
        homes,
        count: points.len() as u32,
    })
}

impl Distance3d {
    /// Fix how many bands each column of the exact transform is split into (1, 2, 4, 8, 16 or
    /// 32), or `None` (the default) to pick by grid size (and 8 for the resolving global pass,
    /// z or the y pass of a field split across bindings, which then sweeps). Every choice gives
    /// the exact distance (on a tie between two seeds, which one is named may differ); only
    /// speed differs.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device) -> Result<(), fieldkit::Error> {
    /// let mut d = fieldkit::distance::Distance3d::new(device)?;
    /// d.set_column_bands(Some(1))?;
    /// assert!(d.set_column_bands(Some(3)).is_err());
    /// # Ok(()) }
    /// ```
    pub fn set_column_bands(&mut self, bands: Option<u32>) -> Result<(), Error> {
        if let Some(b) = bands
            && !BAND_CHOICES.contains(&b)
        {
            return Err(Error::Invalid {
                stage: edt_columns::STAGE,
                what: format!("column bands must be one of {BAND_CHOICES:?}, got {b}"),
            });
        }
        self.column_bands = bands;
        Ok(())
    }

    /// For benchmarks: `false` runs the 3D row pass on its own (its field written, then read
    /// by the y pass) where the exact transform otherwise folds it into the y pass's load.
    #[doc(hidden)]
    pub fn set_fold_rows(&mut self, fold: bool) {
        self.fold_rows = fold;
    }

    /// For benchmarks and tests: `true` (the default) lets the resolving global z pass at 8
    /// bands sweep the workgroups whose every voxel has a site near it (`edt_columns.wgsl`'s
    /// SCAN; it runs after the y pass from the row words, which then writes into the kept
    /// stack for it), and the resolving y pass of a field split across bindings likewise (it
    /// reads the part the z pass wrote); `false` has every workgroup build the envelopes, as
    /// those passes do at other band counts and in workgroup memory.
    #[doc(hidden)]
    pub fn set_sweep(&mut self, sweep: bool) {
        self.sweep = sweep;
    }

    /// For tests: split the exact transform's field across bindings past `bytes` (or, `None`,
    /// past the device's `max_storage_buffer_binding_size` only, the default), so that the
    /// split runs at sizes a software adapter handles.
    #[doc(hidden)]
    pub fn set_split_bytes(&mut self, bytes: Option<u64>) {
        self.split_bytes = bytes;
    }

    /// For benchmarks: the fewest columns per tile (1 to 16, a power of two) of the y pass of a
    /// split field (default [`MIN_TILE_COLUMNS`]; `None` restores it).
    #[doc(hidden)]
    pub fn set_split_columns(&mut self, columns: Option<u32>) -> Result<(), Error> {
        let c = columns.unwrap_or(MIN_TILE_COLUMNS);
        if !(c.is_power_of_two() && c <= MAX_TILE_COLUMNS) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!("split columns must be a power of two up to 16, got {c}"),
            });
        }
        self.split_columns = c;
        Ok(())
    }

    /// Choose where the exact transform's column passes hold their columns (default
    /// [`ColumnPasses::Auto`]). Only speed differs, and which of two equally near seeds is named.
    pub fn set_column_passes(&mut self, passes: ColumnPasses) {
        self.column_passes = passes;
    }

    /// Create every 3D pipeline (and the 2D exact transform's).
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            seed: ComputePipeline::new(device)?,
            seed_points: ComputePipeline::new(device)?,
            jump: ComputePipeline::new(device)?,
            jump_points: ComputePipeline::new(device)?,
            lines_x: ComputePipeline::new(device)?,
            lines_y: ComputePipeline::new(device)?,
            lines_z: ComputePipeline::new(device)?,
            lines_z_signed: ComputePipeline::new(device)?,
            rows: Default::default(),
            rows_2d: ComputePipeline::new(device)?,
            row_words: Default::default(),
            columns: Default::default(),
            columns_copy: Default::default(),
            columns_copy_resolve: Default::default(),
            columns_resolve: Default::default(),
            columns_resolve_signed: Default::default(),
            columns_resolve_2d: Default::default(),
            columns_resolve_signed_2d: Default::default(),
            column_bands: None,
            tile_columns: Default::default(),
            tile_columns_words: Default::default(),
            tile_columns_resolve: Default::default(),
            tile_columns_resolve_signed: Default::default(),
            tile_columns_resolve_2d: Default::default(),
            tile_columns_resolve_signed_2d: Default::default(),
            tile_copy: Default::default(),
            tile_copy_resolve: Default::default(),
            column_passes: ColumnPasses::Auto,
            fold_rows: true,
            split_bytes: None,
            split_columns: MIN_TILE_COLUMNS,
            stack: Default::default(),
            swept: Default::default(),
            words: Default::default(),
            part: Default::default(),
            recycled: Default::default(),
            sweep: true,
            no_source: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("edt: no source, no words"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            no_swept: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("edt: no sweep"),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
            resolve_unsigned: ComputePipeline::new(device)?,
            resolve_signed: ComputePipeline::new(device)?,
            resolve_points: ComputePipeline::new(device)?,
            resolve_points_signed: ComputePipeline::new(device)?,
            resolve_unsigned_2d: ComputePipeline::new(device)?,
            resolve_signed_2d: ComputePipeline::new(device)?,
        })
    }

    /// Distance field of the marked voxels of `volume` (a mask or a density, see [`Inside`]).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        options: &Options3d,
    ) -> Result<Field3d, Error> {
        options.check()?;
        let size = match options.method {
            // Checked against the split it takes where the field is larger than one binding.
            Method::Exact => exact_volume_size(device, volume)?,
            _ => check_volume(device, volume)?,
        };
        let rec = &mut rec.recorder();
        let flood = |rec: &mut Recorder<'_>, invert: bool| -> Result<wgpu::Buffer, Error> {
            match options.method {
                Method::Exact => unreachable!("the exact transform returns below"),
                Method::Lines => Err(Error::Invalid {
                    stage: STAGE,
                    what: "the line passes are for sub-voxel seeds; integer seeds take the exact \
                           transform (Method::Exact), which is exact at every distance"
                        .into(),
                }),
                Method::Jfa(variant) => {
                    let seeds = self.encode_seed(device, rec, volume, options.inside, invert)?;
                    self.encode_flood(
                        device,
                        rec,
                        seeds,
                        size,
                        &options.steps(variant, size.into_iter().max().unwrap()),
                    )
                }
            }
        };
        if matches!(options.method, Method::Exact) {
            // The last column pass resolves as it answers (`columns_resolve*`): the field is not
            // read a second time.
            let distance = self.distance_texture(device, size, wgpu::TextureDimension::D3);
            let dv = view(&distance);
            let resolve = |inside_field| Fuse {
                distance: &dv,
                flat: false,
                voxel_size: options.voxel_size,
                band: options.world_band(),
                inside_field,
            };
            let nearest = self.encode_exact_fused(
                device,
                rec,
                volume,
                options.inside,
                false,
                (!options.signed).then(|| resolve(None)),
            )?;
            let nearest_outside = if options.signed {
                Some(self.encode_exact_fused(
                    device,
                    rec,
                    volume,
                    options.inside,
                    true,
                    Some(resolve(Some(&nearest.buffers))),
                )?)
            } else {
                None
            };
            return Ok(Field3d {
                size,
                packing: SeedPacking::for_size(size).expect("checked by exact_volume_size"),
                nearest,
                nearest_outside,
                distance,
            });
        }
        let nearest = flood(rec, false)?;
        let nearest_outside = if options.signed {
            Some(flood(rec, true)?)
        } else {
            None
        };
        let distance = self.encode_resolve(
            device,
            rec,
            size,
            &nearest,
            nearest_outside.as_ref(),
            options,
        )?;
        Ok(Field3d {
            size,
            packing: SeedPacking::STANDARD,
            nearest: Slabs::one(nearest, size[2]),
            nearest_outside: nearest_outside.map(|b| Slabs::one(b, size[2])),
            distance,
        })
    }

    /// Distance field of sub-voxel seeds (JFA or the line passes; the exact transform takes
    /// integer seeds only).
    /// Signed when `inside` is given: negative where its value ≥ `options.inside`'s threshold.
    pub fn encode_points(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        points: &PointSeeds,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Options3d,
    ) -> Result<Field3d, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        options.check_points()?;
        if points.count == 0
            || points.count > MAX_POINTS
            || points.buffer.size() < points.count as u64 * 16
        {
            return Err(Error::Size {
                stage: STAGE,
                what: "number of seed points (table size)",
                got: points.count as u64,
                max: (points.buffer.size() / 16).min(MAX_POINTS as u64),
            });
        }
        check_inside(device, inside, size)?;
        let seeds = self.field_buffer(device, "nearest seed", size);
        rec.recorder().encoder.clear_buffer(&seeds, 0, None);
        if let Some(h) = &points.homes
            && h.size() < points.count as u64 * 4
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "homes buffer has {} bytes for {} points",
                    h.size(),
                    points.count
                ),
            });
        }
        let params = uniform(
            device,
            "seed points params",
            &jfa3_seed_points::PointParams {
                size: size.into(),
                count: points.count,
                use_homes: points.homes.is_some() as u32,
            },
        );
        // Without homes the slot still needs a buffer; the shader does not read it.
        let no_homes;
        let homes = match &points.homes {
            Some(h) => h,
            None => {
                no_homes = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("no homes"),
                    size: 4,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                });
                &no_homes
            }
        };
        self.seed_points.record(
            device,
            rec,
            &jfa3_seed_points::seed_points::Resources {
                params: (&params).into(),
                points: (&points.buffer).into(),
                nearest: (&seeds).into(),
                homes: homes.into(),
            },
            [points.count.div_ceil(64), 1, 1],
            "seed points",
        )?;
        self.encode_keyed_points(device, rec, seeds, &points.buffer, size, inside, options)
    }

    /// Flood and resolve a field of seed keys that a caller's stage wrote itself: `keys` holds,
    /// per voxel, `point_key(index, offset)` (0: no seed) naming a point of `points` (vec4 per
    /// point, voxel coordinates). The metaball surface-seed stage writes one this way. Signed
    /// when `inside` is given, as in [`Self::encode_points`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode_keyed_points(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        keys: wgpu::Buffer,
        points: &wgpu::Buffer,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Options3d,
    ) -> Result<Field3d, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        options.check_points()?;
        check_len(STAGE, "keys", &keys, voxels(size) * 4, size)?;
        check_inside(device, inside, size)?;
        let nearest = match (options.method, options.band) {
            (Method::Jfa(variant), _) => {
                let steps = options.steps(variant, size.into_iter().max().unwrap());
                self.encode_flood_inner(device, rec, keys, size, &steps, Some(points))?
            }
            // The line passes resolve in their last pass.
            (Method::Lines, Some(band)) => {
                let (nearest, distance) =
                    self.encode_lines(device, rec, keys, points, size, inside, options, band)?;
                return Ok(Field3d {
                    size,
                    packing: SeedPacking::STANDARD,
                    nearest: Slabs::one(nearest, size[2]),
                    nearest_outside: None,
                    distance,
                });
            }
            // `check_points` refuses the rest.
            _ => unreachable!("checked by Options3d::check_points"),
        };
        let points = PointSeeds {
            buffer: points.clone(),
            homes: None,
            count: 0,
        };
        let params = self.resolve_params(device, size, options);
        let distance = self.distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = view(&distance);
        let groups = ComputePipeline::<field_resolve::resolve_points::Entry>::groups_for(size);
        match inside {
            None => {
                self.resolve_points.record(
                    device,
                    rec,
                    &field_resolve::resolve_points::Resources {
                        params: (&params).into(),
                        nearest: (&nearest).into(),
                        points: (&points.buffer).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
            Some(v) => {
                let vv = view(v);
                self.resolve_points_signed.record(
                    device,
                    rec,
                    &field_resolve::resolve_points_signed::Resources {
                        params: (&params).into(),
                        nearest: (&nearest).into(),
                        points: (&points.buffer).into(),
                        volume: (&vv).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
        }
        Ok(Field3d {
            size,
            packing: SeedPacking::STANDARD,
            nearest: Slabs::one(nearest, size[2]),
            nearest_outside: None,
            distance,
        })
    }

    /// Seed stage alone: a new buffer of packed seeds from the marked (or, inverted, unmarked)
    /// voxels.
    pub fn encode_seed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
    ) -> Result<wgpu::Buffer, Error> {
        let size = check_volume(device, volume)?;
        let out = self.field_buffer(device, "nearest seed", size);
        let params = uniform(
            device,
            "seed params",
            &jfa3_seed::SeedParams {
                size: size.into(),
                threshold: inside.threshold(),
                invert: invert as u32,
            },
        );
        let vv = view(volume);
        self.seed.record(
            device,
            rec,
            &jfa3_seed::seed::Resources {
                params: (&params).into(),
                volume: (&vv).into(),
                nearest: (&out).into(),
            },
            ComputePipeline::<jfa3_seed::seed::Entry>::groups_for(size),
            "seed",
        )?;
        Ok(out)
    }

    /// JFA passes of `steps` over packed seeds in `nearest` (ping-ponging with a second buffer);
    /// returns the buffer holding the result.
    pub fn encode_flood(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Buffer,
        size: [u32; 3],
        steps: &[u32],
    ) -> Result<wgpu::Buffer, Error> {
        self.encode_flood_inner(device, rec, nearest, size, steps, None)
    }

    /// The line passes over seed keys (`point_lines.wgsl`): x from the keys and their points,
    /// then y and z over carried candidates. The z pass also resolves: returns the nearest keys
    /// and the distance texture, signed when `inside` is given.
    #[allow(clippy::too_many_arguments)]
    fn encode_lines(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        keys: wgpu::Buffer,
        points: &wgpu::Buffer,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Options3d,
        band: f32,
    ) -> Result<(wgpu::Buffer, wgpu::Texture), Error> {
        // Each voxel carries an 8-byte candidate between passes.
        check_bytes(&device.limits(), voxels(size) * 8)?;
        let candidates = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: voxels(size) * 8,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let (a, b) = (
            candidates("line candidates x"),
            candidates("line candidates y"),
        );
        // A point within `band` of a voxel centre lies within √3/2 of its own voxel's centre.
        let reach = (band + 0.8660254).floor().min(u32::MAX as f32) as u32;
        let params = uniform(
            device,
            "line params",
            &point_lines::LineParams {
                size: size.into(),
                reach,
                voxel_size: options.voxel_size,
                band: band * options.voxel_size,
                threshold: options.inside.threshold(),
            },
        );
        self.lines_x.record(
            device,
            rec,
            &point_lines::lines_x::Resources {
                params: (&params).into(),
                keys: (&keys).into(),
                points: points.into(),
                dst: (&a).into(),
            },
            ComputePipeline::<point_lines::lines_x::Entry>::groups_for(size),
            "lines x",
        )?;
        self.lines_y.record(
            device,
            rec,
            &point_lines::lines_y::Resources {
                params: (&params).into(),
                src: (&a).into(),
                dst: (&b).into(),
            },
            ComputePipeline::<point_lines::lines_y::Entry>::groups_for(size),
            "lines y",
        )?;
        let nearest = self.field_buffer(device, "nearest seed", size);
        let distance = self.distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = view(&distance);
        let groups = ComputePipeline::<point_lines::lines_z::Entry>::groups_for(size);
        match inside {
            None => {
                self.lines_z.record(
                    device,
                    rec,
                    &point_lines::lines_z::Resources {
                        params: (&params).into(),
                        keys: (&keys).into(),
                        points: points.into(),
                        src: (&b).into(),
                        nearest: (&nearest).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "lines z + resolve",
                )?;
            }
            Some(v) => {
                let vv = view(v);
                self.lines_z_signed.record(
                    device,
                    rec,
                    &point_lines::lines_z_signed::Resources {
                        params: (&params).into(),
                        keys: (&keys).into(),
                        points: points.into(),
                        src: (&b).into(),
                        nearest: (&nearest).into(),
                        volume: (&vv).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "lines z + resolve",
                )?;
            }
        }
        Ok((nearest, distance))
    }

    #[allow(clippy::too_many_arguments)]
    fn encode_flood_inner(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Buffer,
        size: [u32; 3],
        steps: &[u32],
        points: Option<&wgpu::Buffer>,
    ) -> Result<wgpu::Buffer, Error> {
        check_size_3d(device, size)?;
        check_len(jfa3_step::STAGE, "field", &nearest, voxels(size) * 4, size)?;
        if steps.contains(&0) {
            return Err(Error::Invalid {
                stage: jfa3_step::STAGE,
                what: "step 0".into(),
            });
        }
        let other = self.field_buffer(device, "jfa ping-pong", size);
        let (mut a, mut b) = (nearest, other);
        let groups = ComputePipeline::<jfa3_step::jump::Entry>::groups_for(size);
        for &step in steps {
            let params = uniform(
                device,
                "jfa jump params",
                &jfa3_step::JumpParams {
                    size: size.into(),
                    step,
                },
            );
            match points {
                None => {
                    self.jump.record(
                        device,
                        rec,
                        &jfa3_step::jump::Resources {
                            params: (&params).into(),
                            src: (&a).into(),
                            dst: (&b).into(),
                        },
                        groups,
                        &format!("jump {step}"),
                    )?;
                }
                Some(pts) => {
                    self.jump_points.record(
                        device,
                        rec,
                        &jfa3_step::jump_points::Resources {
                            params: (&params).into(),
                            src: (&a).into(),
                            dst: (&b).into(),
                            points: pts.into(),
                        },
                        groups,
                        &format!("jump {step}"),
                    )?;
                }
            }
            std::mem::swap(&mut a, &mut b);
        }
        Ok(a)
    }

    /// The exact transform (rows, then columns along y and z) of the marked voxels: packed
    /// nearest seeds in a new buffer, or in slabs where the field is larger than one.
    pub fn encode_exact(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
    ) -> Result<Slabs, Error> {
        self.encode_exact_fused(device, rec, volume, inside, invert, None)
    }

    /// [`Self::encode_exact`], resolving into `fuse` in its last pass when given.
    #[allow(clippy::too_many_arguments)]
    fn encode_exact_fused(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
        fuse: Option<Fuse>,
    ) -> Result<Slabs, Error> {
        let size = exact_volume_size(device, volume)?;
        if let Some(split) = self.split_for(device, size)? {
            return self.encode_exact_split(device, rec, volume, inside, invert, fuse, split);
        }
        // Along y, and not the last pass: the row pass folds into the y pass, which makes its
        // sites from the row words (`row_words`, then `tile_columns_words` in workgroup memory
        // or `edt_columns.wgsl` with FROM_WORDS in global memory); else rows, then columns.
        // The z pass resolving a volume in global memory sweeps where it can (`edt_columns.wgsl`'s
        // SCAN), at SWEEP_BANDS (unless set otherwise) whatever the automatic count: a grid of
        // few columns (x · y under 65 536) asks for 16 or 32 bands, and on the H100
        // (2026-11-27, `bench distance --shapes`, 1% seeds) 8 bands and the sweep took
        // 128 × 128 × 1024 from 0.704 to 0.454 ms and 192 × 192 × 512 from 0.662 to 0.502
        // (1e-5 seeds 0.696 → 0.464 and 0.554 → 0.526; 30% 0.764 → 0.420 and 0.773 → 0.496).
        // Its sites come from the y pass (from the row words) through the kept stack, so that
        // it writes into `nearest` from the first (`edt_columns.wgsl`'s IN_STACK).
        let folds = self.fold_rows && size[1] > 1 && size[2] > 1;
        let sweep = (self.sweep
            && folds
            && fuse.as_ref().is_some_and(|f| !f.flat)
            && self.tile_for(device, size, 2, false)?.is_none()
            && self.column_bands.is_none_or(|b| b == SWEEP_BANDS))
        .then(|| self.swept_for(device, size[0].div_ceil(256 / SWEEP_BANDS) * size[1]));
        let (nearest, first_axis) = if folds {
            let words = self.row_words(device, rec, volume, inside, invert, true)?;
            let nearest = self.field_buffer(device, "nearest seed", size);
            let tile = self.tile_for(device, size, 1, false)?;
            // Where the z pass sweeps, into the stack, with `nearest` the y pass's own stack.
            let stack = sweep.is_some().then(|| self.stack_for(device, size));
            let (out, scratch) = match &stack {
                Some(stack) => (stack, Some(&nearest)),
                None => (&nearest, None),
            };
            let io = TileIo::in_place(out, size);
            self.encode_from_words(device, rec, &words, io, size, 1, tile, size, scratch)?;
            (nearest, 2)
        } else {
            (self.encode_rows(device, rec, volume, inside, invert)?, 1)
        };
        let axes: Vec<u32> = (first_axis..=2u32)
            .filter(|&a| size[a as usize] > 1)
            .collect();
        // The envelope stack only where a pass runs in global memory.
        let mut global = false;
        for &axis in &axes {
            global |= self.tile_for(device, size, axis, false)?.is_none();
        }
        let stack = global.then(|| self.stack_for(device, size));
        let mut fuse = fuse;
        for (k, &axis) in axes.iter().enumerate() {
            let last = k + 1 == axes.len();
            let f = if last { fuse.take() } else { None };
            self.encode_columns(
                device,
                rec,
                false,
                &nearest,
                stack.as_ref(),
                size,
                axis,
                size[3 - axis as usize],
                f,
                sweep.as_ref().filter(|_| last),
            )?;
        }
        if let Some(f) = fuse {
            // A single row (no column pass ran): resolve on its own.
            self.resolve_into(device, rec, size, &nearest, f)?;
        }
        Ok(Slabs::one(nearest, size[2]))
    }

    /// Unsigned or signed resolve of integer seeds into `fuse.distance` in a pass of its own.
    fn resolve_into(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        size: [u32; 3],
        nearest: &wgpu::Buffer,
        fuse: Fuse,
    ) -> Result<(), Error> {
        let params = uniform(
            device,
            "resolve params",
            &field_resolve::ResolveParams {
                size: size.into(),
                voxel_size: fuse.voxel_size,
                band: fuse.band,
                threshold: 0.0,
                unreached_inside: fuse.band,
                unreached_outside: fuse.band,
            },
        );
        let groups = ComputePipeline::<field_resolve::resolve_unsigned::Entry>::groups_for(size);
        match fuse.inside_field {
            None => {
                self.resolve_unsigned.record(
                    device,
                    rec,
                    &field_resolve::resolve_unsigned::Resources {
                        params: (&params).into(),
                        nearest: nearest.into(),
                        distance: fuse.distance.into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
            Some(inside) => {
                self.resolve_signed.record(
                    device,
                    rec,
                    &field_resolve::resolve_signed::Resources {
                        params: (&params).into(),
                        nearest: (&inside[0]).into(),
                        nearest_outside: nearest.into(),
                        distance: fuse.distance.into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
        }
        Ok(())
    }

    /// First exact pass alone: per row, the nearest marked voxel along x (a new buffer).
    pub fn encode_rows(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
    ) -> Result<wgpu::Buffer, Error> {
        let size = exact_volume_size(device, volume)?;
        check_bytes(&device.limits(), voxels(size) * 4)?;
        let nearest = self.field_buffer(device, "nearest seed", size);
        let params = row_params(device, size, inside, invert);
        let vv = view(volume);
        let per_group = rows_per_group(size[0], size[1]);
        let [x_bits, y_bits] = packing_of(size).overrides();
        let rows = self
            .rows
            .get(device, &[("ROWS", per_group as f64), x_bits, y_bits], true)?;
        rows.record(
            device,
            rec,
            &edt_rows::rows::Resources {
                params: (&params).into(),
                volume: (&vv).into(),
                nearest: (&nearest).into(),
            },
            [size[1].div_ceil(per_group), size[2], 1],
            "rows (x)",
        )?;
        Ok(nearest)
    }

    /// The 3D row pass as words (`row_words`): per 32 voxels of a row, their marks and the
    /// nearest marks on either side (a new buffer of `vec2<u32>`, `ceil(width / 32)` per row),
    /// which [`Self::encode_columns_from_words`] reads in place of the row pass's field.
    pub fn encode_row_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
    ) -> Result<wgpu::Buffer, Error> {
        self.row_words(device, rec, volume, inside, invert, false)
    }

    /// [`Self::encode_row_words`], into the words kept from call to call where `kept` (the
    /// exact transform's own row words, which no caller sees), else into a new buffer.
    fn row_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
        kept: bool,
    ) -> Result<wgpu::Buffer, Error> {
        let size = exact_volume_size(device, volume)?;
        let new = || row_words_buffer(device, size);
        let words = if kept {
            kept_buffer(&self.words, row_words_bytes(size), true, new)
        } else {
            new()
        };
        let count = size[0].div_ceil(32);
        let params = row_params(device, size, inside, invert);
        let vv = view(volume);
        // 2048 cells of workgroup memory per workgroup: rows of up to 2048 voxels (64 words),
        // as many as fit (a power of two).
        let per_group = 64 / count.next_power_of_two();
        self.row_words
            .get(device, &[("ROWS", per_group as f64)], false)?
            .record(
                device,
                rec,
                &edt_rows::row_words::Resources {
                    params: (&params).into(),
                    volume: (&vv).into(),
                    words: (&words).into(),
                },
                [size[1].div_ceil(per_group), size[2], 1],
                "row words (x)",
            )?;
        Ok(words)
    }

    /// The y column pass of a 3D field of `size` from the row words of
    /// [`Self::encode_row_words`], in workgroup or global memory as the exact transform takes
    /// it ([`Self::set_column_passes`]): writes the nearest seed of every voxel within its xy
    /// plane into `nearest`, as [`Self::encode_rows`] followed by the y pass of
    /// [`Self::encode_column_pass`] would.
    pub fn encode_columns_from_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        words: &wgpu::Buffer,
        nearest: &wgpu::Buffer,
        size: [u32; 3],
    ) -> Result<(), Error> {
        check_size_3d(device, size)?;
        let need = [
            ("words", words, row_words_bytes(size)),
            ("nearest", nearest, voxels(size) * 4),
        ];
        for (what, b, bytes) in need {
            check_len(edt_tile::STAGE, what, b, bytes, size)?;
        }
        let tile = self.tile_for(device, size, 1, false)?;
        let io = TileIo::in_place(nearest, size);
        self.encode_from_words(device, rec, words, io, size, 1, tile, size, None)
    }

    /// The column pass along `axis` (1: y, 2: z) that makes its sites from the row words, into
    /// `io.nearest` where `io.span` places it: in workgroup memory where `tile` is given, else
    /// in global memory with the envelope stack kept for a field of `stack_size` (or `scratch`
    /// where given: the stack itself is where `io` writes).
    #[allow(clippy::too_many_arguments)]
    fn encode_from_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        words: &wgpu::Buffer,
        io: TileIo,
        size: [u32; 3],
        axis: u32,
        tile: Option<TileGeometry>,
        stack_size: [u32; 3],
        scratch: Option<&wgpu::Buffer>,
    ) -> Result<(), Error> {
        match tile {
            Some(tile) => self.encode_tile_columns_words(device, rec, words, io, size, axis, tile),
            None => self.encode_global_columns(
                device,
                rec,
                false,
                ColumnsIo {
                    source: None,
                    words: Some(words),
                    nearest: io.nearest,
                    stack: &match scratch {
                        Some(s) => s.clone(),
                        None => self.stack_for(device, stack_size),
                    },
                    slab: 0,
                    span: io.span,
                    sweep: None,
                },
                size,
                axis,
                size[3 - axis as usize],
                None,
            ),
        }
    }

    /// The column pass along `axis` from the row words, writing where `io` says (its `source`
    /// is not read).
    #[allow(clippy::too_many_arguments)]
    fn encode_tile_columns_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        words: &wgpu::Buffer,
        io: TileIo,
        size: [u32; 3],
        axis: u32,
        tile: TileGeometry,
    ) -> Result<(), Error> {
        let (params, overrides) = tile.bind(device, size, axis, false, None, &io.span, false);
        let others = if axis == 1 { size[2] } else { size[1] };
        self.tile_columns_words
            .get(device, &overrides, false)?
            .record(
                device,
                rec,
                &edt_tile::tile_columns_words::Resources {
                    params: (&params).into(),
                    nearest: io.nearest.into(),
                    words: words.into(),
                },
                tile.groups(&io.span, others),
                if axis == 1 {
                    "columns (y, workgroup) from row words"
                } else {
                    "columns (z, workgroup) from row words"
                },
            )?;
        Ok(())
    }

    /// How the exact transform splits a field of `size`, or `None` where one binding holds it.
    /// [`Error::Size`] past the device's `max_buffer_size`, or where even a split part is too
    /// large for a binding.
    fn split_for(&self, device: &wgpu::Device, size: [u32; 3]) -> Result<Option<Split>, Error> {
        let limits = device.limits();
        let bytes = voxels(size) * 4;
        let binding = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            .min(self.split_bytes.unwrap_or(u64::MAX));
        if bytes <= binding {
            return Ok(None);
        }
        let storage = limits.max_compute_workgroup_storage_size;
        // Each pass in workgroup memory where the unsplit transform would hold it there. At
        // 1024³ on the H100 (2026-11-26, one command, 8 bands in global memory) the y pass took
        // 23.4 ms for the nine slabs in global memory against 26.0 in workgroup memory, the z
        // pass from the words 4.27 to 4.33 ms per part against 7.72 to 7.91.
        let y = match self.tile_for(device, size, 1, false)? {
            Some(_) => Some(TileGeometry::split(size[1], storage, self.split_columns)?),
            None => None,
        };
        // Bands of 8 for the z pass from the words in workgroup memory: at 1024³ on the H100
        // it took 7.95 ms per part with 2 columns per tile against 8.70 with 4 (the y pass took
        // 2.87 ms per slab with 4, 3.15 with 2; the whole transform 54.4 ms with 4 for both).
        let z = match self.tile_for(device, size, 2, false)? {
            Some(_) => Some(TileGeometry::split(size[2], storage, 1)?),
            None => None,
        };
        // Parts are whole tiles wide for both passes.
        let columns = 1u64
            << [y, z]
                .iter()
                .flatten()
                .map(|t| t.lg_columns)
                .max()
                .unwrap_or(0);
        let (part_width, slab_depth) =
            split_layout(size, binding, limits.max_buffer_size, columns)?;
        Ok(Some(Split {
            part_width,
            slab_depth,
            y,
            z,
        }))
    }
    /// The exact transform of a field too large for one binding. The row words as always; then
    /// per part of `split.part_width` columns (x), the z pass from the words into a buffer that
    /// holds that part alone; then per slab of `split.slab_depth` planes of the field, the y
    /// pass from the part into the field, bound one slab at a time (resolving as it goes where
    /// `fuse` says). z before y: each pass then reads and writes whole bindings.
    #[allow(clippy::too_many_arguments)]
    fn encode_exact_split(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        inside: Inside,
        invert: bool,
        fuse: Option<Fuse>,
        split: Split,
    ) -> Result<Slabs, Error> {
        let size = exact_volume_size(device, volume)?;
        let [w, h, d] = size;
        let words = self.row_words(device, rec, volume, inside, invert, true)?;
        let slabs: Vec<(u32, u32)> = (0..d)
            .step_by(split.slab_depth as usize)
            .map(|z0| (z0, (z0 + split.slab_depth).min(d)))
            .collect();
        let nearest: Vec<wgpu::Buffer> = slabs
            .iter()
            .map(|&(z0, z_end)| {
                self.field_buffer(device, "nearest seed (a slab)", [w, h, z_end - z0])
            })
            .collect();
        let part_bytes = voxels([split.part_width, h, d]) * 4;
        let part = kept_buffer(&self.part, part_bytes, true, || {
            field_buffer(
                device,
                "nearest seed (a part of the field)",
                [split.part_width, h, d],
            )
        });
        let part_at = |x0: u32| placement([x0, 0, 0], split.part_width, split.part_width * h);
        // A pass in global memory keeps its envelopes in the part's layout: a part's worth.
        let part_size = [split.part_width, h, d];
        // The y pass resolving a volume in global memory sweeps as the unsplit z pass does
        // (`edt_columns.wgsl`'s SCAN): its sites come from the part, its answers go to the
        // slab, so it writes from the first without reading its sites from the stack. It takes
        // SWEEP_BANDS then (unless set otherwise), whatever the automatic count: a dispatch is
        // one part × one slab, whose fewer columns ask for more bands (32 at 512³ split at
        // 180 MB, 128 columns × 171 planes), and on the H100 there 8 bands and the sweep took
        // the y pass + resolve from 2.427 to 1.776 ms at 1% seeds and 3.467 to 2.167 at 1e-5
        // (8 bands without the sweep: 2.471 and 2.150). One record of the workgroups swept
        // serves every dispatch (each sweep writes the entries of its own before the pass
        // after it reads them).
        let swept = (self.sweep
            && split.y.is_none()
            && fuse.as_ref().is_some_and(|f| !f.flat)
            && self.column_bands.is_none_or(|b| b == SWEEP_BANDS))
        .then(|| {
            self.swept_for(
                device,
                split.part_width.div_ceil(256 / SWEEP_BANDS) * split.slab_depth,
            )
        });
        for x0 in (0..w).step_by(split.part_width as usize) {
            let x_end = (x0 + split.part_width).min(w);
            let span = Span {
                first: [x0, 0],
                x_end,
                y_after_z: false,
                src: part_at(x0),
                dst: part_at(x0),
            };
            let io = TileIo {
                source: None,
                nearest: &part,
                slab: 0,
                span,
            };
            self.encode_from_words(device, rec, &words, io, size, 2, split.z, part_size, None)?;
            for (k, &(z0, z_end)) in slabs.iter().enumerate() {
                let span = Span {
                    first: [x0, z0],
                    x_end,
                    y_after_z: true,
                    src: part_at(x0),
                    dst: placement([0, 0, z0], w, w * h),
                };
                match split.y {
                    Some(tile) => self.encode_tile_columns(
                        device,
                        rec,
                        false,
                        TileIo {
                            source: Some(&part),
                            nearest: &nearest[k],
                            slab: k,
                            span,
                        },
                        size,
                        1,
                        z_end - z0,
                        tile,
                        fuse,
                    )?,
                    // The stack in the part's layout, as the z pass used it.
                    None => self.encode_global_columns(
                        device,
                        rec,
                        false,
                        ColumnsIo {
                            source: Some(&part),
                            words: None,
                            nearest: &nearest[k],
                            stack: &self.stack_for(device, part_size),
                            slab: k,
                            span,
                            sweep: swept.as_ref(),
                        },
                        size,
                        1,
                        z_end - z0,
                        fuse,
                    )?,
                }
            }
        }
        Ok(Slabs {
            buffers: nearest,
            depth: split.slab_depth,
            planes: d,
        })
    }

    /// One exact column pass alone (`axis` 1 = y, 2 = z), in place on `nearest`; `stack` is
    /// scratch of the same size.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_column_pass(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: &wgpu::Buffer,
        stack: &wgpu::Buffer,
        size: [u32; 3],
        axis: u32,
    ) -> Result<(), Error> {
        check_column_axis(device, edt_columns::STAGE, size, axis)?;
        for (what, b) in [("nearest", nearest), ("stack", stack)] {
            check_len(edt_columns::STAGE, what, b, voxels(size) * 4, size)?;
        }
        let others = if axis == 1 { size[2] } else { size[1] };
        self.encode_columns(
            device,
            rec,
            false,
            nearest,
            Some(stack),
            size,
            axis,
            others,
            None,
            None,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn encode_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pack_2d: bool,
        nearest: &wgpu::Buffer,
        stack: Option<&wgpu::Buffer>,
        size: [u32; 3],
        axis: u32,
        others: u32,
        fuse: Option<Fuse>,
        sweep: Option<&wgpu::Buffer>,
    ) -> Result<(), Error> {
        let tile = self.tile_for(device, size, axis, pack_2d)?;
        if let Some(tile) = tile {
            return self.encode_tile_columns(
                device,
                rec,
                pack_2d,
                TileIo::in_place(nearest, size),
                size,
                axis,
                others,
                tile,
                fuse,
            );
        }
        let owned;
        let stack = match stack {
            Some(s) => s,
            None => {
                owned = self.stack_for(device, size);
                &owned
            }
        };
        let io = ColumnsIo {
            source: None,
            words: None,
            nearest,
            stack,
            slab: 0,
            span: Span::whole(size),
            sweep,
        };
        self.encode_global_columns(device, rec, pack_2d, io, size, axis, others, fuse)
    }

    /// One column pass in global memory (`edt_columns.wgsl`) over the columns `io.span` names ×
    /// `others`, resolving into `fuse` where given.
    #[allow(clippy::too_many_arguments)]
    fn encode_global_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pack_2d: bool,
        io: ColumnsIo,
        size: [u32; 3],
        axis: u32,
        others: u32,
        fuse: Option<Fuse>,
    ) -> Result<(), Error> {
        let (nearest, stack, slab) = (io.nearest, io.stack, io.slab);
        let source = io.source.unwrap_or(&self.no_source);
        let words = io.words.unwrap_or(&self.no_source);
        // A resolving 3D pass that sweeps is two dispatches: the sweep, then the envelopes of
        // the workgroups it left (the same entry point, other override constants).
        let resolve = Fuse::resolve(fuse.as_ref(), slab);
        let volume = matches!(resolve, Resolve::Volume(_) | Resolve::SignedVolume(..));
        let (parts, swept): (&[SweepPart], _) = match io.sweep {
            Some(swept) if volume => (&[SweepPart::Sweep, SweepPart::Rest], swept),
            _ => (&[SweepPart::No], &self.no_swept),
        };
        for &part in parts {
            let (params, overrides, groups) = self.global_columns_setup(
                device,
                &io,
                size,
                axis,
                others,
                pack_2d,
                fuse.as_ref(),
                part,
            );
            let name = match (axis, &fuse, io.words.is_some(), part) {
                (1, _, _, SweepPart::Sweep) => "columns (y) sweep + resolve",
                (1, _, _, SweepPart::Rest) => "columns (y) + resolve (rest)",
                (_, _, _, SweepPart::Sweep) => "columns (z) sweep + resolve",
                (_, _, _, SweepPart::Rest) => "columns (z) + resolve (rest)",
                (1, _, true, _) => "columns (y) from row words",
                (_, _, true, _) => "columns (z) from row words",
                (1, None, _, _) => "columns (y)",
                (1, Some(_), _, _) => "columns (y) + resolve",
                (_, None, _, _) => "columns (z)",
                (_, Some(_), _, _) => "columns (z) + resolve",
            };

            // One arm per entry point: the same resources, plus what its resolve writes.
            macro_rules! record {
                ($cache:expr, $entry:ident { $($field:ident: $value:expr),* }) => {
                    $cache.get(device, &overrides, true)?.record(
                        device,
                        rec,
                        &edt_columns::$entry::Resources {
                            params: (&params).into(),
                            nearest: nearest.into(),
                            stack: stack.into(),
                            source: source.into(),
                            words: words.into(),
                            $($field: $value.into()),*
                        },
                        groups,
                        name,
                    )?
                };
            }
            record_resolved! {
                record,
                resolve,
                volume { swept: swept },
                self.columns => columns,
                self.columns_resolve_2d => columns_resolve_2d,
                self.columns_resolve_signed_2d => columns_resolve_signed_2d,
                self.columns_resolve => columns_resolve,
                self.columns_resolve_signed => columns_resolve_signed,
            }
        }
        Ok(())
    }

    /// The parameters, override constants and workgroup count of a global-memory column pass
    /// along `axis` over `io.span`'s columns × `others`, reading and writing as `io` says and
    /// resolving as `fuse` says.
    #[allow(clippy::too_many_arguments)]
    fn global_columns_setup(
        &self,
        device: &wgpu::Device,
        io: &ColumnsIo,
        size: [u32; 3],
        axis: u32,
        others: u32,
        pack_2d: bool,
        fuse: Option<&Fuse>,
        part: SweepPart,
    ) -> (wgpu::Buffer, [(&'static str, f64); 13], [u32; 3]) {
        let span = &io.span;
        let width = span.x_end - span.first[0];
        // A pass that sweeps takes the sweep's bands (its ring's layout, and the workgroups
        // its record names, are those of SWEEP_BANDS).
        let bands = if part == SweepPart::No {
            self.global_bands(width * others, pack_2d)
        } else {
            SWEEP_BANDS
        };
        let [x_bits, y_bits] = packing_of(size).overrides();
        let scan = part == SweepPart::Sweep;
        let overrides = [
            ("PACK_2D", pack_2d as u32 as f64),
            ("BANDS", bands as f64),
            ("AXIS", axis as f64),
            // Sites within the column's plane: made from the row words, or the y pass of a
            // field not split (it runs before z; a split field's y pass reads the z pass's part).
            (
                "PLANAR",
                (!pack_2d && (io.words.is_some() || (axis == 1 && io.source.is_none()))) as u32
                    as f64,
            ),
            ("SOURCE_APART", io.source.is_some() as u32 as f64),
            ("FROM_WORDS", io.words.is_some() as u32 as f64),
            x_bits,
            y_bits,
            ("SCAN", scan as u32 as f64),
            ("AFTER_SCAN", (part == SweepPart::Rest) as u32 as f64),
            // A pass that sweeps in place reads its sites from the stack (see
            // `encode_exact_fused`); a split field's reads them from its part.
            (
                "IN_STACK",
                (part != SweepPart::No && io.source.is_none()) as u32 as f64,
            ),
            ("RING", SWEEP_RING as f64),
            (
                "RING_CELLS",
                if scan { SWEEP_RING * 256 / bands } else { 1 } as f64,
            ),
        ];
        let params = uniform(
            device,
            "edt columns params",
            &edt_columns::ColumnParams {
                size: size.into(),
                voxel_size: fuse.map_or(1.0, |f| f.voxel_size),
                band: fuse.map_or(f32::MAX, |f| f.band),
                first: span.first.into(),
                x_end: span.x_end,
                src: columns_placement(&span.src),
                dst: columns_placement(&span.dst),
            },
        );
        (params, overrides, [width.div_ceil(256 / bands), others, 1])
    }

    /// For benchmarks: the loads and stores of the global-memory column pass along `axis` (1:
    /// y, 2: z) of a 3D field of `size` in `nearest` (from the row words `words` where given, as
    /// the y pass reads them), without the envelopes and their stack: the floor that pass is
    /// measured against. `None` where the pass runs in workgroup memory
    /// ([`Self::encode_tile_copy`]). With `distance` (along z) it also stores a value per voxel
    /// there, as the resolving pass stores its distances.
    #[doc(hidden)]
    #[allow(clippy::too_many_arguments)]
    pub fn encode_global_copy(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: &wgpu::Buffer,
        words: Option<&wgpu::Buffer>,
        size: [u32; 3],
        axis: u32,
        distance: Option<&wgpu::Texture>,
    ) -> Result<Option<()>, Error> {
        check_copy(device, edt_columns::STAGE, nearest, words, size, axis)?;
        let view = distance
            .map(|d| copy_distance_view(edt_columns::STAGE, d, size, axis))
            .transpose()?;
        if self.tile_for(device, size, axis, false)?.is_some() {
            return Ok(None);
        }
        let io = ColumnsIo {
            source: None,
            words,
            nearest,
            stack: &self.no_source,
            slab: 0,
            span: Span::whole(size),
            sweep: None,
        };
        let others = size[3 - axis as usize];
        let (params, overrides, groups) =
            self.global_columns_setup(device, &io, size, axis, others, false, None, SweepPart::No);
        // The stack is unread (IN_STACK is off): a placeholder, not `no_source` (bound read-only
        // beside it: the layout binds the stack read-write).
        match &view {
            None => self.columns_copy.get(device, &overrides, true)?.record(
                device,
                rec,
                &edt_columns::columns_copy::Resources {
                    params: (&params).into(),
                    nearest: nearest.into(),
                    stack: (&self.no_swept).into(),
                    source: (&self.no_source).into(),
                    words: words.unwrap_or(&self.no_source).into(),
                },
                groups,
                if axis == 1 { "copy (y)" } else { "copy (z)" },
            )?,
            Some(view) => self
                .columns_copy_resolve
                .get(device, &overrides, true)?
                .record(
                    device,
                    rec,
                    &edt_columns::columns_copy_resolve::Resources {
                        params: (&params).into(),
                        nearest: nearest.into(),
                        stack: (&self.no_swept).into(),
                        source: (&self.no_source).into(),
                        words: words.unwrap_or(&self.no_source).into(),
                        distance: view.into(),
                    },
                    groups,
                    "copy (z) + distance store",
                )?,
        }
        Ok(Some(()))
    }

    /// Bands per column of a global-memory column pass over `columns` columns.
    fn global_bands(&self, columns: u32, pack_2d: bool) -> u32 {
        self.column_bands
            .unwrap_or(BAND_CHOICES[bands_for(columns, pack_2d)])
    }

    /// Hand back a field no longer needed, so that the next calls take its buffers and
    /// texture instead of allocating new ones: a loop that runs the transform every frame
    /// allocates nothing a frame once it recycles the field before the next (on the H200 the
    /// new buffers of a 512³ field cost the CPU about 26 ms a call, 190 ms at 1024³).
    ///
    /// Kept until a call takes them or the next `recycle` replaces them (this keeps one field's
    /// worth, the last handed back). A call takes a buffer of exactly the size it needs and a
    /// texture of the same size and dimension; what it takes it writes whole before reading,
    /// so the field's old contents never show. Commands are ordered as recorded, so a field may
    /// be recycled as soon as the passes that read it are recorded, even into the same encoder.
    /// A clone of one of its buffers or its texture kept elsewhere would see the next field's
    /// values.
    ///
    /// ```
    /// # fn f(ctx: &fieldkit::gpu::Context, volume: &wgpu::Texture) -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance3d, Options3d};
    /// let d3 = Distance3d::new(&ctx.device)?;
    /// let mut last = None;
    /// for _frame in 0..3 {
    ///     if let Some(field) = last.take() {
    ///         d3.recycle(field);
    ///     }
    ///     let mut encoder = ctx.encoder("distance");
    ///     last = Some(d3.encode(&ctx.device, &mut encoder, volume, &Options3d::default())?);
    ///     ctx.submit_and_wait("distance", encoder)?;
    /// }
    /// # Ok(()) }
    /// ```
    pub fn recycle(&self, field: Field3d) {
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        r.buffers = field.nearest.buffers;
        r.buffers
            .extend(field.nearest_outside.into_iter().flat_map(|s| s.buffers));
        r.textures = vec![field.distance];
    }

    /// [`Self::recycle`] for a 2D field of the exact transform.
    pub fn recycle_2d(&self, field: FieldBuf2d) {
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        r.buffers = std::iter::once(field.nearest)
            .chain(field.nearest_outside)
            .collect();
        r.textures = vec![field.distance];
    }

    /// A buffer for a field of `size`: one handed back to [`Self::recycle`] of exactly its
    /// bytes where there is one, else a new one.
    fn field_buffer(&self, device: &wgpu::Device, label: &str, size: [u32; 3]) -> wgpu::Buffer {
        let bytes = voxels(size) * 4;
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        match r.buffers.iter().position(|b| b.size() == bytes) {
            Some(i) => r.buffers.swap_remove(i),
            None => field_buffer(device, label, size),
        }
    }

    /// A distance texture of `size`: one handed back to [`Self::recycle`] of that size and
    /// dimension where there is one, else a new one.
    fn distance_texture(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        dimension: wgpu::TextureDimension,
    ) -> wgpu::Texture {
        let extent = wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: size[2],
        };
        let mut r = self.recycled.lock().unwrap_or_else(|e| e.into_inner());
        match r
            .textures
            .iter()
            .position(|t| t.size() == extent && t.dimension() == dimension)
        {
            Some(i) => r.textures.swap_remove(i),
            None => distance_texture(device, size, dimension),
        }
    }

    /// The sweep's record of the workgroups it answered (`edt_columns.wgsl`'s `swept`), one
    /// entry for each of `groups` workgroups, kept from call to call as the stack is. The sweep
    /// writes every entry before the pass after it reads them.
    fn swept_for(&self, device: &wgpu::Device, groups: u32) -> wgpu::Buffer {
        let bytes = groups as u64 * 4;
        kept_buffer(&self.swept, bytes, false, || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("edt swept workgroups"),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        })
    }

    /// The envelope stack of the global-memory column passes for a field of `size`: the one
    /// kept from an earlier call where it is large enough, else a new one, kept for the next.
    /// Every pass writes the stack's entries before it reads them, so passes recorded one after
    /// another may share it (wgpu orders their use of it).
    fn stack_for(&self, device: &wgpu::Device, size: [u32; 3]) -> wgpu::Buffer {
        kept_buffer(&self.stack, voxels(size) * 4, false, || {
            field_buffer(device, "edt envelope stack", size)
        })
    }

    /// The workgroup-memory tile the column passes take along `axis` (1: y, 2: z; of a 2D field
    /// of `size` = [w, h, 1] where `flat`) of a field of `size`, or `None` for the global-memory
    /// passes (as [`Self::set_column_passes`] chose).
    fn tile_for(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        axis: u32,
        flat: bool,
    ) -> Result<Option<TileGeometry>, Error> {
        let storage = device.limits().max_compute_workgroup_storage_size;
        Ok(match self.column_passes {
            ColumnPasses::Global => None,
            ColumnPasses::Auto => TileGeometry::auto_for(size, storage, axis, flat),
            ColumnPasses::Workgroup => Some(TileGeometry::forced(size[axis as usize], storage)?),
        })
    }

    /// For benchmarks: the loads and stores of one workgroup-memory column pass along `axis` (1:
    /// y, 2: z) of a 3D field of `size` in `nearest`, without the envelopes, with the tile the
    /// pass itself takes: the floor that pass is measured against. `None` where the pass runs
    /// in global memory. With `distance` (along z) it also stores a value per voxel there, as
    /// the resolving pass stores its distances.
    #[doc(hidden)]
    pub fn encode_tile_copy(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: &wgpu::Buffer,
        size: [u32; 3],
        axis: u32,
        distance: Option<&wgpu::Texture>,
    ) -> Result<Option<()>, Error> {
        check_copy(device, edt_tile::STAGE, nearest, None, size, axis)?;
        let view = distance
            .map(|d| copy_distance_view(edt_tile::STAGE, d, size, axis))
            .transpose()?;
        let Some(tile) = self.tile_for(device, size, axis, false)? else {
            return Ok(None);
        };
        let span = Span::whole(size);
        let (params, overrides) = tile.bind(device, size, axis, false, None, &span, false);
        let groups = tile.groups(&span, size[3 - axis as usize]);
        match &view {
            None => self.tile_copy.get(device, &overrides, false)?.record(
                device,
                rec,
                &edt_tile::tile_copy::Resources {
                    params: (&params).into(),
                    nearest: nearest.into(),
                    source: (&self.no_source).into(),
                },
                groups,
                if axis == 1 {
                    "copy (y, workgroup)"
                } else {
                    "copy (z, workgroup)"
                },
            )?,
            Some(view) => self
                .tile_copy_resolve
                .get(device, &overrides, false)?
                .record(
                    device,
                    rec,
                    &edt_tile::tile_copy_resolve::Resources {
                        params: (&params).into(),
                        nearest: nearest.into(),
                        source: (&self.no_source).into(),
                        distance: view.into(),
                    },
                    groups,
                    "copy (z, workgroup) + distance store",
                )?,
        }
        Ok(Some(()))
    }

    /// A column pass in workgroup memory (`edt_tile.wgsl`), tiles laid out as `tile` says.
    #[allow(clippy::too_many_arguments)]
    fn encode_tile_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pack_2d: bool,
        io: TileIo,
        size: [u32; 3],
        axis: u32,
        others: u32,
        tile: TileGeometry,
        fuse: Option<Fuse>,
    ) -> Result<(), Error> {
        let apart = io.source.is_some();
        let (params, overrides) =
            tile.bind(device, size, axis, pack_2d, fuse.as_ref(), &io.span, apart);
        let groups = tile.groups(&io.span, others);
        let nearest = io.nearest.into();
        let source = io.source.unwrap_or(&self.no_source).into();
        let slab = io.slab;
        let name = match (axis, &fuse) {
            (1, None) => "columns (y, workgroup)",
            (1, Some(_)) => "columns (y, workgroup) + resolve",
            (_, None) => "columns (z, workgroup)",
            (_, Some(_)) => "columns (z, workgroup) + resolve",
        };
        // Every tile cell a thread reads was written by the load first: no zero fill needed (on
        // the H100 the fill cost nothing measurable: 0.872 ms at 256³ with it and without).
        let zero = false;
        // One arm per entry point: the same resources, plus what its resolve writes.
        macro_rules! record {
            ($variants:expr, $entry:ident { $($field:ident: $value:expr),* }) => {
                $variants.get(device, &overrides, zero)?.record(
                    device,
                    rec,
                    &edt_tile::$entry::Resources {
                        params: (&params).into(),
                        nearest,
                        source,
                        $($field: $value.into()),*
                    },
                    groups,
                    name,
                )
            };
        }
        record_resolved! {
            record,
            Fuse::resolve(fuse.as_ref(), slab),
            self.tile_columns => tile_columns,
            self.tile_columns_resolve_2d => tile_columns_resolve_2d,
            self.tile_columns_resolve_signed_2d => tile_columns_resolve_signed_2d,
            self.tile_columns_resolve => tile_columns_resolve,
            self.tile_columns_resolve_signed => tile_columns_resolve_signed,
        }
    }

    /// The exact transform of a 2D mask (any of [`super::SEED_FORMATS`]; red channel marks).
    pub fn encode_exact_2d(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mask: &wgpu::Texture,
        options: &Options3d,
    ) -> Result<FieldBuf2d, Error> {
        let rule = super::SeedRule {
            above: match options.inside {
                // Any value above 0 (the shaders compare ≥ the least normal f32 above it).
                Inside::Mask => 0.0,
                Inside::Threshold(t) => t.next_down(),
            },
            ..super::SeedRule::default()
        };
        self.encode_exact_2d_with(device, rec, mask, options, &rule)
    }

    /// [`Distance3d::encode_exact_2d`] with `rule` choosing the seeds (its `inside` is not
    /// read).
    pub fn encode_exact_2d_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mask: &wgpu::Texture,
        options: &Options3d,
        rule: &super::SeedRule,
    ) -> Result<FieldBuf2d, Error> {
        options.check()?;
        rule.check()?;
        // The same checks as the 2D JFA's seed texture (the same formats work), then the exact
        // transform's own size limit.
        let (w, h) = super::check_seed_texture(device, mask)?;
        check_size_2d_exact(device, w, h)?;
        let size = [w, h, 1];
        let mv = view(mask);
        let stack = self
            .tile_for(device, size, 1, true)?
            .is_none()
            .then(|| self.stack_for(device, size));
        let rec = &mut rec.recorder();
        let distance = self.distance_texture(device, size, wgpu::TextureDimension::D2);
        let dv = view(&distance);
        // The column pass resolves as it answers (`*_resolve*_2d`), as in 3D; a single row has
        // no column pass and is resolved on its own.
        let fuse = |inside_field| {
            (h > 1).then_some(Fuse {
                distance: &dv,
                flat: true,
                voxel_size: options.voxel_size,
                band: options.world_band(),
                inside_field,
            })
        };
        let flood = |rec: &mut Recorder<'_>,
                     invert: bool,
                     fuse: Option<Fuse>|
         -> Result<wgpu::Buffer, Error> {
            let nearest = self.field_buffer(device, "nearest seed", size);
            let params = uniform(
                device,
                "edt rows params",
                &edt_rows::RowParams {
                    size: size.into(),
                    threshold: rule.threshold(),
                    invert: invert as u32,
                    channels: rule.weights(),
                },
            );
            self.rows_2d.record(
                device,
                rec,
                &edt_rows::rows_2d::Resources {
                    params: (&params).into(),
                    mask_2d: (&mv).into(),
                    nearest: (&nearest).into(),
                },
                [h, 1, 1],
                "rows (x)",
            )?;
            if h > 1 {
                self.encode_columns(
                    device,
                    rec,
                    true,
                    &nearest,
                    stack.as_ref(),
                    size,
                    1,
                    1,
                    fuse,
                    None,
                )?;
            }
            Ok(nearest)
        };
        let nearest = flood(rec, false, fuse(None).filter(|_| !options.signed))?;
        let nearest_outside = if options.signed {
            Some(flood(
                rec,
                true,
                fuse(Some(std::slice::from_ref(&nearest))),
            )?)
        } else {
            None
        };
        if h == 1 {
            let params = self.resolve_params(device, size, options);
            let groups =
                ComputePipeline::<field_resolve::resolve_unsigned_2d::Entry>::groups_for(size);
            match &nearest_outside {
                None => {
                    self.resolve_unsigned_2d.record(
                        device,
                        rec,
                        &field_resolve::resolve_unsigned_2d::Resources {
                            params: (&params).into(),
                            nearest: (&nearest).into(),
                            distance_2d: (&dv).into(),
                        },
                        groups,
                        "resolve",
                    )?;
                }
                Some(o) => {
                    self.resolve_signed_2d.record(
                        device,
                        rec,
                        &field_resolve::resolve_signed_2d::Resources {
                            params: (&params).into(),
                            nearest: (&nearest).into(),
                            nearest_outside: o.into(),
                            distance_2d: (&dv).into(),
                        },
                        groups,
                        "resolve",
                    )?;
                }
            }
        }
        Ok(FieldBuf2d {
            width: w,
            height: h,
            nearest,
            nearest_outside,
            distance,
        })
    }

    fn resolve_params(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        options: &Options3d,
    ) -> wgpu::Buffer {
        let band = options.world_band();
        let unreached = options.unreached.unwrap_or(Unreached {
            inside: band,
            outside: band,
        });
        uniform(
            device,
            "resolve params",
            &field_resolve::ResolveParams {
                size: size.into(),
                voxel_size: options.voxel_size,
                band,
                threshold: options.inside.threshold(),
                unreached_inside: unreached.inside,
                unreached_outside: unreached.outside,
            },
        )
    }

    /// Resolve stage alone: packed nearest seeds (and, for signed, the outside field) to distance.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_resolve(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        size: [u32; 3],
        nearest: &wgpu::Buffer,
        nearest_outside: Option<&wgpu::Buffer>,
        options: &Options3d,
    ) -> Result<wgpu::Texture, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        let distance = self.distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = view(&distance);
        let fuse = Fuse {
            distance: &dv,
            flat: false,
            voxel_size: options.voxel_size,
            band: options.world_band(),
            // The signed pass runs "in" the outside field with the inside field beside it.
            inside_field: nearest_outside.map(|_| std::slice::from_ref(nearest)),
        };
        self.resolve_into(device, rec, size, nearest_outside.unwrap_or(nearest), fuse)?;
        Ok(distance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// wgpu's storage binding (2 GiB − 1) and NVIDIA's largest buffer (4 GiB − 2 MiB).
    const BINDING: u64 = (1 << 31) - 1;
    const BUFFER: u64 = (1 << 32) - (2 << 20);

    /// Auto's y pass: in workgroup memory up to 128 long over fewer than 65 536 columns (x · z;
    /// the tile won at 16 384 and 32 768 columns, the global pass from 65 536); else global.
    /// The z pass and 2D columns do not depend on the column count.
    #[test]
    fn the_y_pass_leaves_workgroup_memory_at_65536_columns() {
        let storage = 48 << 10;
        let y = |n: u32, columns: u32| TileGeometry::auto(n, columns, storage, 1, false).is_some();
        assert!(y(128, 128 * 128));
        assert!(y(128, 128 * 256 + 127 * 256));
        assert!(!y(128, 256 * 256));
        assert!(!y(128, 128 * 1024));
        assert!(!y(129, 16));
        let z = |n: u32, columns: u32| TileGeometry::auto(n, columns, storage, 2, false).is_some();
        assert!(z(256, 1 << 20) && !z(257, 16));
        assert!(TileGeometry::auto(256, 1 << 20, storage, 1, true).is_some());
    }

    /// Bands of the global passes: 8 in 3D from 16 384 columns up (2^17 threads), more below,
    /// 32 at most; 2D aims at 2^17 threads with no floor.
    #[test]
    fn global_passes_take_8_bands_from_16384_columns_in_3d() {
        let bands = |columns: u32, flat: bool| BAND_CHOICES[bands_for(columns, flat)];
        assert_eq!(bands(1 << 20, false), 8);
        assert_eq!(bands(16384, false), 8);
        assert_eq!(bands(16383, false), 16);
        assert_eq!(bands(8192, false), 16);
        assert_eq!(bands(4096, false), 32);
        assert_eq!(bands(1, false), 32);
        assert_eq!(bands(16384, true), 8);
        assert_eq!(bands(65536, true), 2);
        assert_eq!(bands(1 << 20, true), 1);
    }

    #[test]
    fn split_parts_start_on_row_boundaries_where_they_can() {
        // 1024³: three parts, each starting on a multiple of 32 columns (342 each, evenly, put
        // two of them off the boundary), and three slabs.
        assert_eq!(
            split_layout([1024; 3], BINDING, BUFFER, 1).unwrap(),
            (352, 342)
        );
        // Wider tiles keep their own multiple where it is larger.
        assert_eq!(
            split_layout([1024; 3], BINDING, BUFFER, 64).unwrap(),
            (384, 342)
        );
        // A binding that holds fewer than 32 columns: whole tiles, as evenly as they fit.
        let size = [40, 12, 300];
        let binding = 40 * 12 * 300 * 4 / 2;
        assert_eq!(split_layout(size, binding, BUFFER, 4).unwrap(), (20, 150));
        assert_eq!(split_layout(size, binding, BUFFER, 1).unwrap(), (20, 150));
        // 40 columns fit: parts of 32 (the last one 4 wide) rather than 34 off the boundary; 3
        // planes of 3200 bytes fit, so 3 slabs of 3 planes.
        assert_eq!(
            split_layout([100, 8, 8], 40 * 8 * 8 * 4, BUFFER, 1).unwrap(),
            (32, 3)
        );
        // Not one tile of columns, or not one plane: typed errors naming which.
        match split_layout([40, 12, 300], 64, BUFFER, 4) {
            Err(Error::Size { what, .. }) => assert!(what.contains("tile of columns"), "{what}"),
            other => panic!("{other:?}"),
        }
        match split_layout([4096, 4096, 2], 1 << 20, BUFFER, 1) {
            Err(Error::Size { what, .. }) => assert!(what.contains("one plane"), "{what}"),
            other => panic!("{other:?}"),
        }
    }
}
