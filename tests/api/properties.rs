//! Property tests over the public API: random and extreme sizes, counts, transforms and
//! parameters (0, 1, limits ± 1, NaN, ±∞, subnormals, huge scales, degenerate transforms, empty
//! and one-element inputs, meshes with NaN or repeated vertices). Each case must return `Ok`
//! with a result that passes a cheap invariant, or a typed error — never a panic, and never an
//! error that reaches wgpu (the uncaptured-error sink stays empty).
//!
//! Thousands of cases run on wgpu's `noop` backend, where no output is read; a few hundred on
//! the real adapter (lavapipe in CI) where the output is checked against the CPU. `PROPTEST_CASES`
//! scales every property; a failing case is printed with its seed and kept in
//! `tests/properties.proptest-regressions`, so it runs again first next time.

use std::sync::OnceLock;

use fieldkit::Error;
use fieldkit::distance::{
    ColumnPasses, Distance2d, Distance3d, Method, Method2d, Settings2d, Settings3d, Variant, cpu,
    upload_mask, upload_volume,
};
use fieldkit::gpu::Context;
use fieldkit::metaball::{Metaballs, Settings, packed_grid};
use fieldkit::metaball::{RaymarchSettings, Raymarcher};
use fieldkit::ocean::{LodSettings, select};
use fieldkit::ocean::{Look, OceanCamera};
use fieldkit::ocean::{Wave, Waves};
use fieldkit::view::View;
use fieldkit::volume::{MarchSettings, TransferFunction, Volume, VolumeRenderer};
use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
use glam::{DVec2, DVec3, Mat4, Vec2, Vec3, Vec4};
use proptest::prelude::*;

/// The noop device and every technique's pipelines, made once.
struct Noop {
    ctx: Context,
    d2: Distance2d,
    d3: Distance3d,
    balls: Metaballs,
    marcher: Raymarcher,
    volume: VolumeRenderer,
    vox: Voxelizer,
}

fn noop() -> &'static Noop {
    static NOOP: OnceLock<Noop> = OnceLock::new();
    NOOP.get_or_init(|| {
        let ctx = Context::noop().expect("wgpu's noop backend");
        let d = &ctx.device;
        Noop {
            d2: Distance2d::new(d).unwrap(),
            d3: Distance3d::new(d).unwrap(),
            balls: Metaballs::new(d).unwrap(),
            marcher: Raymarcher::new(
                d,
                &ctx.queue,
                wgpu::TextureFormat::Rgba8Unorm,
                wgpu::TextureFormat::Depth32Float,
                false,
            )
            .unwrap(),
            volume: VolumeRenderer::new(d, &ctx.queue, wgpu::TextureFormat::Rgba8Unorm).unwrap(),
            vox: Voxelizer::new(d).unwrap(),
            ctx,
        }
    })
}

/// Nothing reached wgpu's error sink since the last call.
fn clean(ctx: &Context) -> Result<(), TestCaseError> {
    let errors = ctx.take_uncaptured();
    prop_assert!(errors.is_empty(), "wgpu errors: {errors:?}");
    Ok(())
}

/// A typed error is an answer; so is `Ok`. Only a panic (which proptest reports) or a wgpu
/// error is a failure.
fn typed<T>(r: Result<T, Error>) -> Option<T> {
    r.ok()
}

fn f32_edge() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0),
        Just(1.0),
        Just(-1.0),
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(f32::MIN_POSITIVE),
        Just(1e-45),
        Just(f32::MAX),
        Just(-f32::MAX),
        Just(1e30),
        -1e3f32..1e3,
        any::<f32>(),
    ]
}

fn u32_edge() -> impl Strategy<Value = u32> {
    prop_oneof![
        Just(0u32),
        Just(1),
        Just(2),
        Just(2047),
        Just(2048),
        Just(2049),
        Just(4095),
        Just(4096),
        Just(4097),
        Just(65536),
        Just(u32::MAX),
        0u32..64,
    ]
}

