//! The gallery: every technique rendered to PNG (and one GIF) on the default adapter.
//!
//! ```sh
//! cargo run --release --example gallery            # into ./gallery
//! cargo run --release --example gallery -- OUT_DIR
//! ```
//!
//! `FIELDKIT_ADAPTER=<part of a name>` picks the adapter. The voxelization scenes use the
//! Stanford bunny from the npm package `bunny` (`scripts/fetch-bunny.sh`, run on first use);
//! without npm they voxelize a torus and say so.

use std::path::{Path, PathBuf};

use fieldkit::Error;
use fieldkit::bind::{RenderPipeline, RenderTargets};
use fieldkit::distance::{Distance2d, Options2d};
use fieldkit::gpu::{Context, read_texture};
use fieldkit::shaders::distance::visualize;

/// 5×7 glyphs for the letters of "FIELDKIT", one row per byte, high bit left.
const GLYPHS: &[(char, [u8; 7])] = &[
    (
        'F',
        [
            0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000,
        ],
    ),
    (
        'I',
        [
            0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b11111,
        ],
    ),
    (
        'E',
        [
            0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111,
        ],
    ),
    (
        'L',
        [
            0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111,
        ],
    ),
    (
        'D',
        [
            0b11110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b11110,
        ],
    ),
    (
        'K',
        [
            0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001,
        ],
    ),
    (
        'T',
        [
            0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100,
        ],
    ),
];

/// A recognisable mask: a circle, a ring, a rotated box, a triangle and the word FIELDKIT.
pub fn shapes_mask(width: u32, height: u32) -> Vec<u8> {
    let (w, h) = (width as f32, height as f32);
    let mut m = vec![0u8; (width * height) as usize];
    for y in 0..height {
        for x in 0..width {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let circle = ((px - 0.16 * w).powi(2) + (py - 0.3 * h).powi(2)).sqrt() < 0.11 * h;
            let r = ((px - 0.42 * w).powi(2) + (py - 0.3 * h).powi(2)).sqrt();
            let ring = r > 0.07 * h && r < 0.13 * h;
            let (bx, by) = (px - 0.66 * w, py - 0.3 * h);
            let (c, s) = (0.5f32.cos(), 0.5f32.sin());
            let (rx, ry) = (c * bx + s * by, -s * bx + c * by);
            let boxed = rx.abs() < 0.09 * h && ry.abs() < 0.06 * h;
            let (tx, ty) = (px - 0.87 * w, py - 0.3 * h);
            let tri = ty < 0.1 * h && ty > -0.12 * h + 1.8 * tx.abs();
            if circle || ring || boxed || tri {
                m[(y * width + x) as usize] = 255;
            }
        }
    }
    // The word, scaled to fill the lower half.
    let text = "FIELDKIT";
    let scale = ((0.9 * w) / (text.len() as f32 * 6.0))
        .min(0.4 * h / 7.0)
        .floor()
        .max(1.0) as u32;
    let x0 = (width - text.len() as u32 * 6 * scale) / 2;
    let y0 = (0.55 * h) as u32;
    for (i, ch) in text.chars().enumerate() {
        let glyph = GLYPHS
            .iter()
            .find(|g| g.0 == ch)
            .map(|g| g.1)
            .unwrap_or([0; 7]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..5 {
                if bits & (1 << (4 - col)) == 0 {
                    continue;
                }
                for sy in 0..scale {
                    for sx in 0..scale {
                        let x = x0 + (i as u32 * 6 + col) * scale + sx;
                        let y = y0 + row as u32 * scale + sy;
                        if x < width && y < height {
                            m[(y * width + x) as usize] = 255;
                        }
                    }
                }
            }
        }
    }
    m
}

/// Colour-map a distance texture (`R32Float`) with iso-lines into RGBA8 pixels.
pub fn visualize_distance(
    ctx: &Context,
    distance: &wgpu::Texture,
    spacing: f32,
    range: f32,
) -> Result<Vec<u8>, Error> {
    if !(spacing.is_finite() && spacing > 0.0 && range.is_finite() && range > 0.0) {
        return Err(Error::Invalid {
            stage: visualize::STAGE,
            what: format!("spacing {spacing} and range {range} must be finite and positive"),
        });
    }
    let device = &ctx.device;
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let pipeline: RenderPipeline<visualize::fs_main::Entry> = RenderPipeline::new(
        device,
        &RenderTargets {
            color: &[Some(format.into())],
            ..Default::default()
        },
    )?;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("gallery target"),
        size: distance.size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let params = fieldkit::gpu::uniform_buffer(
        device,
        "view params",
        &visualize::ViewParams { spacing, range },
    );
    let dv = distance.create_view(&Default::default());
    let bound = pipeline.bind(
        device,
        &visualize::fs_main::Resources {
            params: (&params).into(),
            distance: (&dv).into(),
        },
    )?;
    let tv = target.create_view(&Default::default());
    let mut enc = ctx.encoder("visualize");
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visualize"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &tv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..3, 0..1);
    }
    ctx.submit_and_wait(visualize::STAGE, enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &target)?;
    Ok(px.concat())
}

/// What the metaball scene draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MetaballView {
    /// The debug cubes, one per voxel.
    Cubes,
    /// The raymarched surface, in one of the raymarcher's outputs.
    Surface(fieldkit::metaball::Output),
    /// The field traced directly from blob bins (no SDF texture).
    Direct(fieldkit::metaball::Direct),
}

/// Whose settings a scene uses: fieldkit's defaults, or the source's (`seed()` presets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preset {
    /// `Default::default()` everywhere.
    Fieldkit,
    /// Each technique's `seed()` preset: the system the source describes.
    Seed,
}

