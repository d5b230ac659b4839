//! The user's own stage, built by fieldkit-build and bound through fieldkit's runtime, run on
//! the default adapter (lavapipe in CI) and checked against what it computes on the CPU.

use fieldkit::gpu::{read_buffer, Context};
use fieldkit_user_crate::shaders::{math::scale, ALL};
use wgpu::util::DeviceExt as _;

#[test]
fn the_users_stage_runs_with_typed_bindings_and_overrides() {
    let ctx = Context::shared();
    // The shader's default offset is 0.0; this pipeline sets 0.5 through the typed overrides.
    assert_eq!(
        scale::Overrides::default(),
        scale::Overrides { offset: 0.0 }
    );
    let pipeline = scale::main::Pipeline::with_overrides(
        &ctx.device,
        &scale::Overrides { offset: 0.5 }.constants(),
    )
    .expect("the user's pipeline");
    let params = scale::Params {
        factor: 3.0,
        count: 100,
    };
    let mut uniform = encase::UniformBuffer::new(Vec::new());
    uniform.write(&params).unwrap();
    let params_buffer = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("params"),
            contents: &uniform.into_inner(),
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let values: Vec<f32> = (0..128).map(|i| i as f32).collect();
    let values_buffer = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("values"),
            contents: bytemuck::cast_slice(&values),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
    let mut encoder = ctx.encoder("scale");
    pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &scale::main::Resources {
                params: (&params_buffer).into(),
                values: (&values_buffer).into(),
            },
            scale::main::Pipeline::groups_for([128, 1, 1]),
            "scale",
        )
        .expect("binds");
    ctx.submit_and_wait("scale", encoder).unwrap();
    let got: Vec<f32> = bytemuck::cast_slice(&read_buffer(&ctx, &values_buffer).unwrap()).to_vec();
    for (i, &v) in got.iter().enumerate() {
        // Exact in f32: small integers times 3, plus 0.5.
        let want = if i < 100 {
            i as f32 * 3.0 + 0.5
        } else {
            i as f32
        };
        assert_eq!(v, want, "value {i}");
    }
    // The generated list names the user's file, not fieldkit's.
    assert_eq!(ALL.len(), 1);
    assert_eq!(scale::PATH, "shaders/math/scale.wgsl");
}

/// A resource of the wrong kind is a typed error naming the stage and binding, as in fieldkit.
#[test]
fn a_small_uniform_is_a_typed_error() {
    let ctx = Context::shared();
    let pipeline = scale::main::Pipeline::new(&ctx.device).unwrap();
    let tiny = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 4,
        usage: wgpu::BufferUsages::UNIFORM,
        mapped_at_creation: false,
    });
    let values = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 64,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.encoder("scale");
    let err = pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &scale::main::Resources {
                params: (&tiny).into(),
                values: (&values).into(),
            },
            [1, 1, 1],
            "scale",
        )
        .unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("math::scale") && text.contains("params"),
        "{text}"
    );
}
