//! The albedo texture the attribute passes of the voxelizer and the octree sample: its checks,
//! and the sampler and stand-in they bind.

use std::sync::OnceLock;

use crate::error::Error;

/// An albedo texture the attribute pass can sample: 2D, one layer, `TEXTURE_BINDING`, a
/// filterable float format.
fn check_albedo(
    device: &wgpu::Device,
    stage: &'static str,
    t: &wgpu::Texture,
) -> Result<(), Error> {
    if t.dimension() != wgpu::TextureDimension::D2 || t.depth_or_array_layers() != 1 {
        return Err(Error::Invalid {
            stage,
            what: format!(
                "the albedo must be one 2D texture, got {:?} × {} layers",
                t.dimension(),
                t.depth_or_array_layers()
            ),
        });
    }
    if !t.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return Err(Error::Invalid {
            stage,
            what: format!("the albedo needs TEXTURE_BINDING, it has {:?}", t.usage()),
        });
    }
    let filterable = matches!(
        t.format().sample_type(None, Some(device.features())),
        Some(wgpu::TextureSampleType::Float { filterable: true })
    );
    if !filterable || t.format().is_depth_stencil_format() || t.sample_count() != 1 {
        return Err(Error::Format {
            stage,
            format: t.format(),
            supported: "a filterable colour format (Rgba8Unorm, Rgba8UnormSrgb, Rgba16Float, …)",
        });
    }
    Ok(())
}

/// How the attribute passes (`voxelize/attributes`, `octree/attributes`) bind an albedo: a
/// sampler (repeat, linear) and a 1×1 stand-in where there is none.
#[derive(Default)]
pub(crate) struct AlbedoBinding {
    sampler: OnceLock<wgpu::Sampler>,
    none: OnceLock<wgpu::TextureView>,
}

impl AlbedoBinding {
    /// `albedo` checked for `mesh` (its texture coordinates) and `stage`'s pass: the view to
    /// bind, or `None`.
    pub(crate) fn check(
        device: &wgpu::Device,
        stage: &'static str,
        albedo: Option<&wgpu::Texture>,
        textured: bool,
    ) -> Result<Option<wgpu::TextureView>, Error> {
        let Some(t) = albedo else {
            return Ok(None);
        };
        check_albedo(device, stage, t)?;
        if !textured {
            return Err(Error::Invalid {
                stage,
                what: "an albedo texture needs the mesh's texture coordinates (Mesh::texcoords)"
                    .into(),
            });
        }
        Ok(Some(t.create_view(&Default::default())))
    }

    /// The view and sampler to bind for `albedo`.
    pub(crate) fn bind<'a>(
        &'a self,
        device: &wgpu::Device,
        albedo: Option<&'a wgpu::TextureView>,
    ) -> (&'a wgpu::TextureView, &'a wgpu::Sampler) {
        let sampler = self.sampler.get_or_init(|| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("voxel albedo"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            })
        });
        let view = match albedo {
            Some(v) => v,
            None => self.none.get_or_init(|| {
                super::texture(
                    device,
                    "no voxel albedo",
                    [1, 1, 1],
                    wgpu::TextureDimension::D2,
                    wgpu::TextureFormat::Rgba8Unorm,
                    wgpu::TextureUsages::TEXTURE_BINDING,
                )
                .create_view(&Default::default())
            }),
        };
        (view, sampler)
    }
}
