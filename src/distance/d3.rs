//! 3D distance fields (and the exact transform in 2D, which [`super::Distance2d`] runs): an exact Euclidean distance transform,
//! the JFA family, sub-voxel seeds, and resolve to unsigned or signed distance in world units.
//!
//! Seeds and nearest-seed fields are storage buffers, x fastest, one `u32` per voxel: a packed
//! integer seed (11/11/10 bits, [`pack_seed3`]; the exact transform packs grids past 2048 ×
//! 2048 × 1024 with the bits their sides need, [`SeedPacking`]) or, for sub-voxel seeds, a key
//! into a table of points. Distances are written to an `R32Float` 3D texture for sampling.
//!

use std::sync::Arc;

use super::buffers::{Pool, view};
use super::check::{check_len, check_size_3d, check_volume, voxels};
use super::exact::Exact;
use super::jfa3d::Jfa3d;
use super::options::Marks;
use super::points::{PointField, Points};
use super::resolve::{Fuse, Resolver};
use super::{ColumnPasses, Field3d, FieldBuf2d, Method, PointSeeds, STAGE_3D as STAGE, Settings3d};
use crate::error::Error;
use crate::gpu::{Record, Recorder};

/// All 3D distance pipelines. Create once, encode many times.
///
/// Besides its pipelines it keeps one buffer between calls: the envelope stack of the exact
/// transform's column passes in global memory (4 bytes per voxel of the largest field whose
/// columns ran there; 512 MiB after a 512³ field), so that a transform run every frame does
/// not allocate, and have wgpu zero, a buffer that size each time. Drop the `Distance3d` to
/// free it.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, occupancy: &[u8]) -> Result<(), fieldkit::Error> {
/// use fieldkit::distance::{upload_volume, Distance3d, Settings3d};
/// let distance = Distance3d::new(device)?; // once
/// let volume = upload_volume(device, queue, occupancy, [64, 64, 64])?; // x fastest, non-zero seeds
/// let mut encoder = device.create_command_encoder(&Default::default());
/// let field = distance.encode(device, &mut encoder, &volume, &Settings3d::default())?;
/// queue.submit([encoder.finish()]);
/// // Use field.distance (R32Float 3D), then hand the buffers back for the next call:
/// distance.recycle(field);
/// # Ok(()) }
/// ```
pub struct Distance3d {
    exact: Exact,
    jfa: Jfa3d,
    points: Points,
    resolve: Arc<Resolver>,
    /// Fields handed back with [`Self::recycle`], which every method's outputs come from first.
    pool: Arc<Pool>,
}

impl Distance3d {
    /// Create every 3D pipeline (and the 2D exact transform's).
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        let pool = Arc::new(Pool::default());
        let resolve = Arc::new(Resolver::new(device)?);
        Ok(Self {
            exact: Exact::new(device, pool.clone(), resolve.clone())?,
            jfa: Jfa3d::new(device, pool.clone())?,
            points: Points::new(device, pool.clone())?,
            resolve,
            pool,
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
    pub fn set_column_bands(&mut self, bands: Option<u32>) -> Result<(), Error> {
        self.exact.set_column_bands(bands)
    }

    /// For benchmarks: `false` runs the 3D row pass on its own (its field written, then read
    /// by the y pass) where the exact transform otherwise folds it into the y pass's load.
    #[doc(hidden)]
    pub fn set_fold_rows(&mut self, fold: bool) {
        self.exact.set_fold_rows(fold)
    }

    /// For benchmarks and tests: `true` (the default) lets the resolving global z pass at 8
    /// bands sweep the workgroups whose every voxel has a site near it (`edt_columns.wgsl`'s
    /// SCAN; it runs after the y pass from the row words, which then writes into the kept
    /// stack for it), and the resolving y pass of a field split across bindings likewise (it
    /// reads the part the z pass wrote); `false` has every workgroup build the envelopes, as
    /// those passes do at other band counts and in workgroup memory.
    #[doc(hidden)]
    pub fn set_sweep(&mut self, sweep: bool) {
        self.exact.set_sweep(sweep)
    }

    /// For tests: split the exact transform's field across bindings past `bytes` (or, `None`,
    /// past the device's `max_storage_buffer_binding_size` only, the default), so that the
    /// split runs at sizes a software adapter handles.
    #[doc(hidden)]
    pub fn set_split_bytes(&mut self, bytes: Option<u64>) {
        self.exact.set_split_bytes(bytes)
    }

    /// For benchmarks: the fewest columns per tile (1 to 16, a power of two) of the y pass of a
    /// split field (default [`MIN_TILE_COLUMNS`]; `None` restores it).
    #[doc(hidden)]
    pub fn set_split_columns(&mut self, columns: Option<u32>) -> Result<(), Error> {
        self.exact.set_split_columns(columns)
    }

    /// Choose where the exact transform's column passes hold their columns (default
    /// [`ColumnPasses::Auto`]). Only speed differs, and which of two equally near seeds is named.
    pub fn set_column_passes(&mut self, passes: ColumnPasses) {
        self.exact.set_column_passes(passes)
    }

    /// The exact transform's stages, to run alone (tests, benchmarks, a pipeline of the
    /// caller's own), and the exact transform of a 2D mask.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, encoder: &mut wgpu::CommandEncoder, volume: &wgpu::Texture)
    /// # -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance3d, Inside, Marks};
    /// let d3 = Distance3d::new(device)?;
    /// // Per row, the nearest marked voxel along x.
    /// let rows = d3.exact().encode_rows(device, encoder, Marks::new(volume, Inside::Mask, false))?;
    /// # Ok(()) }
    /// ```
    pub fn exact(&self) -> &Exact {
        &self.exact
    }

    /// 3D jump flooding's stages, to run alone.
    pub fn jfa(&self) -> &Jfa3d {
        &self.jfa
    }

    /// Distance field of the marked voxels of `volume` (a mask or a density, see [`super::Inside`]).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &wgpu::Texture,
        options: &Settings3d,
    ) -> Result<Field3d, Error> {
        options.check()?;
        let variant = match options.method {
            Method::Exact => return self.exact.encode_volume(device, rec, volume, options),
            Method::Lines => {
                check_volume(device, volume)?;
                return Err(Error::Invalid {
                    stage: STAGE,
                    what: "the line passes are for sub-voxel seeds; integer seeds take the exact \
                           transform (Method::Exact), which is exact at every distance"
                        .into(),
                });
            }
            Method::Jfa(variant) => variant,
        };
        let size = check_volume(device, volume)?;
        let rec = &mut rec.recorder();
        let steps = options.steps(variant, size.into_iter().max().unwrap());
        let flood = |rec: &mut Recorder<'_>, invert: bool| -> Result<wgpu::Buffer, Error> {
            let seeds =
                self.jfa
                    .encode_seed(device, rec, Marks::new(volume, options.inside, invert))?;
            self.jfa
                .encode_flood(device, rec, seeds, size, &steps, None)
        };
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
        Ok(Field3d::whole(size, nearest, nearest_outside, distance))
    }

