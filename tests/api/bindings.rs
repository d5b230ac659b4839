//! Host bindings cannot drift from the shaders: every generated pipeline is accepted by wgpu (on
//! the noop backend, no GPU needed), a resource of the wrong kind or format is a typed error naming
//! the stage and binding, and host code that disagrees with a shader does not compile (those
//! cases run in `tests/user-crate/tests/drift.rs`).

use fieldkit::Error;
use fieldkit::bind::ComputePipeline;
use fieldkit::gpu::Context;
use fieldkit::shaders::distance::{jfa_seed, jfa_step};

fn noop() -> Context {
    Context::noop().expect("wgpu's noop backend is compiled in (feature `noop`)")
}

#[test]
fn every_generated_pipeline_is_created_on_the_noop_backend() {
    let ctx = noop();
    assert!(!fieldkit::shaders::ALL.is_empty());
    for info in fieldkit::shaders::ALL {
        fieldkit::bind::create_any(&ctx.device, info)
            .unwrap_or_else(|e| panic!("{}::{}: {e}", info.stage, info.entry_point));
    }
    assert!(ctx.take_uncaptured().is_empty());
}

fn texture(
    ctx: &Context,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    crate::common::texture(ctx, [8, 8, 1], format, usage)
}

fn buffer(ctx: &Context, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage,
        mapped_at_creation: false,
    })
}

const TEX: wgpu::TextureUsages =
    wgpu::TextureUsages::TEXTURE_BINDING.union(wgpu::TextureUsages::STORAGE_BINDING);

/// Bind `jump` with one resource swapped for a bad one; return the error.
fn bind_jump(
    ctx: &Context,
    params: &wgpu::Buffer,
    src: &wgpu::Texture,
    dst: &wgpu::Texture,
) -> Result<(), Error> {
    let p: jfa_step::jump::Pipeline = ComputePipeline::new(&ctx.device)?;
    let (sv, dv) = (
        src.create_view(&Default::default()),
        dst.create_view(&Default::default()),
    );
    p.bind(
        &ctx.device,
        &jfa_step::jump::Resources {
            params: params.into(),
            src: (&sv).into(),
            dst: (&dv).into(),
        },
    )
    .map(|_| ())
}

fn binding_error(r: Result<(), Error>) -> fieldkit::BindingError {
    match r {
        Err(Error::Binding(b)) => b,
        other => panic!("expected a binding error, got {other:?}"),
    }
}

#[test]
fn correct_resources_bind() {
    let ctx = noop();
    let params = buffer(&ctx, 16, wgpu::BufferUsages::UNIFORM);
    let t = || texture(&ctx, wgpu::TextureFormat::R32Uint, TEX);
    bind_jump(&ctx, &params, &t(), &t()).expect("correct resources bind");
}

#[test]
fn wrong_storage_format_names_stage_and_binding() {
    let ctx = noop();
    let params = buffer(&ctx, 16, wgpu::BufferUsages::UNIFORM);
    let src = texture(&ctx, wgpu::TextureFormat::R32Uint, TEX);
    let dst = texture(&ctx, wgpu::TextureFormat::Rgba8Unorm, TEX);
    let e = binding_error(bind_jump(&ctx, &params, &src, &dst));
    assert_eq!(
        (e.stage, e.entry_point, e.binding, e.group, e.index),
        ("distance::jfa_step", "jump", "dst", 0, 2)
    );
    assert!(
        e.problem.contains("Rgba8Unorm") && e.problem.contains("R32Uint"),
        "{}",
        e.problem
    );
    assert!(
        ctx.take_uncaptured().is_empty(),
        "the check runs before wgpu sees the bind group"
    );
}

#[test]
fn wrong_sample_type_names_binding() {
    let ctx = noop();
    let params = buffer(&ctx, 16, wgpu::BufferUsages::UNIFORM);
    // A float texture where the shader reads texture_2d<u32>.
    let src = texture(&ctx, wgpu::TextureFormat::R32Float, TEX);
    let dst = texture(&ctx, wgpu::TextureFormat::R32Uint, TEX);
    assert_eq!(
        binding_error(bind_jump(&ctx, &params, &src, &dst)).binding,
        "src"
    );
}

