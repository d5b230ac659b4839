//! `cargo xtask bench ocean`: triangles and time per frame against the largest screen-space
//! height error, the quadtree LOD at several error targets against the write-up's layout
//! (patches of 256 vertices per row, split near the camera), 1920×1080 (480×270 with `--quick`).
//!
//! Time: GPU timestamps around the depth copy and the forward-shaded draw into an 8-bit target
//! with depth fade on, median of the timed runs. Error: the projected height error the LOD
//! computes (`fieldkit::ocean::lod`), in pixels. Writes `ocean.csv` and `ocean.png`.

use std::process::ExitCode;

use fieldkit::gpu::Context;
use fieldkit::ocean::Waves;
use fieldkit::ocean::lod::{LodSettings, select, writeup_patches};
use fieldkit::ocean::render::{Look, OceanCamera, OceanRenderer, Output, PATCH_QUADS, Patch};
use glam::{DVec2, DVec3};

use crate::bench_metaball::{Stamps, median};

pub fn run(args: &crate::bench::Args) -> ExitCode {
    match bench(args.quick, args.reps, args.warmup, &args.out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench ocean: {e}");
            ExitCode::FAILURE
        }
    }
}

struct Row {
    layout: String,
    patches: usize,
    triangles: u64,
    max_error_px: f64,
    frame_ms: f64,
}

fn bench(quick: bool, reps: usize, warmup: usize, out: &std::path::Path) -> Result<(), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    let adapter = ctx.adapter_name();
    println!("adapter: {adapter}");
    let stamps = Stamps::new(&ctx)?;
    let (width, height) = if quick { (480, 270) } else { (1920, 1080) };
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let renderer = OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(format), false)
        .map_err(|e| e.to_string())?;
    let make = |format, usage| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("bench ocean target"),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let colour = make(format, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let depth = make(
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let colour_view = colour.create_view(&Default::default());
    let waves = Waves::open_sea();
    let look = Look::default();
    let eye = DVec3::new(130.0, 12.0, -260.0);
    let camera = OceanCamera::look_at(
        eye,
        eye + DVec3::new(0.6, -0.14, -0.79).normalize(),
        glam::camera::rh::proj::directx::perspective(
            60f32.to_radians(),
            width as f32 / height as f32,
            0.5,
            5000.0,
        ),
    );
    let settings = LodSettings::default();
    let one_wave =
        Waves::new(waves.waves()[..1].to_vec(), waves.steepness()).map_err(|e| e.to_string())?;
    let time = |waves: &Waves, patches: &[Patch], look: &Look, fade: bool| -> Result<f64, String> {
        let mut times = Vec::new();
        for i in 0..warmup.max(3) + reps {
            let ms = stamps.time(&ctx, |enc| {
                renderer
                    .encode(
                        &ctx.device,
                        enc,
                        waves,
                        10.0,
                        &camera,
                        look,
                        patches,
                        &[&colour_view],
                        &depth,
                        fade,
                    )
                    .map_err(|e| e.to_string())
            })?;
            if i >= warmup.max(3) {
                times.push(ms);
            }
        }
        Ok(median(times))
    };
    println!(
        "| layout | patches | triangles | largest error (px) | frame ms |\n|---|---|---|---|---|"
    );
    let mut rows = Vec::new();
    let mut push = |layout: String,
                    waves: &Waves,
                    patches: &[Patch],
                    triangles: u64,
                    err: f64,
                    look: &Look,
                    fade: bool|
     -> Result<(), String> {
        let ms = time(waves, patches, look, fade)?;
        println!(
            "| {layout} | {} | {triangles} | {err:.3} | {ms:.3} |",
            patches.len()
        );
        rows.push(Row {
            layout,
            patches: patches.len(),
            triangles,
            max_error_px: err,
            frame_ms: ms,
        });
        Ok(())
    };
    for target in [0.25, 0.5, 1.0, 2.0, 4.0, 8.0] {
        let sel = select(
            &waves,
            &look,
            &camera,
            height,
            &LodSettings {
                max_error_px: target,
                ..settings
            },
        )
        .map_err(|e| e.to_string())?;
        let name = if target == settings.max_error_px {
            format!("quadtree, {target} px (default)")
        } else {
            format!("quadtree, {target} px")
        };
        push(
            name,
            &waves,
            &sel.patches,
            sel.triangles,
            sel.max_error_px,
            &look,
            true,
        )?;
        if target == settings.max_error_px {
            // What each part of the frame costs, at the default error.
            let bare = Look {
                height_layers: vec![],
                normal_layers: vec![],
                ..look.clone()
            };
            let no_height = Look {
                height_layers: vec![],
                ..look.clone()
            };
            let no_normal = Look {
                normal_layers: vec![],
                ..look.clone()
            };
            for (what, w, l, fade) in [
                ("no depth fade", &waves, &look, false),
                ("no height layers", &waves, &no_height, true),
                ("no normal layers", &waves, &no_normal, true),
                ("no layers, no fade", &waves, &bare, false),
                (
                    "no layers, no fade, one wave of four",
                    &one_wave,
                    &bare,
                    false,
                ),
            ] {
                push(
                    format!("quadtree, {target} px, {what}"),
                    w,
                    &sel.patches,
                    sel.triangles,
                    sel.max_error_px,
                    l,
                    fade,
                )?;
            }
        }
    }
    // The write-up's patches of 256 vertices per row, drawn as 4 × 4 of ours (256 quads a side).
    let writeup = writeup_patches(&waves, &look, &camera, height, &settings, 4 * PATCH_QUADS);
    let split: Vec<Patch> = writeup
        .patches
        .iter()
        .flat_map(|p| {
            let q = p.size / 4.0;
            (0..16).map(move |k| {
                Patch::new(p.corner + DVec2::new((k % 4) as f64, (k / 4) as f64) * q, q)
            })
        })
        .collect();
    let per = fieldkit::ocean::lod::patch_triangles(PATCH_QUADS);
    push(
        "write-up: 256 per row, split near the camera".into(),
        &waves,
        &split,
        split.len() as u64 * per,
        writeup.max_error_px,
        &look,
        true,
    )?;
    let csv = crate::bench::write_table(
        out,
        "ocean.csv",
        "adapter,resolution,layout,patches,triangles,max_error_px,frame_ms",
        rows.iter().map(|r| {
            format!(
                "\"{adapter}\",{width}x{height},\"{}\",{},{},{:.4},{:.4}",
                r.layout, r.patches, r.triangles, r.max_error_px, r.frame_ms
            )
        }),
    )?;
    // The rows with parts left out share the default's error: in the CSV, not the chart.
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .filter(|r| !r.layout.contains(", no "))
        .map(|r| crate::chart::Point {
            group: if r.layout.starts_with("quadtree") {
                "quadtree".into()
            } else {
                "write-up".into()
            },
            ms: r.frame_ms,
            err: r.max_error_px,
            label: format!("{} ({:.2} M triangles)", r.layout, r.triangles as f64 / 1e6),
        })
        .collect();
    let axes = crate::chart::Axes {
        caption: format!(
            "ocean at {width}×{height}: frame time vs largest height error, {adapter}"
        ),
        x: "frame time, ms (depth copy + draw, median, log)",
        y: "largest projected height error, pixels (log)",
        floor: 1e-2,
    };
    crate::chart::time_vs_error(&out.join("ocean.png"), &axes, &points)?;
    println!("wrote {} and ocean.png", csv.display());
    Ok(())
}
