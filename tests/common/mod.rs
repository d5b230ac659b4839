//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod metaball;
pub mod ocean;
pub mod octree;
pub mod volume;
pub mod voxelize;

use fieldkit::distance::{Jfa2d, JfaSettings2d, Variant, upload_mask};
use fieldkit::gpu::{Context, read_texture};

/// Deterministic pseudo-random mask (no RNG crate needed, same on every machine).
pub fn random_mask(w: usize, h: usize, density: f64, seed: u64) -> Vec<bool> {
    let mut s = seed.wrapping_add(0x9e3779b97f4a7c15);
    (0..w * h)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) < density
        })
        .collect()
}

pub fn to_bytes(mask: &[bool]) -> Vec<u8> {
    mask.iter().map(|&m| if m { 255 } else { 0 }).collect()
}

/// Run the whole 2D chain; returns (nearest, distance).
pub fn run_jfa(
    ctx: &Context,
    jfa: &Jfa2d,
    mask: &[bool],
    w: usize,
    h: usize,
    options: JfaSettings2d,
) -> (Vec<u32>, Vec<f32>) {
    let seeds =
        upload_mask(&ctx.device, &ctx.queue, &to_bytes(mask), w as u32, h as u32).expect("upload");
    let mut enc = ctx.encoder("test");
    let field = jfa
        .encode(&ctx.device, &mut enc, &seeds, &options)
        .expect("encode");
    ctx.submit_and_wait("test", enc).expect("run");
    (
        read_texture(ctx, &field.nearest).unwrap(),
        read_texture(ctx, &field.distance).unwrap(),
    )
}

pub fn variant_options(variant: Variant) -> JfaSettings2d {
    JfaSettings2d {
        variant,
        ..JfaSettings2d::default()
    }
}

/// Deterministic pseudo-random 3D mask, x fastest.
pub fn random_mask_3d(size: [usize; 3], density: f64, seed: u64) -> Vec<bool> {
    random_mask(size[0] * size[1], size[2], density, seed)
}

pub fn mask_3d(size: [usize; 3], pts: &[[usize; 3]]) -> Vec<bool> {
    let mut m = vec![false; size.iter().product()];
    for p in pts {
        m[(p[2] * size[1] + p[1]) * size[0] + p[0]] = true;
    }
    m
}

pub fn size_u32(size: [usize; 3]) -> [u32; 3] {
    size.map(|s| s as u32)
}

/// Run a 3D distance computation on a mask; returns (nearest, nearest outside, distance).
pub fn run_3d(
    ctx: &Context,
    d3: &fieldkit::distance::Distance3d,
    mask: &[bool],
    size: [usize; 3],
    options: &fieldkit::distance::Settings3d,
) -> (Vec<u32>, Option<Vec<u32>>, Vec<f32>) {
    let volume =
        fieldkit::distance::upload_volume(&ctx.device, &ctx.queue, &to_bytes(mask), size_u32(size))
            .expect("upload");
    let mut enc = ctx.encoder("test");
    let field = d3
        .encode(&ctx.device, &mut enc, &volume, options)
        .expect("encode");
    ctx.submit_and_wait("test", enc).expect("run");
    (
        field
            .nearest
            .read(&ctx.device, &ctx.queue)
            .wait(ctx)
            .unwrap(),
        field
            .nearest_outside
            .as_ref()
            .map(|s| s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()),
        read_texture(ctx, &field.distance).unwrap(),
    )
}

/// Build a metaball field on a fitted grid; returns the field and the seeds stage's outputs
/// read back (keys, points) from a separate run of the seeds stage alone.
pub fn metaball_field(
    ctx: &Context,
    voxels: &[glam::Vec4],
    edge: f32,
    settings: &fieldkit::metaball::Settings,
) -> fieldkit::metaball::MetaballField {
    let balls = fieldkit::metaball::Metaballs::new(&ctx.device).unwrap();
    let grid = settings
        .fit_grid(voxels, edge)
        .unwrap()
        .expect("a non-empty voxel set");
    let inst = balls.upload(&ctx.device, &ctx.queue, voxels).unwrap();
    let mut enc = ctx.encoder("metaball test");
    let field = balls
        .encode(&ctx.device, &mut enc, &inst, &grid, edge, settings)
        .unwrap();
    ctx.submit_and_wait("metaball test", enc).unwrap();
    field
}

