//! Stages wherever a project keeps them: a file directly in `shaders/` and one two folders down
//! get bindings at their folder paths, and both run.

mod common;

use fieldkit::gpu::{read_buffer, Context};
use fieldkit_user_crate::shaders::{flat, groups, scene::water::ripple, ALL};
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
    // The nested stage binds the shared group, reached from four modules down.
    let frame = common::uniform(
        &ctx,
        "frame",
        &ripple::Frame {
            time: 0.0,
            scale: 3.0,
        },
    );
    let frame = groups::frame::Group::new(
        &ctx.device,
        &groups::frame::Resources {
            frame: (&frame).into(),
        },
    )
    .unwrap();
    ripple::main::Pipeline::new(&ctx.device)
        .unwrap()
        .record(
            &ctx.device,
            &mut encoder,
            &ripple::main::Resources {
                frame: &frame,
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
    assert_eq!(got, (0..100).map(|i| i * i + 3).collect::<Vec<u32>>());
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

/// A forward renderer's file (a shadow pass's vertex entry, the main one, two fragment entries):
/// every entry gets a pipeline, the shadow pass a depth-only one, and it writes depth.
#[test]
fn every_entry_of_a_forward_renderer_gets_a_pipeline() {
    use fieldkit::bind::RenderTargets;
    use fieldkit_user_crate::shaders::corpus::forward;
    let ctx = Context::shared();
    let depth_state = |write| wgpu::DepthStencilState {
        format: wgpu::TextureFormat::Depth32Float,
        depth_write_enabled: Some(write),
        depth_compare: Some(wgpu::CompareFunction::Always),
        stencil: Default::default(),
        bias: Default::default(),
    };
    let colour = [Some(wgpu::ColorTargetState::from(
        wgpu::TextureFormat::Rgba8Unorm,
    ))];
    let lit = RenderTargets {
        color: &colour,
        depth_stencil: Some(depth_state(false)),
        ..Default::default()
    };
    forward::main_vs_fs_lit::Pipeline::new(&ctx.device, &lit).expect("lit pipeline");
    forward::main_vs_fs_flat::Pipeline::new(&ctx.device, &lit).expect("flat pipeline");
    let shadow = forward::shadow_vs::Pipeline::new(
        &ctx.device,
        &RenderTargets {
            depth_stencil: Some(depth_state(true)),
            ..Default::default()
        },
    )
    .expect("depth-only pipeline");
    let depth = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shadow map"),
        size: wgpu::Extent3d {
            width: 8,
            height: 8,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Depth32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let camera = forward::Camera {
        depth: 0.375,
        tint: glam::Vec3::ONE,
    };
    let mut bytes = encase::UniformBuffer::new(Vec::new());
    bytes.write(&camera).unwrap();
    let camera = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("camera"),
            contents: &bytes.into_inner(),
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let bound = shadow
        .bind(
            &ctx.device,
            &forward::shadow_vs::Resources {
                camera: (&camera).into(),
            },
        )
        .unwrap();
    let mut encoder = ctx.encoder("shadow");
    {
        let view = depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow"),
            color_attachments: &[],
            depth_stencil_attachment: Some(fieldkit::gpu::depth_cleared(&view, 1.0)),
            ..Default::default()
        });
        pass.set_pipeline(&shadow.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..3, 0..1);
    }
    ctx.submit_and_wait("shadow", encoder).unwrap();
    let got: Vec<f32> = fieldkit::gpu::read_texture(&ctx, &depth).unwrap();
    // 0.375 is exact in every depth format's f32.
    assert!(got.iter().all(|&d| d == 0.375), "{got:?}");
}

/// The rule, from the generated list: every entry point of every stage is the entry (or the
/// vertex entry) of a generated pipeline.
#[test]
fn every_entry_point_of_every_stage_has_a_pipeline() {
    use fieldkit::bind::EntryKind;
    let mut stages: Vec<(&str, &str)> = ALL.iter().map(|i| (i.stage, i.source)).collect();
    stages.sort();
    stages.dedup();
    // Every file under shaders/ but shared/ is a stage with pipelines (and build.rs adds one
    // density march): a file whose every entry was dropped would be missing here.
    fn files(dir: &std::path::Path) -> usize {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .map(|p| match p.is_dir() {
                true if p.file_name().unwrap() != "shared" => files(&p),
                true => 0,
                false => usize::from(p.extension().is_some_and(|e| e == "wgsl" || e == "wesl")),
            })
            .sum()
    }
    // The crate's folder (the working directory where the binary runs elsewhere, as on the GPU
    // machine).
    let crate_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let root = if crate_dir.exists() {
        crate_dir.join("shaders")
    } else {
        std::env::current_dir().unwrap().join("shaders")
    };
    assert_eq!(stages.len(), files(&root) + 1, "{stages:?}");
    for (stage, source) in stages {
        let module = wgpu::naga::front::wgsl::parse_str(source).unwrap();
        for ep in &module.entry_points {
            let held = ALL.iter().filter(|i| i.stage == stage).any(|i| {
                i.entry_point == ep.name
                    || matches!(i.kind, EntryKind::Render { vertex, .. } if vertex == ep.name)
            });
            assert!(held, "{stage}: entry point `{}` has no pipeline", ep.name);
        }
    }
}

/// Two variables on one slot, each used by its own entry point: each pipeline's `Resources`
/// and layout hold its own variable (a storage buffer for one, a uniform for the other), and
/// both run on one buffer.
#[test]
fn a_slot_shared_by_two_variables_binds_each_pipelines_own() {
    use fieldkit_user_crate::shaders::corpus::views;
    let ctx = Context::shared();
    let scale = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scale"),
            contents: bytemuck::cast_slice(&[5.0f32, 0.0, 0.0, 0.0]),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM,
        });
    let out = values(&ctx, &[0; 2]);
    let mut encoder = ctx.encoder("views");
    views::from_storage::Pipeline::new(&ctx.device)
        .unwrap()
        .record(
            &ctx.device,
            &mut encoder,
            &views::from_storage::Resources {
                scale_storage: (&scale).into(),
                out: (&out).into(),
            },
            [1, 1, 1],
            "from storage",
        )
        .unwrap();
    views::from_uniform::Pipeline::new(&ctx.device)
        .unwrap()
        .record(
            &ctx.device,
            &mut encoder,
            &views::from_uniform::Resources {
                scale_uniform: (&scale).into(),
                out: (&out).into(),
            },
            [1, 1, 1],
            "from uniform",
        )
        .unwrap();
    ctx.submit_and_wait("views", encoder).unwrap();
    let got: Vec<f32> = bytemuck::cast_slice(&read_buffer(&ctx, &out).unwrap()).to_vec();
    assert_eq!(got, [10.0, 15.0]);
}

