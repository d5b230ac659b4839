//! `cargo xtask bench ocean`: triangles and time per frame against the largest screen-space
//! height error, the quadtree LOD at several error targets against the write-up's layout
//! (patches of 256 vertices per row, split near the camera), 1920×1080 (480×270 with `--quick`).
//!
//! Time: GPU timestamps around the targets' clear, the depth copy and the forward-shaded draw
//! into an 8-bit target with depth fade on, median of the timed runs; with the patches chosen
//! on the GPU, its selection pass too. The CPU's time to choose and record a frame both ways
//! goes to `ocean_cpu.csv`. Error: the projected height error the LOD
//! computes (`fieldkit::ocean::lod`), in pixels. Writes `ocean.csv` and `ocean.png`.

use fieldkit::gpu::Context;
use fieldkit::ocean::Waves;
use fieldkit::ocean::{LodSettings, select, writeup_patches};
use fieldkit::ocean::{Look, OceanCamera, OceanRenderer, Output, PATCH_QUADS, Patch};
use glam::{DVec2, DVec3};

use crate::measure::{Stamps, median};

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args.quick, args.reps, args.warmup, &args.out)
}

struct Row {
    layout: String,
    patches: usize,
    triangles: u64,
    max_error_px: f64,
    frame_ms: f64,
}

