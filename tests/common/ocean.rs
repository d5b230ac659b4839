//! What the ocean render tests share: a small sea and camera, its patches, targets cleared and
//! drawn into, and the closed forms the pictures are held to.
#![allow(unused_imports)]

use fieldkit::Error;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::harness::Summary;
use fieldkit::ocean::{ALL_SKIRTS, Look, OceanCamera, OceanRenderer, Output, Patch};
use fieldkit::ocean::{Wave, Waves};
use glam::{DVec2, DVec3, DVec4, Vec2, Vec3, Vec4};

pub const W: u32 = 96;

pub const H: u32 = 64;

pub const RGBA32: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub const CLEAR: f64 = -1.0;

pub fn wave(dx: f32, dz: f32, amplitude: f32, wavelength: f32, speed: f32) -> Wave {
    Wave {
        direction: Vec2::new(dx, dz),
        amplitude,
        wavelength,
        speed,
    }
}

pub fn sea() -> Waves {
    Waves::new(
        vec![
            wave(1.0, 0.15, 0.5, 31.0, 7.0),
            wave(0.4, 1.0, 0.25, 13.5, 4.6),
            wave(-0.7, 0.6, 0.08, 5.3, 2.9),
        ],
        0.6,
    )
    .unwrap()
}

/// Far from the world origin, looking down the z axis at about 17°.
pub fn camera() -> OceanCamera {
    let eye = DVec3::new(2.0e4, 6.0, -3.5e4);
    OceanCamera::look_at(
        eye,
        eye + DVec3::new(0.0, -6.0, -20.0),
        glam::camera::rh::proj::directx::perspective(1.0, W as f32 / H as f32, 0.1, 400.0),
    )
}

/// 6 × 6 patches of 16 m around the eye.
pub fn patches(cam: &OceanCamera) -> Vec<Patch> {
    let eye = cam.eye();
    let mut out = Vec::new();
    for j in 0..6 {
        for i in 0..6 {
            out.push(Patch::new(
                DVec2::new(
                    eye.x - 48.0 + 16.0 * i as f64,
                    eye.z - 80.0 + 16.0 * j as f64,
                ),
                16.0,
            ));
        }
    }
    out
}

pub fn target(ctx: &Context, format: wgpu::TextureFormat) -> wgpu::Texture {
    super::texture(
        ctx,
        [W, H, 1],
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
    )
}

/// Clear `views` to CLEAR and `depth` to `clear_depth`.
pub fn clear(
    enc: &mut wgpu::CommandEncoder,
    views: &[&wgpu::TextureView],
    depth: &wgpu::TextureView,
    clear_depth: f32,
) {
    let attachments: Vec<_> = views
        .iter()
        .map(|v| {
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: CLEAR,
                        g: CLEAR,
                        b: CLEAR,
                        a: CLEAR,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear"),
        color_attachments: &attachments,
        depth_stencil_attachment: Some(fieldkit::gpu::depth_cleared(depth, clear_depth)),
        ..Default::default()
    });
}

/// Clear the colour targets to CLEAR and the depth to `depth`, then draw.
#[allow(clippy::too_many_arguments)]
pub fn draw(
    ctx: &Context,
    renderer: &OceanRenderer,
    waves: &Waves,
    look: &Look,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
    clear_depth: f32,
    fade: bool,
) {
    draw_from(
        ctx,
        renderer,
        waves,
        look,
        targets,
        depth,
        clear_depth,
        fade,
        camera(),
    );
}

/// [`draw`] from another camera.
#[allow(clippy::too_many_arguments)]
pub fn draw_from(
    ctx: &Context,
    renderer: &OceanRenderer,
    waves: &Waves,
    look: &Look,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
    clear_depth: f32,
    fade: bool,
    cam: OceanCamera,
) {
    let views: Vec<wgpu::TextureView> = targets
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let depth_view = depth.create_view(&Default::default());
    let mut enc = ctx.encoder("ocean test");
    clear(
        &mut enc,
        &views.iter().collect::<Vec<_>>(),
        &depth_view,
        clear_depth,
    );
    let refs: Vec<&wgpu::TextureView> = views.iter().collect();
    renderer
        .encode(
            &ctx.device,
            &mut enc,
            waves,
            12.5,
            &cam,
            look,
            &patches(&cam),
            &refs,
            depth,
            fade,
        )
        .unwrap();
    ctx.submit_and_wait("ocean test", enc).unwrap();
}

