//! The exact transform of a 2D mask: the row pass, then one column pass that resolves as it
//! answers.

use super::Exact;
use super::plan::Pass;
use crate::distance::buffers::view;
use crate::distance::check::check_size_2d_exact;
use crate::distance::resolve::{Fuse, resolve_params};
use crate::distance::{FieldBuf2d, Inside, SeedRule, Settings3d, check_seed_texture};
use crate::error::Error;
use crate::gpu::{Record, Recorder, uniform_buffer as uniform};
use crate::shaders::distance::edt_rows;

impl Exact {
    /// The exact transform of a 2D mask (any of [`SEED_FORMATS`](crate::distance::SEED_FORMATS); red channel marks).
    pub fn encode_exact_2d(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mask: &wgpu::Texture,
        options: &Settings3d,
    ) -> Result<FieldBuf2d, Error> {
        let rule = SeedRule {
            above: match options.inside {
                // Any value above 0 (the shaders compare ≥ the least normal f32 above it).
                Inside::Mask => 0.0,
                Inside::Threshold(t) => t.next_down(),
            },
            ..SeedRule::default()
        };
        self.encode_exact_2d_with(device, rec, mask, options, &rule)
    }

    /// [`Self::encode_exact_2d`] with `rule` choosing the seeds (its `inside` is not
    /// read).
    pub fn encode_exact_2d_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mask: &wgpu::Texture,
        options: &Settings3d,
        rule: &SeedRule,
    ) -> Result<FieldBuf2d, Error> {
        options.check()?;
        rule.check()?;
        // The same checks as the 2D JFA's seed texture (the same formats work), then the exact
        // transform's own size limit.
        let (w, h) = check_seed_texture(device, mask)?;
        check_size_2d_exact(device, w, h)?;
        let size = [w, h, 1];
        let mv = view(mask);
        let stack = self
            .tile_for(device, size, 1, true)?
            .is_none()
            .then(|| self.stack_for(device, size));
        let rec = &mut rec.recorder();
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D2);
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
            let nearest = self.pool.field_buffer(device, "nearest seed", size);
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
                let pass = Pass {
                    size,
                    axis: 1,
                    others: 1,
                    pack_2d: true,
                };
                self.encode_columns(device, rec, &nearest, stack.as_ref(), pass, fuse, None)?;
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
            // A single row: no column pass resolved it.
            let params = resolve_params(device, size, options);
            self.resolve.resolve_2d(
                device,
                rec,
                size,
                &params,
                &nearest,
                nearest_outside.as_ref(),
                &dv,
            )?;
        }
        Ok(FieldBuf2d {
            width: w,
            height: h,
            nearest,
            nearest_outside,
            distance,
        })
    }
}