/// The gallery's metaball scene: a packed 5×4×3 voxel set, animated to time `t` (seconds), seen
/// from a fixed camera over a grey floor-coloured background, into RGBA8 pixels.
pub fn metaball_scene(
    ctx: &Context,
    width: u32,
    height: u32,
    t: f32,
    what: MetaballView,
) -> Result<Vec<u8>, Error> {
    metaball_scene_with(ctx, width, height, t, what, Preset::Fieldkit)
}

/// [`metaball_scene`] with `preset`'s settings: the seed preset builds the set from an extent
/// and a block size, animates it with the source's ratios, widens the falloff, builds the
/// full-volume field by plain JFA, marches and shades as the source does and draws its debug
/// cubes as wireframes with depth read only.
pub fn metaball_scene_with(
    ctx: &Context,
    width: u32,
    height: u32,
    t: f32,
    what: MetaballView,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::metaball::{Animation, Metaballs, Settings, animate, extent_grid, packed_grid};
    use fieldkit::metaball::{CubeStyle, Cubes, RaymarchSettings, Raymarcher};
    use fieldkit::view::{Targets, View};
    use glam::{Mat4, Vec3};
    let device = &ctx.device;
    let edge = 1.0;
    let (voxels, settings, march, cube_style) = match preset {
        Preset::Fieldkit => (
            animate(&packed_grid([5, 4, 3], edge)?, edge, t, 0.5, 0.15),
            Settings::default(),
            RaymarchSettings::default(),
            CubeStyle::default(),
        ),
        Preset::Seed => (
            // Extent 5 × 4 × 3 in blocks of 1: the same 60 voxels, built the source's way.
            Animation::seed().apply(&extent_grid(Vec3::new(5.0, 4.0, 3.0), edge)?, edge, t)?,
            Settings::seed(),
            RaymarchSettings::seed(),
            CubeStyle {
                wireframe: true,
                ..CubeStyle::seed()
            },
        ),
    };
    let balls = Metaballs::new(device)?;
    let instances = balls.upload(&ctx.device, &ctx.queue, &voxels)?;
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [width, height], colour_format, depth_format);
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    let proj = glam::camera::rh::proj::directx::perspective(
        0.75,
        width as f32 / height as f32,
        0.1,
        100.0,
    );
    let eye = Vec3::new(4.5, 3.5, 7.5);
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y),
        viewport: [width, height],
        reversed_z: false,
        origin: [0, 0],
    };
    let mut enc = ctx.encoder("gallery metaballs");
    let background = wgpu::Color {
        r: 0.09,
        g: 0.1,
        b: 0.12,
        a: 1.0,
    };
    targets.clear(&mut enc, background, 1.0);
    match what {
        MetaballView::Cubes => {
            let cubes = Cubes::new(device, colour_format, depth_format, cube_style)?;
            cubes.encode(
                device,
                &mut enc,
                cv,
                dv,
                &instances,
                edge,
                Mat4::IDENTITY,
                view.view_proj,
            )?;
        }
        MetaballView::Surface(output) => {
            let Some(grid) = settings.fit_grid(&voxels, edge)? else {
                return Err(Error::Invalid {
                    stage: "gallery",
                    what: "the scene's voxel set is empty".into(),
                });
            };
            let field = balls.encode(device, &mut enc, &instances, &grid, edge, &settings)?;
            let marcher = Raymarcher::new(device, colour_format, depth_format, false)?;
            let rs = RaymarchSettings { output, ..march };
            marcher.encode(device, &mut enc, cv, dv, &field, Mat4::IDENTITY, &view, &rs)?;
        }
        MetaballView::Direct(method) => {
            let Some(grid) = settings.fit_grid(&voxels, edge)? else {
                return Err(Error::Invalid {
                    stage: "gallery",
                    what: "the scene's voxel set is empty".into(),
                });
            };
            let bins = balls.encode_bins(device, &mut enc, &instances, &grid, edge, &settings)?;
            let marcher = Raymarcher::new(device, colour_format, depth_format, false)?;
            let rs = RaymarchSettings {
                max_steps: 4096,
                ..RaymarchSettings::default()
            };
            marcher.encode_direct(
                device,
                &mut enc,
                cv,
                dv,
                &bins,
                method,
                Mat4::IDENTITY,
                &view,
                &rs,
            )?;
        }
    }
    ctx.submit_and_wait("gallery metaballs", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &targets.colour)?;
    Ok(px.concat())
}

