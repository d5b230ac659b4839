//! Nearest seeds to distances in a pass of their own (`field_resolve.wgsl`): JFA's fields, and
//! the exact transform's where no column pass ran to resolve as it answered. [`Fuse`] says where
//! and how a field's distances are written.

use super::{Settings3d, Unreached};
use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Record, uniform_buffer as uniform};
use crate::shaders::distance::field_resolve;

/// Where the last exact column pass writes distances (`columns_resolve*` in `edt_columns.wgsl`).
#[derive(Clone, Copy)]
pub(crate) struct Fuse<'a> {
    /// `R32Float` storage view: 3D, or 2D where `flat`.
    pub(crate) distance: &'a wgpu::TextureView,
    pub(crate) flat: bool,
    pub(crate) voxel_size: f32,
    /// World units; `f32::MAX` for none.
    pub(crate) band: f32,
    /// Signed: the inside seeds' field (the pass runs in the outside seeds' field); its slabs
    /// where the field is split, else one buffer.
    pub(crate) inside_field: Option<&'a [wgpu::Buffer]>,
}

/// The resolve pipelines, shared by the methods that resolve in a pass of their own.
pub(crate) struct Resolver {
    resolve_unsigned: ComputePipeline<field_resolve::resolve_unsigned::Entry>,
    resolve_signed: ComputePipeline<field_resolve::resolve_signed::Entry>,
    resolve_unsigned_2d: ComputePipeline<field_resolve::resolve_unsigned_2d::Entry>,
    resolve_signed_2d: ComputePipeline<field_resolve::resolve_signed_2d::Entry>,
}

impl Resolver {
    pub(crate) fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            resolve_unsigned: ComputePipeline::new(device)?,
            resolve_signed: ComputePipeline::new(device)?,
            resolve_unsigned_2d: ComputePipeline::new(device)?,
            resolve_signed_2d: ComputePipeline::new(device)?,
        })
    }

    /// Unsigned or signed resolve of integer seeds into `fuse.distance` in a pass of its own.
    pub(crate) fn resolve_into(
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

    /// Unsigned or signed resolve of a 2D field (a single row, which no column pass resolved)
    /// into `distance`, with `params` from [`resolve_params`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn resolve_2d(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        size: [u32; 3],
        params: &wgpu::Buffer,
        nearest: &wgpu::Buffer,
        nearest_outside: Option<&wgpu::Buffer>,
        distance: &wgpu::TextureView,
    ) -> Result<(), Error> {
        let groups = ComputePipeline::<field_resolve::resolve_unsigned_2d::Entry>::groups_for(size);
        match nearest_outside {
            None => self.resolve_unsigned_2d.record(
                device,
                rec,
                &field_resolve::resolve_unsigned_2d::Resources {
                    params: params.into(),
                    nearest: nearest.into(),
                    distance_2d: distance.into(),
                },
                groups,
                "resolve",
            ),
            Some(o) => self.resolve_signed_2d.record(
                device,
                rec,
                &field_resolve::resolve_signed_2d::Resources {
                    params: params.into(),
                    nearest: nearest.into(),
                    nearest_outside: o.into(),
                    distance_2d: distance.into(),
                },
                groups,
                "resolve",
            ),
        }
    }
}

/// The resolve parameters of a field of `size` computed with `options`, in a new uniform.
pub(crate) fn resolve_params(
    device: &wgpu::Device,
    size: [u32; 3],
    options: &Settings3d,
) -> wgpu::Buffer {
    uniform(device, "resolve params", &resolve_values(size, options))
}

/// The resolve parameters of a field of `size` computed with `options`.
pub(crate) fn resolve_values(size: [u32; 3], options: &Settings3d) -> field_resolve::ResolveParams {
    let band = options.world_band();
    let unreached = options.unreached.unwrap_or(Unreached {
        inside: band,
        outside: band,
    });
    field_resolve::ResolveParams {
        size: size.into(),
        voxel_size: options.voxel_size,
        band,
        threshold: options.inside.threshold(),
        unreached_inside: unreached.inside,
        unreached_outside: unreached.outside,
    }
}
