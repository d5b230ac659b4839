//! The cloud scene: seed 002's procedural cloud, marched from a texture and from its function.

use super::*;

/// A 96³ fBm cloud under a sky-blue background, lit through the light volume, seen from `eye`.
pub fn cloud_scene(
    ctx: &Context,
    w: u32,
    h: u32,
    eye: glam::Vec3,
    target: glam::Vec3,
) -> Result<Vec<u8>, Error> {
    cloud_scene_with(ctx, w, h, eye, target, Preset::Fieldkit)
}

/// [`cloud_scene`] with `preset`'s cloud: the seed preset evaluates the fBm function at every
/// sample (`CloudMarch`, the function linked into the march at build time), shadowed by shadow
/// rays through it, instead of a baked 96³ texture and its light volume.
pub fn cloud_scene_with(
    ctx: &Context,
    w: u32,
    h: u32,
    eye: glam::Vec3,
    target: glam::Vec3,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::view::View;
    use fieldkit::volume::{
        CloudMarch, FunctionVolume, MarchSettings, Shadow, TransferFunction, Volume,
        VolumeRenderer, fbm_cloud,
    };
    let dims = [96; 3];
    let volume = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &fbm_cloud(dims, 0),
        dims,
        wgpu::TextureFormat::R8Unorm,
        glam::Vec3::splat(1.0 / 96.0),
        glam::Vec3::splat(-0.5),
    )?;
    let renderer = VolumeRenderer::new(&ctx.device, &ctx.queue, wgpu::TextureFormat::Rgba8Unorm)?;
    let tf = TransferFunction::cloud();
    let settings = MarchSettings {
        step: 1.0 / 96.0,
        ..MarchSettings::default()
    };
    let proj = glam::camera::rh::proj::directx::perspective(0.9, w as f32 / h as f32, 0.01, 50.0);
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, glam::Vec3::Y),
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    let colour = fieldkit::gpu::texture(
        &ctx.device,
        "gallery cloud",
        [w, h, 1],
        wgpu::TextureDimension::D2,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let cv = colour.create_view(&Default::default());
    let mut enc = ctx.encoder("gallery cloud");
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("sky"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &cv,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: 0.32,
                    g: 0.52,
                    b: 0.82,
                    a: 1.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let marched = match preset {
        Preset::Fieldkit => {
            let bricks = renderer.encode_bricks(&ctx.device, &mut enc, &volume)?;
            let light = renderer.encode_light(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                &tf,
                glam::Mat4::IDENTITY,
                &settings,
            )?;
            renderer.encode_march(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                Some(&light),
                &tf,
                glam::Mat4::IDENTITY,
                &view,
                None,
                &settings,
            )?
        }
        Preset::Seed => {
            // The function's box is the unit cube of its texture coordinates; moved to where
            // the texture's box is.
            let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue)?;
            let box_ = FunctionVolume::unit(96);
            let bricks = cloud.encode_bricks(&ctx.device, &mut enc, &box_)?;
            let settings = MarchSettings {
                shadow: Shadow::Rays { step: 1.0 / 32.0 },
                ..settings
            };
            cloud.encode_march(
                &ctx.device,
                &mut enc,
                &box_,
                &bricks,
                &tf,
                glam::Mat4::from_translation(glam::Vec3::splat(-0.5)),
                &view,
                None,
                &settings,
            )?
        }
    };
    if let Some(m) = marched {
        renderer.encode_composite(&ctx.device, &mut enc, &cv, &m)?;
    }
    ctx.submit_and_wait("gallery cloud", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &colour)?;
    Ok(px.concat())
}