/// Render every scene into `out_dir`; returns the files written. `bunny` is the mesh the
/// voxelization scenes use (the npm package `bunny`, which `cargo xtask gallery` fetches);
/// without it they voxelize a torus.
fn run(
    ctx: &Context,
    out_dir: &Path,
    bunny: Option<&fieldkit::voxelize::Mesh>,
    mut progress: impl FnMut(&str),
) -> Result<Vec<PathBuf>, Error> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::Invalid {
        stage: "gallery",
        what: format!("{}: {e}", out_dir.display()),
    })?;
    let mut written = Vec::new();
    let save = |name: &str,
                rgba: &[u8],
                w: u32,
                h: u32,
                written: &mut Vec<PathBuf>|
     -> Result<(), Error> {
        let path = out_dir.join(name);
        image::save_buffer(&path, rgba, w, h, image::ExtendedColorType::Rgba8).map_err(|e| {
            Error::Invalid {
                stage: "gallery",
                what: format!("{}: {e}", path.display()),
            }
        })?;
        written.push(path);
        Ok(())
    };

    progress("distance: 2D signed distance of shapes and text (exact)");
    let (w, h) = (640, 360);
    let mask = shapes_mask(w, h);
    let seeds = fieldkit::distance::upload_mask(&ctx.device, &ctx.queue, &mask, w, h)?;
    let distance = Distance2d::new(&ctx.device)?;
    let mut enc = ctx.encoder("gallery distance");
    let field = distance.encode(
        &ctx.device,
        &mut enc,
        &seeds,
        &Options2d {
            signed: true,
            ..Options2d::default()
        },
    )?;
    ctx.submit_and_wait("gallery distance", enc)?;
    let rgba = visualize_distance(ctx, &field.distance, 8.0, 60.0)?;
    save("distance_2d_signed.png", &rgba, w, h, &mut written)?;
    // The source tool's exports: 16 bits with the scale in the file, floats, and 8 bits to look
    // at.
    let values: Vec<f32> = read_texture(ctx, &field.distance)?;
    for (name, bytes) in [
        (
            "distance_2d_signed_16bit.png",
            fieldkit::distance::export::png16(&values, w, h, 128.0)?,
        ),
        (
            "distance_2d_signed.pfm",
            fieldkit::distance::export::pfm(&values, w, h)?,
        ),
        (
            "distance_2d_signed_8bit.png",
            fieldkit::distance::export::png8(&values, w, h)?,
        ),
    ] {
        let path = out_dir.join(name);
        std::fs::write(&path, bytes).map_err(|e| Error::Invalid {
            stage: "gallery",
            what: format!("{}: {e}", path.display()),
        })?;
        written.push(path);
    }
    let mask_rgba: Vec<u8> = mask.iter().flat_map(|&m| [m, m, m, 255]).collect();
    save("distance_2d_mask.png", &mask_rgba, w, h, &mut written)?;

    use fieldkit::metaball::Output;
    let (w, h) = (640, 400);
    for (name, what, label) in [
        (
            "metaball_cubes.png",
            MetaballView::Cubes,
            "metaball: debug cubes",
        ),
        (
            "metaball_surface.png",
            MetaballView::Surface(Output::Shaded),
            "metaball: raymarched surface",
        ),
        (
            "metaball_steps.png",
            MetaballView::Surface(Output::Steps),
            "metaball: step count per pixel",
        ),
        (
            "metaball_density.png",
            MetaballView::Surface(Output::Density),
            "metaball: density view",
        ),
        (
            "metaball_segment.png",
            MetaballView::Direct(fieldkit::metaball::Direct::Segment),
            "metaball: segment tracing of the field itself",
        ),
    ] {
        progress(label);
        let rgba = metaball_scene(ctx, w, h, 0.0, what)?;
        save(name, &rgba, w, h, &mut written)?;
    }
    // One period of the animation (0.5 Hz: 2 s) as a looping GIF, and every other frame as a
    // lossless PNG still.
    const FRAMES: u32 = 12;
    const PERIOD_S: f32 = 2.0;
    progress("metaball: animation, 12 frames");
    let (aw, ah) = (w / 2, h / 2);
    let mut frames = Vec::new();
    for frame in 0..FRAMES {
        let t = frame as f32 / FRAMES as f32 * PERIOD_S;
        let rgba = metaball_scene(ctx, aw, ah, t, MetaballView::Surface(Output::Shaded))?;
        if frame % 2 == 0 {
            save(
                &format!("metaball_anim_{}.png", frame / 2),
                &rgba,
                aw,
                ah,
                &mut written,
            )?;
        }
        frames.push(rgba);
    }
    let path = out_dir.join("metaball_anim.gif");
    save_gif(&path, &frames, aw, ah, PERIOD_S * 1000.0 / FRAMES as f32)?;
    written.push(path);
    progress("volume: an fBm cloud from outside and from inside");
    for (name, eye, target) in [
        (
            "volume_cloud_outside.png",
            glam::Vec3::new(0.9, 0.45, 1.4),
            glam::Vec3::ZERO,
        ),
        (
            "volume_cloud_inside.png",
            glam::Vec3::new(0.06, 0.04, 0.1),
            glam::Vec3::new(-0.6, 0.15, -1.0),
        ),
    ] {
        let rgba = cloud_scene(ctx, w, h, eye, target)?;
        save(name, &rgba, w, h, &mut written)?;
    }
    progress("ocean: a shoreline with depth fade, and its G-buffer targets");
    for (name, gbuffer) in [("ocean_shore.png", false), ("ocean_gbuffer.png", true)] {
        let rgba = ocean_scene(ctx, w, h, gbuffer)?;
        save(name, &rgba, w, h, &mut written)?;
    }
    progress("seed presets: the sources' settings beside fieldkit's");
    let mut presets = String::from(
        "# Seed presets beside fieldkit's defaults\n\n\
         Each technique's `seed()` preset is the system its source describes; the default is \
         fieldkit's choice. Both rendered by the gallery on the same adapter.\n\n\
         | fieldkit (default) | seed preset | the difference |\n|---|---|---|\n",
    );
    for (default, seed, what, sentence) in [
        (
            "metaball_surface.png",
            "metaball_seed_surface.png",
            MetaballView::Surface(Output::Shaded),
            "The source's blobs reach 1.5× as far (`falloffExtend`), so the 60 voxels melt into \
             one lump; its Hermite reads, 0.3–0.5·d steps, blue rim and darkening pile colour \
             (`Settings::seed`, `RaymarchSettings::seed`, `Animation::seed`).",
        ),
        (
            "metaball_cubes.png",
            "metaball_seed_cubes.png",
            MetaballView::Cubes,
            "The source's debug cubes: both faces, depth `Always` and read only, here as \
             wireframes (line-list edges where the adapter lacks `POLYGON_MODE_LINE`) \
             (`CubeStyle::seed`).",
        ),
    ] {
        let rgba = metaball_scene_with(ctx, w, h, 0.0, what, Preset::Seed)?;
        save(seed, &rgba, w, h, &mut written)?;
        presets.push_str(&format!(
            "| ![{default}]({default}) | ![{seed}]({seed}) | {sentence} |\n"
        ));
    }
    let rgba = ocean_scene_with(ctx, w, h, false, Preset::Seed)?;
    save("ocean_seed_shore.png", &rgba, w, h, &mut written)?;
    let rgba = cloud_scene_with(
        ctx,
        w,
        h,
        glam::Vec3::new(0.9, 0.45, 1.4),
        glam::Vec3::ZERO,
        Preset::Seed,
    )?;
    save("volume_seed_cloud_function.png", &rgba, w, h, &mut written)?;
    presets.push_str(
        "| ![volume_cloud_outside.png](volume_cloud_outside.png) | \
         ![volume_seed_cloud_function.png](volume_seed_cloud_function.png) | The source \
         evaluates its fBm at every sample: the same cloud as a function linked into the march \
         (`CloudMarch`, `Builder::density_march`), finer than the 96³ texture and shadowed by \
         rays through the function; fieldkit's default bakes it into a texture lit through a \
         light volume, several times cheaper per frame. |\n",
    );
    presets.push_str(
        "| ![ocean_shore.png](ocean_shore.png) | ![ocean_seed_shore.png](ocean_seed_shore.png) | \
         The source fades over 30 cm, so the shelf's turquoise shrinks to a line at the \
         island; its water tests the scene's depth without writing it and hangs no skirts \
         (`Look::seed`, `DepthMode::seed`). |\n",
    );
    let path = out_dir.join("presets.md");
    std::fs::write(&path, presets).map_err(|e| Error::Invalid {
        stage: "gallery",
        what: format!("{}: {e}", path.display()),
    })?;
    written.push(path);
    let torus;
    let (mesh, what) = match bunny {
        Some(b) => (b, "the Stanford bunny"),
        None => {
            torus = fieldkit::voxelize::Mesh::torus(glam::DVec3::ZERO, 1.0, 0.4, 96, 48);
            (&torus, "a torus (no bunny given)")
        }
    };
    progress(&format!(
        "voxelize: {what} as cubes coloured by the averaged normal, and its distance field"
    ));
    let rgba = voxelize_scene(ctx, mesh, 96, w, h)?;
    save("voxelize_cubes.png", &rgba, w, h, &mut written)?;
    let rgba = voxelize_scene_with(ctx, mesh, 96, w, h, Preset::Seed)?;
    save("voxelize_seed_point_lit.png", &rgba, w, h, &mut written)?;
    let mut presets = std::fs::read_to_string(out_dir.join("presets.md")).unwrap_or_default();
    presets.push_str(
        "| ![voxelize_cubes.png](voxelize_cubes.png) | \
         ![voxelize_seed_point_lit.png](voxelize_seed_point_lit.png) | The source's demo \
         scene lights the voxels with a point light, (1 − (d/range)²)² per cube corner \
         (`voxelize::Light::Point`); fieldkit's default is a directional light. |\n",
    );
    let path = out_dir.join("presets.md");
    std::fs::write(&path, presets).map_err(|e| Error::Invalid {
        stage: "gallery",
        what: format!("{}: {e}", path.display()),
    })?;
    let (rgba, sw, sh) = voxelize_distance_slice(ctx, mesh, 128, 4)?;
    save("voxelize_distance_slice.png", &rgba, sw, sh, &mut written)?;

    // The sparse voxel octree: 2048³ with attributes where the device's buffers hold the
    // build, else 2048³ shaded by the hit faces, else the largest grid that fits; by footprint
    // and at three fixed levels of detail.
    let mut n = 2048;
    let mut attributes = true;
    let (octree, grid) = loop {
        match octree_of(ctx, mesh, n, attributes) {
            Ok(built) => break built,
            Err(Error::Size { what, got, max, .. }) if n > 128 => {
                let next = if attributes {
                    attributes = false;
                    format!("{n}³ without attributes")
                } else {
                    n /= 2;
                    attributes = true;
                    format!("{n}³")
                };
                progress(&format!(
                    "octree: does not fit this device ({what}: {got} > {max}); trying {next}"
                ));
            }
            Err(e) => return Err(e),
        }
    };
    progress(&format!(
        "octree: {what} at {n}³ through the sparse voxel octree ({} nodes, {:.1} MiB; a dense \
         bitset would be {:.1} MiB), shaded by {}, by footprint and at levels {}, {}, {}",
        octree.capacity,
        octree.capacity as f64 * 8.0 / (1 << 20) as f64,
        grid.voxels() as f64 / 8.0 / (1 << 20) as f64,
        if attributes {
            "the filtered normals"
        } else {
            "the hit faces"
        },
        octree.log_side - 6,
        octree.log_side - 4,
        octree.log_side - 2,
    ));
    use fieldkit::octree::Lod;
    for (name, lod) in [
        ("octree_bunny.png".to_string(), Lod::Footprint(1.0)),
        (
            format!("octree_bunny_level_{}.png", octree.log_side - 6),
            Lod::Level(octree.log_side - 6),
        ),
        (
            format!("octree_bunny_level_{}.png", octree.log_side - 4),
            Lod::Level(octree.log_side - 4),
        ),
        (
            format!("octree_bunny_level_{}.png", octree.log_side - 2),
            Lod::Level(octree.log_side - 2),
        ),
    ] {
        let rgba = octree_scene(ctx, &octree, &grid, lod, w, h)?;
        save(&name, &rgba, w, h, &mut written)?;
    }
    Ok(written)
}