fn vec3_edge() -> impl Strategy<Value = Vec3> {
    (f32_edge(), f32_edge(), f32_edge()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn mat4_edge() -> impl Strategy<Value = Mat4> {
    prop_oneof![
        Just(Mat4::IDENTITY),
        Just(Mat4::ZERO),
        Just(Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0))),
        Just(Mat4::from_scale(Vec3::splat(1e30))),
        Just(Mat4::from_scale(Vec3::splat(1e-30))),
        vec3_edge().prop_map(Mat4::from_translation),
        (vec3_edge(), f32_edge())
            .prop_map(|(a, t)| Mat4::from_axis_angle(a.normalize_or_zero(), t)),
        proptest::array::uniform16(f32_edge()).prop_map(|a| Mat4::from_cols_array(&a)),
    ]
}

/// x·y·z, saturating (sides up to u32::MAX overflow u64).
fn volume_of(size: [u32; 3]) -> u64 {
    size.iter()
        .try_fold(1u64, |c, &n| c.checked_mul(n as u64))
        .unwrap_or(u64::MAX)
}

fn camera_view(eye: Vec3, size: [u32; 2]) -> View {
    let proj = glam::camera::rh::proj::directx::perspective(
        0.8,
        size[0].max(1) as f32 / size[1].max(1) as f32,
        0.1,
        100.0,
    );
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, Vec3::ZERO, Vec3::Y),
        viewport: size,
        reversed_z: false,
        origin: [0, 0],
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Waves: a validated set samples finite heights and normals anywhere, any time.
    #[test]
    fn waves_validate_and_sample_finitely(
        waves in proptest::collection::vec((f32_edge(), f32_edge(), f32_edge(), f32_edge(), f32_edge()), 0..5),
        steepness in f32_edge(),
        at in (-1e5f64..1e5, -1e5f64..1e5, 0f64..1e5),
    ) {
        let waves: Vec<Wave> = waves.into_iter().map(|(dx, dz, a, l, s)| Wave {
            direction: Vec2::new(dx, dz), amplitude: a, wavelength: l, speed: s,
        }).collect();
        if let Some(w) = typed(Waves::new(waves, steepness)) {
            let s = w.sample(DVec2::new(at.0, at.1), at.2);
            prop_assert!(s.height.is_finite(), "{s:?}");
            prop_assert!(s.normal.is_finite(), "{s:?}");
        }
    }

    /// Mesh → grid: a fitted grid has sides 1..=n and a finite, positive voxel.
    #[test]
    fn grid_fit_fits_or_refuses(
        points in proptest::collection::vec((f32_edge(), f32_edge(), f32_edge()), 0..10),
        repeat in any::<bool>(),
        n in u32_edge(),
    ) {
        let mut positions: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64)).collect();
        if repeat && !positions.is_empty() {
            positions.push(positions[0]);
        }
        let k = positions.len() as u32;
        let triangles = (0..k.saturating_sub(2)).map(|i| [i, i + 1, i + 2]).collect();
        let mesh = Mesh { positions, triangles, ..Mesh::default() };
        if let Some(g) = typed(Grid::fit(&mesh, n)) {
            prop_assert!(g.size.iter().all(|&s| s >= 1 && s <= n.max(1)), "{g:?}");
            prop_assert!(g.voxel.is_finite() && g.voxel > 0.0, "{g:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// The grid builder: the voxels asked for, all finite, or a typed error.
    #[test]
    fn packed_grid_builds_or_refuses(
        region in proptest::array::uniform3(prop_oneof![
            Just(0u32), Just(1), Just(2), Just(40), Just((1 << 24) + 1), Just(u32::MAX), 0u32..16,
        ]),
        block in f32_edge(),
    ) {
        if let Some(v) = typed(packed_grid(region, block)) {
            prop_assert_eq!(v.len() as u64, volume_of(region));
            prop_assert!(v.iter().all(|p| p.is_finite()));
        }
    }

    /// 2D distance on the noop device: masks of any size, any texel size, every method.
    #[test]
    fn distance_2d_encodes_or_refuses(w in u32_edge(), h in u32_edge(), texel in f32_edge(), signed in any::<bool>(), method in 0usize..3) {
        let n = noop();
        let ctx = &n.ctx;
        let len = (w as u64 * h as u64).min(1 << 20) as usize;
        if let Some(mask) = typed(upload_mask(&ctx.device, &ctx.queue, &vec![255u8; len], w, h)) {
            prop_assert_eq!((mask.width(), mask.height()), (w, h));
            let method = [Method2d::Exact, Method2d::Jfa(Variant::JfaPlus2), Method2d::Jfa(Variant::Jfa)][method];
            let options = Settings2d { method, signed, texel_size: texel, ..Settings2d::default() };
            let mut enc = ctx.encoder("prop 2d");
            if let Some(f) = typed(n.d2.encode(&ctx.device, &mut enc, &mask, &options)) {
                prop_assert_eq!((f.width, f.height), (w, h));
                prop_assert_eq!(f.nearest_outside.is_some(), signed);
            }
            ctx.queue.submit([enc.finish()]);
        }
        clean(ctx)?;
    }

    /// 3D distance on the noop device: volumes of any size, any options.
    #[test]
    fn distance_3d_encodes_or_refuses(
        size in proptest::array::uniform3(u32_edge()),
        voxel in f32_edge(),
        band in proptest::option::of(f32_edge()),
        signed in any::<bool>(),
        method in 0usize..3,
    ) {
        let n = noop();
        let ctx = &n.ctx;
        let data = vec![1u8; volume_of(size).min(1 << 20) as usize];
        if let Some(volume) = typed(upload_volume(&ctx.device, &ctx.queue, &data, size)) {
            let method = [Method::Exact, Method::Jfa(Variant::JfaPlus2), Method::Lines][method];
            let options = Settings3d { method, signed, voxel_size: voxel, band, ..Settings3d::default() };
            let mut enc = ctx.encoder("prop 3d");
            if let Some(f) = typed(n.d3.encode(&ctx.device, &mut enc, &volume, &options)) {
                prop_assert_eq!(f.size, size);
            }
            ctx.queue.submit([enc.finish()]);
        }
        clean(ctx)?;
    }

    /// Metaballs on the noop device: any voxel set (NaN, huge, zero scales), any settings,
    /// then the raymarch from any camera.
    #[test]
    fn metaballs_encode_or_refuse(
        voxels in proptest::collection::vec((vec3_edge(), f32_edge()), 0..6),
        threshold in f32_edge(),
        overlap in f32_edge(),
        cells in f32_edge(),
        band in f32_edge(),
        edge in f32_edge(),
        eye in vec3_edge(),
        model in mat4_edge(),
        viewport in proptest::array::uniform2(prop_oneof![Just(0u32), Just(1), 1u32..64, Just(16384)]),
    ) {
        let n = noop();
        let ctx = &n.ctx;
        let voxels: Vec<Vec4> = voxels.into_iter().map(|(c, s)| c.extend(s)).collect();
        let s = Settings { threshold, overlap, cells_per_edge: cells, band, ..Settings::default() };
        if let Some(inst) = typed(n.balls.upload(&ctx.device, &ctx.queue, &voxels))
            && let Some(Some(grid)) = typed(s.fit_grid(&voxels, edge))
        {
            prop_assert!(grid.size.iter().all(|&c| c >= 1));
            let mut enc = ctx.encoder("prop metaballs");
            if let Some(field) = typed(n.balls.encode(&ctx.device, &mut enc, &inst, &grid, edge, &s)) {
                let view = camera_view(eye, viewport);
                let _ = typed(n.marcher.encode_march(&ctx.device, &mut enc, &field, model, &view, &RaymarchSettings::default()));
            }
            ctx.queue.submit([enc.finish()]);
        }
        clean(ctx)?;
    }

    /// Volumes on the noop device: any dims, spacing and origin; any march settings, transform
    /// and camera.
    #[test]
    fn volumes_upload_and_march_or_refuse(
        dims in proptest::array::uniform3(prop_oneof![Just(0u32), Just(1), 1u32..12, Just(2049)]),
        spacing in vec3_edge(),
        origin in vec3_edge(),
        format in 0usize..4,
        step in f32_edge(),
        model in mat4_edge(),
        eye in vec3_edge(),
        viewport in proptest::array::uniform2(prop_oneof![Just(0u32), Just(1), 1u32..64]),
    ) {
        let n = noop();
        let ctx = &n.ctx;
        let count = volume_of(dims).min(1 << 16) as usize;
        let format = [
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureFormat::R16Float,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureFormat::Rgba8Unorm,
        ][format];
        if let Some(volume) = typed(Volume::upload(&ctx.device, &ctx.queue, &vec![0.5f32; count], dims, format, spacing, origin)) {
            let mut enc = ctx.encoder("prop volume");
            if let Some(bricks) = typed(n.volume.encode_bricks(&ctx.device, &mut enc, &volume)) {
                let s = MarchSettings { step, ..MarchSettings::default() };
                let view = camera_view(eye, viewport);
                let _ = typed(n.volume.encode_march(&ctx.device, &mut enc, &volume, &bricks, None, &TransferFunction::cloud(), model, &view, None, &s));
            }
            ctx.queue.submit([enc.finish()]);
        }
        clean(ctx)?;
    }

    /// The ocean's patch selection from any camera and LOD settings.
    #[test]
    fn ocean_lod_selects_or_refuses(
        eye in (f32_edge(), f32_edge(), f32_edge()),
        centre in (f32_edge(), f32_edge()),
        size in f32_edge(),
        error in f32_edge(),
        depth in u32_edge(),
        quads in u32_edge(),
        height in u32_edge(),
    ) {
        let waves = Waves::new(vec![Wave { direction: Vec2::X, amplitude: 0.3, wavelength: 10.0, speed: 4.0 }], 0.5).unwrap();
        let proj = glam::camera::rh::proj::directx::perspective(0.8, 1.5, 0.1, 1000.0);
        let camera = OceanCamera::look_at(DVec3::new(eye.0 as f64, eye.1 as f64, eye.2 as f64), DVec3::ZERO, proj);
        let settings = LodSettings {
            centre: DVec2::new(centre.0 as f64, centre.1 as f64),
            size: size as f64,
            max_error_px: error as f64,
            max_depth: depth.min(64),
            patch_quads: quads,
        };
        if let Some(sel) = typed(select(&waves, &Look::default(), &camera, height, &settings)) {
            prop_assert!(sel.patches.iter().all(|p| p.size.is_finite() && p.size > 0.0 && p.corner.is_finite()));
            prop_assert!(sel.patches.len() < 1 << 20);
        }
    }

    /// Voxelization on the noop device: any triangles (NaN, repeated, degenerate) in any grid.
    #[test]
    fn voxelize_encodes_or_refuses(
        points in proptest::collection::vec((f32_edge(), f32_edge(), f32_edge()), 0..9),
        n in prop_oneof![Just(0u32), Just(1), 1u32..40, Just(4097)],
        solid in any::<bool>(),
    ) {
        let nn = noop();
        let ctx = &nn.ctx;
        let positions: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64)).collect();
        let k = positions.len() as u32;
        let triangles = (0..k / 3).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let mesh = Mesh { positions, triangles, ..Mesh::default() };
        let grid = Grid::fit(&mesh, n).unwrap_or(Grid { origin: DVec3::ZERO, voxel: 0.1, size: [n.clamp(1, 64); 3] });
        let mut enc = ctx.encoder("prop voxelize");
        let r = if solid {
            nn.vox.encode_solid(&ctx.device, &mut enc, &mesh, &grid, true)
        } else {
            nn.vox.encode_surface(&ctx.device, &mut enc, &mesh, &grid)
        };
        if let Some(s) = typed(r) {
            prop_assert_eq!(s.size, grid.size);
        }
        ctx.queue.submit([enc.finish()]);
        clean(ctx)?;
    }

    /// Resident meshes placed by any matrices (singular, NaN, huge, tiny) in any grid.
    #[test]
    fn placed_meshes_encode_or_refuse(
        points in proptest::collection::vec((f32_edge(), f32_edge(), f32_edge()), 0..9),
        models in proptest::collection::vec(mat4_edge(), 0..3),
        n in prop_oneof![Just(0u32), Just(1), 1u32..40, Just(4097)],
        voxel in prop_oneof![Just(0.1f64), Just(0.0), Just(f64::NAN), Just(1e-300), Just(1e300)],
        six in any::<bool>(),
    ) {
        use fieldkit::voxelize::{GpuMesh, Separation};
        let nn = noop();
        let ctx = &nn.ctx;
        let positions: Vec<DVec3> = points.iter().map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64)).collect();
        let k = positions.len() as u32;
        let triangles = (0..k / 3).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let mesh = Mesh { positions, triangles, ..Mesh::default() };
        let Some(gpu) = typed(GpuMesh::upload(&ctx.device, &mesh)) else {
            return Ok(());
        };
        prop_assert!(gpu.triangles() as usize + gpu.degenerate() == mesh.triangles.len());
        let grid = Grid { origin: DVec3::splat(-1.0), voxel, size: [n.clamp(0, 4097), 8, 8] };
        let parts: Vec<_> = models.iter().map(|m| (&gpu, m.as_dmat4())).collect();
        let sep = if six { Separation::Six } else { Separation::Conservative };
        let mut enc = ctx.encoder("prop placed");
        if let Some(s) = typed(nn.vox.encode_surface_placed(&ctx.device, &mut enc, &parts, &grid, sep)) {
            prop_assert_eq!(s.size, grid.size);
        }
        ctx.queue.submit([enc.finish()]);
        clean(ctx)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 120, ..ProptestConfig::default() })]

    /// On the real adapter: the exact 2D transform of a random mask (empty, full, one seed,
    /// scattered) is the CPU's, texel for texel.
    #[test]
    fn exact_2d_matches_the_cpu_on_random_masks(
        w in 1u32..40,
        h in 1u32..40,
        density in prop_oneof![Just(0.0f64), Just(1.0), 0.0f64..0.3],
        seed in any::<u64>(),
    ) {
        let ctx = real();
        let d2 = real_d2();
        let inside = random_mask((w * h) as usize, density, seed);
        let mask = mask_bytes(&inside);
        let tex = upload_mask(&ctx.device, &ctx.queue, &mask, w, h).unwrap();
        let mut enc = ctx.encoder("prop exact 2d");
        let f = d2.encode(&ctx.device, &mut enc, &tex, &Settings2d { signed: true, ..Settings2d::default() }).unwrap();
        ctx.submit_and_wait("prop exact 2d", enc).unwrap();
        let got: Vec<f32> = fieldkit::gpu::read_texture(ctx, &f.distance).unwrap();
        let want = cpu::signed_2d(&inside, w as usize, h as usize);
        for (i, (&g, &e)) in got.iter().zip(&want).enumerate() {
            // With no seed of a kind the field is ±∞ or the format's far value on both sides.
            if !e.is_finite() {
                prop_assert!(g.abs() >= 1e6 || g.is_infinite(), "texel {i}: {g} for {e}");
                continue;
            }
            prop_assert!((g as f64 - e).abs() <= 1e-5 * (1.0 + e.abs()), "texel {i}: {g} vs {e}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 60, ..ProptestConfig::default() })]

    /// On the real adapter: the exact 3D transform of a random mask (empty, full, sparse,
    /// scattered) names, for every voxel, a seed as near as the CPU's nearest, on every column
    /// path: the tiles, and the global passes with any band count, so that the walks along the
    /// neighbour bands' envelopes (carried from position to position in the y pass) and the far
    /// bands' searches all run on columns of many bands.
    #[test]
    fn exact_3d_matches_the_cpu_on_random_masks(
        w in 1u32..24,
        h in 1u32..48,
        d in 1u32..40,
        density in prop_oneof![Just(0.0f64), Just(1.0), 0.0f64..0.03, 0.0f64..0.3],
        seed in any::<u64>(),
        path in 0usize..3,
        bands in prop_oneof![Just(None), (0u32..6).prop_map(|k| Some(1u32 << k))],
    ) {
        let ctx = real();
        let mask = random_mask((w * h * d) as usize, density, seed);
        let bytes = mask_bytes(&mask);
        let volume = upload_volume(&ctx.device, &ctx.queue, &bytes, [w, h, d]).unwrap();
        let passes = [ColumnPasses::Auto, ColumnPasses::Workgroup, ColumnPasses::Global][path];
        let field = {
            let mut d3 = real_d3().lock().unwrap();
            d3.set_column_passes(passes);
            d3.set_column_bands(bands).unwrap();
            let mut enc = ctx.encoder("prop exact 3d");
            let field = d3.encode(&ctx.device, &mut enc, &volume, &Settings3d::default()).unwrap();
            ctx.submit_and_wait("prop exact 3d", enc).unwrap();
            field
        };
        let nearest = field.nearest.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
        let dist: Vec<f32> = fieldkit::gpu::read_texture(ctx, &field.distance).unwrap();
        let size = [w as usize, h as usize, d as usize];
        let want = cpu::edt_3d_squared(&mask, size);
        for (i, &e) in want.iter().enumerate() {
            let got = cpu::seed_d2_3(nearest[i], i, size).unwrap_or(cpu::NONE);
            prop_assert_eq!(got, e, "{:?} {:?} bands {:?}: voxel {}", passes, size, bands, i);
            if e != cpu::NONE {
                let r = (e as f64).sqrt();
                prop_assert!((dist[i] as f64 - r).abs() <= 1e-5 * (1.0 + r), "voxel {i}: {} vs {r}", dist[i]);
            }
        }
    }
}

/// `cells` marks, each set with probability `density`, from a xorshift stream of `seed` (the
/// same mask for the same seed, so a kept regression reproduces).
fn random_mask(cells: usize, density: f64, seed: u64) -> Vec<bool> {
    let mut x = seed | 1;
    (0..cells)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            ((x >> 11) as f64 / (1u64 << 53) as f64) < density
        })
        .collect()
}

