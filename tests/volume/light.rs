//! The volume march's light: the light volume against shadow rays through the density, and
//! the lit density (`volume/lit_density`) against the density and the light nodes' interpolant.
//!
//! Tolerances were set on llvmpipe (lavapipe, Mesa 25), as in `volume_march.rs`.

use crate::common;

use common::volume::*;
use fieldkit::gpu::read_texture;
use fieldkit::volume::{MarchSettings, Shadow, TransferFunction, Volume, fbm_cloud};
use glam::{Mat4, Vec3};

#[test]
fn light_volume_and_shadow_rays_agree() {
    let rig = Rig::new();
    let volume = rig.cloud(24, 5);
    let tf = TransferFunction::cloud();
    let view = view_from(Vec3::new(0.6, 0.3, 1.5), Vec3::ZERO, 0.05);
    let base = MarchSettings {
        jitter: false,
        ..MarchSettings::default()
    };
    let rays = rig.march(
        &volume,
        &tf,
        &view,
        None,
        &MarchSettings {
            shadow: Shadow::Rays { step: 1.0 / 64.0 },
            ..base
        },
    );
    let baked_settings = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 64.0 },
        ..base
    };
    let baked =
        rig.image(rig.marched_folded(&volume, &tf, &view, None, &baked_settings, Some(true)));
    let separate =
        rig.image(rig.marched_folded(&volume, &tf, &view, None, &baked_settings, Some(false)));
    let unlit = rig.march(
        &volume,
        &tf,
        &view,
        None,
        &MarchSettings {
            shadow: Shadow::None,
            ..base
        },
    );
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p[0] - q[0]).abs() as f64)
            .sum::<f64>()
            / a.len() as f64
    };
    let (baked_off, unlit_off) = (diff(&baked, &rays), diff(&unlit, &rays));
    println!(
        "mean |Δ red| against shadow rays: light volume {baked_off:.4}, unshadowed {unlit_off:.4}"
    );
    // The half-resolution light volume is an approximation of the shadow rays, far closer to
    // them than no shadowing is. Bounds from llvmpipe.
    assert!(baked_off < 0.25 * unlit_off, "{baked_off} vs {unlit_off}");
    // Opacity does not depend on lighting.
    assert!(rays.iter().zip(&baked).all(|(p, q)| p[3] == q[3]));
    assert!(rays.iter().zip(&separate).all(|(p, q)| p[3] == q[3]));
    // Folded into the density or fetched from its own texture, the light is the same trilinear
    // interpolant of the same nodes, but for the folded copy's rounding (Rg16Float here) and
    // the last half voxel before each high face: there the copy, clamped like the density,
    // holds the last voxel centre's light, while the light texture goes on toward the node
    // half a voxel past the box. So the mean difference is tiny and a few edge pixels differ
    // more. Bounds from llvmpipe (mean 2.6e-5, worst 1.0e-2 on this cloud).
    let diffs: Vec<f32> = baked
        .iter()
        .zip(&separate)
        .map(|(p, q)| (p[0] - q[0]).abs())
        .collect();
    let worst = diffs.iter().copied().fold(0.0f32, f32::max);
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    println!("folded against separate light: mean |Δ red| {mean:.2e}, worst {worst:.2e}");
    assert!(mean < 1e-4 && worst < 0.03, "mean {mean}, worst {worst}");
    // A light volume is refused for a march with another transfer function, transform or
    // volume: it would shadow with the old one.
    let ctx = &rig.ctx;
    let s = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 64.0 },
        ..base
    };
    let mut enc = ctx.encoder("stale light");
    let (bricks, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
    let other_tf = TransferFunction::constant(Vec3::ONE, 0.2);
    // Another volume of the same size: its lit density would hold the old densities.
    let other_volume = rig.cloud(24, 6);
    for (volume, tf, l2w) in [
        (&volume, &other_tf, Mat4::IDENTITY),
        (&volume, &tf, Mat4::from_translation(Vec3::X)),
        (&other_volume, &tf, Mat4::IDENTITY),
    ] {
        let e = rig
            .renderer
            .encode_march(
                &ctx.device,
                &mut enc,
                volume,
                &bricks,
                Some(&light),
                tf,
                l2w,
                &view,
                None,
                &s,
            )
            .err()
            .expect("a stale light volume should be refused")
            .to_string();
        assert!(e.contains("rebuild"), "{e}");
    }
}