/// The sparse voxel octree of `mesh`'s surface in a grid of `n` along its longest side; with
/// `attributes`, each voxel's averaged colour and normal filtered up the tree.
pub fn octree_of(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    attributes: bool,
) -> Result<(fieldkit::octree::Octree, fieldkit::voxelize::Grid), Error> {
    use fieldkit::octree::OctreeBuilder;
    use fieldkit::voxelize::{Grid, Separation, Voxelizer};
    let grid = Grid::fit(mesh, n)?;
    let (builder, voxelizer) = (
        OctreeBuilder::new(&ctx.device)?,
        Voxelizer::new(&ctx.device)?,
    );
    let (device, queue) = (&ctx.device, &ctx.queue);
    let octree = if attributes {
        ctx.block_on(builder.voxelize_with_attributes(device, queue, &voxelizer, mesh, &grid))?
    } else {
        ctx.block_on(builder.voxelize(
            device,
            queue,
            &voxelizer,
            mesh,
            &grid,
            Separation::Conservative,
        ))?
    };
    Ok((octree, grid))
}

/// A first-hit render of `octree` at `lod` over a dark background, into RGBA8 pixels.
pub fn octree_scene(
    ctx: &Context,
    octree: &fieldkit::octree::Octree,
    grid: &fieldkit::voxelize::Grid,
    lod: fieldkit::octree::Lod,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, Error> {
    use fieldkit::octree::{OctreeCaster, RenderSettings};
    use glam::Vec3;
    let centre =
        (grid.origin + glam::DVec3::from(grid.size.map(f64::from)) * grid.voxel * 0.5).as_vec3();
    let radius = grid.size.into_iter().max().unwrap_or(1) as f32 * grid.voxel as f32 * 0.5;
    let eye = centre + Vec3::new(0.75, 0.45, 1.0).normalize() * radius * 3.4;
    let view = fieldkit::view::View {
        view_proj: glam::camera::rh::proj::directx::perspective(
            0.7,
            w as f32 / h as f32,
            radius * 0.1,
            radius * 10.0,
        ) * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y),
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    let settings = RenderSettings {
        lod,
        ..Default::default()
    };
    let mut enc = ctx.encoder("gallery octree");
    let image =
        OctreeCaster::new().encode_render(&ctx.device, &mut enc, octree, grid, &view, &settings)?;
    ctx.submit_and_wait("gallery octree", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &image.colour)?;
    Ok(px
        .into_iter()
        .flat_map(|p| if p[3] == 0 { [41, 43, 51, 255] } else { p })
        .collect())
}

/// A 96³ fBm cloud under a sky-blue background, lit through the light volume, seen from `eye`.
pub fn cloud_scene(
    ctx: &Context,
    w: u32,
    h: u32,
    eye: glam::Vec3,
    target: glam::Vec3,
) -> Result<Vec<u8>, Error> {
    cloud_scene_with(ctx, w, h, eye, target, Preset::Fieldkit)
}

/// [`cloud_scene`] with `preset`'s cloud: the seed preset evaluates the fBm function at every
/// sample (`CloudMarch`, the function linked into the march at build time), shadowed by shadow
/// rays through it, instead of a baked 96³ texture and its light volume.
pub fn cloud_scene_with(
    ctx: &Context,
    w: u32,
    h: u32,
    eye: glam::Vec3,
    target: glam::Vec3,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::view::View;
    use fieldkit::volume::{
        CloudMarch, FunctionVolume, MarchSettings, Shadow, TransferFunction, Volume,
        VolumeRenderer, fbm_cloud,
    };
    let dims = [96; 3];
    let volume = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &fbm_cloud(dims, 0),
        dims,
        wgpu::TextureFormat::R8Unorm,
        glam::Vec3::splat(1.0 / 96.0),
        glam::Vec3::splat(-0.5),
    )?;
    let renderer = VolumeRenderer::new(&ctx.device, wgpu::TextureFormat::Rgba8Unorm)?;
    let tf = TransferFunction::cloud();
    let settings = MarchSettings {
        step: 1.0 / 96.0,
        ..MarchSettings::default()
    };
    let proj = glam::camera::rh::proj::directx::perspective(0.9, w as f32 / h as f32, 0.01, 50.0);
    let view = View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, glam::Vec3::Y),
        viewport: [w, h],
        reversed_z: false,
        origin: [0, 0],
    };
    let colour = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("gallery cloud"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let cv = colour.create_view(&Default::default());
    let mut enc = ctx.encoder("gallery cloud");
    enc.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("sky"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &cv,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: 0.32,
                    g: 0.52,
                    b: 0.82,
                    a: 1.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    let marched = match preset {
        Preset::Fieldkit => {
            let bricks = renderer.encode_bricks(&ctx.device, &mut enc, &volume)?;
            let light = renderer.encode_light(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                &tf,
                glam::Mat4::IDENTITY,
                &settings,
            )?;
            renderer.encode_march(
                &ctx.device,
                &mut enc,
                &volume,
                &bricks,
                Some(&light),
                &tf,
                glam::Mat4::IDENTITY,
                &view,
                None,
                &settings,
            )?
        }
        Preset::Seed => {
            // The function's box is the unit cube of its texture coordinates; moved to where
            // the texture's box is.
            let cloud = CloudMarch::cloud(&ctx.device)?;
            let box_ = FunctionVolume::unit(96);
            let bricks = cloud.encode_bricks(&ctx.device, &mut enc, &box_)?;
            let settings = MarchSettings {
                shadow: Shadow::Rays { step: 1.0 / 32.0 },
                ..settings
            };
            cloud.encode_march(
                &ctx.device,
                &mut enc,
                &box_,
                &bricks,
                &tf,
                glam::Mat4::from_translation(glam::Vec3::splat(-0.5)),
                &view,
                None,
                &settings,
            )?
        }
    };
    if let Some(m) = marched {
        renderer.encode_composite(&ctx.device, &mut enc, &cv, &m)?;
    }
    ctx.submit_and_wait("gallery cloud", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &colour)?;
    Ok(px.concat())
}

/// The gallery's shoreline: an island of metaballs (raymarched into colour and depth) in a
/// Gerstner sea whose colour fades with the depth of the water over it. `gbuffer`: the four
/// G-buffer targets in a 2 × 2 grid (scene colour, normal; material, base colour) instead of the
/// forward-shaded image; each quarter is `w/2 × h/2`.
pub fn ocean_scene(ctx: &Context, w: u32, h: u32, gbuffer: bool) -> Result<Vec<u8>, Error> {
    ocean_scene_with(ctx, w, h, gbuffer, Preset::Fieldkit)
}

/// [`ocean_scene`] with `preset`'s look: the seed preset fades over 30 cm and tests the scene's
/// depth without writing it (the source's `bUseDepthBlend`).
pub fn ocean_scene_with(
    ctx: &Context,
    w: u32,
    h: u32,
    gbuffer: bool,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::metaball::{Metaballs, Settings, packed_grid};
    use fieldkit::metaball::{RaymarchSettings, Raymarcher};
    use fieldkit::ocean::DepthMode;
    use fieldkit::ocean::{Look, OceanCamera, OceanRenderer, Output, Patch};
    use fieldkit::ocean::{Wave, Waves};
    use fieldkit::view::{Targets, View};
    use glam::{DVec2, DVec3, Mat4, Vec2, Vec3};
    let device = &ctx.device;
    let (tw, th) = if gbuffer { (w / 2, h / 2) } else { (w, h) };
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [tw, th], colour_format, depth_format);
    // The island: a mound of blobs 3 m across on a wide shelf just under the water, so the
    // water over the shelf is shallow and fades.
    let edge = 3.0;
    let voxels: Vec<glam::Vec4> = packed_grid([13, 3, 9], edge)?
        .into_iter()
        .map(|v| v - glam::Vec4::new(0.0, 3.5, 0.0, 0.0))
        .filter(|v| {
            let r = (v.x * v.x + 1.6 * v.z * v.z).sqrt();
            r < 19.0 - 4.0 * (v.y + 3.5)
        })
        .collect();
    let balls = Metaballs::new(device)?;
    let instances = balls.upload(&ctx.device, &ctx.queue, &voxels)?;
    let settings = Settings::default();
    let eye = DVec3::new(-5.0, 8.0, 30.0);
    let proj = glam::camera::rh::proj::directx::perspective(0.8, tw as f32 / th as f32, 0.1, 500.0);
    let camera = OceanCamera::look_at(eye, DVec3::new(0.0, -1.0, 0.0), proj);
    let view = View {
        view_proj: proj * camera.view.as_mat4(),
        viewport: [tw, th],
        reversed_z: false,
        origin: [0, 0],
    };
    let mut enc = ctx.encoder("gallery ocean");
    let sky = wgpu::Color {
        r: 0.55,
        g: 0.7,
        b: 0.85,
        a: 1.0,
    };
    targets.clear(&mut enc, sky, 1.0);
    if let Some(grid) = settings.fit_grid(&voxels, edge)? {
        let field = balls.encode(device, &mut enc, &instances, &grid, edge, &settings)?;
        let marcher = Raymarcher::new(device, colour_format, depth_format, false)?;
        marcher.encode(
            device,
            &mut enc,
            &targets.colour_view,
            &targets.depth_view,
            &field,
            Mat4::IDENTITY,
            &view,
            &RaymarchSettings::default(),
        )?;
    }
    let waves = Waves::new(
        vec![
            Wave {
                direction: Vec2::new(1.0, 0.3),
                amplitude: 0.35,
                wavelength: 21.0,
                speed: 5.7,
            },
            Wave {
                direction: Vec2::new(0.2, 1.0),
                amplitude: 0.18,
                wavelength: 9.5,
                speed: 3.8,
            },
            Wave {
                direction: Vec2::new(-0.8, 0.5),
                amplitude: 0.06,
                wavelength: 4.1,
                speed: 2.5,
            },
        ],
        0.7,
    )?;
    let (base_look, depth_mode) = match preset {
        Preset::Fieldkit => (Look::default(), DepthMode::default()),
        Preset::Seed => (Look::seed(), DepthMode::seed()),
    };
    let look = Look {
        sun_direction: Vec3::new(-0.4, 0.5, -0.75),
        ..base_look
    };
    let patches: Vec<Patch> = (0..100)
        .map(|k| {
            Patch::new(
                DVec2::new(
                    -160.0 + 32.0 * (k % 10) as f64,
                    -160.0 + 32.0 * (k / 10) as f64,
                ),
                32.0,
            )
        })
        .collect();
    let out = if gbuffer {
        let formats = [wgpu::TextureFormat::Rgba8Unorm; 4];
        let renderer = OceanRenderer::with_depth(
            device,
            &ctx.queue,
            Output::GBuffer(formats),
            false,
            depth_mode,
        )?;
        let g: Vec<Targets> = (0..4)
            .map(|_| Targets::new(device, [tw, th], colour_format, depth_format))
            .collect();
        for t in &g {
            t.clear(&mut enc, wgpu::Color::BLACK, 1.0);
        }
        let views: Vec<&wgpu::TextureView> = g.iter().map(|t| &t.colour_view).collect();
        renderer.encode(
            device,
            &mut enc,
            &waves,
            4.0,
            &camera,
            &look,
            &patches,
            &views,
            &targets.depth,
            true,
        )?;
        ctx.submit_and_wait("gallery ocean", enc)?;
        let quarters: Vec<Vec<[u8; 4]>> = g
            .iter()
            .map(|t| read_texture(ctx, &t.colour))
            .collect::<Result<_, _>>()?;
        let mut px = vec![[0u8; 4]; (w * h) as usize];
        for (q, quarter) in quarters.iter().enumerate() {
            let (ox, oy) = ((q as u32 % 2) * tw, (q as u32 / 2) * th);
            for y in 0..th {
                for x in 0..tw {
                    // Alpha shown opaque (the material target keeps the shading model there).
                    let [r, g, b, _] = quarter[(y * tw + x) as usize];
                    px[((oy + y) * w + ox + x) as usize] = [r, g, b, 255];
                }
            }
        }
        px
    } else {
        let renderer = OceanRenderer::with_depth(
            device,
            &ctx.queue,
            Output::Forward(colour_format),
            false,
            depth_mode,
        )?;
        renderer.encode(
            device,
            &mut enc,
            &waves,
            4.0,
            &camera,
            &look,
            &patches,
            &[&targets.colour_view],
            &targets.depth,
            true,
        )?;
        ctx.submit_and_wait("gallery ocean", enc)?;
        read_texture(ctx, &targets.colour)?
    };
    Ok(out.concat())
}

