//! The user's own stage, built by fieldkit-build and bound through fieldkit's runtime, run on
//! the default adapter (lavapipe in CI) and checked against what it computes on the CPU.

mod common;

use fieldkit::gpu::{read_buffer, Context};
use fieldkit_user_crate::shaders::{
    math::{layers, push, scale, seeds},
    ALL,
};
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
    let params_buffer = common::uniform(&ctx, "params", &params);
    let values: Vec<f32> = (0..128).map(|i| i as f32).collect();
    let values_buffer = common::storage(&ctx, "values", &values);
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
    let got = common::read_f32(&ctx, &values_buffer);
    for (i, &v) in got.iter().enumerate() {
        // Exact in f32: small integers times 3, plus 0.5.
        let want = if i < 100 {
            i as f32 * 3.0 + 0.5
        } else {
            i as f32
        };
        assert_eq!(v, want, "value {i}");
    }
    // The generated list names the user's files, not fieldkit's (and the three entry points
    // of the density march build.rs asks for).
    assert_eq!(ALL.len(), 30);
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

/// The user's stage imports fieldkit's own seed packing (`import fieldkit::seed::…`, the
/// `fieldkit-wesl` package that fieldkit-build adds to every link): the packed seeds it writes
/// are the ones fieldkit's host code packs, and they unpack to the voxel again.
#[test]
fn the_users_stage_packs_seeds_with_fieldkits_helpers() {
    let ctx = Context::shared();
    let pipeline = seeds::main::Pipeline::new(&ctx.device).expect("the user's pipeline");
    let size = [37u32, 29, 23];
    let count = (size[0] * size[1] * size[2]) as usize;
    let grid = seeds::Grid {
        size: size.into(),
        every: 3,
    };
    let grid_buffer = common::uniform(&ctx, "grid", &grid);
    let storage = |label: &str, bytes: u64| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    };
    let packed = storage("packed", count as u64 * 4);
    let unpacked = storage("unpacked", count as u64 * 16);
    let mut encoder = ctx.encoder("seeds");
    pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &seeds::main::Resources {
                grid: (&grid_buffer).into(),
                packed: (&packed).into(),
                unpacked: (&unpacked).into(),
            },
            seeds::main::Pipeline::groups_for([count as u32, 1, 1]),
            "seeds",
        )
        .expect("binds");
    ctx.submit_and_wait("seeds", encoder).unwrap();
    let packed: Vec<u32> = bytemuck::cast_slice(&read_buffer(&ctx, &packed).unwrap()).to_vec();
    let unpacked: Vec<[i32; 4]> =
        bytemuck::cast_slice(&read_buffer(&ctx, &unpacked).unwrap()).to_vec();
    for i in 0..count {
        let v = [
            i as u32 % size[0],
            (i as u32 / size[0]) % size[1],
            i as u32 / (size[0] * size[1]),
        ];
        if i % 3 == 0 {
            assert_eq!(
                packed[i],
                fieldkit::distance::pack_seed3(v[0], v[1], v[2]),
                "voxel {i}"
            );
            assert_eq!(
                fieldkit::distance::unpack_seed3(packed[i]),
                Some(v),
                "voxel {i}"
            );
            assert_eq!(
                unpacked[i],
                [v[0] as i32, v[1] as i32, v[2] as i32, 0],
                "voxel {i}"
            );
        } else {
            assert_eq!(packed[i], fieldkit::distance::NO_SEED, "voxel {i}");
            assert_eq!(unpacked[i], [-1; 4], "voxel {i}");
        }
    }
}