/// The lit density (`volume/lit_density`) against its definition, per format: red is the
/// density texel bit for bit, green the trilinear interpolant of the light volume's nodes (node
/// i on voxel 2i) at the voxel, i.e. the node itself on even indices and the mean of its
/// neighbours along each odd axis. Odd and even sizes, so the extra node past the box is used.
#[test]
fn lit_density_is_the_density_and_the_light_nodes_interpolant() {
    let rig = Rig::new();
    let ctx = &rig.ctx;
    let dims = [9u32, 6, 5];
    let data = fbm_cloud(dims, 3);
    let tf = TransferFunction::cloud();
    let s = MarchSettings {
        shadow: Shadow::LightVolume { step: 1.0 / 16.0 },
        ..MarchSettings::default()
    };
    use wgpu::TextureFormat::{R8Unorm, R16Float, R32Float};
    // R32Float volumes need FLOAT32_FILTERABLE (llvmpipe has it).
    assert!(
        ctx.device
            .features()
            .contains(wgpu::Features::FLOAT32_FILTERABLE),
        "the test adapter should filter R32Float"
    );
    for format in [R8Unorm, R16Float, R32Float] {
        let volume = Volume::upload(
            &ctx.device,
            &ctx.queue,
            &data,
            dims,
            format,
            Vec3::new(0.1, 0.15, 0.2),
            Vec3::splat(-0.4),
        )
        .unwrap();
        let mut enc = ctx.encoder("lit density");
        let (_, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
        ctx.submit_and_wait("lit density", enc).unwrap();
        let lit_density = light
            .lit_density
            .as_ref()
            .expect("a small volume is folded");
        let size = light.texture.size();
        assert_eq!(
            [size.width, size.height, size.depth_or_array_layers],
            [5, 4, 3],
            "nodes on every other voxel, one past an even size"
        );
        let nodes: Vec<[u16; 4]> = read_texture(ctx, &light.texture).unwrap();
        let node = |x: u32, y: u32, z: u32| {
            let i = ((z * size.height + y) * size.width + x) as usize;
            half::f16::from_bits(nodes[i][0]).to_f32()
        };
        // (density bits as the upload stored them, green) per voxel, and the green tolerance,
        // from the format's quantum and the arithmetic: R8 — Vulkan lets a store return either
        // of the two nearest levels (one level, 1/255), and the light's trilinear filter over
        // Rgba16Float nodes may be off by one f16 step near 1 (2⁻¹¹) on hardware that filters
        // half floats in reduced precision. Measured: llvmpipe within half a level; the H100
        // 0.53 levels off at (3,5,1) (251/255 stored for 0.98224). R16Float — one f16 step
        // below 1 for the store (llvmpipe's storage write rounds toward zero) and one for the
        // filter. R32Float — the filter's one f16 step (llvmpipe: within 1e-6; the H100:
        // 3.1e-5 at (1,0,0), 0.5620117 for 0.5620422).
        let (texels, tolerance): (Vec<(u32, f32)>, f32) = match format {
            R8Unorm => {
                let t: Vec<[u8; 4]> = read_texture(ctx, lit_density).unwrap();
                let texels = t
                    .iter()
                    .map(|p| (p[0] as u32, p[1] as f32 / 255.0))
                    .collect();
                (texels, 1.0 / 255.0 + 4.9e-4)
            }
            R16Float => {
                let t: Vec<[u16; 4]> = read_texture(ctx, lit_density).unwrap();
                let texels = t
                    .iter()
                    .map(|p| (p[0] as u32, half::f16::from_bits(p[1]).to_f32()))
                    .collect();
                (texels, 2.0 * 4.9e-4)
            }
            _ => {
                let t: Vec<[u32; 2]> = read_texture(ctx, lit_density).unwrap();
                (
                    t.iter().map(|p| (p[0], f32::from_bits(p[1]))).collect(),
                    4.9e-4,
                )
            }
        };
        let mut worst = 0.0f32;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let i = ((z * dims[1] + y) * dims[0] + x) as usize;
                    let stored = match format {
                        R8Unorm => (data[i].clamp(0.0, 1.0) * 255.0).round() as u32,
                        R16Float => half::f16::from_f32(data[i]).to_bits() as u32,
                        _ => data[i].to_bits(),
                    };
                    assert_eq!(texels[i].0, stored, "{format:?} density at {x},{y},{z}");
                    // Per axis the nodes at ⌊v/2⌋ and ⌈v/2⌉, weighted ½ each.
                    let mut want = 0.0;
                    for nx in [x / 2, x.div_ceil(2)] {
                        for ny in [y / 2, y.div_ceil(2)] {
                            for nz in [z / 2, z.div_ceil(2)] {
                                want += 0.125 * node(nx, ny, nz);
                            }
                        }
                    }
                    let err = (texels[i].1 - want).abs();
                    worst = worst.max(err);
                    assert!(
                        err <= tolerance,
                        "{format:?} light at {x},{y},{z}: {} against {want}",
                        texels[i].1
                    );
                }
            }
        }
        println!("{format:?}: densities exact, worst light difference {worst:.2e}");
    }
    // R16Float densities at the edges of the format survive the fold's f32 round trip: zero,
    // negatives, subnormals (the smallest, 2⁻²⁴, and one near the normal range), the largest
    // finite value.
    let edge = [0.0f32, -0.0, -0.75, 5.96e-8, 6.0e-5, 65504.0, -3.1e-6, 0.1];
    let dims = [edge.len() as u32, 1, 1];
    let volume = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &edge,
        dims,
        R16Float,
        Vec3::ONE,
        Vec3::ZERO,
    )
    .unwrap();
    let mut enc = ctx.encoder("lit density edges");
    let (_, light) = rig.bricks_and_light(&mut enc, &volume, &tf, &s);
    ctx.submit_and_wait("lit density edges", enc).unwrap();
    let t: Vec<[u16; 4]> = read_texture(ctx, light.lit_density.as_ref().unwrap()).unwrap();
    let got: Vec<u16> = t.iter().map(|p| p[0]).collect();
    let want: Vec<u16> = edge
        .iter()
        .map(|&v| half::f16::from_f32(v).to_bits())
        .collect();
    assert_eq!(got, want, "R16Float densities {edge:?}");
}