/// A struct declared once in `shared/` is one Rust type for every stage that binds it, defined
/// in the generated `shared` module and re-exported by each stage.
#[test]
fn a_shared_struct_is_one_type() {
    use fieldkit_user_crate::shaders::{scene, shared};
    let a: scene::advance::Frame = scene::stretch::Frame {
        time: 1.0,
        scale: 2.0,
    };
    let b: shared::frame::Frame = a;
    assert_eq!(
        b,
        shared::frame::Frame {
            time: 1.0,
            scale: 2.0
        }
    );
}

/// A struct that is both a vertex input and a storage buffer's element gets its Rust type (it
/// was left out as an interface struct, and the buffer's `Resources` field named a type that
/// did not exist).
#[test]
fn a_vertex_struct_in_a_buffer_has_its_type() {
    use fieldkit_user_crate::shaders::corpus::particles;
    let p = particles::Particle {
        position: glam::Vec4::ONE,
        velocity: glam::Vec4::ZERO,
    };
    assert_eq!(
        <particles::Particle as encase::ShaderType>::min_size().get(),
        32
    );
    let _: fn(&particles::advance::Resources<'_>) = |r| {
        let _ = &r.particles;
    };
    assert_eq!(p.position.x, 1.0);
}

/// Vertex inputs declared in packed formats (`// vertex: snorm16x2`, `unorm8x4`, `uint8`,
/// `float16x2, instance`) reach the shader as those formats: a triangle made of 16-bit
/// positions, scaled per instance by half floats to cover the target, writes the byte colour
/// and tag it was given, exactly (unorm8 → f32 → unorm8 is exact).
#[test]
fn declared_vertex_formats_draw_what_the_buffers_hold() {
    use fieldkit::bind::RenderTargets;
    use fieldkit_user_crate::shaders::corpus::packed::fs_main::{
        Instance, Pipeline, Resources, Vertex,
    };
    let ctx = Context::shared();
    let colour = [
        Some(wgpu::ColorTargetState::from(
            wgpu::TextureFormat::Rgba8Unorm,
        )),
        Some(wgpu::ColorTargetState::from(wgpu::TextureFormat::R32Uint)),
    ];
    let pipeline = Pipeline::new(
        &ctx.device,
        &RenderTargets {
            color: &colour,
            ..Default::default()
        },
    )
    .expect("packed pipeline");
    let corner = |x: i16, y: i16| Vertex {
        position: [x, y],
        color: [255, 128, 0, 255],
        tag: 7,
        ..Default::default()
    };
    // snorm16: 32767 is 1; the half-float 4.0 scales the unit triangle to (0..4) − 1 in clip
    // space, which covers the whole target.
    let vertices = [corner(0, 0), corner(32767, 0), corner(0, 32767)];
    let instance = Instance {
        scale: [half::f16::from_f32(4.0).to_bits(); 2],
    };
    let buffer = |label, bytes: &[u8]| {
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::VERTEX,
            })
    };
    let vertex_buffer = buffer("vertices", bytemuck::cast_slice(&vertices));
    let instance_buffer = buffer("instance", bytemuck::bytes_of(&instance));
    let (rgba, tags) = (
        common::target(&ctx, 4, 4, wgpu::TextureFormat::Rgba8Unorm),
        common::target(&ctx, 4, 4, wgpu::TextureFormat::R32Uint),
    );
    let bound = pipeline
        .bind(
            &ctx.device,
            &Resources {
                _marker: core::marker::PhantomData,
            },
        )
        .unwrap();
    let mut encoder = ctx.encoder("packed");
    {
        let views = [
            rgba.create_view(&Default::default()),
            tags.create_view(&Default::default()),
        ];
        let mut pass = common::colour_pass(&mut encoder, &views, wgpu::Color::TRANSPARENT);
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.set_vertex_buffer(0, vertex_buffer.slice(..));
        pass.set_vertex_buffer(1, instance_buffer.slice(..));
        pass.draw(0..3, 0..1);
    }
    ctx.submit_and_wait("packed", encoder).unwrap();
    let got: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, &rgba).unwrap();
    assert!(got.iter().all(|&c| c == [255, 128, 0, 255]), "{got:?}");
    let got: Vec<u32> = fieldkit::gpu::read_texture(&ctx, &tags).unwrap();
    assert!(got.iter().all(|&t| t == 7), "{got:?}");
}