/// `target/<profile>/examples/<name>`, which `cargo test` builds with the other examples.
pub fn example_binary(name: &str) -> std::path::PathBuf {
    let exe = std::env::current_exe().expect("the test binary's path");
    let profile_dir = exe
        .parent()
        .and_then(|deps| deps.parent())
        .expect("target/<profile>/deps/<test>");
    let bin = profile_dir
        .join("examples")
        .join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    assert!(
        bin.exists(),
        "{} is missing: `cargo test` builds the examples; run `cargo build --example {name}`",
        bin.display()
    );
    bin
}

/// A right triangle in the plane z = 1.5 with its right angle at (0.5, 0.5) and legs to
/// x = `leg` and y = `leg` (in voxels of a unit grid): its legs lie at half a voxel and its
/// hypotenuse on x + y = leg + 0.5, so no edge runs through a voxel corner and no voxel is a
/// matter of rounding.
pub fn right_triangle(leg: f64) -> fieldkit::voxelize::Mesh {
    use glam::DVec3;
    fieldkit::voxelize::Mesh {
        positions: vec![
            DVec3::new(0.5, 0.5, 1.5),
            DVec3::new(leg, 0.5, 1.5),
            DVec3::new(0.5, leg, 1.5),
        ],
        triangles: vec![[0, 1, 2]],
        ..Default::default()
    }
}

/// The voxels whose closed box meets [`right_triangle`]`(leg)` (an integer `leg`) in a unit
/// grid of `size` (x fastest; at least 2 layers): those of layer 1 with x + y ≤ leg.
pub fn right_triangle_voxels(leg: usize, size: [usize; 3]) -> Vec<bool> {
    let [nx, ny, nz] = size;
    (0..nx * ny * nz)
        .map(|i| {
            let (x, y, z) = (i % nx, i / nx % ny, i / (nx * ny));
            z == 1 && x + y <= leg
        })
        .collect()
}

/// `copies` copies of `one` in one mesh (positions and any per-vertex colours repeated).
pub fn repeated(one: &fieldkit::voxelize::Mesh, copies: u32) -> fieldkit::voxelize::Mesh {
    let mut mesh = one.clone();
    let n = one.positions.len() as u32;
    for k in 1..copies {
        mesh.positions.extend(one.positions.iter().copied());
        mesh.colors.extend(one.colors.iter().copied());
        mesh.triangles
            .extend(one.triangles.iter().map(|t| t.map(|v| v + k * n)));
    }
    mesh
}

/// A 2D texture of `size` and `format` holding `bytes` (rows packed), for sampling.
pub fn upload_2d(
    ctx: &Context,
    size: [u32; 2],
    format: wgpu::TextureFormat,
    bytes: &[u8],
) -> wgpu::Texture {
    upload_layers(ctx, [size[0], size[1], 1], format, bytes)
}

/// A 2D texture (array) of `size` = [width, height, layers] and `format` holding `bytes`
/// (rows packed, layer after layer), for sampling.
pub fn upload_layers(
    ctx: &Context,
    size: [u32; 3],
    format: wgpu::TextureFormat,
    bytes: &[u8],
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some("test upload"),
            size: wgpu::Extent3d {
                width: size[0],
                height: size[1],
                depth_or_array_layers: size[2],
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytes,
    )
}

/// Two seed textures of `seeds` (a JFA pass's source and destination), recorded into `enc`.
pub fn seed_pair(
    ctx: &Context,
    jfa: &Jfa2d,
    enc: &mut wgpu::CommandEncoder,
    seeds: &wgpu::Texture,
) -> (wgpu::Texture, wgpu::Texture) {
    let mut seed = || {
        jfa.encode_seed(&ctx.device, &mut *enc, seeds, false)
            .unwrap()
    };
    (seed(), seed())
}

