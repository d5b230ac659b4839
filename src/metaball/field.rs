//! Building a metaball field: the splat, the surface seeds, the signed distance from them and
//! the packed volume the raymarch reads. [`Metaballs::encode`] keeps what it builds with from
//! frame to frame: the field's buffers and textures (taken back once the [`MetaballField`]
//! holding them is dropped: see [`gpu::Lease`](crate::gpu::Lease)), its uniforms (one buffer
//! per value) and its bind groups. On a grid that holds from frame to frame (a grid fitted to
//! an animation's [`envelope`](super::Animation::envelope)) a frame then makes no GPU object.

use super::Instances;
use super::{
    FULL_VOLUME_FAR, MAX_POINTS, MetaballField, Metaballs, STAGE, Settings, SurfaceSeeds,
    check_inputs, fixed_scale, full_band, storage_buffer,
};
use crate::bind::{ComputePipeline, KeptBound};
use crate::distance::{Field3d, Grid, Inside, Settings3d, Unreached};
use crate::error::Error;
use crate::gpu::{KeptUniform, KeptView, Leased, Record};
use crate::shaders::metaball::{march_field, splat, surface_seeds};

/// What a field is built from, checked together: the blobs, the grid, the voxel edge their
/// scales are in and the settings.
#[derive(Clone, Copy)]
struct Blobs<'a> {
    instances: &'a Instances,
    grid: &'a Grid,
    edge: f32,
    settings: &'a Settings,
}

impl<'a> Blobs<'a> {
    /// The settings, the grid (one seed point per cell, a field one binding holds) and the
    /// instance buffer checked.
    fn checked(
        device: &wgpu::Device,
        instances: &'a Instances,
        grid: &'a Grid,
        edge: f32,
        settings: &'a Settings,
    ) -> Result<Self, Error> {
        check_inputs(settings, edge, grid, STAGE)?;
        crate::distance::check_size_3d(device, grid.size)?;
        let cells: u64 = grid.size.iter().map(|&s| s as u64).product();
        if cells > MAX_POINTS as u64 + 1 {
            return Err(Error::Size {
                stage: STAGE,
                what: "grid cells (one seed point per cell)",
                got: cells,
                max: MAX_POINTS as u64 + 1,
            });
        }
        if instances.buffer.size() < instances.count as u64 * 16 {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "instance buffer has {} bytes for {} instances",
                    instances.buffer.size(),
                    instances.count
                ),
            });
        }
        Ok(Self {
            instances,
            grid,
            edge,
            settings,
        })
    }
}

/// The buffers and textures of one field, kept and handed out again.
#[derive(Clone)]
pub(super) struct FieldSet {
    size: [u32; 3],
    density_fixed: wgpu::Buffer,
    density: wgpu::Texture,
    density_view: wgpu::TextureView,
    keys: wgpu::Buffer,
    points: wgpu::Buffer,
    march: wgpu::Texture,
    march_view: wgpu::TextureView,
    /// The distance transform's nearest seeds and distance texture from the first build of
    /// this set, handed back to it before each later build, which then writes them again.
    distance: Option<(wgpu::Buffer, wgpu::Texture)>,
}

impl FieldSet {
    fn new(device: &wgpu::Device, size: [u32; 3]) -> Self {
        let cells: u64 = size.iter().map(|&s| s as u64).product();
        let storage = |label: &str, bytes: u64| storage_buffer(device, label, bytes);
        let volume = |label, format| crate::gpu::volume_texture(device, label, size, format);
        let density = volume("metaball density", wgpu::TextureFormat::R32Float);
        let march = volume("metaball march field", wgpu::TextureFormat::Rgba16Float);
        Self {
            size,
            density_fixed: storage("metaball density (fixed point)", cells * 4),
            density_view: density.create_view(&Default::default()),
            density,
            keys: storage("metaball seed keys", cells * 4),
            points: storage("metaball seed points", cells * 16),
            march_view: march.create_view(&Default::default()),
            march,
            distance: None,
        }
    }
}

/// What [`Metaballs::encode`] keeps from call to call.
#[derive(Default)]
pub(super) struct FieldKept {
    sets: Leased<FieldSet>,
    splat_params: KeptUniform,
    seed_params: KeptUniform,
    pack_params: KeptUniform,
    splat: KeptBound<splat::splat::Entry>,
    seeds: KeptBound<surface_seeds::surface_seeds::Entry>,
    pack: KeptBound<march_field::march_field::Entry>,
    sdf_view: KeptView,
}

