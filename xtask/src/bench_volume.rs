//! `cargo xtask bench volume`: time per frame against image error for the volume raymarch of an
//! fBm cloud, 256³ and 512³ (64³ and 128³ with `--quick`), at 1920×1080 (480×270 quick), with
//! the camera outside the box and inside it; across step length, brick skipping on and off,
//! jitter on and off, shadowing by shadow rays against the precomputed light volume, and the
//! same cloud as a density function evaluated per sample (`CloudMarch`, issue 24's seed 002:
//! what the source does), shadow rays and unshadowed. `--sizes 256,384` times those volume
//! sizes instead.
//!
//! Time: GPU timestamps around the march and the composite into an 8-bit target, median of the
//! timed runs, each after a 20 ms spin kernel on a hardware adapter so the clocks are up
//! (`heater`); the brick grid and the light volume are built once per volume and timed apart.
//! Error: RMS and largest difference of the premultiplied RGBA against a reference march (a
//! quarter-voxel step, no skipping, no jitter, the same light volume), over every pixel.
//! Writes `volume.csv` and `volume.png`.

use fieldkit::gpu::{Context, read_texture};
use fieldkit::view::View;
use fieldkit::volume::{
    Bricks, CloudMarch, FunctionVolume, LightVolume, MarchSettings, Shadow, TransferFunction,
    Volume, VolumeMarched, VolumeRenderer, fbm_cloud, folds,
};
use glam::{Mat4, Vec3};

use crate::measure::{Stamps, median};

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args.quick, args.reps, args.warmup, &args.sizes, &args.out)
}

struct Row {
    size: u32,
    camera: &'static str,
    config: String,
    step_voxels: f32,
    skip: bool,
    jitter: bool,
    shadow: &'static str,
    frame_ms: f64,
    rms_err: f64,
    max_err: f64,
}

struct Scene<'a> {
    ctx: &'a Context,
    renderer: &'a VolumeRenderer,
    volume: &'a Volume,
    bricks: &'a Bricks,
    light: &'a LightVolume,
    /// The light volume built the other way (folded into the density or not).
    other_light: &'a LightVolume,
    /// The cloud as a function, its lattice (the texture's voxels) and bricks.
    function: (&'a CloudMarch, FunctionVolume, &'a Bricks),
    tf: &'a TransferFunction,
    view: &'a View,
    target: &'a wgpu::TextureView,
    heater: Option<&'a crate::heater::Heater>,
}

impl Scene<'_> {
    fn march(
        &self,
        enc: &mut wgpu::CommandEncoder,
        s: &MarchSettings,
        source: Source,
    ) -> Result<Option<VolumeMarched>, String> {
        if source == Source::Function {
            let (cloud, lattice, bricks) = self.function;
            // The function's box is the unit cube of texture coordinates: moved onto the
            // texture's box.
            return cloud
                .encode_march(
                    &self.ctx.device,
                    enc,
                    &lattice,
                    bricks,
                    self.tf,
                    Mat4::from_translation(Vec3::splat(-0.5)),
                    self.view,
                    None,
                    s,
                )
                .map_err(|e| e.to_string());
        }
        let light = if source == Source::OtherLight {
            self.other_light
        } else {
            self.light
        };
        let light = matches!(s.shadow, Shadow::LightVolume { .. }).then_some(light);
        self.renderer
            .encode_march(
                &self.ctx.device,
                enc,
                self.volume,
                self.bricks,
                light,
                self.tf,
                Mat4::IDENTITY,
                self.view,
                None,
                s,
            )
            .map_err(|e| e.to_string())
    }

    /// The march's premultiplied RGBA.
    fn image(&self, s: &MarchSettings, source: Source) -> Result<Vec<[f32; 4]>, String> {
        let mut enc = self.ctx.encoder("bench volume image");
        let m = self
            .march(&mut enc, s, source)?
            .ok_or("the volume is off screen")?;
        self.ctx
            .submit_and_wait("bench volume image", enc)
            .map_err(|e| e.to_string())?;
        let px: Vec<[u16; 4]> = read_texture(self.ctx, &m.colour).map_err(|e| e.to_string())?;
        // The kept image may be larger than the viewport: its first rows and columns.
        let w = m.colour.width() as usize;
        let [vw, vh] = m.viewport.map(|n| n as usize);
        Ok((0..vh)
            .flat_map(|y| px[y * w..y * w + vw].iter())
            .map(|p| p.map(|h| half::f16::from_bits(h).to_f32()))
            .collect())
    }

    fn frame_ms(
        &self,
        stamps: &Stamps,
        s: &MarchSettings,
        source: Source,
        warmup: usize,
        reps: usize,
    ) -> Result<f64, String> {
        let mut times = Vec::new();
        for i in 0..warmup + reps {
            let ms = stamps.time_after(self.ctx, self.heater, |enc| {
                let m = self
                    .march(enc, s, source)?
                    .ok_or("the volume is off screen")?;
                self.renderer
                    .encode_composite(&self.ctx.device, enc, self.target, &m)
                    .map_err(|e| e.to_string())
            })?;
            if i >= warmup {
                times.push(ms);
            }
        }
        Ok(median(times))
    }
}