/// A fragment entry alone in its file draws with another file's vertex entry it names in a
/// `// draw with:` line: one pipeline, its `Resources` the union of both files' bindings (the
/// vertex file's camera, the fragment file's tint), each read by its own stage.
#[test]
fn a_fragment_file_draws_with_another_files_vertex_entry() {
    use fieldkit::bind::RenderTargets;
    use fieldkit_user_crate::shaders::corpus::{pair_frag, pair_vert};
    use pair_frag::fs_main::{Pipeline, Resources, Vertex};
    let ctx = Context::shared();
    let colour = [Some(wgpu::ColorTargetState::from(
        wgpu::TextureFormat::Rgba8Unorm,
    ))];
    let pipeline = Pipeline::new(
        &ctx.device,
        &RenderTargets {
            color: &colour,
            ..Default::default()
        },
    )
    .expect("pipeline of two files");
    // The triangle's corners are (0,0), (2,0), (0,2): moved by −1 it covers the left, lower
    // half of clip space's square, and exactly the texels below the diagonal.
    let camera = common::uniform(
        &ctx,
        "camera",
        &pair_vert::Camera {
            offset: glam::Vec2::splat(-1.0),
        },
    );
    let tint = common::uniform(
        &ctx,
        "tint",
        &pair_frag::Tint {
            color: glam::Vec4::new(1.0, 0.0, 1.0, 1.0),
        },
    );
    let bound = pipeline
        .bind(
            &ctx.device,
            &Resources {
                camera: (&camera).into(),
                tint: (&tint).into(),
            },
        )
        .unwrap();
    let corners = [
        Vertex { corner: [0.0, 0.0] },
        Vertex { corner: [2.0, 0.0] },
        Vertex { corner: [0.0, 2.0] },
    ];
    let corners = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("corners"),
            contents: bytemuck::cast_slice(&corners),
            usage: wgpu::BufferUsages::VERTEX,
        });
    let target = common::target(&ctx, 4, 4, wgpu::TextureFormat::Rgba8Unorm);
    let mut encoder = ctx.encoder("pair");
    {
        let views = [target.create_view(&Default::default())];
        let mut pass = common::colour_pass(&mut encoder, &views, wgpu::Color::BLACK);
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.set_vertex_buffer(0, corners.slice(..));
        pass.draw(0..3, 0..1);
    }
    ctx.submit_and_wait("pair", encoder).unwrap();
    let got: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, &target).unwrap();
    // Texel (x, y), y down, has its centre at clip ((x + ½)/2 − 1, 1 − (y + ½)/2): inside the
    // triangle (x + y < 0 in clip space) where x < y.
    for (i, c) in got.iter().enumerate() {
        let (x, y) = (i % 4, i / 4);
        let want = if x < y {
            [255, 0, 255, 255]
        } else if x > y {
            [0, 0, 0, 255]
        } else {
            *c // on the diagonal: the rasterizer's tie rule decides
        };
        assert_eq!(*c, want, "texel ({x}, {y}) of {got:?}");
    }
    assert!(got.contains(&[255, 0, 255, 255]) && got.contains(&[0, 0, 0, 255]));
}