/// An immediate block (push constants) in the user's own shader: the generated code gives its
/// size and the feature, and the stage runs with the block set on the pass from the generated
/// struct, exactly as the CPU computes it.
#[test]
fn immediates_run_with_the_generated_struct() {
    let shared = Context::shared();
    let info = &push::main::INFO;
    assert_eq!(info.required_features(), wgpu::Features::IMMEDIATES);
    assert_eq!(push::main::IMMEDIATE_SIZE, 12);
    assert_eq!(info.immediate_size, 12);
    // The shared context does not ask for immediates: a typed error, not a wgpu panic.
    match push::main::Pipeline::new(&shared.device) {
        Err(fieldkit::Error::Unsupported { what, .. }) => {
            assert!(what.contains("IMMEDIATES"), "{what}")
        }
        other => panic!("expected Error::Unsupported, got {:?}", other.err()),
    }
    // The generated limits: WebGPU's defaults with room for the immediates.
    assert_eq!(push::main::required_limits().max_immediate_size, 12);
    let ctx = device_with(&shared, info.required_features(), |_| {
        push::main::required_limits()
    });
    let pipeline = push::main::Pipeline::new(&ctx.device).expect("the user's pipeline");
    let values: Vec<f32> = (0..100).map(|i| i as f32).collect();
    let buffer = common::storage(&ctx, "values", &values);
    let block = push::Push {
        scale: 0.25,
        offset: -3.0,
        count: 90,
    };
    let mut bytes = encase::StorageBuffer::new(Vec::new());
    bytes.write(&block).unwrap();
    let bytes = bytes.into_inner();
    assert_eq!(bytes.len(), 12);
    let bound = pipeline
        .bind(
            &ctx.device,
            &push::main::Resources {
                values: (&buffer).into(),
            },
        )
        .expect("binds");
    let mut encoder = ctx.encoder("push");
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_compute(&mut pass);
        pass.set_immediates(0, &bytes);
        let g = push::main::Pipeline::groups_for([100, 1, 1]);
        pass.dispatch_workgroups(g[0], g[1], g[2]);
    }
    ctx.submit_and_wait("push", encoder).unwrap();
    let got = common::read_f32(&ctx, &buffer);
    for (i, &v) in got.iter().enumerate() {
        // Quarters of small integers less 3: exact in f32.
        let want = if i < 90 {
            i as f32 * 0.25 - 3.0
        } else {
            i as f32
        };
        assert_eq!(v, want, "value {i}");
    }
}

/// A device on the shared context's adapter with `features` and the limits `limits` makes of
/// the adapter's: the test fails, saying what is missing, where the adapter lacks them.
fn device_with(
    shared: &Context,
    features: wgpu::Features,
    limits: impl FnOnce(wgpu::Limits) -> wgpu::Limits,
) -> Context {
    let adapter = shared
        .adapter
        .as_ref()
        .expect("Context::shared opens an adapter");
    assert!(
        adapter.features().contains(features),
        "the adapter ({}) lacks {:?}",
        adapter.get_info().name,
        features - adapter.features()
    );
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("user crate, native features"),
        required_features: features,
        required_limits: limits(adapter.limits()),
        ..Default::default()
    }))
    .expect("a device with the features the shader needs");
    Context::from_device(device, queue)
}

/// A binding array of textures in the user's own shader: the generated code names the features
/// it needs (naga's uniformity analysis, which wgpu validates with, counts the loop counter
/// that indexes it as non-uniform), and a device without them gets a typed error instead of a
/// wgpu validation panic. Where the adapter has them (NVIDIA, AMD, Intel, Apple; not the
/// lavapipe of Debian's Mesa 22.3, which lacks the descriptor indexing wgpu asks for), the
/// stage also runs: a wrong count is a binding error, and each texel weighs the layers exactly
/// as the CPU does.
#[test]
fn binding_arrays_say_what_they_need_and_run_where_the_device_has_it() {
    let shared = Context::shared();
    let info = &layers::main::INFO;
    let needed = info.required_features();
    assert_eq!(
        needed,
        wgpu::Features::TEXTURE_BINDING_ARRAY
            | wgpu::Features::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING
    );
    assert_eq!(info.slots[0].count.map(|c| c.get()), Some(3));
    match layers::main::Pipeline::new(&shared.device) {
        Err(fieldkit::Error::Unsupported { what, .. }) => {
            assert!(what.contains("TEXTURE_BINDING_ARRAY"), "{what}")
        }
        other => panic!("expected Error::Unsupported, got {:?}", other.err()),
    }
    let adapter = shared.adapter.as_ref().expect("an adapter");
    if !adapter.features().contains(needed) {
        eprintln!(
            "{} lacks {:?}: binding arrays checked for their typed error only",
            adapter.get_info().name,
            needed - adapter.features()
        );
        return;
    }
    assert_eq!(
        layers::main::required_limits().max_binding_array_elements_per_shader_stage,
        3
    );
    let ctx = device_with(&shared, needed, |_| layers::main::required_limits());
    let pipeline = layers::main::Pipeline::new(&ctx.device).expect("the user's pipeline");
    let [w, h] = [11u32, 5];
    let texel = |k: u32, x: u32, y: u32| (k * 100 + y * w + x) as f32 * 0.25;
    let views = common::float_layers(&ctx, 3, [w, h], texel);
    let view_refs: Vec<&wgpu::TextureView> = views.iter().collect();
    let sums = common::output(&ctx, (w * h * 4) as u64);
    match pipeline.bind(
        &ctx.device,
        &layers::main::Resources {
            layers: view_refs[..2].into(),
            sums: (&sums).into(),
        },
    ) {
        Err(fieldkit::Error::Binding(e)) => {
            assert_eq!(e.binding, "layers");
            assert!(
                e.problem.contains("2 resources bound") && e.problem.contains("holds 3"),
                "{}",
                e.problem
            );
        }
        other => panic!("expected a binding error, got {:?}", other.err()),
    }
    let mut encoder = ctx.encoder("layers");
    pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &layers::main::Resources {
                layers: view_refs[..].into(),
                sums: (&sums).into(),
            },
            layers::main::Pipeline::groups_for([w, h, 1]),
            "layers",
        )
        .expect("binds");
    ctx.submit_and_wait("layers", encoder).unwrap();
    let got = common::read_f32(&ctx, &sums);
    for y in 0..h {
        for x in 0..w {
            // Quarters of small integers weighted by 1, 2 and 3: exact in f32.
            let want = texel(0, x, y) + 2.0 * texel(1, x, y) + 3.0 * texel(2, x, y);
            assert_eq!(got[(y * w + x) as usize], want, "texel ({x}, {y})");
        }
    }
}