/// A device on the same adapter as `ctx` with WebGPU's default limits (16 KiB of workgroup
/// memory, 32 colour bytes a sample, …): what every WebGPU device offers.
pub fn default_limits(ctx: &Context) -> Context {
    let adapter = ctx
        .adapter
        .as_ref()
        .expect("Context::shared opens an adapter");
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("default limits"),
        required_limits: wgpu::Limits::default(),
        ..Default::default()
    }))
    .expect("every WebGPU adapter takes the default limits");
    Context::from_device(device, queue)
}

/// A colour target read back as four floats a texel, whatever its format: float formats as
/// they are, unorm formats scaled to [0, 1], and an `R32Uint` as the four 8-bit unorm channels
/// WGSL's `pack4x8unorm` packs (x in the low byte).
pub fn read_rgba(ctx: &Context, t: &wgpu::Texture) -> Vec<[f32; 4]> {
    use wgpu::TextureFormat as F;
    let unorm8 = |b: u32| std::array::from_fn(|k| ((b >> (8 * k)) & 255) as f32 / 255.0);
    match t.format() {
        F::Rgba32Float => read_texture(ctx, t).unwrap(),
        F::Rgba16Float => {
            let bits: Vec<[u16; 4]> = read_texture(ctx, t).unwrap();
            bits.iter()
                .map(|p| p.map(|h| half::f16::from_bits(h).to_f32()))
                .collect()
        }
        F::Rgba8Unorm | F::R32Uint => {
            let words: Vec<u32> = read_texture(ctx, t).unwrap();
            words.into_iter().map(unorm8).collect()
        }
        F::Rgb10a2Unorm => {
            let words: Vec<u32> = read_texture(ctx, t).unwrap();
            let field = |w: u32, shift: u32, bits: u32| ((w >> shift) & ((1 << bits) - 1)) as f32;
            words
                .into_iter()
                .map(|w| {
                    [
                        field(w, 0, 10) / 1023.0,
                        field(w, 10, 10) / 1023.0,
                        field(w, 20, 10) / 1023.0,
                        field(w, 30, 2) / 3.0,
                    ]
                })
                .collect()
        }
        f => panic!("read_rgba does not read {f:?}"),
    }
}

/// The largest rounding error of a colour target of `format` on [0, 1]: one step, as Vulkan,
/// Metal and D3D let a float → unorm or float → half conversion take either neighbour (8 and
/// 10 bits for the unorm formats and an `R32Uint` of four 8-bit channels; half floats' 11
/// bits, relative to the value from 1 up), 0 for `Rgba32Float`.
pub fn format_step(format: wgpu::TextureFormat) -> f32 {
    use wgpu::TextureFormat as F;
    match format {
        F::Rgba32Float => 0.0,
        F::Rgba16Float => 1.0 / 1024.0,
        F::Rgba8Unorm | F::R32Uint => 1.0 / 255.0,
        F::Rgb10a2Unorm => 1.0 / 1023.0,
        f => panic!("format_step does not know {f:?}"),
    }
}

/// An empty texture of `size` (`[w, h, 1]`: 2D, a depth above 1: 3D), `format` and `usage`.
pub fn texture(
    ctx: &Context,
    size: [u32; 3],
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    let dimension = if size[2] > 1 {
        wgpu::TextureDimension::D3
    } else {
        wgpu::TextureDimension::D2
    };
    fieldkit::gpu::texture(&ctx.device, "test texture", size, dimension, format, usage)
}

/// [`texture`] for sampling only (`TEXTURE_BINDING`): what a stage that must refuse it is given.
pub fn sampled(ctx: &Context, size: [u32; 3], format: wgpu::TextureFormat) -> wgpu::Texture {
    texture(ctx, size, format, wgpu::TextureUsages::TEXTURE_BINDING)
}

/// The compute pipelines `device` holds, by wgpu's own counter (the `counters` feature): a
/// test that counts what a call makes uses a device of its own.
pub fn compute_pipelines(device: &wgpu::Device) -> isize {
    device.get_internal_counters().hal.compute_pipelines.read()
}
