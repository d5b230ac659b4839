//! The column passes in workgroup memory (`edt_tile.wgsl`).

use super::Exact;
use super::fuse::Resolve;
use super::plan::{Pass, TileGeometry, TileIo};
use crate::distance::resolve::Fuse;
use crate::error::Error;
use crate::gpu::Record;
use crate::shaders::distance::edt_tile;

impl Exact {
    /// A column pass in workgroup memory (`edt_tile.wgsl`), tiles laid out as `tile` says.
    pub(crate) fn encode_tile_columns(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        io: TileIo,
        pass: Pass,
        tile: TileGeometry,
        fuse: Option<Fuse>,
    ) -> Result<(), Error> {
        let apart = io.source.is_some();
        let (params, overrides) = tile.bind(device, pass, fuse.as_ref(), &io.span, apart);
        let resolve = Resolve::of(fuse.as_ref(), io.slab);
        let groups = tile.groups(&io.span, pass.others);
        let nearest = io.nearest.into();
        let source = io.source.unwrap_or(&self.no_source).into();
        let name = match (pass.axis, &fuse) {
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
            resolve,
            &self.no_source,
            self.tile_columns => tile_columns,
            self.tile_columns_resolve_2d => tile_columns_resolve_2d,
            self.tile_columns_resolve => tile_columns_resolve,
        }
    }

    /// The column pass along `axis` from the row words, writing where `io` says (its `source`
    /// is not read).
    pub(crate) fn encode_tile_columns_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        words: &wgpu::Buffer,
        io: TileIo,
        pass: Pass,
        tile: TileGeometry,
    ) -> Result<(), Error> {
        let (params, overrides) = tile.bind(device, pass, None, &io.span, false);
        let (axis, others) = (pass.axis, pass.others);
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
}