/// A uniform with a dynamic offset (`Builder::dynamic_offset("math::scale::params")` in the
/// build script): one buffer holds two parameter blocks, and each dispatch picks its block by
/// offset; the wrong number of offsets is a typed error.
#[test]
fn a_dynamic_offset_picks_the_uniform_block() {
    let ctx = Context::shared();
    let slot = &scale::main::INFO.slots[0];
    assert!(matches!(
        slot.ty,
        wgpu::BindingType::Buffer {
            has_dynamic_offset: true,
            ..
        }
    ));
    let pipeline = scale::main::Pipeline::new(&ctx.device).expect("the user's pipeline");
    let stride = ctx.device.limits().min_uniform_buffer_offset_alignment as usize;
    let blocks = [
        scale::Params {
            factor: 3.0,
            count: 100,
        },
        scale::Params {
            factor: 2.0,
            count: 40,
        },
    ];
    let mut bytes = vec![0u8; stride * 2];
    for (k, block) in blocks.iter().enumerate() {
        let mut one = encase::UniformBuffer::new(Vec::new());
        one.write(block).unwrap();
        let one = one.into_inner();
        bytes[k * stride..k * stride + one.len()].copy_from_slice(&one);
    }
    let params = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("two parameter blocks"),
            contents: &bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        });
    let values: Vec<f32> = (0..64).map(|i| i as f32).collect();
    let buffer = common::storage(&ctx, "values", &values);
    let bound = pipeline
        .bind(
            &ctx.device,
            &scale::main::Resources {
                // One block's worth: the dynamic offset moves it.
                params: fieldkit::bind::Uniform::range(&params, 0, std::num::NonZeroU64::new(8)),
                values: (&buffer).into(),
            },
        )
        .expect("binds");
    assert_eq!(bound.dynamic_offsets(), 1);
    let mut encoder = ctx.encoder("dynamic");
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline.pipeline);
        match bound.set_compute_with_offsets(&mut pass, &[]) {
            Err(fieldkit::Error::Invalid { what, .. }) => {
                assert!(
                    what.contains("0 dynamic offsets given") && what.contains("take 1"),
                    "{what}"
                )
            }
            other => panic!("expected Error::Invalid, got {other:?}"),
        }
        bound
            .set_compute_with_offsets(&mut pass, &[stride as u32])
            .expect("one offset");
        pass.dispatch_workgroups(1, 1, 1);
    }
    ctx.submit_and_wait("dynamic", encoder).unwrap();
    let got = common::read_f32(&ctx, &buffer);
    for (i, &v) in got.iter().enumerate() {
        // The second block: the first 40 values doubled (exact), the rest untouched.
        let want = if i < 40 { i as f32 * 2.0 } else { i as f32 };
        assert_eq!(v, want, "value {i}");
    }
}

