//! Per-stage snapshots: each 2D JFA stage run alone through the harness, summarised for insta,
//! and the colour-mapped field compared with a reference image.

use crate::common;

// The gallery example's scenes and test pictures (the example is the one place they live).
use crate::gallery;

use common::*;
use fieldkit::distance::{Jfa2d, JfaSettings2d, Variant, cpu, upload_mask};
use fieldkit::gpu::Context;
use fieldkit::gpu::read_texture;
use fieldkit::harness::{Summary, Tolerance, compare_image};

const W: usize = 40;
const H: usize = 24;

fn mask() -> Vec<bool> {
    random_mask(W, H, 0.02, 42)
}

#[test]
fn seed_stage() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let m = mask();
    let seeds = upload_mask(&ctx.device, &ctx.queue, &to_bytes(&m), W as u32, H as u32).unwrap();
    let mut enc = ctx.encoder("seed");
    let out = jfa
        .encode_seed(&ctx.device, &mut enc, &seeds, false)
        .unwrap();
    ctx.submit_and_wait("seed", enc).unwrap();
    let nearest: Vec<u32> = read_texture(&ctx, &out).unwrap();
    assert_eq!(
        nearest,
        cpu::jfa_2d(&m, W, H, &[]),
        "seed stage = CPU model with no passes"
    );
    insta::assert_snapshot!(Summary::ints(&[H, W], &nearest).to_string());
}

#[test]
fn one_jump_pass() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let m = mask();
    let seeds = upload_mask(&ctx.device, &ctx.queue, &to_bytes(&m), W as u32, H as u32).unwrap();
    let mut enc = ctx.encoder("jump");
    let (a, b) = seed_pair(&ctx, &jfa, &mut enc, &seeds);
    jfa.encode_jump(&ctx.device, &mut enc, &a, &b, 4).unwrap();
    ctx.submit_and_wait("jump", enc).unwrap();
    let nearest: Vec<u32> = read_texture(&ctx, &b).unwrap();
    assert_eq!(nearest, cpu::jfa_2d(&m, W, H, &[4]));
    insta::assert_snapshot!(Summary::ints(&[H, W], &nearest).to_string());
}

#[test]
fn resolve_stage() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let m = mask();
    // Resolve alone, from a nearest-seed texture made on the CPU.
    let nearest = cpu::jfa_2d(&m, W, H, &Variant::JfaPlus2.steps(W as u32));
    let tex = crate::common::texture(
        &ctx,
        [W as u32, H as u32, 1],
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    ctx.queue.write_texture(
        tex.as_image_copy(),
        bytemuck::cast_slice(&nearest),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(4 * W as u32),
            rows_per_image: None,
        },
        tex.size(),
    );
    let mut enc = ctx.encoder("resolve");
    let out = jfa
        .encode_resolve(&ctx.device, &mut enc, &tex, None, 1.0)
        .unwrap();
    ctx.submit_and_wait("resolve", enc).unwrap();
    let d: Vec<f32> = read_texture(&ctx, &out).unwrap();
    // Squared distances are integers: rounding d² recovers them exactly despite sqrt's last bit.
    let d2: Vec<u32> = d.iter().map(|v| (v * v).round() as u32).collect();
    let exact: Vec<u32> = cpu::edt_2d_squared(&m, W, H)
        .iter()
        .map(|&v| v as u32)
        .collect();
    assert_eq!(d2, exact);
    fieldkit::assert_summary!(
        "resolve_stage",
        Summary::floats(&[H, W], &d, 3)
            .and("d² rounded", Summary::ints(&[H, W], &d2))
            .to_string()
    );
}

#[test]
fn whole_chain_signed() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let m: Vec<bool> = gallery::shapes_mask(W as u32 * 2, H as u32 * 2)
        .iter()
        .map(|&v| v != 0)
        .collect();
    let (nearest, d) = run_jfa(&ctx, &jfa, &m, W * 2, H * 2, JfaSettings2d::signed());
    fieldkit::assert_summary!(
        "whole_chain_signed",
        Summary::floats(&[H * 2, W * 2], &d, 3)
            .and("nearest inside", Summary::ints(&[H * 2, W * 2], &nearest))
            .to_string()
    );
}

