//! The exact Euclidean distance transform (Felzenszwalb & Huttenlocher's lower envelopes, one
//! axis at a time): rows along x ([`rows`]), then columns along y and z, in workgroup memory
//! ([`tile`]) or global memory ([`global`]), the last one resolving as it answers ([`fuse`]);
//! fields past one binding split ([`split`]); 2D masks ([`flat`]); [`plan`] says how each pass
//! is laid out.

mod copy;
mod flat;
#[macro_use]
mod fuse;
mod global;
pub(crate) mod plan;
mod rows;
mod split;
mod tile;

use std::sync::{Arc, Mutex};

use crate::bind::{ComputePipeline, Variants};
use crate::distance::STAGE_3D as STAGE;
use crate::distance::buffers::view;
use crate::distance::buffers::{Pool, kept_buffer, new_field_buffer};
use crate::distance::check::{check_column_axis, check_len, exact_volume_size, voxels};
use crate::distance::options::Marks;
use crate::distance::resolve::{Fuse, Resolver};
use crate::distance::{Field3d, SeedPacking, Settings3d, Slabs};
use crate::error::Error;
use crate::gpu::Record;
use crate::shaders::distance::{edt_columns, edt_rows, edt_tile};
use plan::{
    BAND_CHOICES, ColumnPasses, ColumnsIo, MAX_TILE_COLUMNS, MIN_TILE_COLUMNS, Pass, SWEEP_BANDS,
    Span, TileGeometry, TileIo,
};

/// Scratch the exact transform keeps from call to call, each the largest made so far: a new one
/// each call would be allocated, and zeroed by wgpu, every frame.
#[derive(Default)]
struct Kept {
    /// The global-memory column passes' envelope stack.
    stack: Mutex<Option<wgpu::Buffer>>,
    /// The sweep's record of the workgroups it answered.
    swept: Mutex<Option<wgpu::Buffer>>,
    /// The row words of the transform's own calls (every word is written before it is read).
    words: Mutex<Option<wgpu::Buffer>>,
    /// A split field's part (the z pass's output, the y pass's input).
    part: Mutex<Option<wgpu::Buffer>>,
}

/// The exact transform's stages, run alone: [`super::Distance3d::exact`]
/// ([`super::Distance3d::encode`] with [`super::Method::Exact`] runs them in turn and resolves
/// as the last one answers). Holds the pipelines (made on first use per variant), the
/// settings `Distance3d`'s setters change and the scratch kept from call to call.
pub struct Exact {
    /// By rows per workgroup (`rows_per_group`) and seed widths.
    rows: Variants<edt_rows::rows::Entry, edt_rows::Overrides>,
    rows_2d: ComputePipeline<edt_rows::rows_2d::Entry>,
    /// The 3D row pass as words of marks, per rows per workgroup (`ROWS`).
    row_words: Variants<edt_rows::row_words::Entry, edt_rows::Overrides>,
    /// Column pass per band count, packing and seed widths, made on first use.
    columns: Variants<edt_columns::columns::Entry, edt_columns::Overrides>,
    columns_copy: Variants<edt_columns::columns_copy::Entry, edt_columns::Overrides>,
    columns_copy_resolve:
        Variants<edt_columns::columns_copy_resolve::Entry, edt_columns::Overrides>,
    /// The last 3D column pass with the resolve (signed or not) folded in.
    columns_resolve: Variants<edt_columns::columns_resolve::Entry, edt_columns::Overrides>,
    /// The same for the column pass of a 2D field.
    columns_resolve_2d: Variants<edt_columns::columns_resolve_2d::Entry, edt_columns::Overrides>,
    /// The column passes in workgroup memory (`edt_tile.wgsl`), per tile size.
    tile_columns: Variants<edt_tile::tile_columns::Entry, edt_tile::Overrides>,
    tile_columns_words: Variants<edt_tile::tile_columns_words::Entry, edt_tile::Overrides>,
    tile_columns_resolve: Variants<edt_tile::tile_columns_resolve::Entry, edt_tile::Overrides>,
    tile_columns_resolve_2d:
        Variants<edt_tile::tile_columns_resolve_2d::Entry, edt_tile::Overrides>,
    tile_copy: Variants<edt_tile::tile_copy::Entry, edt_tile::Overrides>,
    tile_copy_resolve: Variants<edt_tile::tile_copy_resolve::Entry, edt_tile::Overrides>,
    /// Bands per column chosen by the caller; `None` picks by grid size.
    column_bands: Option<u32>,
    column_passes: ColumnPasses,
    /// Fold the 3D row pass into the y pass (its sites made from the row words) where y is
    /// not the last pass.
    fold_rows: bool,
    /// The largest field the exact transform binds whole (below the device's limit: for tests).
    split_bytes: Option<u64>,
    /// Fewest columns per tile of a split field's passes.
    split_columns: u32,
    /// The resolving global pass (z; y of a split field) sweeps the workgroups whose every
    /// voxel has a site near it.
    sweep: bool,
    kept: Kept,
    /// Bound as `edt_tile.wgsl`'s `source` where a pass reads the buffer it writes (a binding
    /// must be there; the shader does not read it then).
    no_source: wgpu::Buffer,
    /// Bound as `edt_columns.wgsl`'s `swept` where there is no sweep (not `no_source`: a
    /// dispatch may not bind one buffer both read-only and read-write).
    no_swept: wgpu::Buffer,
    /// Where outputs come from (fields handed back with `recycle`, else new).
    pool: Arc<Pool>,
    /// The resolve of a field no column pass resolved (a single row).
    resolve: Arc<Resolver>,
}