    /// Resolve stage alone: packed nearest seeds (and, for signed, the outside field) to distance.
    pub fn encode_resolve(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        size: [u32; 3],
        nearest: &wgpu::Buffer,
        nearest_outside: Option<&wgpu::Buffer>,
        options: &Settings3d,
    ) -> Result<wgpu::Texture, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = view(&distance);
        let fuse = Fuse {
            distance: &dv,
            flat: false,
            voxel_size: options.voxel_size,
            band: options.world_band(),
            // The signed pass runs "in" the outside field with the inside field beside it.
            inside_field: nearest_outside.map(|_| std::slice::from_ref(nearest)),
        };
        self.resolve
            .resolve_into(device, rec, size, nearest_outside.unwrap_or(nearest), fuse)?;
        Ok(distance)
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
        options: &Settings3d,
    ) -> Result<Field3d, Error> {
        let field = PointField::checked(device, &points.buffer, size, inside, options)?;
        let keys = self.points.seed(device, rec, points, size)?;
        self.flood_points(device, rec, keys, field)
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
        options: &Settings3d,
    ) -> Result<Field3d, Error> {
        let field = PointField::checked(device, points, size, inside, options)?;
        check_len(STAGE, "keys", &keys, voxels(size) * 4, size)?;
        self.flood_points(device, rec, keys, field)
    }

    /// The flood of checked point keys by the method the settings name, and its resolve.
    fn flood_points(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        keys: wgpu::Buffer,
        field: PointField,
    ) -> Result<Field3d, Error> {
        let PointField {
            points,
            size,
            options,
            ..
        } = field;
        match (options.method, options.band) {
            (Method::Jfa(variant), _) => {
                let steps = options.steps(variant, size.into_iter().max().unwrap());
                let nearest =
                    self.jfa
                        .encode_flood(device, rec, keys, size, &steps, Some(points))?;
                self.points.resolve(device, rec, nearest, field)
            }
            // The line passes resolve in their last pass.
            (Method::Lines, Some(band)) => {
                let (nearest, distance) =
                    self.points.encode_lines(device, rec, keys, field, band)?;
                Ok(Field3d::whole(size, nearest, None, distance))
            }
            // `check_points` refuses the rest.
            _ => unreachable!("checked by Settings3d::check_points"),
        }
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
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, volume: &wgpu::Texture) -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance3d, Settings3d};
    /// let d3 = Distance3d::new(device)?;
    /// let mut last = None;
    /// for _frame in 0..3 {
    ///     if let Some(field) = last.take() {
    ///         d3.recycle(field);
    ///     }
    ///     let mut encoder = device.create_command_encoder(&Default::default());
    ///     last = Some(d3.encode(device, &mut encoder, volume, &Settings3d::default())?);
    ///     queue.submit([encoder.finish()]);
    /// }
    /// # Ok(()) }
    /// ```
    pub fn recycle(&self, field: Field3d) {
        self.pool.recycle(field)
    }

    /// [`Self::recycle`] for a 2D field of the exact transform.
    pub fn recycle_2d(&self, field: FieldBuf2d) {
        self.pool.recycle_2d(field)
    }
}