/// An unsized binding array (`binding_array<texture_2d<f32>>`, `corpus/any_layers.wgsl`): its
/// length is given when the pipeline is made, through the generated `ArrayCounts`. Without a
/// length, or with 0, making the pipeline is a typed error naming the array on any device; a
/// length past the device's limit is `Error::Unsupported`. Where the adapter has binding arrays
/// (not the lavapipe of Debian's Mesa 22.3, see above) the stage runs at the length given, and
/// binding another number of textures is a binding error.
#[test]
fn unsized_binding_arrays_take_their_length_when_the_pipeline_is_made() {
    use fieldkit_user_crate::shaders::corpus::any_layers::main::{
        self as stage, ArrayCounts, Pipeline, Resources, INFO,
    };
    let shared = Context::shared();
    assert!(INFO.slots[0].unsized_array && INFO.slots[0].count.is_none());
    for made in [
        Pipeline::new(&shared.device),
        Pipeline::with_counts(&shared.device, &ArrayCounts { layers: 0 }),
    ] {
        match made {
            Err(fieldkit::Error::Invalid { what, .. }) => assert!(
                what.contains("`layers` is an unsized binding array")
                    && what.contains("with_counts"),
                "{what}"
            ),
            other => panic!("expected Error::Invalid, got {:?}", other.err()),
        }
    }
    let needed = INFO.required_features();
    let adapter = shared.adapter.as_ref().expect("an adapter");
    if !adapter.features().contains(needed) {
        match Pipeline::with_counts(&shared.device, &ArrayCounts { layers: 4 }) {
            // The length past the device's limit, or (where the limit allows it) the features.
            Err(fieldkit::Error::Unsupported { what, .. }) => assert!(
                what.contains("max_binding_array_elements_per_shader_stage")
                    || what.contains("TEXTURE_BINDING_ARRAY"),
                "{what}"
            ),
            other => panic!("expected Error::Unsupported, got {:?}", other.err()),
        }
        eprintln!(
            "{} lacks {:?}: unsized binding arrays checked for their typed errors only",
            adapter.get_info().name,
            needed - adapter.features()
        );
        return;
    }
    let ctx = device_with(&shared, needed, |_| {
        let mut limits = stage::required_limits();
        limits.max_binding_array_elements_per_shader_stage = 4;
        limits
    });
    match Pipeline::with_counts(&ctx.device, &ArrayCounts { layers: 5 }) {
        Err(fieldkit::Error::Unsupported { what, .. }) => assert!(what.contains("(4)"), "{what}"),
        other => panic!("expected Error::Unsupported, got {:?}", other.err()),
    }
    let [w, h] = [9u32, 6];
    let texel = |k: u32, x: u32, y: u32| (k * 100 + y * w + x) as f32 * 0.5;
    let views = common::float_layers(&ctx, 4, [w, h], texel);
    let views: Vec<&wgpu::TextureView> = views.iter().collect();
    for n in [4u32, 2] {
        let pipeline =
            Pipeline::with_counts(&ctx.device, &ArrayCounts { layers: n }).expect("made");
        let sums = common::output(&ctx, (w * h * 4) as u64);
        let count = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("count"),
                contents: bytemuck::bytes_of(&n),
                usage: wgpu::BufferUsages::UNIFORM,
            });
        let other = if n == 4 { &views[..3] } else { &views[..] };
        match pipeline.bind(
            &ctx.device,
            &Resources {
                layers: other.into(),
                sums: (&sums).into(),
                count: (&count).into(),
            },
        ) {
            Err(fieldkit::Error::Binding(e)) => assert!(
                e.problem
                    .contains(&format!("the pipeline was made with a length of {n}")),
                "{}",
                e.problem
            ),
            other => panic!("expected a binding error, got {:?}", other.err()),
        }
        let mut encoder = ctx.encoder("any layers");
        pipeline
            .record(
                &ctx.device,
                &mut encoder,
                &Resources {
                    layers: views[..n as usize].into(),
                    sums: (&sums).into(),
                    count: (&count).into(),
                },
                Pipeline::groups_for([w, h, 1]),
                "any layers",
            )
            .expect("binds");
        ctx.submit_and_wait("any layers", encoder).unwrap();
        let got = common::read_f32(&ctx, &sums);
        for y in 0..h {
            for x in 0..w {
                // Halves of small integers times small integers: exact in f32.
                let want: f32 = (0..n).map(|k| texel(k, x, y) * (k + 1) as f32).sum();
                assert_eq!(
                    got[(y * w + x) as usize],
                    want,
                    "{n} layers, texel ({x}, {y})"
                );
            }
        }
    }
}
