//! The exact transform of a field too large for one storage binding: parts of columns held
//! apart between the z and the y pass, slabs of planes bound one at a time.

use super::Exact;
use super::plan::{ColumnsIo, Pass, SWEEP_BANDS, Span, TileGeometry, TileIo, placement};
use crate::distance::STAGE_3D as STAGE;
use crate::distance::Slabs;
use crate::distance::buffers::{kept_buffer, new_field_buffer};
use crate::distance::check::{exact_volume_size, voxels};
use crate::distance::options::Marks;
use crate::distance::resolve::Fuse;
use crate::error::Error;
use crate::gpu::Record;

/// How the exact transform splits a field too large for one binding (`Distance3d::split_for`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Split {
    /// Columns (x) per part held apart between the z and the y pass: a multiple of both
    /// tiles' columns.
    part_width: u32,
    /// Planes (z) of the field per binding of the y pass.
    slab_depth: u32,
    /// The y and z passes' tiles, or `None` for a pass in global memory.
    y: Option<TileGeometry>,
    z: Option<TileGeometry>,
}

/// Parts (columns along x) and slabs (planes along z) of a field of `size` that the exact
/// transform splits across bindings of `binding` bytes, buffers of `max_buffer_size` (each slab
/// is one), with parts whole tiles of `columns` wide: `(part_width, slab_depth)`, as few and as
/// even as fit, parts on 128-byte row boundaries where a binding holds that much.
pub(crate) fn split_layout(
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
pub(crate) const ALIGNED_COLUMNS: u64 = 32;

impl Exact {
    /// How the exact transform splits a field of `size`, or `None` where one binding holds it.
    /// [`Error::Size`] past the device's `max_buffer_size`, or where even a split part is too
    /// large for a binding.
    pub(crate) fn split_for(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
    ) -> Result<Option<Split>, Error> {
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
    pub(crate) fn encode_exact_split(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
        fuse: Option<Fuse>,
        split: Split,
    ) -> Result<Slabs, Error> {
        let size = exact_volume_size(device, marks.volume)?;
        let [w, h, d] = size;
        let words = self.row_words(device, rec, marks, true)?;
        let slabs: Vec<(u32, u32)> = (0..d)
            .step_by(split.slab_depth as usize)
            .map(|z0| (z0, (z0 + split.slab_depth).min(d)))
            .collect();
        let nearest: Vec<wgpu::Buffer> = slabs
            .iter()
            .map(|&(z0, z_end)| {
                self.pool
                    .field_buffer(device, "nearest seed (a slab)", [w, h, z_end - z0])
            })
            .collect();
        let part_bytes = voxels([split.part_width, h, d]) * 4;
        let part = kept_buffer(&self.kept.part, part_bytes, true, || {
            new_field_buffer(
                device,
                "nearest seed (a part of the field)",
                [split.part_width, h, d],
            )
        });
        let part_at = |x0: u32| placement([x0, 0, 0], split.part_width, split.part_width * h);
        // A pass in global memory keeps its envelopes in the part's layout: a part's worth.
        let part_size = [split.part_width, h, d];
        let swept = self.split_sweep(device, &split, fuse.as_ref());
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
            let pass = Pass::along(size, 2);
            self.encode_from_words(device, rec, &words, io, pass, split.z, part_size, None)?;
            for (k, &(z0, z_end)) in slabs.iter().enumerate() {
                let io = TileIo {
                    source: Some(&part),
                    nearest: &nearest[k],
                    slab: k,
                    span: Span {
                        first: [x0, z0],
                        x_end,
                        y_after_z: true,
                        src: part_at(x0),
                        dst: placement([0, 0, z0], w, w * h),
                    },
                };
                let pass = Pass {
                    size,
                    axis: 1,
                    others: z_end - z0,
                    pack_2d: false,
                };
                self.encode_slab_y(device, rec, io, pass, &split, fuse, swept.as_ref())?;
            }
        }
        Ok(Slabs {
            buffers: nearest,
            depth: split.slab_depth,
            planes: d,
        })
    }

    /// The sweep's record for a split field's resolving y pass, where it sweeps. That pass
    /// sweeps as the unsplit z pass does (`edt_columns.wgsl`'s SCAN): its sites come from the
    /// part, its answers go to the slab, so it writes from the first without reading its sites
    /// from the stack. It takes SWEEP_BANDS then (unless set otherwise), whatever the automatic
    /// count: a dispatch is one part × one slab, whose fewer columns ask for more bands (32 at
    /// 512³ split at 180 MB, 128 columns × 171 planes), and on the H100 there 8 bands and the
    /// sweep took the y pass + resolve from 2.427 to 1.776 ms at 1% seeds and 3.467 to 2.167 at
    /// 1e-5 (8 bands without the sweep: 2.471 and 2.150). One record of the workgroups swept
    /// serves every dispatch (each sweep writes the entries of its own before the pass after it
    /// reads them).
    fn split_sweep(
        &self,
        device: &wgpu::Device,
        split: &Split,
        fuse: Option<&Fuse>,
    ) -> Option<wgpu::Buffer> {
        (self.sweep
            && split.y.is_none()
            && fuse.is_some_and(|f| !f.flat)
            && self.column_bands.is_none_or(|b| b == SWEEP_BANDS))
        .then(|| {
            self.swept_for(
                device,
                split.part_width.div_ceil(256 / SWEEP_BANDS) * split.slab_depth,
            )
        })
    }

    /// The y pass of one part × one slab of `planes` planes of a split field: from the part
    /// (`io.source`) into the slab, in workgroup memory where `split.y` says, else in global
    /// memory with the stack in the part's layout, as the z pass used it.
    #[allow(clippy::too_many_arguments)]
    fn encode_slab_y(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        io: TileIo,
        pass: Pass,
        split: &Split,
        fuse: Option<Fuse>,
        swept: Option<&wgpu::Buffer>,
    ) -> Result<(), Error> {
        match split.y {
            Some(tile) => self.encode_tile_columns(device, rec, io, pass, tile, fuse),
            None => {
                let part_size = [split.part_width, pass.size[1], pass.size[2]];
                let io = ColumnsIo {
                    source: io.source,
                    words: None,
                    nearest: io.nearest,
                    stack: &self.stack_for(device, part_size),
                    slab: io.slab,
                    span: io.span,
                    sweep: swept,
                };
                self.encode_global_columns(device, rec, io, pass, fuse)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// wgpu's storage binding (2 GiB − 1) and NVIDIA's largest buffer (4 GiB − 2 MiB).
    const BINDING: u64 = (1 << 31) - 1;
    const BUFFER: u64 = (1 << 32) - (2 << 20);

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
