//! Bad input to the 2D distance stages: each a typed error naming the problem, never a panic,
//! a wgpu validation error or a lost device.

use crate::common;

use common::seed_pair;
use fieldkit::Error;
use fieldkit::distance::{Jfa2d, JfaSettings2d, MAX_PACKED_SIDE, upload_mask};
use fieldkit::gpu::Context;

fn seed_texture(
    ctx: &Context,
    format: wgpu::TextureFormat,
    size: wgpu::Extent3d,
    dimension: wgpu::TextureDimension,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

fn encode(ctx: &Context, seeds: &wgpu::Texture, options: JfaSettings2d) -> Result<(), Error> {
    let jfa = Jfa2d::new(&ctx.device)?;
    let mut enc = ctx.encoder("bad input");
    jfa.encode(&ctx.device, &mut enc, seeds, &options)?;
    ctx.submit_and_wait("bad input", enc)
}

const EXT: wgpu::Extent3d = wgpu::Extent3d {
    width: 8,
    height: 8,
    depth_or_array_layers: 1,
};

#[test]
fn zero_sized_mask() {
    let ctx = Context::shared();
    assert!(matches!(
        upload_mask(&ctx.device, &ctx.queue, &[], 0, 5),
        Err(Error::Size {
            what: "width",
            got: 0,
            ..
        })
    ));
    assert!(matches!(
        upload_mask(&ctx.device, &ctx.queue, &[], 5, 0),
        Err(Error::Size {
            what: "height",
            got: 0,
            ..
        })
    ));
}

#[test]
fn mask_length_mismatch() {
    let ctx = Context::shared();
    let e = upload_mask(&ctx.device, &ctx.queue, &[0; 10], 4, 4).unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("10 bytes")),
        "{e}"
    );
}

#[test]
fn size_past_limits() {
    let ctx = Context::shared();
    let max = ctx
        .device
        .limits()
        .max_texture_dimension_2d
        .min(MAX_PACKED_SIDE);
    let e = upload_mask(&ctx.device, &ctx.queue, &[], max + 1, 1).unwrap_err();
    assert!(
        matches!(e, Error::Size { what: "width", got, max: m, .. } if got == (max + 1) as u64 && m == max as u64),
        "{e}"
    );
}

#[test]
fn unsupported_seed_format() {
    let ctx = Context::shared();
    let t = seed_texture(
        &ctx,
        wgpu::TextureFormat::R32Uint,
        EXT,
        wgpu::TextureDimension::D2,
    );
    let e = encode(&ctx, &t, JfaSettings2d::default()).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Format {
                format: wgpu::TextureFormat::R32Uint,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string().contains("R8Unorm"),
        "the message lists what is supported: {e}"
    );
}

#[test]
fn three_d_seed_texture() {
    let ctx = Context::shared();
    let t = seed_texture(
        &ctx,
        wgpu::TextureFormat::R8Unorm,
        wgpu::Extent3d {
            depth_or_array_layers: 4,
            ..EXT
        },
        wgpu::TextureDimension::D3,
    );
    assert!(matches!(
        encode(&ctx, &t, JfaSettings2d::default()),
        Err(Error::Invalid { .. })
    ));
}

#[test]
fn nan_and_negative_texel_size() {
    let ctx = Context::shared();
    let t = upload_mask(&ctx.device, &ctx.queue, &[255; 64], 8, 8).unwrap();
    for bad in [f32::NAN, -1.0, 0.0, f32::INFINITY] {
        let e = encode(
            &ctx,
            &t,
            JfaSettings2d {
                texel_size: bad,
                ..JfaSettings2d::default()
            },
        )
        .unwrap_err();
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains("texel_size")),
            "{bad}: {e}"
        );
    }
}

#[test]
fn zero_step_and_mismatched_ping_pong() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let seeds = upload_mask(&ctx.device, &ctx.queue, &[255; 64], 8, 8).unwrap();
    let mut enc = ctx.encoder("bad");
    let (a, b) = seed_pair(&ctx, &jfa, &mut enc, &seeds);
    assert!(matches!(
        jfa.encode_jump(&ctx.device, &mut enc, &a, &b, 0),
        Err(Error::Invalid { .. })
    ));
    let small = upload_mask(&ctx.device, &ctx.queue, &[255; 16], 4, 4).unwrap();
    let c = jfa
        .encode_seed(&ctx.device, &mut enc, &small, false)
        .unwrap();
    assert!(matches!(
        jfa.encode_jump(&ctx.device, &mut enc, &a, &c, 1),
        Err(Error::Invalid { .. })
    ));
    // Nothing bad reached wgpu: the encoder still submits cleanly.
    ctx.submit_and_wait("bad", enc).unwrap();
}

#[test]
fn missing_adapter_message_says_how_to_get_one() {
    let e = Error::NoAdapter {
        detail: "none".into(),
    };
    assert!(
        e.to_string()
            .contains("apt-get install mesa-vulkan-drivers")
    );
}
