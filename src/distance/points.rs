//! Sub-voxel seeds: points placed in voxels (their keys), flooded by JFA or by the line passes
//! (`point_lines.wgsl`), resolved to distances from the points themselves.

use std::sync::Arc;

use super::buffers::{Pool, kept_buffer, view};
use super::check::{check_bytes, check_inside, check_size_3d, voxels};
use super::resolve::resolve_values;
use super::{Field3d, MAX_POINTS, PointSeeds, STAGE_3D as STAGE, SeedPacking, Settings3d, Slabs};
use crate::bind::{ComputePipeline, KeptBound};
use crate::error::Error;
use crate::gpu::{KeptUniform, KeptView, Record, uniform_buffer as uniform};
use crate::shaders::distance::{field_resolve, jfa3_seed_points, point_lines};

/// The pipelines of sub-voxel seeds: placing them, the line passes and the resolve from points.
pub(crate) struct Points {
    seed_points: ComputePipeline<jfa3_seed_points::seed_points::Entry>,
    lines_x: ComputePipeline<point_lines::lines_x::Entry>,
    lines_y: ComputePipeline<point_lines::lines_y::Entry>,
    lines_z: ComputePipeline<point_lines::lines_z::Entry>,
    lines_z_signed: ComputePipeline<point_lines::lines_z_signed::Entry>,
    resolve_points: ComputePipeline<field_resolve::resolve_points::Entry>,
    resolve_points_signed: ComputePipeline<field_resolve::resolve_points_signed::Entry>,
    pool: Arc<Pool>,
    /// The line passes' scratch, uniforms, views and bind groups, kept from call to call: a
    /// field rebuilt every frame on one grid (and recycled) makes no object a frame.
    lines: KeptLines,
    /// The resolve's, kept the same way.
    resolved: KeptResolve,
}

#[derive(Default)]
struct KeptResolve {
    params: KeptUniform,
    inside: KeptView,
    distance: KeptView,
    unsigned: KeptBound<field_resolve::resolve_points::Entry>,
    signed: KeptBound<field_resolve::resolve_points_signed::Entry>,
}

#[derive(Default)]
struct KeptLines {
    candidates: [std::sync::Mutex<Option<wgpu::Buffer>>; 2],
    params: KeptUniform,
    inside: KeptView,
    distance: KeptView,
    x: KeptBound<point_lines::lines_x::Entry>,
    y: KeptBound<point_lines::lines_y::Entry>,
    z: KeptBound<point_lines::lines_z::Entry>,
    z_signed: KeptBound<point_lines::lines_z_signed::Entry>,
}

impl Points {
    pub(crate) fn new(device: &wgpu::Device, pool: Arc<Pool>) -> Result<Self, Error> {
        Ok(Self {
            seed_points: ComputePipeline::new(device)?,
            lines_x: ComputePipeline::new(device)?,
            lines_y: ComputePipeline::new(device)?,
            lines_z: ComputePipeline::new(device)?,
            lines_z_signed: ComputePipeline::new(device)?,
            resolve_points: ComputePipeline::new(device)?,
            resolve_points_signed: ComputePipeline::new(device)?,
            pool,
            lines: KeptLines::default(),
            resolved: KeptResolve::default(),
        })
    }

