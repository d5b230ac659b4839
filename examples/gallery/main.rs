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

mod cloud;
mod distance;
mod mesh_sdf;
mod metaball;
mod ocean;
mod octree;
mod voxelize;

pub use cloud::*;
pub use distance::*;
pub use mesh_sdf::*;
pub use metaball::*;
pub use ocean::*;
pub use octree::*;
pub use voxelize::*;

use std::path::{Path, PathBuf};

use fieldkit::Error;
use fieldkit::bind::{RenderPipeline, RenderTargets};
use fieldkit::distance::{Distance2d, Settings2d};
use fieldkit::gpu::{Context, read_texture};
use fieldkit::shaders::distance::visualize;

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
    let field = distance.encode(&ctx.device, &mut enc, &seeds, &Settings2d::signed())?;
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
    progress(&format!(
        "mesh_sdf: {what}'s signed distance field, 128 voxels a side, drawn by the SDF march"
    ));
    let rgba = mesh_sdf_scene(ctx, mesh, 128, w, h)?;
    save("mesh_sdf_surface.png", &rgba, w, h, &mut written)?;

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