impl Exact {
    pub(crate) fn new(
        device: &wgpu::Device,
        pool: Arc<Pool>,
        resolve: Arc<Resolver>,
    ) -> Result<Self, Error> {
        let placeholder = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        Ok(Self {
            rows: Default::default(),
            rows_2d: ComputePipeline::new(device)?,
            row_words: Default::default(),
            columns: Default::default(),
            columns_copy: Default::default(),
            columns_copy_resolve: Default::default(),
            columns_resolve: Default::default(),
            columns_resolve_2d: Default::default(),
            tile_columns: Default::default(),
            tile_columns_words: Default::default(),
            tile_columns_resolve: Default::default(),
            tile_columns_resolve_2d: Default::default(),
            tile_copy: Default::default(),
            tile_copy_resolve: Default::default(),
            column_bands: None,
            column_passes: ColumnPasses::Auto,
            fold_rows: true,
            split_bytes: None,
            split_columns: MIN_TILE_COLUMNS,
            sweep: true,
            kept: Kept::default(),
            no_source: placeholder("edt: no source, no words"),
            no_swept: placeholder("edt: no sweep"),
            pool,
            resolve,
        })
    }

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
    pub(crate) fn set_column_bands(&mut self, bands: Option<u32>) -> Result<(), Error> {
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
    pub(crate) fn set_fold_rows(&mut self, fold: bool) {
        self.fold_rows = fold;
    }

    /// For benchmarks and tests: `true` (the default) lets the resolving global z pass at 8
    /// bands sweep the workgroups whose every voxel has a site near it (`edt_columns.wgsl`'s
    /// SCAN; it runs after the y pass from the row words, which then writes into the kept
    /// stack for it), and the resolving y pass of a field split across bindings likewise (it
    /// reads the part the z pass wrote); `false` has every workgroup build the envelopes, as
    /// those passes do at other band counts and in workgroup memory.
    #[doc(hidden)]
    pub(crate) fn set_sweep(&mut self, sweep: bool) {
        self.sweep = sweep;
    }

    /// For tests: split the exact transform's field across bindings past `bytes` (or, `None`,
    /// past the device's `max_storage_buffer_binding_size` only, the default), so that the
    /// split runs at sizes a software adapter handles.
    #[doc(hidden)]
    pub(crate) fn set_split_bytes(&mut self, bytes: Option<u64>) {
        self.split_bytes = bytes;
    }

    /// For benchmarks: the fewest columns per tile (1 to 16, a power of two) of the y pass of a
    /// split field (default [`MIN_TILE_COLUMNS`]; `None` restores it).
    #[doc(hidden)]
    pub(crate) fn set_split_columns(&mut self, columns: Option<u32>) -> Result<(), Error> {
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
    pub(crate) fn set_column_passes(&mut self, passes: ColumnPasses) {
        self.column_passes = passes;
    }

    /// The exact distance field of the marked voxels of `volume`: the last column pass resolves
    /// as it answers (`columns_resolve*`), so the field is not read a second time.
    pub(crate) fn encode_volume(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        options: &Settings3d,
    ) -> Result<Field3d, Error> {
        // Checked against the split it takes where the field is larger than one binding.
        let size = exact_volume_size(device, volume)?;
        let rec = &mut rec.recorder();
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = view(&distance);
        let resolve = |inside_field| Fuse {
            distance: &dv,
            flat: false,
            voxel_size: options.voxel_size,
            band: options.world_band(),
            inside_field,
        };
        let marks = |invert| Marks::new(volume, options.inside, invert);
        let nearest = self.encode_exact_fused(
            device,
            rec,
            marks(false),
            (!options.signed).then(|| resolve(None)),
        )?;
        let nearest_outside = if options.signed {
            let inside_field = Some(&nearest.buffers[..]);
            Some(self.encode_exact_fused(device, rec, marks(true), Some(resolve(inside_field)))?)
        } else {
            None
        };
        Ok(Field3d {
            size,
            packing: SeedPacking::for_size(size).expect("checked by exact_volume_size"),
            nearest,
            nearest_outside,
            distance,
        })
    }

    /// The exact transform (rows, then columns along y and z) of the marked voxels: packed
    /// nearest seeds in a new buffer, or in slabs where the field is larger than one.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
    ) -> Result<Slabs, Error> {
        self.encode_exact_fused(device, rec, marks, None)
    }

    /// [`Self::encode`], resolving into `fuse` in its last pass when given.
    pub(crate) fn encode_exact_fused(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
        fuse: Option<Fuse>,
    ) -> Result<Slabs, Error> {
        let size = exact_volume_size(device, marks.volume)?;
        if let Some(split) = self.split_for(device, size)? {
            return self.encode_exact_split(device, rec, marks, fuse, split);
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
            let words = self.row_words(device, rec, marks, true)?;
            let nearest = self.pool.field_buffer(device, "nearest seed", size);
            let tile = self.tile_for(device, size, 1, false)?;
            // Where the z pass sweeps, into the stack, with `nearest` the y pass's own stack.
            let stack = sweep.is_some().then(|| self.stack_for(device, size));
            let (out, scratch) = match &stack {
                Some(stack) => (stack, Some(&nearest)),
                None => (&nearest, None),
            };
            let io = TileIo::in_place(out, size);
            let pass = Pass::along(size, 1);
            self.encode_from_words(device, rec, &words, io, pass, tile, size, scratch)?;
            (nearest, 2)
        } else {
            (self.encode_rows(device, rec, marks)?, 1)
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
            let pass = Pass::along(size, axis);
            let sweep = sweep.as_ref().filter(|_| last);
            self.encode_columns(device, rec, &nearest, stack.as_ref(), pass, f, sweep)?;
        }
        if let Some(f) = fuse {
            // A single row (no column pass ran): resolve on its own.
            self.resolve.resolve_into(device, rec, size, &nearest, f)?;
        }
        Ok(Slabs::one(nearest, size[2]))
    }

    /// One exact column pass alone (`axis` 1 = y, 2 = z), in place on `nearest`; `stack` is
    /// scratch of the same size.
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
        let pass = Pass::along(size, axis);
        self.encode_columns(device, rec, nearest, Some(stack), pass, None, None)
    }