/// A looping GIF of RGBA frames, `frame_ms` each.
fn save_gif(path: &Path, frames: &[Vec<u8>], w: u32, h: u32, frame_ms: f32) -> Result<(), Error> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let err = |e: &dyn std::fmt::Display| Error::Invalid {
        stage: "gallery",
        what: format!("{}: {e}", path.display()),
    };
    let file = std::fs::File::create(path).map_err(|e| err(&e))?;
    // Speed 10 of 1–30: NeuQuant palettes good enough for a preview, in a fraction of speed 1's time.
    let mut gif = GifEncoder::new_with_speed(std::io::BufWriter::new(file), 10);
    gif.set_repeat(Repeat::Infinite).map_err(|e| err(&e))?;
    let delay = image::Delay::from_numer_denom_ms(frame_ms.round() as u32, 1);
    for rgba in frames {
        let img = image::RgbaImage::from_raw(w, h, rgba.clone())
            .ok_or_else(|| err(&"frame size does not match its pixels"))?;
        gif.encode_frame(image::Frame::from_parts(img, 0, 0, delay))
            .map_err(|e| err(&e))?;
    }
    Ok(())
}

/// `mesh` voxelized in a grid of `n` along its longest side, drawn as cubes coloured by each
/// voxel's averaged normal, into RGBA8 pixels.
pub fn voxelize_scene(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    w: u32,
    h: u32,
) -> Result<Vec<u8>, Error> {
    voxelize_scene_with(ctx, mesh, n, w, h, Preset::Fieldkit)
}