/// A mask as the seed textures and volumes take it: 255 marked, 0 not.
fn mask_bytes(mask: &[bool]) -> Vec<u8> {
    mask.iter().map(|&m| if m { 255 } else { 0 }).collect()
}

/// One `Distance3d` for the 3D property (its pipelines are kept between cases), set to each
/// case's column path.
fn real_d3() -> &'static std::sync::Mutex<Distance3d> {
    static D3: OnceLock<std::sync::Mutex<Distance3d>> = OnceLock::new();
    D3.get_or_init(|| std::sync::Mutex::new(Distance3d::new(&real().device).unwrap()))
}

fn real() -> &'static Context {
    static REAL: OnceLock<Context> = OnceLock::new();
    REAL.get_or_init(|| {
        Context::new().unwrap_or_else(|e| {
            panic!("this test needs a GPU adapter (apt-get install -y mesa-vulkan-drivers): {e}")
        })
    })
}

fn real_d2() -> &'static Distance2d {
    static D2: OnceLock<Distance2d> = OnceLock::new();
    D2.get_or_init(|| Distance2d::new(&real().device).unwrap())
}

/// The exact transform on grids no seed packing names (on the noop device: no memory is
/// touched): 2048 × 1024 × 2048 needs 11 + 10 + 11 bits, and its last voxel's code + 1 wraps;
/// past 2048 on a side is a size error; 16 × 16 × 2048 packs 4/4/24 and records.
#[test]
fn exact_grids_past_every_packing_are_refused() {
    let n = noop();
    let ctx = &n.ctx;
    let texture = |size: [u32; 3]| {
        fieldkit::gpu::texture(
            &ctx.device,
            "large volume",
            [size[0], size[1], size[2]],
            wgpu::TextureDimension::D3,
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureUsages::TEXTURE_BINDING,
        )
    };
    let options = fieldkit::distance::Settings3d::default();
    let mut enc = ctx.encoder("large exact");
    let wraps =
        n.d3.encode(
            &ctx.device,
            &mut enc,
            &texture([2048, 1024, 2048]),
            &options,
        )
        .unwrap_err();
    assert!(
        matches!(&wraps, fieldkit::Error::Invalid { what, .. } if what.contains("11, 10 and 11 bits")),
        "{wraps}"
    );
    if ctx.device.limits().max_texture_dimension_3d > 2048 {
        let long =
            n.d3.encode(&ctx.device, &mut enc, &texture([4, 4, 2049]), &options)
                .unwrap_err();
        assert!(
            matches!(
                long,
                fieldkit::Error::Size {
                    got: 2049,
                    max: 2048,
                    ..
                }
            ),
            "{long}"
        );
    }
    let field =
        n.d3.encode(&ctx.device, &mut enc, &texture([16, 16, 2048]), &options)
            .unwrap();
    assert_eq!(
        field.packing,
        fieldkit::distance::SeedPacking {
            x_bits: 4,
            y_bits: 4
        }
    );
    drop(enc);
    let _ = ctx.take_uncaptured();
}
