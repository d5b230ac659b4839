//! The 2D distance tool's seed rule (issue 24, seed 003): any non-black texel of any colour
//! format is a seed under `SeedRule::seed()`, red above 0 by default, with a threshold; the seed
//! texels are found on the GPU from the texture itself. Against the CPU transform of the mask
//! the rule's formula gives, written out here.

use crate::common;

use common::upload_2d;
use fieldkit::distance::{
    Channels, Distance2d, Jfa2d, Method2d, SeedRule, Settings2d, Variant, cpu, unpack_seed,
};
use fieldkit::gpu::{Context, read_texture};
use half::f16;

const W: u32 = 37;
const H: u32 = 23;

/// A colour image: a few texels of each kind on black (linear RGBA).
fn image() -> Vec<[f32; 4]> {
    let mut px = vec![[0.0, 0.0, 0.0, 1.0]; (W * H) as usize];
    let mut put = |x: u32, y: u32, c: [f32; 4]| px[(y * W + x) as usize] = c;
    put(3, 4, [1.0, 0.0, 0.0, 1.0]); // red
    put(30, 5, [0.0, 0.8, 0.0, 1.0]); // green only
    put(12, 18, [0.0, 0.0, 0.3, 1.0]); // dark blue only
    put(20, 10, [0.2, 0.2, 0.2, 1.0]); // dark grey
    put(33, 20, [0.0, 0.0, 0.0, 0.0]); // transparent black
    put(7, 15, [0.6, 0.7, 0.0, 0.5]); // yellow, half alpha
    px
}

/// The rule, written out: the largest of the chosen channels above the threshold.
fn rule_mask(px: &[[f32; 4]], rule: &SeedRule) -> Vec<bool> {
    px.iter()
        .map(|c| {
            let v = match rule.channels {
                Channels::Red => c[0],
                Channels::AnyColour => c[0].max(c[1]).max(c[2]),
                Channels::Alpha => c[3],
            };
            v > rule.above
        })
        .collect()
}

fn upload(ctx: &Context, format: wgpu::TextureFormat, px: &[[f32; 4]]) -> wgpu::Texture {
    let bytes: Vec<u8> = match format {
        wgpu::TextureFormat::Rgba32Float => bytemuck::cast_slice(px).to_vec(),
        wgpu::TextureFormat::Rgba16Float => px
            .iter()
            .flatten()
            .flat_map(|&v| f16::from_f32(v).to_le_bytes())
            .collect(),
        wgpu::TextureFormat::Rgba8Unorm => px
            .iter()
            .flatten()
            .map(|&v| (v * 255.0).round() as u8)
            .collect(),
        wgpu::TextureFormat::Bgra8Unorm => px
            .iter()
            .flat_map(|c| [c[2], c[1], c[0], c[3]])
            .map(|v| (v * 255.0).round() as u8)
            .collect(),
        f => panic!("no upload for {f:?}"),
    };
    upload_2d(ctx, [W, H], format, &bytes)
}

