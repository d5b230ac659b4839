//! Helpers shared by the integration tests.
#![allow(dead_code)]

use fieldkit::distance::{Jfa2d, Options, Variant, upload_mask};
use fieldkit::gpu::{Context, read_texture};

/// Deterministic pseudo-random mask (no RNG crate needed, same on every machine).
pub fn random_mask(w: usize, h: usize, density: f64, seed: u64) -> Vec<bool> {
    let mut s = seed.wrapping_add(0x9e3779b97f4a7c15);
    (0..w * h)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) < density
        })
        .collect()
}

pub fn to_bytes(mask: &[bool]) -> Vec<u8> {
    mask.iter().map(|&m| if m { 255 } else { 0 }).collect()
}

/// Run the whole 2D chain; returns (nearest, distance).
pub fn run_jfa(ctx: &Context, jfa: &Jfa2d, mask: &[bool], w: usize, h: usize, options: Options) -> (Vec<u32>, Vec<f32>) {
    let seeds = upload_mask(ctx, &to_bytes(mask), w as u32, h as u32).expect("upload");
    let mut enc = ctx.encoder("test");
    let field = jfa.encode(&ctx.device, &mut enc, &seeds, &options).expect("encode");
    ctx.submit_and_wait("test", enc).expect("run");
    (read_texture(ctx, &field.nearest).unwrap(), read_texture(ctx, &field.distance).unwrap())
}

pub fn variant_options(variant: Variant) -> Options {
    Options { variant, ..Options::default() }
}
