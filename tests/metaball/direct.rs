//! The direct tracers (no SDF texture: the field traced from its blobs, by the global
//! Lipschitz bound or by segments) against f64 bisection on the analytic field, and grazing rays
//! at the silhouette for both the SDF march and the direct tracer.

use crate::common;

use common::metaball::*;
use common::metaball_field;
use fieldkit::gpu::Context;
use fieldkit::metaball::{Direct, Output, RaymarchSettings, cpu};
use glam::{Mat4, Vec3, Vec4};

/// Tracing the analytic field directly (no grid): both step rules against the exact sphere and
/// f64 bisection, to the bisection's precision rather than a grid's.
#[test]
fn direct_tracing_matches_the_analytic_field() {
    let ctx = Context::shared();
    let s = blob_settings();
    let settings = RaymarchSettings {
        max_steps: 4000,
        ..normals()
    };
    let one = vec![Vec4::new(0.02, -0.03, 0.01, 1.0)];
    let cases = [
        ("one blob", one, Vec3::new(0.3, 0.4, 2.5)),
        ("three blobs", three_blobs(), Vec3::new(0.0, 0.2, 2.8)),
    ];
    for (name, voxels, eye) in cases {
        let bins = blob_bins(&ctx, &voxels, &s);
        let view = camera(eye, Vec3::ZERO, false);
        for method in [Direct::SphereGlobal, Direct::Segment] {
            let shot = shoot(
                &ctx,
                Tracer::Direct(&bins, method),
                &view,
                Mat4::IDENTITY,
                &settings,
                1.0,
            );
            let a = against_analytic(&shot, &view, &voxels, &s, bins.cell as f64);
            // Measured on llvmpipe: 0 silhouette pixels off, depth and hit point ≤ 0.0001 cells
            // (six bisections and a secant on f32 sums), normals ≤ 0.011°; the grid-free tracers
            // are two orders of magnitude closer than the SDF march above.
            a.check(
                &format!("{name}, {method:?}"),
                &Agreement {
                    hits: 200,
                    silhouette_off: 1,
                    max_depth_err: 0.005,
                    max_surface_err: 0.005,
                    max_normal_deg: 0.1,
                },
            );
        }
    }
}

/// The point of segment tracing: on a cluster of blobs the global bound (the worst bin's sum of
/// slopes) forces small steps everywhere, the per-segment bound does not.
#[test]
fn segment_tracing_takes_fewer_steps_than_the_global_bound() {
    let ctx = Context::shared();
    let s = blob_settings();
    let voxels = fieldkit::metaball::packed_grid([3, 3, 3], 1.0).unwrap();
    let bins = blob_bins(&ctx, &voxels, &s);
    let view = camera(Vec3::new(1.2, 1.5, 4.5), Vec3::ZERO, false);
    let settings = RaymarchSettings {
        max_steps: 4000,
        output: Output::Steps,
        ..RaymarchSettings::default()
    };
    let mut means = Vec::new();
    for method in [Direct::SphereGlobal, Direct::Segment] {
        let shot = shoot(
            &ctx,
            Tracer::Direct(&bins, method),
            &view,
            Mat4::IDENTITY,
            &settings,
            1.0,
        );
        means.push(mean_steps(&shot, settings.max_steps));
    }
    println!(
        "mean steps: global bound {:.1}, segment {:.1}",
        means[0], means[1]
    );
    // Measured on llvmpipe: 61.1 against 13.0 (4.7×) on 27 packed blobs.
    assert!(means[1] * 3.5 < means[0], "{means:?}");
}

/// Grazing rays at the silhouette, where sphere tracing converges slowest and a grid surface
/// differs most: one blob filling much of the view. Every pixel where the march and the analytic
/// sphere disagree on hit or miss must lie on the rim (a 4-neighbour of a pixel whose analytic
/// answer differs), and grazing hits (ray within 25° of the tangent plane) must still land near
/// the surface. The direct tracer is held to the exact rim.
#[test]
fn grazing_rays_at_the_silhouette() {
    let ctx = Context::shared();
    let s = blob_settings();
    let voxels = vec![Vec4::new(0.013, -0.021, 0.008, 1.0)];
    let field = metaball_field(&ctx, &voxels, 1.0, &s);
    let bins = blob_bins(&ctx, &voxels, &s);
    let view = camera(Vec3::new(0.2, -0.3, 1.6), Vec3::ZERO, false);
    let cell = field.grid.voxel;
    // The analytic answer per pixel: the hit distance and the cosine between ray and normal.
    let exact: Vec<Option<(f64, f64)>> = (0..W * H)
        .map(|i| {
            let (o, d, len) = ray(&view, i % W, i / W);
            cpu::ray_hit(&voxels, 1.0, &s, o, d, len.min(30.0), 0.01).map(|t| {
                let n = -cpu::gradient_at(&voxels, 1.0, &s, o + d * t).normalize();
                (t, n.dot(-d))
            })
        })
        .collect();
    let on_rim = |i: usize| {
        let (x, y) = ((i as u32 % W) as i32, (i as u32 / W) as i32);
        [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dx, dy)| {
            let (u, v) = (x + dx, y + dy);
            (0..W as i32).contains(&u)
                && (0..H as i32).contains(&v)
                && exact[(v as u32 * W + u as u32) as usize].is_some() != exact[i].is_some()
        })
    };
    let grazing = exact
        .iter()
        .filter(|e| e.is_some_and(|e| e.1 < 0.42))
        .count();
    assert!(grazing > 40, "the view has grazing pixels ({grazing})");
    for (name, tracer, max_off) in [
        ("SDF texture", Tracer::Sdf(&field), usize::MAX),
        ("segment", Tracer::Direct(&bins, Direct::Segment), 0),
    ] {
        let shot = shoot(&ctx, tracer, &view, Mat4::IDENTITY, &normals(), 1.0);
        let (mut off, mut worst) = (0, 0.0f64);
        for (i, (e, got)) in exact.iter().zip(&shot.hits).enumerate() {
            match (e, got) {
                (Some(_), None) | (None, Some(_)) => {
                    off += 1;
                    assert!(on_rim(i), "{name}: pixel {i} disagrees away from the rim");
                }
                (Some((_, cos)), Some((_, dist))) if *cos < 0.42 => {
                    // Off the surface, not along the ray: along a grazing ray a small offset of
                    // the surface is a long one.
                    let (o, d, _) = ray(&view, i as u32 % W, i as u32 / W);
                    let p = o + d * *dist as f64;
                    let r = cpu::density_at(&voxels, 1.0, &s, p) - 0.5;
                    let g = cpu::gradient_at(&voxels, 1.0, &s, p).length();
                    worst = worst.max((r / g).abs() / cell);
                }
                _ => {}
            }
        }
        println!(
            "{name}: {grazing} grazing pixels, {off} rim pixels off, grazing hits ≤ {worst:.4} cells off the surface"
        );
        assert!(off <= max_off, "{name}: {off}");
        // Measured on llvmpipe: SDF texture 17 rim pixels off and 0.188 cells (the grid's
        // trilinear surface, one cell from the analytic one); segment 0 pixels and < 0.0001 cells.
        let bound = if max_off == 0 { 0.005 } else { 0.25 };
        assert!(worst < bound, "{name}: {worst}");
    }
}