/// The typed error `renderer` gives drawing `look` over calm water into `targets` and `depth`
/// from [`camera`] (nothing is submitted).
pub fn refusal(
    ctx: &Context,
    renderer: &OceanRenderer,
    look: &Look,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
) -> fieldkit::Error {
    let views: Vec<wgpu::TextureView> = targets
        .iter()
        .map(|t| t.create_view(&Default::default()))
        .collect();
    let refs: Vec<&wgpu::TextureView> = views.iter().collect();
    let cam = camera();
    let mut enc = ctx.encoder("refused");
    let waves = calm();
    let patches = patches(&cam);
    let drawn = renderer.encode(
        &ctx.device,
        &mut enc,
        &waves,
        0.0,
        &cam,
        look,
        &patches,
        &refs,
        depth,
        false,
    );
    drawn.expect_err("refused")
}

/// Where the ray through the centre of pixel (x, y) of a `w` × `h` image meets the plane y = 0,
/// if it does between the near and far planes.
pub fn plane_point(cam: &OceanCamera, size: [u32; 2], x: u32, y: u32) -> Option<DVec3> {
    level_point(cam, size, x, y, 0.0)
}

/// Where the ray through the centre of pixel (x, y) of a `w` × `h` image meets the plane
/// y = `level`, if it does between the near and far planes.
pub fn level_point(
    cam: &OceanCamera,
    [w, h]: [u32; 2],
    x: u32,
    y: u32,
    level: f64,
) -> Option<DVec3> {
    let inv = (cam.proj.as_dmat4() * cam.view).inverse();
    let ndc = DVec2::new(
        (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
        1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
    );
    let un = |z: f64| {
        let q = inv * DVec4::new(ndc.x, ndc.y, z, 1.0);
        q.truncate() / q.w
    };
    let (a, b) = (un(0.0), un(1.0));
    let t = (a.y - level) / (a.y - b.y);
    (t > 0.0 && t < 1.0).then(|| a + (b - a) * t)
}

/// The pixel centre's ray hitting y = 0: view depth and NDC depth, if it hits ahead.
pub fn plane_hit(cam: &OceanCamera, x: u32, y: u32) -> Option<(f64, f64)> {
    level_hit(cam, x, y, 0.0)
}

/// NDC depth of view depth `d`.
pub fn ndc_of(cam: &OceanCamera, d: f64) -> f64 {
    let clip = cam.proj.as_dmat4() * DVec4::new(0.0, 0.0, -d, 1.0);
    clip.z / clip.w
}

pub fn calm_look() -> Look {
    Look {
        height_layers: vec![],
        normal_layers: vec![],
        deep_colour: Vec3::ZERO,
        shallow_colour: Vec3::ONE,
        fade_distance: 3.0,
        skirt: 0.0,
        ..Look::default()
    }
}

pub fn depth_desc() -> wgpu::TextureDescriptor<'static> {
    wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d {
            width: W,
            height: H,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    }
}

/// Where the ray through the centre of pixel (x, y) meets the plane y = `level`: view depth
/// and NDC depth, if ahead.
pub fn level_hit(cam: &OceanCamera, x: u32, y: u32, level: f64) -> Option<(f64, f64)> {
    let v = cam.view * level_point(cam, [W, H], x, y, level)?.extend(1.0);
    let clip = cam.proj.as_dmat4() * v;
    Some((-v.z, clip.z / clip.w))
}

pub fn calm() -> Waves {
    Waves::new(vec![wave(1.0, 0.0, 1e-4, 50.0, 0.0)], 0.0).unwrap()
}

/// The view depth of the scene the calm sea fades against.
pub const FADE_SCENE: f64 = 15.0;

/// The calm sea drawn from [`camera`] into `targets` (a G-buffer's four), fading against a
/// scene at [`FADE_SCENE`] whose depth `depth` starts with.
pub fn draw_faded(
    ctx: &Context,
    renderer: &OceanRenderer,
    targets: &[wgpu::Texture],
    depth: &wgpu::Texture,
) {
    let scene_ndc = ndc_of(&camera(), FADE_SCENE) as f32;
    draw(
        ctx,
        renderer,
        &calm(),
        &calm_look(),
        targets,
        depth,
        scene_ndc,
        true,
    );
}

/// A texture array of `layers` constant layers.
pub fn constant_maps(
    ctx: &Context,
    format: wgpu::TextureFormat,
    layers: &[[u8; 4]],
    channels: usize,
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    let side = 8u32;
    let texels: Vec<u8> = layers
        .iter()
        .flat_map(|c| std::iter::repeat_n(c[..channels].to_vec(), (side * side) as usize).flatten())
        .collect();
    super::upload_layers(ctx, [side, side, layers.len() as u32], format, &texels)
}