fn bench(quick: bool, reps: usize, warmup: usize, out: &std::path::Path) -> Result<(), String> {
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    let (width, height) = if quick { (480, 270) } else { (1920, 1080) };
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let renderer = OceanRenderer::new(&ctx.device, &ctx.queue, Output::Forward(format), false)
        .map_err(|e| e.to_string())?;
    let make = |format, usage| {
        fieldkit::gpu::texture(
            &ctx.device,
            "bench ocean target",
            [width, height, 1],
            wgpu::TextureDimension::D2,
            format,
            usage,
        )
    };
    let colour = make(format, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let depth = make(
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
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
    // Each timed frame starts from cleared targets, as an app's frame does: drawn over its own
    // depth, every fragment of the surface would fail the depth test and skip shading.
    let depth_view = depth.create_view(&Default::default());
    let clear = |enc: &mut wgpu::CommandEncoder| {
        cleared(enc, "bench ocean clear", &colour_view, &depth_view);
    };
    let time_draw = |draw: &dyn Fn(&mut wgpu::CommandEncoder) -> Result<(), fieldkit::Error>| {
        let mut times = Vec::new();
        let start = std::time::Instant::now();
        let mut i = 0;
        while times.len() < reps {
            i += 1;
            let ms = stamps.time(&ctx, |enc| {
                clear(enc);
                draw(enc).map_err(|e| e.to_string())
            })?;
            if i > warmup.max(3) && start.elapsed() >= crate::measure::WARMUP_TIME {
                times.push(ms);
            }
        }
        Ok::<f64, String>(median(times))
    };
    let time = |waves: &Waves, patches: &[Patch], look: &Look, fade: bool| -> Result<f64, String> {
        time_draw(&|enc| {
            let targets = [&colour_view];
            renderer.encode(
                &ctx.device,
                enc,
                waves,
                10.0,
                &camera,
                look,
                patches,
                &targets,
                &depth,
                fade,
            )
        })
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
            // Other patch sizes at the default error: smaller patches follow the error more
            // closely (fewer triangles) but cost more CPU to select and more instances.
            for quads in [8, 16, 32] {
                if quads == settings.patch_quads {
                    continue;
                }
                let t = std::time::Instant::now();
                let other = select(
                    &waves,
                    &look,
                    &camera,
                    height,
                    &LodSettings {
                        patch_quads: quads,
                        ..settings
                    },
                )
                .map_err(|e| e.to_string())?;
                println!(
                    "  select with {quads} quads a patch: {:?} on the CPU",
                    t.elapsed()
                );
                push(
                    format!("quadtree, {target} px, {quads} quads a patch"),
                    &waves,
                    &other.patches,
                    other.triangles,
                    other.max_error_px,
                    &look,
                    true,
                )?;
            }
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
    // The fade's fixed part: the depth copy with nothing drawn.
    push(
        "depth copy alone (no patches)".into(),
        &waves,
        &[],
        0,
        0.0,
        &look,
        true,
    )?;
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
    let per = fieldkit::ocean::patch_triangles(PATCH_QUADS);
    push(
        "write-up: 256 per row, split near the camera".into(),
        &waves,
        &split,
        split.len() as u64 * per,
        writeup.max_error_px,
        &look,
        true,
    )?;
    // The default error with the patches chosen on the GPU (the same patches: `tests/ocean/gpu_lod.rs`),
    // its selection pass included.
    let on_gpu_with = |enc: &mut wgpu::CommandEncoder, lod: &LodSettings| {
        let targets = [&colour_view];
        let d = &ctx.device;
        renderer.encode_lod(
            d, enc, &waves, 10.0, &camera, &look, lod, &targets, &depth, true,
        )
    };
    let on_gpu = |enc: &mut wgpu::CommandEncoder| on_gpu_with(enc, &settings);
    if renderer.lod_on_gpu() {
        let ms = time_draw(&on_gpu)?;
        let drawn = renderer.last_lod().ok_or("encode_lod left no draws")?;
        let read =
            |b: &wgpu::Buffer| fieldkit::gpu::read_buffer(&ctx, b).map_err(|e| e.to_string());
        let patches = drawn.patches(&read(&drawn.draws)?, &read(&drawn.instances)?);
        let cpu = select(&waves, &look, &camera, height, &settings).map_err(|e| e.to_string())?;
        let triangles = patches.iter().map(Patch::triangles).sum();
        let layout = format!(
            "quadtree on the GPU, {} px (default)",
            settings.max_error_px
        );
        println!(
            "| {layout} | {} | {triangles} | {:.3} | {ms:.3} |",
            patches.len(),
            cpu.max_error_px
        );
        rows.push(Row {
            layout,
            patches: patches.len(),
            triangles,
            max_error_px: cpu.max_error_px,
            frame_ms: ms,
        });
    } else {
        println!(
            "  {adapter} lacks INDIRECT_FIRST_INSTANCE: no row for the patches chosen on the GPU"
        );
    }
    // The CPU's share of a frame: choosing and recording, submitted (median of at least 60).
    let draw_list = |enc: &mut wgpu::CommandEncoder, patches: &[Patch]| {
        let targets = [&colour_view];
        let d = &ctx.device;
        renderer
            .encode(
                d, enc, &waves, 10.0, &camera, &look, patches, &targets, &depth, true,
            )
            .map_err(|e| e.to_string())
    };
    let on_cpu_with = |enc: &mut wgpu::CommandEncoder, lod: &LodSettings| {
        let sel = select(&waves, &look, &camera, height, lod).map_err(|e| e.to_string())?;
        draw_list(enc, &sel.patches)
    };
    let on_cpu = |enc: &mut wgpu::CommandEncoder| on_cpu_with(enc, &settings);
    // Smaller patches: four times the nodes to walk.
    let eight = LodSettings {
        patch_quads: 8,
        ..settings
    };
    let on_cpu_8 = |enc: &mut wgpu::CommandEncoder| on_cpu_with(enc, &eight);
    let on_gpu_8 =
        |enc: &mut wgpu::CommandEncoder| on_gpu_with(enc, &eight).map_err(|e| e.to_string());
    // The parts: an empty frame (an encoder submitted), the frame without patches (uniforms,
    // the depth copy), the CPU's choice alone, the draw alone (select's list made beforehand,
    // and a single patch).
    let nothing = |_: &mut wgpu::CommandEncoder| Ok(());
    let no_patches = |enc: &mut wgpu::CommandEncoder| draw_list(enc, &[]);
    let choice = |_: &mut wgpu::CommandEncoder| {
        select(&waves, &look, &camera, height, &settings)
            .map(drop)
            .map_err(|e| e.to_string())
    };
    let on_gpu_frame = |enc: &mut wgpu::CommandEncoder| on_gpu(enc).map_err(|e| e.to_string());
    let listed = select(&waves, &look, &camera, height, &settings).map_err(|e| e.to_string())?;
    let made_before = |enc: &mut wgpu::CommandEncoder| draw_list(enc, &listed.patches);
    let one_patch = |enc: &mut wgpu::CommandEncoder| draw_list(enc, &listed.patches[..1]);
    type Frame<'a> = &'a dyn Fn(&mut wgpu::CommandEncoder) -> Result<(), String>;
    let mut cpu_rows = Vec::new();
    for (what, record) in [
        ("an empty encoder, submitted", &nothing as Frame),
        ("encode with no patches (uniforms, depth copy)", &no_patches),
        ("select alone", &choice),
        ("encode, select's list made beforehand", &made_before),
        ("encode, one patch", &one_patch),
        ("select on the CPU + encode", &on_cpu),
        ("encode_lod (chosen on the GPU)", &on_gpu_frame),
        ("select on the CPU + encode, 8 quads a patch", &on_cpu_8),
        ("encode_lod, 8 quads a patch", &on_gpu_8),
    ] {
        let (med, lo, hi) = crate::measure::host_times(&ctx, reps.max(60), record)?;
        println!("  CPU a frame, {what}: {med:.4} ms (min {lo:.4}, max {hi:.4})");
        cpu_rows.push(format!(
            "\"{adapter}\",{width}x{height},\"{what}\",{med:.4},{lo:.4},{hi:.4}"
        ));
    }
    crate::measure::write_table(
        out,
        "ocean_cpu.csv",
        "adapter,resolution,frame,cpu_ms,min_ms,max_ms",
        cpu_rows,
    )?;
    let floor = floor(
        &ctx,
        &stamps,
        width,
        height,
        format,
        &colour_view,
        &depth,
        warmup,
        reps,
    )?;
    crate::measure::write_table(
        out,
        "ocean_floor.csv",
        "adapter,resolution,triangles,px_per_triangle,frame_ms,ns_per_triangle",
        floor.iter().map(|(t, ms)| {
            format!(
                "\"{adapter}\",{width}x{height},{t},{:.2},{ms:.4},{:.3}",
                (width * height) as f64 / *t as f64,
                ms * 1e6 / *t as f64
            )
        }),
    )?;
    let csv = crate::measure::write_table(
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
    // The rows with parts left out or other patch sizes share the default's error: in the CSV,
    // not the chart.
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .filter(|r| !r.layout.contains(", no ") && !r.layout.contains("quads a patch"))
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

/// What the rasterizer alone costs: a screen-filling grid of `2·n²` triangles drawn with a
/// pass-through vertex stage and a constant colour (no buffers, no textures), depth tested like
/// the ocean. The ocean's frame cannot be cheaper than this for as many triangles of that size.
/// A probe of the adapter, not a stage of the crate, so its shader lives here.
#[allow(clippy::too_many_arguments)]
fn floor(
    ctx: &Context,
    stamps: &Stamps,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    colour: &wgpu::TextureView,
    depth: &wgpu::Texture,
    warmup: usize,
    reps: usize,
) -> Result<Vec<(u64, f64)>, String> {
    const PROBE: &str = "
struct P { n: u32 }
@group(0) @binding(0) var<uniform> p: P;
@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // Quad q = i / 6, corner from the two-triangle pattern.
    let q = i / 6u;
    let c = array<vec2<u32>, 6>(vec2(0u, 0u), vec2(1u, 0u), vec2(0u, 1u), vec2(1u, 0u), vec2(1u, 1u), vec2(0u, 1u))[i % 6u];
    let xy = vec2<f32>(vec2(q % p.n, q / p.n) + c) / f32(p.n);
    return vec4<f32>(xy * 2.0 - 1.0, 0.5, 1.0);
}
@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(0.1, 0.3, 0.5, 1.0); }
";
    let device = &ctx.device;
    let pipeline = fieldkit::harness::wgsl_pipeline(
        device,
        "ocean bench floor probe",
        PROBE,
        format,
        Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        &[],
        Default::default(),
    );
    let depth_view = depth.create_view(&Default::default());
    let mut rows = Vec::new();
    println!("| probe: triangles | px each | frame ms | ns per triangle |\n|---|---|---|---|");
    for n in [128u32, 256, 384, 512, 724] {
        use wgpu::util::DeviceExt;
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("floor probe params"),
            contents: bytemuck::bytes_of(&n),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            }],
        });
        let mut times = Vec::new();
        let start = std::time::Instant::now();
        let mut i = 0;
        while times.len() < reps {
            i += 1;
            let ms = stamps.time(ctx, |enc| {
                let mut pass = cleared(enc, "floor probe", colour, &depth_view);
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &bind, &[]);
                pass.draw(0..n * n * 6, 0..1);
                Ok(())
            })?;
            if i > warmup.max(3) && start.elapsed() >= crate::measure::WARMUP_TIME {
                times.push(ms);
            }
        }
        let ms = median(times);
        let triangles = 2 * (n as u64) * (n as u64);
        println!(
            "| {triangles} | {:.2} | {ms:.4} | {:.3} |",
            (width * height) as f64 / triangles as f64,
            ms * 1e6 / triangles as f64
        );
        rows.push((triangles, ms));
    }
    Ok(rows)
}

/// A render pass into `colour` and `depth`, both cleared (black, far).
fn cleared<'a>(
    enc: &'a mut wgpu::CommandEncoder,
    label: &str,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
) -> wgpu::RenderPass<'a> {
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: colour,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(fieldkit::gpu::depth_cleared(depth, 1.0)),
        ..Default::default()
    })
}
