//! A bind group declared once in a shared module (`shaders/shared/frame.wesl`) and used by two
//! stages: generated as `shaders::groups::frame`, made once, handed to both pipelines.

mod common;

use fieldkit::gpu::Context;
use fieldkit_user_crate::shaders::{
    groups::frame,
    scene::{advance, stretch},
};

#[test]
fn one_shared_group_serves_both_pipelines() {
    let ctx = Context::shared();
    // Both pipelines bind group 1 whole, from the shared module, with the same slots.
    assert_eq!(advance::main::INFO.shared_groups, &[1]);
    assert_eq!(stretch::main::INFO.shared_groups, &[1]);
    let slot = |info: &fieldkit::bind::EntryInfo| {
        let s = info.slots.iter().find(|s| s.group == 1).expect("group 1");
        (s.binding, s.name, s.visibility, s.ty)
    };
    assert_eq!(slot(&advance::main::INFO), slot(&stretch::main::INFO));
    assert_eq!(slot(&advance::main::INFO).1, "frame");

    let uniform = common::uniform(
        &ctx,
        "frame",
        &advance::Frame {
            time: 1.5,
            scale: 4.0,
        },
    );
    // A buffer without UNIFORM usage: a typed error naming the group's binding.
    let wrong = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("not a uniform"),
        size: 8,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    match frame::Group::new(
        &ctx.device,
        &frame::Resources {
            frame: (&wrong).into(),
        },
    ) {
        Err(fieldkit::Error::Binding(e)) => {
            assert_eq!((e.stage, e.binding, e.group), ("frame", "frame", 1));
            assert!(e.problem.contains("UNIFORM"), "{}", e.problem);
        }
        other => panic!("expected a binding error, got {:?}", other.err()),
    }
    let group = frame::Group::new(
        &ctx.device,
        &frame::Resources {
            frame: (&uniform).into(),
        },
    )
    .expect("the shared group");

    let values: Vec<f32> = (0..100).map(|i| i as f32).collect();
    let buffer = common::storage(&ctx, "values", &values);
    let advance = advance::main::Pipeline::new(&ctx.device).expect("advance");
    let stretch = stretch::main::Pipeline::new(&ctx.device).expect("stretch");
    let mut encoder = ctx.encoder("shared group");
    let groups = advance::main::Pipeline::groups_for([100, 1, 1]);
    advance
        .record(
            &ctx.device,
            &mut encoder,
            &advance::main::Resources {
                frame: &group,
                values: (&buffer).into(),
            },
            groups,
            "advance",
        )
        .expect("advance binds");
    stretch
        .record(
            &ctx.device,
            &mut encoder,
            &stretch::main::Resources {
                frame: &group,
                values: (&buffer).into(),
            },
            groups,
            "stretch",
        )
        .expect("stretch binds");
    ctx.submit_and_wait("shared group", encoder).unwrap();
    let got = common::read_f32(&ctx, &buffer);
    for (i, &v) in got.iter().enumerate() {
        // (i + 1.5) · 4: exact in f32.
        assert_eq!(v, (i as f32 + 1.5) * 4.0, "value {i}");
    }
}
