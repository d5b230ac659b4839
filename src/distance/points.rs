//! Sub-voxel seeds: points placed in voxels (their keys), flooded by JFA or by the line passes
//! (`point_lines.wgsl`), resolved to distances from the points themselves.

use std::sync::Arc;

use super::buffers::{Pool, kept_buffer, view};
use super::check::{check_bytes, check_inside, check_size_3d, voxels};
use super::resolve::resolve_values;
use super::{Field3d, MAX_POINTS, PointSeeds, STAGE_3D as STAGE, Settings3d};
use crate::bind::{ComputePipeline, KeptBound};
use crate::error::Error;
use crate::gpu::{KeptUniform, KeptView, Record, uniform_buffer as uniform};
use crate::shaders::distance::{field_resolve, jfa3_seed_points, point_lines};

/// Record `$plain` (a pipeline of `self` named as its entry point in `$module`) with the
/// fields given over the grid of `$field` (a [`PointField`]), or where the field has an inside
/// test its signed twin `$signed`, which binds the same and the inside test as `volume`. The
/// bind groups and views are kept in `$kept`. The resolving passes come in such pairs because
/// an entry point's layout holds only what it reads.
macro_rules! record_signed {
    ($this:ident, $device:expr, $rec:expr, $field:expr, $kept:ident,
        $module:ident { $($name:ident: $value:expr),* $(,)? },
        $plain:ident / $plain_groups:ident, $signed:ident / $signed_groups:ident,
        $label:expr $(,)?) => {{
        let groups = ComputePipeline::<$module::$plain::Entry>::groups_for($field.size);
        match $field.inside {
            None => $this.$plain.record_kept(
                $device,
                $rec,
                &$kept.$plain_groups,
                &$module::$plain::Resources { $($name: $value.into()),* },
                groups,
                $label,
            )?,
            Some(v) => $this.$signed.record_kept(
                $device,
                $rec,
                &$kept.$signed_groups,
                &$module::$signed::Resources {
                    volume: (&$kept.inside.get(v, view)).into(),
                    $($name: $value.into()),*
                },
                groups,
                $label,
            )?,
        }
    }};
}

/// What the flood and resolve of sub-voxel seeds read: the points (vec4 each, voxel
/// coordinates), the grid, the inside test of a signed field and the settings.
#[derive(Clone, Copy)]
pub(crate) struct PointField<'a> {
    pub points: &'a wgpu::Buffer,
    pub size: [u32; 3],
    pub inside: Option<&'a wgpu::Texture>,
    pub options: &'a Settings3d,
}

impl<'a> PointField<'a> {
    /// The field of `points` on the grid of `size`, checked: the settings, the grid, a method
    /// that takes points, and the inside test's size.
    pub(crate) fn checked(
        device: &wgpu::Device,
        points: &'a wgpu::Buffer,
        size: [u32; 3],
        inside: Option<&'a wgpu::Texture>,
        options: &'a Settings3d,
    ) -> Result<Self, Error> {
        options.check()?;
        check_size_3d(device, size)?;
        options.check_points()?;
        check_inside(device, inside, size)?;
        Ok(Self {
            points,
            size,
            inside,
            options,
        })
    }
}

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
    ) -> Result<wgpu::Buffer, Error> {
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

    /// A distance texture for a field of `size` (one handed back where it fits) and its view,
    /// kept in `views`.
    fn distance_out(
        &self,
        device: &wgpu::Device,
        size: [u32; 3],
        views: &KeptView,
    ) -> (wgpu::Texture, wgpu::TextureView) {
        let distance = self
            .pool
            .distance_texture(device, size, wgpu::TextureDimension::D3);
        let dv = views.get(&distance, view);
        (distance, dv)
    }

    /// Distances from the points that `nearest` names (flooded keys), signed where `inside` is
    /// given.
    pub(crate) fn resolve(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Buffer,
        field: PointField,
    ) -> Result<Field3d, Error> {
        let (points, size) = (field.points, field.size);
        let kept = &self.resolved;
        let values = resolve_values(size, field.options);
        let params = kept.params.get(device, "resolve params", &values);
        let (distance, dv) = self.distance_out(device, size, &kept.distance);
        record_signed!(
            self,
            device,
            rec,
            field,
            kept,
            field_resolve {
                params: &params,
                nearest: &nearest,
                points: points,
                distance: &dv
            },
            resolve_points / unsigned,
            resolve_points_signed / signed,
            "resolve"
        );
        Ok(Field3d::whole(size, nearest, None, distance))
    }

    /// The line passes over seed keys (`point_lines.wgsl`): x from the keys and their points,
    /// then y and z over carried candidates. The z pass also resolves: returns the nearest keys
    /// and the distance texture, signed when `inside` is given.
    pub(crate) fn encode_lines(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        keys: wgpu::Buffer,
        field: PointField,
        band: f32,
    ) -> Result<(wgpu::Buffer, wgpu::Texture), Error> {
        let (points, size, options) = (field.points, field.size, field.options);
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
        let (distance, dv) = self.distance_out(device, size, &kept.distance);
        // The z pass also resolves.
        record_signed!(
            self,
            device,
            rec,
            field,
            kept,
            point_lines {
                params: &params,
                keys: &keys,
                points: points,
                src: &b,
                nearest: &nearest,
                distance: &dv
            },
            lines_z / z,
            lines_z_signed / z_signed,
            "lines z + resolve"
        );
        Ok((nearest, distance))
    }
}
