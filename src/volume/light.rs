//! The light volume: transmittance toward the light at every other voxel centre, built once
//! for a volume, transfer function, light and transform ([`VolumeRenderer::encode_light`]) and
//! kept by the app while [`LightVolume::is_for`] holds, optionally folded into a copy of the
//! density ([`LightVolume::lit_density`]) so that the march takes both in one fetch.

use glam::{Mat4, Vec3};

use super::kept::Target;
use super::{
    Bricks, MarchSettings, STAGE, Shadow, TransferFunction, Volume, VolumeRenderer, check_transform,
};
use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Lease, Record};
use crate::shaders::volume::{lit_density, volume_march};
use crate::view::View;

/// Transmittance toward the light, built by [`VolumeRenderer::encode_light`] for one volume,
/// transfer function, light, shadow step and transform.
pub struct LightVolume {
    /// Transmittance at every other voxel centre (red, `Rgba16Float`): texel i at the centre
    /// of density voxel 2i, `dims / 2 + 1` per axis.
    pub texture: wgpu::Texture,
    /// When folded ([`VolumeRenderer::encode_light_folded`]), what the march samples in place
    /// of the density: at the density's resolution, the density in red, copied exactly, and the
    /// trilinear interpolant of `texture` at each voxel centre in green, so one fetch gives
    /// both. `Rgba8Unorm` for an `R8Unorm` volume (4 bytes a voxel), `Rgba16Float` for
    /// `R16Float`, `Rg32Float` for `R32Float` (blue and alpha unused: two-channel 8- and 16-bit
    /// formats are not writable by a shader in WebGPU). `None`: the march fetches `texture` as
    /// well.
    pub lit_density: Option<wgpu::Texture>,
    /// What it was built for: a march with anything else is refused, not drawn wrong.
    built_for: (Vec3, f32, Mat4, TransferFunction, wgpu::Texture),
    /// The views the march binds (the light texture's, the lit density's).
    pub(super) views: (wgpu::TextureView, Option<wgpu::TextureView>),
    /// Holds on the textures: the renderer takes them back for a later build once dropped.
    _leases: (Lease, Option<Lease>),
}

impl LightVolume {
    /// Whether this was built for `volume`, `tf`, `local_to_world` and the light and shadow
    /// step of `settings` (`Shadow::LightVolume`): a march with them may use it, so an app
    /// rebuilds it only when this turns false.
    pub fn is_for(
        &self,
        volume: &Volume,
        tf: &TransferFunction,
        local_to_world: Mat4,
        settings: &MarchSettings,
    ) -> bool {
        let Shadow::LightVolume { step } = settings.shadow else {
            return false;
        };
        let (dir, built_step, transform, built_tf, built_volume) = &self.built_for;
        *built_step == step
            && *dir == settings.light_dir
            && *transform == local_to_world
            && built_tf == tf
            && *built_volume == volume.texture
    }
}

/// The lit-density format for a density format: the smallest a shader may write.
pub(super) fn lit_format(density: wgpu::TextureFormat) -> wgpu::TextureFormat {
    match density {
        wgpu::TextureFormat::R8Unorm => wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureFormat::R16Float => wgpu::TextureFormat::Rgba16Float,
        _ => wgpu::TextureFormat::Rg32Float,
    }
}

/// The lit-density pass, one entry point per format.
pub(super) struct LitPipelines {
    pub(super) unorm8: ComputePipeline<lit_density::lit_unorm8::Entry>,
    pub(super) float16: ComputePipeline<lit_density::lit_float16::Entry>,
    pub(super) float32: ComputePipeline<lit_density::lit_float32::Entry>,
}

/// The largest lit density [`VolumeRenderer::encode_light`] folds, in bytes: a bound on memory
/// (an `R8Unorm` volume folds into 4 bytes a voxel, so 512³ takes 512 MiB), not on speed. On the
/// H100 folding took the 256³ cloud's frame from inside from 1.16 to 0.89 ms and 512³ from
/// 2.17 to 1.54 ms, and cost 0.16 ms more to build at 256³ (`cargo xtask bench volume`).
pub const FOLD_MAX_BYTES: u64 = 512 << 20;

/// Whether [`VolumeRenderer::encode_light`] folds the light volume of `volume` into a copy of
/// its density: when that copy takes at most [`FOLD_MAX_BYTES`].
pub fn folds(volume: &Volume) -> bool {
    let texel = lit_format(volume.texture.format())
        .block_copy_size(None)
        .expect("colour format") as u64;
    volume.dims.iter().map(|&d| d as u64).product::<u64>() * texel <= FOLD_MAX_BYTES
}

impl VolumeRenderer {
    /// Transmittance toward the light for `settings.shadow == Shadow::LightVolume` (rebuild when
    /// the volume, transfer function, light or transform changes), folded into a copy of the
    /// density when that copy takes at most [`FOLD_MAX_BYTES`].
    #[allow(clippy::too_many_arguments)]
    pub fn encode_light(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &Volume,
        bricks: &Bricks,
        tf: &TransferFunction,
        local_to_world: Mat4,
        settings: &MarchSettings,
    ) -> Result<LightVolume, Error> {
        self.encode_light_folded(
            device,
            rec,
            volume,
            bricks,
            tf,
            local_to_world,
            settings,
            folds(volume),
        )
    }

