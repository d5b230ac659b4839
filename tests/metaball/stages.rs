//! Per-stage snapshots of the metaball pipeline (splat, seeds, JFA, SDF, raymarch image,
//! debug-cube image), each summarised for insta. The accuracy checks are in `metaball_field` and
//! `metaball_render`; these catch any change in what a stage produces.

use crate::common;

use common::metaball::run_stage;

// The gallery example's scenes and test pictures (the example is the one place they live).

use crate::gallery::{MetaballView, metaball_scene};
use common::*;
use fieldkit::distance::Method;
use fieldkit::distance::Variant;
use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::harness::Summary;
use fieldkit::metaball::Output;
use fieldkit::metaball::{Settings, SurfaceSeeds};
use glam::Vec4;

fn voxels() -> Vec<Vec4> {
    vec![
        Vec4::new(0.0, 0.0, 0.0, 1.0),
        Vec4::new(0.8, 0.3, 0.1, 0.8),
        Vec4::new(-0.4, 0.9, -0.3, 1.2),
    ]
}

fn settings() -> Settings {
    Settings {
        cells_per_edge: 5.0,
        ..Settings::default()
    }
}

fn words(ctx: &Context, b: &wgpu::Buffer) -> Vec<u32> {
    bytemuck::cast_slice(&read_buffer(ctx, b).unwrap()).to_vec()
}

fn seeds(ctx: &Context) -> (SurfaceSeeds, [usize; 3]) {
    let s = settings();
    let v = voxels();
    let grid = s.fit_grid(&v, 1.0).unwrap().unwrap();
    let out = run_stage(ctx, &v, |balls, enc, inst| {
        balls.encode_seeds(&ctx.device, enc, inst, &grid, 1.0, &s)
    });
    let [w, h, d] = grid.size.map(|x| x as usize);
    (out, [d, h, w])
}

#[test]
fn splat_stage() {
    let ctx = Context::shared();
    let (out, shape) = seeds(&ctx);
    let fixed = words(&ctx, &out.density_fixed);
    let dens: Vec<f32> = fixed.iter().map(|&f| f as f32 / out.fixed_scale).collect();
    fieldkit::assert_summary!("splat_stage", Summary::floats(&shape, &dens, 3).to_string());
}

#[test]
fn seed_stage() {
    let ctx = Context::shared();
    let (out, shape) = seeds(&ctx);
    let keys = words(&ctx, &out.keys);
    let is_seed: Vec<u32> = keys.iter().map(|&k| (k != 0) as u32).collect();
    let pts: Vec<f32> =
        bytemuck::cast_slice::<u8, f32>(&read_buffer(&ctx, &out.points).unwrap()).to_vec();
    fieldkit::assert_summary!(
        "seed_stage",
        Summary::ints(&shape, &is_seed)
            .and(
                "points",
                Summary::floats(&[shape.iter().product::<usize>(), 4], &pts, 3)
            )
            .to_string()
    );
}

#[test]
fn jfa_and_sdf_stages() {
    fieldkit::assert_summary!(
        "jfa_and_sdf_stages",
        distance_summary(Method::Jfa(Variant::JfaPlus2))
    );
}

#[test]
fn line_passes_and_sdf_stages() {
    fieldkit::assert_summary!(
        "line_passes_and_sdf_stages",
        distance_summary(Method::Lines)
    );
}

/// The nearest seed (by table index) and the SDF after the distance stage with `method`.
fn distance_summary(method: Method) -> String {
    let ctx = Context::shared();
    let s = Settings {
        method,
        ..settings()
    };
    let field = metaball_field(&ctx, &voxels(), 1.0, &s);
    let [w, h, d] = field.grid.size.map(|x| x as usize);
    let nearest = words(&ctx, &field.nearest);
    // The seed each voxel ends with, by table index.
    let seeded: Vec<u32> = nearest
        .iter()
        .map(|&k| fieldkit::distance::key_index(k).unwrap_or(u32::MAX))
        .collect();
    let sdf: Vec<f32> = read_texture(&ctx, &field.sdf).unwrap();
    // Both methods pick between sub-voxel seeds by f32 distances (the line passes to offsets
    // quantized to 1/511 voxel, JFA to the points themselves), and later passes build on those
    // picks: where two seeds are near-equal, which one a voxel keeps depends on the adapter's
    // rounding (the H100 and llvmpipe disagree on a few voxels for both). Which voxels hold a
    // seed does not; the kept seeds' distances are the SDF below, compared within its last
    // decimal.
    let _ = method;
    let ints = Summary(format!(
        "shape: {:?}\nseeded voxels: {}\n",
        [d, h, w],
        seeded.iter().filter(|&&k| k != u32::MAX).count()
    ));
    ints.and("sdf", Summary::floats(&[d, h, w], &sdf, 3))
        .to_string()
}

/// Images summarised by coverage and mean colour (1 decimal, 0..255), over the background.
fn image_summary(rgba: &[u8], w: usize, h: usize) -> String {
    let bg = [rgba[0], rgba[1], rgba[2]];
    let px: Vec<&[u8]> = rgba.chunks(4).collect();
    let covered: Vec<&&[u8]> = px.iter().filter(|p| p[..3] != bg).collect();
    let mean =
        |c: usize| covered.iter().map(|p| p[c] as f64).sum::<f64>() / covered.len().max(1) as f64;
    format!(
        "size: {w}×{h}\ncovered: {}\nmean rgb: {:.1} {:.1} {:.1}\n",
        covered.len(),
        mean(0),
        mean(1),
        mean(2)
    )
}

#[test]
fn raymarch_and_cube_images() {
    let ctx = Context::shared();
    let (w, h) = (160, 100);
    let surface = metaball_scene(&ctx, w, h, 0.0, MetaballView::Surface(Output::Shaded)).unwrap();
    let cubes = metaball_scene(&ctx, w, h, 0.0, MetaballView::Cubes).unwrap();
    let s = image_summary(&surface, w as usize, h as usize);
    let c = image_summary(&cubes, w as usize, h as usize);
    fieldkit::assert_summary!(
        "raymarch_and_cube_images",
        format!("[surface]\n{s}[cubes]\n{c}")
    );
}
