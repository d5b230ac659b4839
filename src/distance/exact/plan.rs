//! How the exact transform lays out its passes: bands per column of the global-memory passes,
//! rows per workgroup of the row pass, and the workgroup-memory tiles of the column passes
//! ([`TileGeometry`]), with the spans of columns a dispatch answers. Pure arithmetic, measured
//! choices; `docs/distance.md` has the measurements behind the constants.

use crate::distance::packing::packing_of;
use crate::distance::resolve::Fuse;
use crate::error::Error;
use crate::gpu::uniform_buffer as uniform;
use crate::shaders::distance::{edt_columns, edt_tile};

/// Bands per column in the exact column passes in global memory (`edt_columns.wgsl`): enough
/// that columns × bands reaches about `TARGET_THREADS_3D` threads in 3D, and never fewer than
/// `MIN_BANDS_3D`; about `TARGET_THREADS_2D` in 2D; 32 at most. In 3D that is 8 bands from
/// 16 384 columns up; the resolving pass takes 8 wherever it sweeps (`encode_exact_fused`).
/// docs/distance.md ("Bands per column") has the measurements behind these.
pub(crate) const TARGET_THREADS_3D: u32 = 1 << 17;
pub(crate) const MIN_BANDS_3D: u32 = 8;
pub(crate) const TARGET_THREADS_2D: u32 = 1 << 17;
pub(crate) const BAND_CHOICES: [u32; 6] = [1, 2, 4, 8, 16, 32];
/// The sweep (`edt_columns.wgsl`'s SCAN) runs where the resolving global pass (z; y of a field
/// split across bindings) takes this many bands (32 columns per workgroup; the pass takes it
/// whatever the automatic count, unless `set_column_bands` says otherwise), in a ring of
/// SWEEP_RING rows (24 either side of a step's 8, rounded up to a power of two: 8 KiB).
pub(crate) const SWEEP_BANDS: u32 = 8;
pub(crate) const SWEEP_RING: u32 = 64;

/// Which dispatch of a resolving pass that sweeps (`edt_columns.wgsl`'s SCAN, AFTER_SCAN) a
/// dispatch is: the sweep, the rest (the workgroups it left to the envelopes), or neither.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum SweepPart {
    No,
    Sweep,
    Rest,
}

