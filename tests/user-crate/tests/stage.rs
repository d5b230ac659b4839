//! The user's own stage, built by fieldkit-build and bound through fieldkit's runtime, run on
//! the default adapter (lavapipe in CI) and checked against what it computes on the CPU.

use fieldkit::gpu::{read_buffer, Context};
use fieldkit_user_crate::shaders::{
    math::{scale, seeds},
    ALL,
};
use wgpu::util::DeviceExt as _;

/// A uniform buffer holding `value`, laid out by encase as the generated struct says.
fn uniform<T: encase::ShaderType + encase::internal::WriteInto>(
    ctx: &Context,
    label: &str,
    value: &T,
) -> wgpu::Buffer {
    let mut bytes = encase::UniformBuffer::new(Vec::new());
    bytes.write(value).unwrap();
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: &bytes.into_inner(),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

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
    let params_buffer = uniform(&ctx, "params", &params);
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
    // The generated list names the user's files, not fieldkit's.
    assert_eq!(ALL.len(), 2);
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
    let grid_buffer = uniform(&ctx, "grid", &grid);
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
