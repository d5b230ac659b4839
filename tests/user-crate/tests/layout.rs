//! Stages wherever a project keeps them: a file directly in `shaders/` and one two folders down
//! get bindings at their folder paths, and both run.

use fieldkit::gpu::{read_buffer, Context};
use fieldkit_user_crate::shaders::{flat, scene::water::ripple, ALL};
use wgpu::util::DeviceExt as _;

fn values(ctx: &Context, v: &[u32]) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("values"),
            contents: bytemuck::cast_slice(v),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        })
}

#[test]
fn flat_and_nested_stages_are_built_and_run() {
    assert_eq!(flat::PATH, "shaders/flat.wgsl");
    assert_eq!(flat::STAGE, "flat");
    assert_eq!(ripple::PATH, "shaders/scene/water/ripple.wgsl");
    assert_eq!(ripple::STAGE, "scene::water::ripple");
    for info in [&flat::main::INFO, &ripple::main::INFO] {
        assert!(
            ALL.iter().any(|i| std::ptr::eq(*i, info)),
            "{} not in ALL",
            info.stage
        );
    }
    let ctx = Context::shared();
    let start: Vec<u32> = (0..100).map(|i| 7 * i).collect();
    let a = values(&ctx, &start);
    let b = values(&ctx, &[0; 100]);
    let mut encoder = ctx.encoder("layout");
    flat::main::Pipeline::new(&ctx.device)
        .unwrap()
        .record(
            &ctx.device,
            &mut encoder,
            &flat::main::Resources {
                values: (&a).into(),
            },
            flat::main::Pipeline::groups_for([100, 1, 1]),
            "flat",
        )
        .unwrap();
    ripple::main::Pipeline::new(&ctx.device)
        .unwrap()
        .record(
            &ctx.device,
            &mut encoder,
            &ripple::main::Resources {
                heights: (&b).into(),
            },
            ripple::main::Pipeline::groups_for([100, 1, 1]),
            "ripple",
        )
        .unwrap();
    ctx.submit_and_wait("layout", encoder).unwrap();
    let got: Vec<u32> = bytemuck::cast_slice(&read_buffer(&ctx, &a).unwrap()).to_vec();
    assert_eq!(got, (0..100).map(|i| 7 * i + 1).collect::<Vec<u32>>());
    let got: Vec<u32> = bytemuck::cast_slice(&read_buffer(&ctx, &b).unwrap()).to_vec();
    assert_eq!(got, (0..100).map(|i| i * i).collect::<Vec<u32>>());
}

/// `@workgroup_size(BLOCK)` with `override BLOCK`: the generated size and groups follow the
/// value given, the pipeline made with it dispatches enough groups of that size, and a size
/// past the device's limits is a typed error when the pipeline is made.
#[test]
fn a_workgroup_sized_by_an_override_dispatches_at_that_size() {
    use fieldkit_user_crate::shaders::math::blocks;
    let sixteen = blocks::Overrides { block: 16 };
    assert_eq!(blocks::main::WORKGROUP_SIZE, [64, 1, 1]);
    assert_eq!(blocks::main::workgroup_size(&sixteen), [16, 1, 1]);
    assert_eq!(blocks::main::groups_for(&sixteen, [100, 1, 1]), [7, 1, 1]);
    assert_eq!(
        blocks::main::INFO
            .needs
            .max_compute_invocations_per_workgroup,
        64
    );
    let ctx = Context::shared();
    let pipeline =
        blocks::main::Pipeline::with_overrides(&ctx.device, &sixteen.constants()).unwrap();
    assert_eq!(pipeline.workgroup_size(), [16, 1, 1]);
    let out = values(&ctx, &[u32::MAX; 100]);
    let mut encoder = ctx.encoder("blocks");
    pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &blocks::main::Resources {
                values: (&out).into(),
            },
            pipeline.groups([100, 1, 1]),
            "blocks",
        )
        .unwrap();
    ctx.submit_and_wait("blocks", encoder).unwrap();
    let got: Vec<u32> = bytemuck::cast_slice(&read_buffer(&ctx, &out).unwrap()).to_vec();
    let want: Vec<u32> = (0..100).map(|i| (i / 16) * 1000 + i % 16).collect();
    assert_eq!(got, want);
    let huge = blocks::Overrides { block: 1 << 20 };
    match blocks::main::Pipeline::with_overrides(&ctx.device, &huge.constants()) {
        Err(fieldkit::Error::Unsupported { what, .. }) => {
            assert!(what.contains("workgroup size"), "{what}")
        }
        other => panic!("a 2^20 workgroup: {:?}", other.map(|_| ())),
    }
}