/// Every format and rule: the exact transform's distances equal the CPU transform of the
/// rule's mask (integer squared distances, so exactly), and JFA's seed stage marks exactly the
/// rule's texels.
#[test]
fn any_colour_format_and_rule_seeds_the_texels_the_rule_names() {
    let ctx = Context::shared();
    let d2 = Distance2d::new(&ctx.device).unwrap();
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let px = image();
    let rules = [
        SeedRule::default(),
        SeedRule::seed(),
        SeedRule {
            channels: Channels::AnyColour,
            above: 0.25,
        },
        SeedRule {
            channels: Channels::Alpha,
            above: 0.75,
        },
    ];
    for format in [
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Rgba16Float,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureFormat::Bgra8Unorm,
    ] {
        let tex = upload(&ctx, format, &px);
        for rule in &rules {
            let mask = rule_mask(&px, rule);
            let count = mask.iter().filter(|&&m| m).count();
            let want = cpu::edt_2d_squared(&mask, W as usize, H as usize);
            let mut enc = ctx.encoder("seed rule");
            let field = d2
                .encode(
                    &ctx.device,
                    &mut enc,
                    &tex,
                    &Settings2d {
                        seeds: *rule,
                        ..Settings2d::default()
                    },
                )
                .unwrap();
            let seeds = jfa
                .encode_seed_with(&ctx.device, &mut enc, &tex, false, rule)
                .unwrap();
            ctx.submit_and_wait("seed rule", enc).unwrap();
            let got: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
            for (i, (&g, &w)) in got.iter().zip(&want).enumerate() {
                assert_eq!(
                    (g as f64 * g as f64).round() as u64,
                    w,
                    "{format:?} {rule:?}: texel {i}"
                );
            }
            let marked: Vec<u32> = read_texture(&ctx, &seeds).unwrap();
            for (i, &m) in marked.iter().enumerate() {
                let own = unpack_seed(m) == Some((i as u32 % W, i as u32 / W));
                assert_eq!(own, mask[i], "{format:?} {rule:?}: JFA seed at {i}");
            }
            println!("{format:?} {rule:?}: {count} seeds");
        }
    }
    // The rules differ on this image: red alone 3 seeds, any colour 5, above 0.25 4.
    assert_eq!(
        rule_mask(&px, &SeedRule::default())
            .iter()
            .filter(|&&m| m)
            .count(),
        3
    );
    assert_eq!(
        rule_mask(&px, &SeedRule::seed())
            .iter()
            .filter(|&&m| m)
            .count(),
        5
    );
    assert_eq!(rule_mask(&px, &rules[2]).iter().filter(|&&m| m).count(), 4);
}

/// JFA from a colour image, end to end under the source's rule: zero distance exactly at the
/// rule's texels, as the exact transform, and JFA+2's usual small error elsewhere.
#[test]
fn jfa_takes_the_rule_too() {
    let ctx = Context::shared();
    let d2 = Distance2d::new(&ctx.device).unwrap();
    let tex = upload(&ctx, wgpu::TextureFormat::Rgba16Float, &image());
    let mut enc = ctx.encoder("jfa rule");
    let run = |method| Settings2d {
        method,
        seeds: SeedRule::seed(),
        ..Settings2d::default()
    };
    let exact = d2
        .encode(&ctx.device, &mut enc, &tex, &run(Method2d::Exact))
        .unwrap();
    let jfa = d2
        .encode(
            &ctx.device,
            &mut enc,
            &tex,
            &run(Method2d::Jfa(Variant::JfaPlus2)),
        )
        .unwrap();
    ctx.submit_and_wait("jfa rule", enc).unwrap();
    let a: Vec<f32> = read_texture(&ctx, &exact.distance).unwrap();
    let b: Vec<f32> = read_texture(&ctx, &jfa.distance).unwrap();
    let zero = |v: &[f32]| v.iter().map(|&d| d == 0.0).collect::<Vec<_>>();
    assert_eq!(zero(&a), zero(&b), "the seeds differ");
    assert_eq!(zero(&a).iter().filter(|&&z| z).count(), 5);
    let off = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max);
    println!("JFA+2 against exact: {off} texels differ, by at most {worst:.3}");
    // llvmpipe: 1 texel, 0.665 texels off (JFA+2 is not exact; tests/distance/jfa_traps_2d.rs).
    assert!(off <= 8 && worst < 1.5, "{off} texels, {worst}");
}

#[test]
fn formats_and_thresholds_that_cannot_seed_are_typed_errors() {
    let ctx = Context::shared();
    let d2 = Distance2d::new(&ctx.device).unwrap();
    let tex = upload(&ctx, wgpu::TextureFormat::Rgba8Unorm, &image());
    let mut enc = ctx.encoder("bad rule");
    let e = d2
        .encode(
            &ctx.device,
            &mut enc,
            &tex,
            &Settings2d {
                seeds: SeedRule {
                    above: f32::NAN,
                    ..SeedRule::seed()
                },
                ..Settings2d::default()
            },
        )
        .expect_err("NaN threshold refused");
    assert!(e.to_string().contains("seed threshold"), "{e}");
    let uint = crate::common::sampled(&ctx, [4, 4, 1], wgpu::TextureFormat::R8Uint);
    let e = d2
        .encode(&ctx.device, &mut enc, &uint, &Settings2d::default())
        .expect_err("an integer texture refused");
    assert!(matches!(e, fieldkit::Error::Format { .. }), "{e}");
}
