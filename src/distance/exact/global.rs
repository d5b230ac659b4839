//! The column passes in global memory (`edt_columns.wgsl`): envelopes as stacks in a buffer
//! beside the field, and the sweep of the resolving pass.

use super::Exact;
use super::fuse::Resolve;
use super::plan::{
    BAND_CHOICES, ColumnsIo, Pass, SWEEP_BANDS, SWEEP_RING, SweepPart, bands_for, columns_placement,
};
use crate::distance::packing::packing_of;
use crate::distance::resolve::Fuse;
use crate::error::Error;
use crate::gpu::{Record, uniform_buffer as uniform};
use crate::shaders::distance::edt_columns;

impl Exact {
    /// One column pass in global memory (`edt_columns.wgsl`) over the columns `io.span` names ×
    /// `others`, resolving into `fuse` where given.
    pub(crate) fn encode_global_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        io: ColumnsIo,
        pass: Pass,
        fuse: Option<Fuse>,
    ) -> Result<(), Error> {
        let axis = pass.axis;
        let (nearest, stack, slab) = (io.nearest, io.stack, io.slab);
        let source = io.source.unwrap_or(&self.no_source);
        let words = io.words.unwrap_or(&self.no_source);
        // A resolving 3D pass that sweeps is two dispatches: the sweep, then the envelopes of
        // the workgroups it left (the same entry point, other override constants).
        let resolve = Resolve::of(fuse.as_ref(), slab);
        let volume = matches!(resolve, Resolve::Volume(..));
        let (parts, swept): (&[SweepPart], _) = match io.sweep {
            Some(swept) if volume => (&[SweepPart::Sweep, SweepPart::Rest], swept),
            _ => (&[SweepPart::No], &self.no_swept),
        };
        for &part in parts {
            let (params, overrides, groups) =
                self.global_columns_setup(device, &io, pass, fuse.as_ref(), part);
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
                &self.no_source,
                volume { swept: swept },
                self.columns => columns,
                self.columns_resolve_2d => columns_resolve_2d,
                self.columns_resolve => columns_resolve,
            }
        }
        Ok(())
    }

    /// The parameters, override constants and workgroup count of a global-memory column pass
    /// along `axis` over `io.span`'s columns × `others`, reading and writing as `io` says and
    /// resolving as `fuse` says.
    pub(crate) fn global_columns_setup(
        &self,
        device: &wgpu::Device,
        io: &ColumnsIo,
        pass: Pass,
        fuse: Option<&Fuse>,
        part: SweepPart,
    ) -> (wgpu::Buffer, edt_columns::Overrides, [u32; 3]) {
        let Pass {
            size,
            axis,
            others,
            pack_2d,
        } = pass;
        let span = &io.span;
        let width = span.x_end - span.first[0];
        // A pass that sweeps takes the sweep's bands (its ring's layout, and the workgroups
        // its record names, are those of SWEEP_BANDS).
        let bands = if part == SweepPart::No {
            self.global_bands(width * others, pack_2d)
        } else {
            SWEEP_BANDS
        };
        let packing = packing_of(size);
        let scan = part == SweepPart::Sweep;
        let overrides = edt_columns::Overrides {
            pack_2d,
            bands,
            axis,
            // Sites within the column's plane: made from the row words, or the y pass of a
            // field not split (it runs before z; a split field's y pass reads the z pass's part).
            planar: !pack_2d && (io.words.is_some() || (axis == 1 && io.source.is_none())),
            source_apart: io.source.is_some(),
            from_words: io.words.is_some(),
            seed_x_bits: packing.x_bits,
            seed_y_bits: packing.y_bits,
            scan,
            after_scan: part == SweepPart::Rest,
            // A pass that sweeps in place reads its sites from the stack (see
            // `encode_exact_fused`); a split field's reads them from its part.
            in_stack: part != SweepPart::No && io.source.is_none(),
            ring: SWEEP_RING,
            ring_cells: if scan { SWEEP_RING * 256 / bands } else { 1 },
            signed: fuse.is_some_and(|f| f.inside_field.is_some()),
        };
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

    /// Bands per column of a global-memory column pass over `columns` columns.
    pub(crate) fn global_bands(&self, columns: u32, pack_2d: bool) -> u32 {
        self.column_bands
            .unwrap_or(BAND_CHOICES[bands_for(columns, pack_2d)])
    }
}
