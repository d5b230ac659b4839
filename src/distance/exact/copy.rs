//! For benchmarks: the loads and stores of one column pass without its envelopes, the floor
//! each pass is measured against (`cargo xtask bench distance`).

use super::Exact;
use super::plan::{ColumnsIo, Pass, Span, SweepPart};
use super::rows::row_words_bytes;
use crate::distance::check::{check_column_axis, check_len, voxels};
use crate::error::Error;
use crate::gpu::Record;
use crate::shaders::distance::{edt_columns, edt_tile};

/// The checks of the benchmarks' copies (`encode_global_copy`, `encode_tile_copy`): a grid the
/// transform takes, axis 1 or 2, and buffers of the size the grid needs.
pub(crate) fn check_copy(
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
pub(crate) fn copy_distance_view(
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

impl Exact {
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
        let pass = Pass::along(size, axis);
        let (params, overrides, groups) =
            self.global_columns_setup(device, &io, pass, None, SweepPart::No);
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
        let (params, overrides) = tile.bind(device, Pass::along(size, axis), None, &span, false);
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
}
