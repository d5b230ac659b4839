//! The exact transform's row pass along x (`edt_rows.wgsl`): the nearest mark per row as a
//! field, or as words of marks that the y pass reads in its place.

use super::Exact;
use super::plan::{ColumnsIo, Pass, TileGeometry, TileIo, rows_per_group};
use crate::distance::buffers::{kept_buffer, view};
use crate::distance::check::{check_bytes, check_len, check_size_3d, exact_volume_size, voxels};
use crate::distance::options::Marks;
use crate::distance::packing::packing_of;
use crate::error::Error;
use crate::gpu::{Record, uniform_buffer as uniform};
use crate::shaders::distance::{edt_rows, edt_tile};

/// What both 3D row passes (`rows`, `row_words`) start from: the grid of the marked volume,
/// the pass's parameters and the volume's view.
pub(crate) fn row_pass(
    device: &wgpu::Device,
    marks: Marks,
) -> Result<([u32; 3], wgpu::Buffer, wgpu::TextureView), Error> {
    let size = exact_volume_size(device, marks.volume)?;
    let params = uniform(
        device,
        "edt rows params",
        &edt_rows::RowParams {
            size: size.into(),
            threshold: marks.inside.threshold(),
            invert: marks.invert as u32,
            channels: glam::Vec4::X,
        },
    );
    Ok((size, params, view(marks.volume)))
}

/// Bytes of the row words (`edt_rows.wgsl`'s `row_words`) of a field of `size`: 8 per 32 voxels
/// of a row, rows rounded up.
/// A new buffer for the row words of a field of `size`.
pub(crate) fn row_words_buffer(device: &wgpu::Device, size: [u32; 3]) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("edt row words"),
        size: row_words_bytes(size),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

pub(crate) fn row_words_bytes(size: [u32; 3]) -> u64 {
    size[0].div_ceil(32) as u64 * size[1] as u64 * size[2] as u64 * 8
}

impl Exact {
    /// First exact pass alone: per row, the nearest marked voxel along x (a new buffer).
    pub fn encode_rows(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
    ) -> Result<wgpu::Buffer, Error> {
        let (size, params, vv) = row_pass(device, marks)?;
        check_bytes(&device.limits(), voxels(size) * 4)?;
        let nearest = self.pool.field_buffer(device, "nearest seed", size);
        let per_group = rows_per_group(size[0], size[1]);
        let packing = packing_of(size);
        let rows = self.rows.get(
            device,
            &edt_rows::Overrides {
                rows: per_group,
                seed_x_bits: packing.x_bits,
                seed_y_bits: packing.y_bits,
            },
            true,
        )?;
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
        marks: Marks,
    ) -> Result<wgpu::Buffer, Error> {
        self.row_words(device, rec, marks, false)
    }

    /// [`Self::encode_row_words`] into the words kept from call to call where `kept` (the
    /// exact transform's own row words, which no caller sees), else into a new buffer.
    pub(crate) fn row_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
        kept: bool,
    ) -> Result<wgpu::Buffer, Error> {
        let (size, params, vv) = row_pass(device, marks)?;
        let new = || row_words_buffer(device, size);
        let words = if kept {
            kept_buffer(&self.kept.words, row_words_bytes(size), true, new)
        } else {
            new()
        };
        let count = size[0].div_ceil(32);
        // 2048 cells of workgroup memory per workgroup: rows of up to 2048 voxels (64 words),
        // as many as fit (a power of two).
        let per_group = 64 / count.next_power_of_two();
        self.row_words
            .get(
                device,
                &edt_rows::Overrides {
                    rows: per_group,
                    ..Default::default()
                },
                false,
            )?
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
    /// it ([`crate::distance::Distance3d::set_column_passes`]): writes the nearest seed of every voxel within its xy
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
        self.encode_from_words(
            device,
            rec,
            words,
            io,
            Pass::along(size, 1),
            tile,
            size,
            None,
        )
    }

    /// The column pass along `axis` (1: y, 2: z) that makes its sites from the row words, into
    /// `io.nearest` where `io.span` places it: in workgroup memory where `tile` is given, else
    /// in global memory with the envelope stack kept for a field of `stack_size` (or `scratch`
    /// where given: the stack itself is where `io` writes).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode_from_words(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        words: &wgpu::Buffer,
        io: TileIo,
        pass: Pass,
        tile: Option<TileGeometry>,
        stack_size: [u32; 3],
        scratch: Option<&wgpu::Buffer>,
    ) -> Result<(), Error> {
        match tile {
            Some(tile) => self.encode_tile_columns_words(device, rec, words, io, pass, tile),
            None => self.encode_global_columns(
                device,
                rec,
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
                pass,
                None,
            ),
        }
    }
}