pub(crate) fn bands_for(columns: u32, flat: bool) -> usize {
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
pub(crate) fn rows_per_group(width: u32, rows: u32) -> u32 {
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

/// Workgroup memory of a tile pass beside its tile, in 4-byte cells: the 256 envelope sizes and
/// the resolving entries' `far_sites` flag.
const TILE_EXTRA_CELLS: u32 = 257;

/// How a column of length `n` is laid out in a workgroup-memory tile (`edt_tile.wgsl`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct TileGeometry {
    pub(crate) lg_columns: u32,
    pub(crate) lg_band: u32,
    pub(crate) bands: u32,
    pub(crate) column_cells: u32,
}

impl TileGeometry {
    /// The most columns (a power of two from `min_columns` to `max_columns`) whose tile fits
    /// `storage` bytes of workgroup memory, with the envelope sizes beside it.
    pub(crate) fn fit(n: u32, storage: u32, min_columns: u32, max_columns: u32) -> Option<Self> {
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
            let bytes = (column_cells as u64 * columns as u64 + TILE_EXTRA_CELLS as u64) * 4;
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
    pub(crate) fn longest(storage: u32) -> u32 {
        (1..=storage / 4)
            .rev()
            .find(|&n| Self::fit(n, storage, 1, 1).is_some())
            .unwrap_or(0)
    }

    /// What [`ColumnPasses::Auto`] takes for `columns` columns of length `n` along `axis` (1:
    /// y, 2: z) of a 3D field, or along y of a 2D field where `flat`.
    pub(crate) fn auto(n: u32, columns: u32, storage: u32, axis: u32, flat: bool) -> Option<Self> {
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
    pub(crate) fn auto_for(size: [u32; 3], storage: u32, axis: u32, flat: bool) -> Option<Self> {
        let columns = size[0] * size[3 - axis as usize];
        Self::auto(size[axis as usize], columns, storage, axis, flat)
    }

    /// The tile [`ColumnPasses::Workgroup`] takes at any length: bands of 8 where they fit (16
    /// columns of 512 took 4.48 ms for y at 512³, 4 columns 2.70), fewer columns where the
    /// storage is short; [`Error::Size`] where not even one column fits.
    pub(crate) fn forced(n: u32, storage: u32) -> Result<Self, Error> {
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
    pub(crate) fn split(n: u32, storage: u32, least: u32) -> Result<Self, Error> {
        let columns = least.max(Self::banded_columns(n));
        match Self::fit(n, storage, least, columns) {
            Some(tile) => Ok(tile),
            None => Self::forced(n, storage),
        }
    }

    /// Columns per tile for bands of [`AUTO_TILE_BAND`] positions: `256 · 8 / n`, 1 to 16.
    pub(crate) fn banded_columns(n: u32) -> u32 {
        (256 * AUTO_TILE_BAND / n.max(1)).clamp(1, MAX_TILE_COLUMNS)
    }

    /// The pass's parameters and override constants, for the columns `span` names, reading
    /// a buffer apart from the one it writes where `source_apart`.
    pub(crate) fn bind(
        &self,
        device: &wgpu::Device,
        pass: Pass,
        fuse: Option<&Fuse>,
        span: &Span,
        source_apart: bool,
    ) -> (wgpu::Buffer, edt_tile::Overrides) {
        let Pass {
            size,
            axis,
            pack_2d,
            ..
        } = pass;
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
        let packing = packing_of(size);
        // A 2D pass sizes its tile for the most the device holds, not for this height: every
        // mask then takes the same pipeline, so a new mask size makes none (the viewer's mask
        // growing took 139 ms on the H200 with the driver's shader cache off, 0.78 ms now). The
        // 2D tile passes are small (columns of at most 256): 256² took 0.0342 ms either way
        // (`docs/bench/distance_2d_tile_cells_h200.csv`). The 3D passes keep their tile to the
        // cell, for occupancy.
        let cells = if pack_2d {
            device.limits().max_compute_workgroup_storage_size / 4 - TILE_EXTRA_CELLS
        } else {
            self.column_cells << self.lg_columns
        };
        let overrides = edt_tile::Overrides {
            pack_2d,
            axis,
            cells,
            y_after_z: span.y_after_z,
            source_apart,
            seed_x_bits: packing.x_bits,
            seed_y_bits: packing.y_bits,
            signed: fuse.is_some_and(|f| f.inside_field.is_some()),
        };
        (params, overrides)
    }

    /// Workgroups for a pass over the span's columns × `others`.
    pub(crate) fn groups(&self, span: &Span, others: u32) -> [u32; 3] {
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
pub(crate) struct Span {
    /// The first column's x, and the other coordinate (z for y columns, y for z columns) of the
    /// first row of workgroups.
    pub(crate) first: [u32; 2],
    /// The x where the span's columns end.
    pub(crate) x_end: u32,
    /// A y pass after the z pass: its sites are off the column's plane in z too.
    pub(crate) y_after_z: bool,
    pub(crate) src: edt_tile::Placement,
    pub(crate) dst: edt_tile::Placement,
}

/// One column pass: the columns along `axis` (1: y, 2: z; y of a 2D field where `pack_2d`) of a
/// field of `size`, over `others` rows of workgroups (the field's third axis, or a slab's
/// planes).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pass {
    pub(crate) size: [u32; 3],
    pub(crate) axis: u32,
    pub(crate) others: u32,
    pub(crate) pack_2d: bool,
}

impl Pass {
    /// Every column of a 3D field of `size` along `axis`.
    pub(crate) fn along(size: [u32; 3], axis: u32) -> Self {
        Self {
            size,
            axis,
            others: size[3 - axis as usize],
            pack_2d: false,
        }
    }
}

/// A buffer holding the voxels from `origin` on, `row` elements per row, `plane` per plane.
pub(crate) fn placement(origin: [u32; 3], row: u32, plane: u32) -> edt_tile::Placement {
    edt_tile::Placement {
        origin: origin.into(),
        row,
        plane,
    }
}

/// What one dispatch of a workgroup column pass reads (`source`, or, `None`, `nearest` itself)
/// and writes (`nearest`, and slab `slab` of a signed pass's inside field), with the columns
/// `span` names.
pub(crate) struct TileIo<'a> {
    pub(crate) source: Option<&'a wgpu::Buffer>,
    pub(crate) nearest: &'a wgpu::Buffer,
    pub(crate) slab: usize,
    pub(crate) span: Span,
}

/// What one dispatch of a global-memory column pass reads and writes, as [`TileIo`] says it
/// for a workgroup pass, plus the envelope stack (in `span.src`'s layout) and, for the z pass
/// of a split field, the row words it makes its sites from.
pub(crate) struct ColumnsIo<'a> {
    pub(crate) source: Option<&'a wgpu::Buffer>,
    pub(crate) words: Option<&'a wgpu::Buffer>,
    pub(crate) nearest: &'a wgpu::Buffer,
    pub(crate) stack: &'a wgpu::Buffer,
    pub(crate) slab: usize,
    pub(crate) span: Span,
    /// The resolving pass sweeps the workgroups whose every voxel has a site near it and
    /// leaves the others to a pass of their own (`edt_columns.wgsl`'s SCAN, AFTER_SCAN), with
    /// its record of which it swept. It reads its sites from `source` where given (a split
    /// field's part), else from `stack` (IN_STACK).
    pub(crate) sweep: Option<&'a wgpu::Buffer>,
}

/// The same placement as `edt_columns.wgsl` declares it.
pub(crate) fn columns_placement(p: &edt_tile::Placement) -> edt_columns::Placement {
    edt_columns::Placement {
        origin: p.origin,
        row: p.row,
        plane: p.plane,
    }
}

impl<'a> TileIo<'a> {
    /// Every column of `nearest` (a field of `size`), in place.
    pub(crate) fn in_place(nearest: &'a wgpu::Buffer, size: [u32; 3]) -> Self {
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
    pub(crate) fn whole(size: [u32; 3]) -> Self {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