impl Metaballs {
    /// Splat, seeds and signed distance for `instances` on `grid` (voxel edge `edge`), recorded
    /// into `rec` (a command encoder, or [`crate::gpu::Profiler::record`] to time each pass).
    /// The field's buffers and textures come back to this `Metaballs` once the field is
    /// dropped, for the next call on a grid of the same size; a field still held is never
    /// written again.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        instances: &Instances,
        grid: &Grid,
        edge: f32,
        settings: &Settings,
    ) -> Result<MetaballField, Error> {
        let blobs = Blobs::checked(device, instances, grid, edge, settings)?;
        let kept = &self.field;
        let (set, lease) = kept
            .sets
            .take(|s| s.size == grid.size, || FieldSet::new(device, grid.size));
        let scale = self.seeds_into(device, rec, blobs, &set)?;
        let options = Settings3d {
            method: settings.method,
            signed: true,
            inside: Inside::Threshold(settings.threshold),
            voxel_size: (grid.voxel as f32),
            band: (!settings.full_volume).then_some(settings.band),
            unreached: settings.full_volume.then_some(Unreached {
                inside: (grid.voxel as f32),
                outside: FULL_VOLUME_FAR,
            }),
        };
        if let Some((nearest, distance)) = &set.distance {
            // The transform takes these back (the same size) instead of making new ones.
            let field = Field3d::whole(grid.size, nearest.clone(), None, distance.clone());
            self.distance.recycle(field);
        }
        // The flood starts from the keys buffer and may leave intermediate steps in it.
        let mut field = self.distance.encode_keyed_points(
            device,
            rec,
            set.keys.clone(),
            &set.points,
            grid.size,
            Some(&set.density),
            &options,
        )?;
        // A field of sub-voxel seeds is one buffer (`check_size_3d`): only the exact
        // transform splits.
        let nearest = field.nearest.buffers.swap_remove(0);
        if set.distance.is_none() {
            let built = (nearest.clone(), field.distance.clone());
            kept.sets.update(&lease, |s| s.distance = Some(built));
        }
        self.encode_pack(device, rec, grid, &field.distance, &set)?;
        let bins = if settings.exact_surface.applies(instances.count) {
            Some(self.encode_bins(device, rec, instances, grid, edge, settings)?)
        } else {
            None
        };
        Ok(MetaballField {
            march: set.march,
            grid: *grid,
            density_fixed: set.density_fixed,
            fixed_scale: scale,
            density: set.density,
            points: set.points,
            nearest,
            sdf: field.distance,
            band: if settings.full_volume {
                full_band(grid)
            } else {
                settings.band * (grid.voxel as f32)
            },
            threshold: settings.threshold,
            bins,
            _lease: lease,
        })
    }

    /// The splat and surface-seed stages alone, into buffers and textures of their own.
    pub fn encode_seeds(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        instances: &Instances,
        grid: &Grid,
        edge: f32,
        settings: &Settings,
    ) -> Result<SurfaceSeeds, Error> {
        let blobs = Blobs::checked(device, instances, grid, edge, settings)?;
        let set = FieldSet::new(device, grid.size);
        let fixed_scale = self.seeds_into(device, rec, blobs, &set)?;
        Ok(SurfaceSeeds {
            density_fixed: set.density_fixed,
            fixed_scale,
            density: set.density,
            keys: set.keys,
            points: set.points,
        })
    }

    /// The splat and the surface seeds into `set`; the density's fixed-point scale.
    fn seeds_into(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        blobs: Blobs,
        set: &FieldSet,
    ) -> Result<f32, Error> {
        let Blobs {
            instances,
            grid,
            edge,
            settings,
        } = blobs;
        let kept = &self.field;
        rec.recorder()
            .encoder
            .clear_buffer(&set.density_fixed, 0, None);
        let scale = fixed_scale(instances.count);
        if instances.count > 0 {
            let params = kept.splat_params.get(
                device,
                "splat params",
                &splat::SplatParams {
                    size: grid.size.into(),
                    count: instances.count,
                    origin: grid.origin.as_vec3(),
                    cell: (grid.voxel as f32),
                    radius_per_scale: settings.radius(edge, 1.0),
                    fixed_scale: scale,
                },
            );
            self.splat.record_kept(
                device,
                rec,
                &kept.splat,
                &splat::splat::Resources {
                    params: (&params).into(),
                    instances: (&instances.buffer).into(),
                    density: (&set.density_fixed).into(),
                },
                [instances.count.div_ceil(64), 1, 1],
                "splat",
            )?;
        }
        let params = kept.seed_params.get(
            device,
            "surface seed params",
            &surface_seeds::SurfaceParams {
                size: grid.size.into(),
                threshold: settings.threshold,
                inv_fixed_scale: 1.0 / scale,
            },
        );
        self.seeds.record_kept(
            device,
            rec,
            &kept.seeds,
            &surface_seeds::surface_seeds::Resources {
                params: (&params).into(),
                density: (&set.density_fixed).into(),
                density_out: (&set.density_view).into(),
                keys: (&set.keys).into(),
                points: (&set.points).into(),
            },
            ComputePipeline::<surface_seeds::surface_seeds::Entry>::groups_for(grid.size),
            "seeds",
        )?;
        Ok(scale)
    }

    /// The distance and density packed into `set`'s filterable volume for the raymarch.
    fn encode_pack(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        grid: &Grid,
        sdf: &wgpu::Texture,
        set: &FieldSet,
    ) -> Result<(), Error> {
        let kept = &self.field;
        let params = kept.pack_params.get(
            device,
            "march field params",
            &march_field::PackParams {
                size: grid.size.into(),
                inv_cell: 1.0 / (grid.voxel as f32),
            },
        );
        let sv = kept
            .sdf_view
            .get(sdf, |t| t.create_view(&Default::default()));
        self.pack.record_kept(
            device,
            rec,
            &kept.pack,
            &march_field::march_field::Resources {
                params: (&params).into(),
                sdf: (&sv).into(),
                density: (&set.density_view).into(),
                packed: (&set.march_view).into(),
            },
            ComputePipeline::<march_field::march_field::Entry>::groups_for(grid.size),
            "pack",
        )
    }
}