/// [`voxelize_scene`] with `preset`'s light: the seed preset is the source's demo scene, a
/// point light near the mesh's top front corner.
pub fn voxelize_scene_with(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    w: u32,
    h: u32,
    preset: Preset,
) -> Result<Vec<u8>, Error> {
    use fieldkit::view::Targets;
    use fieldkit::voxelize::Voxelizer;
    use fieldkit::voxelize::{ColourBy, Light, VoxelView};
    use glam::Vec3;
    let device = &ctx.device;
    let grid = fieldkit::voxelize::Grid::fit(mesh, n)?;
    let voxels =
        ctx.block_on(Voxelizer::new(device)?.attributes(device, &ctx.queue, mesh, &grid))?;
    let colour_format = wgpu::TextureFormat::Rgba8Unorm;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let targets = Targets::new(device, [w, h], colour_format, depth_format);
    let centre =
        (grid.origin + glam::DVec3::from(grid.size.map(f64::from)) * grid.voxel * 0.5).as_vec3();
    let radius = grid.size.into_iter().max().unwrap_or(1) as f32 * grid.voxel as f32 * 0.5;
    let eye = centre + Vec3::new(0.75, 0.45, 1.0).normalize() * radius * 3.2;
    let proj = glam::camera::rh::proj::directx::perspective(
        0.7,
        w as f32 / h as f32,
        radius * 0.1,
        radius * 10.0,
    );
    let view_proj = proj * glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y);
    let view = VoxelView::new(device, colour_format, depth_format)?;
    let mut enc = ctx.encoder("gallery voxelize");
    targets.clear(
        &mut enc,
        wgpu::Color {
            r: 0.16,
            g: 0.17,
            b: 0.2,
            a: 1.0,
        },
        1.0,
    );
    let light = match preset {
        Preset::Fieldkit => Light::Directional(Vec3::new(0.4, 0.8, 0.5)),
        Preset::Seed => Light::Point {
            position: centre + Vec3::new(0.6, 1.2, 1.0) * radius,
            range: radius * 3.5,
        },
    };
    view.encode_lit(
        device,
        &mut enc,
        &targets.colour_view,
        &targets.depth_view,
        &voxels,
        &grid,
        view_proj,
        light,
        ColourBy::Normal,
    )?;
    ctx.submit_and_wait("gallery voxelize", enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &targets.colour)?;
    Ok(px.concat())
}