    /// The seed stage of sub-voxel seeds: a new field of keys, each voxel naming the point
    /// placed in it (the one nearest its centre, or the point whose home it is). Checks the
    /// points against the grid of `size`.
    pub(crate) fn seed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        points: &PointSeeds,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Settings3d,
    ) -> Result<wgpu::Buffer, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        options.check_points()?;
        if points.count == 0
            || points.count > MAX_POINTS
            || points.buffer.size() < points.count as u64 * 16
        {
            return Err(Error::Size {
                stage: STAGE,
                what: "number of seed points (table size)",
                got: points.count as u64,
                max: (points.buffer.size() / 16).min(MAX_POINTS as u64),
            });
        }
        check_inside(device, inside, size)?;
        let seeds = self.pool.field_buffer(device, "nearest seed", size);
        rec.recorder().encoder.clear_buffer(&seeds, 0, None);
        if let Some(h) = &points.homes
            && h.size() < points.count as u64 * 4
        {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "homes buffer has {} bytes for {} points",
                    h.size(),
                    points.count
                ),
            });
        }
        let params = uniform(
            device,
            "seed points params",
            &jfa3_seed_points::PointParams {
                size: size.into(),
                count: points.count,
                use_homes: points.homes.is_some() as u32,
            },
        );
        // Without homes the slot still needs a buffer; the shader does not read it.
        let no_homes;
        let homes = match &points.homes {
            Some(h) => h,
            None => {
                no_homes = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("no homes"),
                    size: 4,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                });
                &no_homes
            }
        };
        self.seed_points.record(
            device,
            rec,
            &jfa3_seed_points::seed_points::Resources {
                params: (&params).into(),
                points: (&points.buffer).into(),
                nearest: (&seeds).into(),
                homes: homes.into(),
            },
            [points.count.div_ceil(64), 1, 1],
            "seed points",
        )?;
        Ok(seeds)
    }

    /// Distances from the points that `nearest` names (flooded keys), signed where `inside` is
    /// given.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn resolve(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Buffer,
        points: &wgpu::Buffer,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Settings3d,
    ) -> Result<Field3d, Error> {
        let kept = &self.resolved;
        let values = resolve_values(size, options);
        let params = kept.params.get(device, "resolve params", &values);
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = kept.distance.get(&distance, view);
        let groups = ComputePipeline::<field_resolve::resolve_points::Entry>::groups_for(size);
        match inside {
            None => {
                self.resolve_points.record_kept(
                    device,
                    rec,
                    &kept.unsigned,
                    &field_resolve::resolve_points::Resources {
                        params: (&params).into(),
                        nearest: (&nearest).into(),
                        points: points.into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
            Some(v) => {
                let vv = kept.inside.get(v, view);
                self.resolve_points_signed.record_kept(
                    device,
                    rec,
                    &kept.signed,
                    &field_resolve::resolve_points_signed::Resources {
                        params: (&params).into(),
                        nearest: (&nearest).into(),
                        points: points.into(),
                        volume: (&vv).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "resolve",
                )?;
            }
        }
        Ok(Field3d {
            size,
            packing: SeedPacking::STANDARD,
            nearest: Slabs::one(nearest, size[2]),
            nearest_outside: None,
            distance,
        })
    }

    /// The line passes over seed keys (`point_lines.wgsl`): x from the keys and their points,
    /// then y and z over carried candidates. The z pass also resolves: returns the nearest keys
    /// and the distance texture, signed when `inside` is given.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn encode_lines(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        keys: wgpu::Buffer,
        points: &wgpu::Buffer,
        size: [u32; 3],
        inside: Option<&wgpu::Texture>,
        options: &Settings3d,
        band: f32,
    ) -> Result<(wgpu::Buffer, wgpu::Texture), Error> {
        // Each voxel carries an 8-byte candidate between passes.
        check_bytes(&device.limits(), voxels(size) * 8)?;
        let kept = &self.lines;
        let candidates = |k: usize, label| {
            kept_buffer(&kept.candidates[k], voxels(size) * 8, false, || {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: voxels(size) * 8,
                    usage: wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                })
            })
        };
        let (a, b) = (
            candidates(0, "line candidates x"),
            candidates(1, "line candidates y"),
        );
        // A point within `band` of a voxel centre lies within √3/2 of its own voxel's centre.
        let reach = (band + 0.8660254).floor().min(u32::MAX as f32) as u32;
        let params = kept.params.get(
            device,
            "line params",
            &point_lines::LineParams {
                size: size.into(),
                reach,
                voxel_size: options.voxel_size,
                band: band * options.voxel_size,
                threshold: options.inside.threshold(),
            },
        );
        self.lines_x.record_kept(
            device,
            rec,
            &kept.x,
            &point_lines::lines_x::Resources {
                params: (&params).into(),
                keys: (&keys).into(),
                points: points.into(),
                dst: (&a).into(),
            },
            ComputePipeline::<point_lines::lines_x::Entry>::groups_for(size),
            "lines x",
        )?;
        self.lines_y.record_kept(
            device,
            rec,
            &kept.y,
            &point_lines::lines_y::Resources {
                params: (&params).into(),
                src: (&a).into(),
                dst: (&b).into(),
            },
            ComputePipeline::<point_lines::lines_y::Entry>::groups_for(size),
            "lines y",
        )?;
        let nearest = self.pool.field_buffer(device, "nearest seed", size);
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = kept.distance.get(&distance, view);
        let groups = ComputePipeline::<point_lines::lines_z::Entry>::groups_for(size);
        match inside {
            None => {
                self.lines_z.record_kept(
                    device,
                    rec,
                    &kept.z,
                    &point_lines::lines_z::Resources {
                        params: (&params).into(),
                        keys: (&keys).into(),
                        points: points.into(),
                        src: (&b).into(),
                        nearest: (&nearest).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "lines z + resolve",
                )?;
            }
            Some(v) => {
                let vv = kept.inside.get(v, view);
                self.lines_z_signed.record_kept(
                    device,
                    rec,
                    &kept.z_signed,
                    &point_lines::lines_z_signed::Resources {
                        params: (&params).into(),
                        keys: (&keys).into(),
                        points: points.into(),
                        src: (&b).into(),
                        nearest: (&nearest).into(),
                        volume: (&vv).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "lines z + resolve",
                )?;
            }
        }
        Ok((nearest, distance))
    }
}