/// What a row marches: the texture with its light volume as `encode_light` builds it, with the
/// light volume built the other way, or the cloud as a function.
#[derive(Clone, Copy, PartialEq)]
enum Source {
    Texture,
    OtherLight,
    Function,
}

fn bench(
    quick: bool,
    reps: usize,
    warmup: usize,
    only: &[usize],
    out: &std::path::Path,
) -> Result<(), String> {
    let (ctx, adapter, stamps) = crate::measure::bench_gpu()?;
    // Building a 512³ cloud on the CPU leaves the GPU idle for seconds and its clocks low: the
    // rows after it read up to 3× slow until a heavy row (shadow rays) brought the clocks back.
    // A 20 ms spin before each timed frame keeps them up (`heater`); not on a software adapter.
    let heater = crate::heater::Heater::for_gpu(&ctx, 20.0)?;
    let sizes: Vec<u32> = if !only.is_empty() {
        only.iter().map(|&n| n as u32).collect()
    } else if quick {
        vec![64, 128]
    } else {
        vec![256, 512]
    };
    let (width, height) = if quick { (480, 270) } else { (1920, 1080) };
    let renderer = VolumeRenderer::new(&ctx.device, &ctx.queue, wgpu::TextureFormat::Rgba8Unorm)
        .map_err(|e| e.to_string())?;
    let cloud = CloudMarch::cloud(&ctx.device, &ctx.queue).map_err(|e| e.to_string())?;
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("bench volume target"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let target_view = target.create_view(&Default::default());
    let tf = TransferFunction::cloud();
    let proj =
        glam::camera::rh::proj::directx::perspective(0.9, width as f32 / height as f32, 0.01, 50.0);
    let cameras = [
        ("outside", Vec3::new(0.9, 0.5, 1.5), Vec3::ZERO),
        (
            "inside",
            Vec3::new(0.08, 0.05, 0.12),
            Vec3::new(-0.6, 0.1, -1.0),
        ),
    ];
    println!(
        "| volume | camera | config | frame ms | RMS err | max err |\n|---|---|---|---|---|---|"
    );
    let mut rows = Vec::new();
    for &n in &sizes {
        let dims = [n; 3];
        let voxel = 1.0 / n as f32;
        let volume = Volume::upload(
            &ctx.device,
            &ctx.queue,
            // Seed 0: the cloud the function rows evaluate.
            &fbm_cloud(dims, 0),
            dims,
            wgpu::TextureFormat::R8Unorm,
            Vec3::splat(voxel),
            Vec3::splat(-0.5),
        )
        .map_err(|e| e.to_string())?;
        let base = MarchSettings {
            step: voxel,
            reference_step: 1.0 / 256.0,
            shadow: Shadow::LightVolume { step: 2.0 * voxel },
            ..MarchSettings::default()
        };
        let mut made = None;
        let bricks_ms = stamps.time_after(&ctx, heater.as_ref(), |enc| {
            made = Some(
                renderer
                    .encode_bricks(&ctx.device, enc, &volume)
                    .map_err(|e| e.to_string())?,
            );
            Ok(())
        })?;
        let bricks = made.ok_or("no bricks")?;
        let lattice = FunctionVolume::unit(n);
        let mut made = None;
        let function_bricks_ms = stamps.time_after(&ctx, heater.as_ref(), |enc| {
            made = Some(
                cloud
                    .encode_bricks(&ctx.device, enc, &lattice)
                    .map_err(|e| e.to_string())?,
            );
            Ok(())
        })?;
        let function_bricks = made.ok_or("no function bricks")?;
        // The light volume as `encode_light` builds it (folded into the density up to
        // FOLD_MAX_BYTES), and the other way, for one row.
        let build = |fold: bool| -> Result<(LightVolume, f64), String> {
            let mut lit = None;
            let ms = stamps.time_after(&ctx, heater.as_ref(), |enc| {
                let made = renderer.encode_light_folded(
                    &ctx.device,
                    enc,
                    &volume,
                    &bricks,
                    &tf,
                    Mat4::IDENTITY,
                    &base,
                    fold,
                );
                lit = Some(made.map_err(|e| e.to_string())?);
                Ok(())
            })?;
            Ok((lit.ok_or("no light volume")?, ms))
        };
        let folded = folds(&volume);
        let (light, light_ms) = build(folded)?;
        let (other_light, other_ms) = build(!folded)?;
        let (how, other_how) = if folded {
            ("light folded", "light not folded")
        } else {
            ("light not folded", "light folded")
        };
        println!(
            "| {n}³ | — | brick grid build {bricks_ms:.3} ms, light volume build {light_ms:.3} ms ({how}), {other_ms:.3} ms ({other_how}); function bricks {function_bricks_ms:.3} ms | | | |"
        );
        for (camera, eye, target) in cameras {
            let view = View {
                view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
                viewport: [width, height],
                reversed_z: false,
                origin: [0, 0],
            };
            let scene = Scene {
                ctx: &ctx,
                renderer: &renderer,
                volume: &volume,
                bricks: &bricks,
                light: &light,
                other_light: &other_light,
                function: (&cloud, lattice, &function_bricks),
                tf: &tf,
                view: &view,
                target: &target_view,
                heater: heater.as_ref(),
            };
            let reference = scene.image(
                &MarchSettings {
                    step: 0.25 * voxel,
                    skip: false,
                    jitter: false,
                    ..base
                },
                Source::Texture,
            )?;
            // (row, settings, shadowing, what is marched)
            let mut configs: Vec<(String, MarchSettings, &'static str, Source)> = Vec::new();
            for k in [0.5f32, 1.0, 2.0] {
                configs.push((
                    format!("step {k} voxel"),
                    MarchSettings {
                        step: k * voxel,
                        ..base
                    },
                    how,
                    Source::Texture,
                ));
            }
            configs.push((
                "step 1, no skipping".into(),
                MarchSettings {
                    skip: false,
                    ..base
                },
                how,
                Source::Texture,
            ));
            configs.push((
                "step 1, no jitter".into(),
                MarchSettings {
                    jitter: false,
                    ..base
                },
                how,
                Source::Texture,
            ));
            configs.push((
                "step 1, shadow rays".into(),
                MarchSettings {
                    shadow: Shadow::Rays { step: 2.0 * voxel },
                    ..base
                },
                "shadow rays",
                Source::Texture,
            ));
            configs.push((
                "step 1, unshadowed".into(),
                MarchSettings {
                    shadow: Shadow::None,
                    ..base
                },
                "none",
                Source::Texture,
            ));
            configs.push((
                format!("step 1, {other_how}"),
                base,
                other_how,
                Source::OtherLight,
            ));
            configs.push((
                "function, step 1, shadow rays".into(),
                MarchSettings {
                    shadow: Shadow::Rays { step: 2.0 * voxel },
                    ..base
                },
                "function, shadow rays",
                Source::Function,
            ));
            configs.push((
                "function, step 1, unshadowed".into(),
                MarchSettings {
                    shadow: Shadow::None,
                    ..base
                },
                "function, none",
                Source::Function,
            ));
            // Density samples per ray (the march's sample-count output), as the CPU model
            // counted them: plain, with brick skipping, with early termination, with both.
            let mut counts = Vec::new();
            for (skip, min_t) in [(false, 0.0), (true, 0.0), (false, 1e-3), (true, 1e-3)] {
                let img = scene.image(
                    &MarchSettings {
                        skip,
                        min_transmittance: min_t,
                        jitter: false,
                        count_samples: true,
                        ..base
                    },
                    Source::Texture,
                )?;
                counts.push(img.iter().map(|p| p[0] as f64).sum::<f64>() / img.len() as f64);
            }
            println!(
                "| {n}³ | {camera} | samples per pixel: plain {:.1}; fewer by skipping {:.2}×, by early termination {:.2}×, by both {:.2}× | | | |",
                counts[0],
                counts[0] / counts[1],
                counts[0] / counts[2],
                counts[0] / counts[3]
            );
            for (name, s, shadow, source) in configs {
                let frame_ms = scene.frame_ms(&stamps, &s, source, warmup, reps)?;
                let img = scene.image(&s, source)?;
                let (mut sum, mut max) = (0.0f64, 0.0f64);
                for (p, q) in img.iter().zip(&reference) {
                    for c in 0..4 {
                        let d = (p[c] - q[c]).abs() as f64;
                        sum += d * d;
                        max = max.max(d);
                    }
                }
                let rms = (sum / (4 * img.len()) as f64).sqrt();
                println!("| {n}³ | {camera} | {name} | {frame_ms:.3} | {rms:.5} | {max:.4} |");
                rows.push(Row {
                    size: n,
                    camera,
                    config: name,
                    step_voxels: s.step / voxel,
                    skip: s.skip,
                    jitter: s.jitter,
                    shadow,
                    frame_ms,
                    rms_err: rms,
                    max_err: max,
                });
            }
        }
    }
    let csv = crate::measure::write_table(
        out,
        "volume.csv",
        "adapter,volume,resolution,camera,config,step_voxels,skip,jitter,shadow,frame_ms,rms_err,max_err",
        rows.iter().map(|r| {
            format!(
                "\"{adapter}\",{},{width}x{height},{},{},{},{},{},{},{:.4},{:.6},{:.5}",
                r.size,
                r.camera,
                r.config,
                r.step_voxels,
                r.skip,
                r.jitter,
                r.shadow,
                r.frame_ms,
                r.rms_err,
                r.max_err
            )
        }),
    )?;
    chart(&out.join("volume.png"), &adapter, &rows)?;
    println!("wrote {} and volume.png", csv.display());
    Ok(())
}

fn chart(path: &std::path::Path, adapter: &str, rows: &[Row]) -> Result<(), String> {
    let points: Vec<crate::chart::Point> = rows
        .iter()
        .map(|r| crate::chart::Point {
            group: format!("{}³, camera {}", r.size, r.camera),
            ms: r.frame_ms,
            err: r.rms_err,
            label: r.config.clone(),
        })
        .collect();
    let axes = crate::chart::Axes {
        caption: format!("volume raymarch: frame time vs RMS RGBA error, {adapter}"),
        x: "frame time, ms (march + composite, median, log)",
        y: "RMS error against a quarter-voxel reference (log)",
        floor: 1e-5,
    };
    crate::chart::time_vs_error(path, &axes, &points)
}