#[test]
fn missing_usage_and_small_uniform_are_typed_errors() {
    let ctx = noop();
    let t = || texture(&ctx, wgpu::TextureFormat::R32Uint, TEX);
    let small = buffer(&ctx, 8, wgpu::BufferUsages::UNIFORM);
    let e = binding_error(bind_jump(&ctx, &small, &t(), &t()));
    assert_eq!(e.binding, "params");
    assert!(e.problem.contains("at least 16"), "{}", e.problem);
    let not_uniform = buffer(&ctx, 16, wgpu::BufferUsages::STORAGE);
    assert_eq!(
        binding_error(bind_jump(&ctx, &not_uniform, &t(), &t())).binding,
        "params"
    );
    let params = buffer(&ctx, 16, wgpu::BufferUsages::UNIFORM);
    let sampled_only = texture(
        &ctx,
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    assert_eq!(
        binding_error(bind_jump(&ctx, &params, &t(), &sampled_only)).binding,
        "dst"
    );
}

#[test]
fn a_buffer_past_the_device_limit_is_a_typed_error() {
    // wgpu's default limits: a 64 KiB uniform binding (the noop adapter offers far more).
    let ctx = Context::noop_with_limits(wgpu::Limits::default())
        .expect("wgpu's noop backend is compiled in (feature `noop`)");
    let t = || texture(&ctx, wgpu::TextureFormat::R32Uint, TEX);
    let max = ctx.device.limits().max_uniform_buffer_binding_size;
    assert_eq!(max, 64 << 10);
    let large = buffer(&ctx, max + 16, wgpu::BufferUsages::UNIFORM);
    let e = binding_error(bind_jump(&ctx, &large, &t(), &t()));
    assert_eq!(e.binding, "params");
    assert!(
        e.problem.contains("max_uniform_buffer_binding_size"),
        "{}",
        e.problem
    );
    let at_limit = buffer(&ctx, max, wgpu::BufferUsages::UNIFORM);
    bind_jump(&ctx, &at_limit, &t(), &t()).expect("a buffer at the limit binds");
    let errors = ctx.take_uncaptured();
    assert!(errors.is_empty(), "{errors:?}");
}

#[test]
fn unknown_override_is_an_error() {
    let ctx = noop();
    let r = jfa_seed::seed::Pipeline::with_overrides(&ctx.device, &[("no_such_constant", 1.0)]);
    assert!(matches!(
        r,
        Err(Error::Invalid {
            stage: "distance::jfa_seed",
            ..
        })
    ));
}

/// A stage's `Overrides` hold the shader's defaults (`override ROWS: u32 = 1u;` in
/// `edt_rows.wgsl`; `PACK_2D`, `AXIS`, `Y_AFTER_Z`, `SOURCE_APART`, `CELLS = 3839u` and
/// `SIGNED` in `edt_tile.wgsl`; `SEED_X_BITS = SEED_Y_BITS = 11u` in both), and their
/// `constants()` make pipelines.
#[test]
fn typed_overrides_hold_the_shader_defaults_and_make_pipelines() {
    use fieldkit::shaders::distance::{edt_rows, edt_tile};
    let ctx = noop();
    assert_eq!(
        edt_rows::Overrides::default(),
        edt_rows::Overrides {
            rows: 1,
            seed_x_bits: 11,
            seed_y_bits: 11
        }
    );
    let rows = edt_rows::Overrides {
        rows: 4,
        ..Default::default()
    };
    assert_eq!(
        rows.constants(),
        vec![("ROWS", 4.0), ("SEED_X_BITS", 11.0), ("SEED_Y_BITS", 11.0)]
    );
    let tile = edt_tile::Overrides {
        cells: 2336,
        ..Default::default()
    };
    assert_eq!(
        tile.constants(),
        vec![
            ("PACK_2D", 0.0),
            ("AXIS", 1.0),
            ("Y_AFTER_Z", 0.0),
            ("SOURCE_APART", 0.0),
            ("CELLS", 2336.0),
            ("SEED_X_BITS", 11.0),
            ("SEED_Y_BITS", 11.0),
            ("SIGNED", 0.0)
        ]
    );
    edt_rows::row_words::Pipeline::with_overrides(&ctx.device, &rows.constants())
        .expect("a pipeline from typed overrides");
    edt_tile::tile_columns::Pipeline::with_overrides(&ctx.device, &tile.constants())
        .expect("a pipeline from typed overrides");
}

/// Each pipeline's `needs` as the build reflected them. The workgroup memory agrees with what the
/// NVIDIA Vulkan driver reported for the same entry points (`xtask shader-stats edt_rows` on
/// the H100: Shared Memory Size 11264 for `rows`, 4096 for `rows_2d`).
#[test]
fn pipelines_state_the_limits_they_need() {
    use fieldkit::shaders::distance::{edt_rows, edt_tile};
    let rows = edt_rows::rows::INFO.needs;
    assert_eq!(rows.max_compute_workgroup_storage_size, 11264);
    assert_eq!(
        edt_rows::rows_2d::INFO
            .needs
            .max_compute_workgroup_storage_size,
        4096
    );
    assert_eq!(rows.max_compute_invocations_per_workgroup, 256);
    // params (uniform), volume (sampled texture), nearest (storage), all in group 0.
    assert_eq!(rows.max_uniform_buffers_per_shader_stage, 1);
    assert_eq!(rows.max_sampled_textures_per_shader_stage, 1);
    assert_eq!(rows.max_storage_buffers_per_shader_stage, 1);
    assert_eq!(rows.max_bind_groups, 1);
    // The tile at CELLS' default (3839), the envelope sizes and the resolving entries'
    // `far_sites` flag: WebGPU's 16 KiB exactly; the entries without the flag 4 bytes less.
    assert_eq!(
        edt_tile::tile_columns_resolve::INFO
            .needs
            .max_compute_workgroup_storage_size,
        16384
    );
    assert_eq!(
        edt_tile::tile_columns::INFO
            .needs
            .max_compute_workgroup_storage_size,
        16380
    );
    // Nothing fieldkit ships needs more than WebGPU's defaults.
    for info in fieldkit::shaders::ALL {
        assert_eq!(
            info.needs.lacking(&wgpu::Limits::default()),
            None,
            "{}::{}",
            info.stage,
            info.entry_point
        );
    }
    let low = wgpu::Limits {
        max_compute_workgroup_storage_size: 8192,
        ..wgpu::Limits::default()
    };
    assert_eq!(
        rows.lacking(&low),
        Some(("max_compute_workgroup_storage_size", 11264, 8192))
    );
    assert_eq!(rows.raise(low).max_compute_workgroup_storage_size, 11264);
}

// Host code written against a different shader interface fails to compile: fieldkit's cases
// are in `tests/user-crate/tests/compile_fail/fieldkit`, run by that crate's `tests/drift.rs`
// (one trybuild project for them and the user's own, whose dev-dependencies are few).