#[test]
fn visualized_field_matches_reference_image() {
    let ctx = Context::shared();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let (w, h) = (160u32, 90u32);
    let seeds = upload_mask(&ctx.device, &ctx.queue, &gallery::shapes_mask(w, h), w, h).unwrap();
    let mut enc = ctx.encoder("chain");
    let field = jfa
        .encode(&ctx.device, &mut enc, &seeds, &JfaSettings2d::signed())
        .unwrap();
    ctx.submit_and_wait("chain", enc).unwrap();
    let rgba = gallery::visualize_distance(&ctx, &field.distance, 4.0, 20.0).unwrap();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots");
    // Set on llvmpipe (lavapipe, LLVM 15): the field is exact, so only the colour map's float
    // rounding can differ between adapters; a broken stage moves whole bands (mean >> 1).
    let tol = Tolerance {
        mean: 1.0,
        outlier_fraction: 0.01,
        pixel: 8,
    };
    compare_image(&dir, "distance_2d_visualize", &rgba, w, h, tol).unwrap();
}

/// A kept `Distance2d` makes its pipelines for the first mask and none for the next sizes (a
/// new size is a slider's step in an editor: it must not wait on a shader compile). Counted
/// by wgpu's own pipeline counter on a device of the test's own.
#[test]
fn a_new_mask_size_makes_no_pipeline() {
    let ctx = Context::new().expect("a GPU adapter (apt-get install mesa-vulkan-drivers)");
    let d2 = fieldkit::distance::Distance2d::new(&ctx.device).unwrap();
    let pipelines = || common::compute_pipelines(&ctx.device);
    let run = |w: u32, h: u32, signed: bool| {
        let mut mask = vec![0u8; (w * h) as usize];
        mask[(h / 2 * w + w / 3) as usize] = 255;
        mask[(w * h - 1) as usize] = 255;
        let tex = upload_mask(&ctx.device, &ctx.queue, &mask, w, h).unwrap();
        let mut enc = ctx.encoder("sizes");
        let settings = fieldkit::distance::Settings2d {
            signed,
            ..Default::default()
        };
        let field = d2.encode(&ctx.device, &mut enc, &tex, &settings).unwrap();
        ctx.submit_and_wait("sizes", enc).unwrap();
        let d: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
        // The seed at the last texel is 0 away from itself (signed: half a texel inside).
        assert_eq!(
            d[(w * h - 1) as usize],
            if signed { -0.5 } else { 0.0 },
            "{w}×{h}"
        );
    };
    for signed in [false, true] {
        run(40, 30, signed);
    }
    let made = pipelines();
    for (w, h) in [(41, 37), (45, 60), (200, 120), (221, 133), (17, 256)] {
        for signed in [false, true] {
            run(w, h, signed);
        }
    }
    assert_eq!(pipelines(), made, "pipelines made for new mask sizes");
}

/// `Distance2d::prepare` makes, for a mask size and settings, every pipeline the encode that
/// follows needs: it then makes none (here the signed field, whose passes are specialised by
/// the sign), and its field is the one the unprepared transform gives.
#[test]
fn prepare_makes_the_pipelines_an_encode_needs() {
    let ctx = Context::new().expect("a GPU adapter (apt-get install mesa-vulkan-drivers)");
    let d2 = fieldkit::distance::Distance2d::new(&ctx.device).unwrap();
    let pipelines = || common::compute_pipelines(&ctx.device);
    let (w, h) = (48u32, 20u32);
    let signed = fieldkit::distance::Settings2d {
        signed: true,
        ..Default::default()
    };
    let before = pipelines();
    d2.prepare(&ctx.device, [w, h], &signed).unwrap();
    let prepared = pipelines();
    assert!(prepared > before, "prepare made no pipeline");
    let mut mask = vec![0u8; (w * h) as usize];
    mask[(h / 2 * w + 7) as usize] = 255;
    let tex = upload_mask(&ctx.device, &ctx.queue, &mask, w, h).unwrap();
    let mut enc = ctx.encoder("prepared");
    let field = d2.encode(&ctx.device, &mut enc, &tex, &signed).unwrap();
    ctx.submit_and_wait("prepared", enc).unwrap();
    assert_eq!(pipelines(), prepared, "the encode made pipelines");
    let d: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
    // Signed, each side is measured to the other's edge: the seed is half a texel inside,
    // the texel 3 to its right 2.5 outside.
    assert_eq!(d[(h / 2 * w + 7) as usize], -0.5);
    assert_eq!(d[(h / 2 * w + 10) as usize], 2.5);
}