    /// The column pass `pass` in place on `nearest`, in workgroup or global memory as
    /// [`Self::tile_for`] says (with `stack`, or the kept one, for its envelopes there),
    /// resolving into `fuse` where given, sweeping where `sweep` is given.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: &wgpu::Buffer,
        stack: Option<&wgpu::Buffer>,
        pass: Pass,
        fuse: Option<Fuse>,
        sweep: Option<&wgpu::Buffer>,
    ) -> Result<(), Error> {
        let size = pass.size;
        let tile = self.tile_for(device, size, pass.axis, pass.pack_2d)?;
        if let Some(tile) = tile {
            let io = TileIo::in_place(nearest, size);
            return self.encode_tile_columns(device, rec, io, pass, tile, fuse);
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
        self.encode_global_columns(device, rec, io, pass, fuse)
    }

    /// The sweep's record of the workgroups it answered (`edt_columns.wgsl`'s `swept`), one
    /// entry for each of `groups` workgroups, kept from call to call as the stack is. The sweep
    /// writes every entry before the pass after it reads them.
    pub(crate) fn swept_for(&self, device: &wgpu::Device, groups: u32) -> wgpu::Buffer {
        let bytes = groups as u64 * 4;
        kept_buffer(&self.kept.swept, bytes, false, || {
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
    pub(crate) fn stack_for(&self, device: &wgpu::Device, size: [u32; 3]) -> wgpu::Buffer {
        kept_buffer(&self.kept.stack, voxels(size) * 4, false, || {
            new_field_buffer(device, "edt envelope stack", size)
        })
    }

    /// The workgroup-memory tile the column passes take along `axis` (1: y, 2: z; of a 2D field
    /// of `size` = [w, h, 1] where `flat`) of a field of `size`, or `None` for the global-memory
    /// passes (as [`Self::set_column_passes`] chose).
    pub(crate) fn tile_for(
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
}