/// The signed distance field of a closed `mesh` (solid voxels, then the exact 3D transform),
/// in a grid of `n` along its longest side: the slice through the middle of z, +y up, colour
/// mapped with iso-lines every 4 voxels and scaled up `zoom` times. Returns pixels, width and
/// height.
pub fn voxelize_distance_slice(
    ctx: &Context,
    mesh: &fieldkit::voxelize::Mesh,
    n: u32,
    zoom: u32,
) -> Result<(Vec<u8>, u32, u32), Error> {
    use fieldkit::distance::{Distance3d, Options3d};
    use fieldkit::voxelize::Voxelizer;
    let device = &ctx.device;
    let grid = fieldkit::voxelize::Grid::fit(mesh, n)?;
    let v = Voxelizer::new(device)?;
    let mut enc = ctx.encoder("gallery mesh distance");
    let solid = v.encode_solid(&ctx.device, &mut enc, mesh, &grid, false)?;
    let volume = v.encode_volume(device, &mut enc, &solid)?;
    let field = Distance3d::new(device)?.encode(
        device,
        &mut enc,
        &volume,
        &Options3d {
            signed: true,
            ..Options3d::default()
        },
    )?;
    ctx.submit_and_wait("gallery mesh distance", enc)?;
    let d: Vec<f32> = read_texture(ctx, &field.distance)?;
    let [nx, ny, nz] = grid.size;
    let z = nz / 2;
    let slice: Vec<f32> = (0..ny)
        .rev()
        .flat_map(|y| {
            let row = ((z * ny + y) * nx) as usize;
            d[row..row + nx as usize].to_vec()
        })
        .collect();
    use wgpu::util::DeviceExt;
    let texture = device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("gallery distance slice"),
            size: wgpu::Extent3d {
                width: nx,
                height: ny,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&slice),
    );
    let small = visualize_distance(ctx, &texture, 4.0, n as f32 * 0.4)?;
    let (w, h) = (nx * zoom, ny * zoom);
    let mut out = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            let i = (((y / zoom) * nx + x / zoom) * 4) as usize;
            out.extend_from_slice(&small[i..i + 4]);
        }
    }
    Ok((out, w, h))
}