    /// [`Self::encode_light`] with the choice made: `fold` builds [`LightVolume::lit_density`],
    /// so the march takes density and light in one fetch per sample, at the cost of a copy of
    /// the density with the light beside it.
    #[allow(clippy::too_many_arguments)]
    pub fn encode_light_folded(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &Volume,
        bricks: &Bricks,
        tf: &TransferFunction,
        local_to_world: Mat4,
        settings: &MarchSettings,
        fold: bool,
    ) -> Result<LightVolume, Error> {
        settings.check()?;
        tf.check()?;
        check_transform(local_to_world)?;
        let Shadow::LightVolume { step } = settings.shadow else {
            return Err(Error::Invalid {
                stage: STAGE,
                what: "encode_light needs settings.shadow = Shadow::LightVolume".into(),
            });
        };
        // Nodes on every other voxel centre, one past the last voxel when the size is even.
        let size = volume.dims.map(|d| d / 2 + 1);
        let format = wgpu::TextureFormat::Rgba16Float;
        let kept = &self.kept;
        let (light, light_lease) = kept.light.take(
            |t| t.is(size, format),
            || {
                Target::new(
                    device,
                    "light volume",
                    size,
                    wgpu::TextureDimension::D3,
                    format,
                )
            },
        );
        // The light pass reads only the volume fields of the view-independent parameters.
        let view = View {
            view_proj: Mat4::IDENTITY,
            viewport: [1, 1],
            reversed_z: false,
            origin: [0, 0],
        };
        let params = self.params(
            volume,
            bricks,
            tf,
            local_to_world,
            &view,
            settings,
            [0, 0, 1, 1],
            false,
        )?;
        let recorder = &mut rec.recorder();
        let label = "volume light params";
        let params =
            (kept.uploads).uniform(device, recorder.encoder, &kept.light_params, label, &params);
        let tf_buffer = self.kept_tf(device, recorder.encoder, tf);
        let dv = kept
            .density_view
            .get(&volume.texture, |t| t.create_view(&Default::default()));
        let groups = ComputePipeline::<volume_march::light_volume::Entry>::groups_for(size);
        self.light.record_kept(
            device,
            recorder,
            &kept.light_bound,
            &volume_march::light_volume::Resources {
                params: (&params).into(),
                density: (&dv).into(),
                linear_clamp: (&self.sampler).into(),
                tf: (&tf_buffer).into(),
                light_out: (&light.view).into(),
            },
            groups,
            "volume light",
        )?;
        let lit = if fold {
            Some(self.encode_lit_density(device, recorder, volume, &dv, &light.view)?)
        } else {
            None
        };
        let (lit_density, lit_view, lit_lease) = match lit {
            Some((t, l)) => (Some(t.texture), Some(t.view), Some(l)),
            None => (None, None, None),
        };
        Ok(LightVolume {
            texture: light.texture,
            lit_density,
            views: (light.view, lit_view),
            _leases: (light_lease, lit_lease),
            built_for: (
                settings.light_dir,
                step,
                local_to_world,
                tf.clone(),
                volume.texture.clone(),
            ),
        })
    }

    /// The lit density of `volume` (`density`) from its light volume's nodes (`light`).
    fn encode_lit_density(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        volume: &Volume,
        density: &wgpu::TextureView,
        light: &wgpu::TextureView,
    ) -> Result<(Target, Lease), Error> {
        let size = volume.dims;
        let format = lit_format(volume.texture.format());
        let (lit, lease) = self.kept.lit.take(
            |t| t.is(size, format),
            || {
                Target::new(
                    device,
                    "lit density",
                    size,
                    wgpu::TextureDimension::D3,
                    format,
                )
            },
        );
        let mut rec = rec.recorder();
        let mut pass = rec.compute_pass(lit_density::STAGE, "lit density");
        let groups = [size[0].div_ceil(8), size[1].div_ceil(8), size[2]];
        let kept = &self.kept.lit_bound;
        // One entry point per format, each with its own generated bindings.
        macro_rules! fold {
            ($pipeline:expr, $kept:expr, $entry:ident, $out:ident) => {{
                let bound = $pipeline.bind_kept(
                    device,
                    $kept,
                    &lit_density::$entry::Resources {
                        density: density.into(),
                        light: light.into(),
                        linear_clamp: (&self.sampler).into(),
                        $out: (&lit.view).into(),
                    },
                )?;
                $pipeline.dispatch(&mut pass, &bound, groups);
            }};
        }
        match format {
            wgpu::TextureFormat::Rgba8Unorm => {
                fold!(self.lit.unorm8, &kept.unorm8, lit_unorm8, lit_out_unorm8)
            }
            wgpu::TextureFormat::Rgba16Float => {
                fold!(
                    self.lit.float16,
                    &kept.float16,
                    lit_float16,
                    lit_out_float16
                )
            }
            _ => fold!(
                self.lit.float32,
                &kept.float32,
                lit_float32,
                lit_out_float32
            ),
        }
        drop(pass);
        Ok((lit, lease))
    }
}