/// The Stanford bunny from the npm package `bunny`: `target/bunny/index.js`, fetched by
/// `scripts/fetch-bunny.sh` when missing. `None` (and a note saying why) when it cannot be had.
fn bunny() -> Option<fieldkit::voxelize::Mesh> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("target/bunny/index.js");
    if !path.exists() {
        eprintln!("fetching the bunny: scripts/fetch-bunny.sh (npm pack bunny@1.0.1)");
        let fetched = std::process::Command::new("bash")
            .arg(root.join("scripts/fetch-bunny.sh"))
            .stdout(std::process::Stdio::null())
            .status();
        if !matches!(fetched, Ok(s) if s.success()) {
            eprintln!(
                "note: could not fetch the bunny (needs npm and the npm registry); the \
                 voxelization scenes use a torus instead"
            );
            return None;
        }
    }
    let text = std::fs::read_to_string(&path).ok()?;
    match fieldkit::voxelize::Mesh::from_positions_cells(&text) {
        Ok(m) => Some(m),
        Err(e) => {
            eprintln!(
                "note: {}: {e}; the voxelization scenes use a torus instead",
                path.display()
            );
            None
        }
    }
}

fn main() -> std::process::ExitCode {
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("gallery"));
    let result = Context::new().and_then(|ctx| {
        eprintln!("adapter: {}", ctx.adapter_name());
        let bunny = bunny();
        run(&ctx, &out, bunny.as_ref(), |step| eprintln!("  {step}"))
    });
    match result {
        Ok(files) => {
            for f in files {
                println!("{}", f.display());
            }
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::AnimationDecoder;

    #[test]
    fn gif_keeps_every_frame_its_delay_and_colours() {
        let (w, h) = (6, 4);
        let colours = [[200u8, 40, 30, 255], [20, 30, 40, 255], [90, 160, 220, 255]];
        let frames: Vec<Vec<u8>> = colours.iter().map(|c| c.repeat(w * h)).collect();
        let path = std::env::temp_dir().join(format!("fieldkit_gif_{}.gif", std::process::id()));
        save_gif(&path, &frames, w as u32, h as u32, 250.0).unwrap();
        let file = std::io::BufReader::new(std::fs::File::open(&path).unwrap());
        let decoded = image::codecs::gif::GifDecoder::new(file)
            .unwrap()
            .into_frames()
            .collect_frames()
            .unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(decoded.len(), colours.len());
        for (frame, colour) in decoded.iter().zip(colours) {
            assert_eq!(frame.delay().numer_denom_ms(), (250, 1));
            assert_eq!(frame.buffer().dimensions(), (w as u32, h as u32));
            // The palette is quantised (NeuQuant); a flat frame comes back within a few levels.
            for px in frame.buffer().pixels() {
                for (got, want) in px.0.iter().zip(colour) {
                    assert!(got.abs_diff(want) <= 4, "{:?} for {colour:?}", px.0);
                }
            }
        }
    }
}
