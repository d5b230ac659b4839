//! The golden corpus (`shaders/corpus/`, with the crate's other stages): shaders that cover
//! WGSL's binding space — atomics, runtime arrays of padded structs, every sampled and depth
//! texture kind, both samplers, storage textures of each dimension and access, binding arrays
//! of textures, samplers, storage textures and buffers, overrides of every type (with an @id,
//! required, computed), immediates, several entry points in one file, vertex inputs of every
//! 32-bit format per vertex and per instance, integer and float fragment outputs, a shared bind
//! group, imports across files and from the fieldkit package. The crate compiling is the first
//! check (layouts and vertex strides are asserted at compile time); the generated file is
//! snapshotted, so any change to what fieldkit-build writes shows up in review; and every
//! pipeline the adapter can make is made from its generated interface.

use fieldkit::gpu::Context;
use fieldkit_user_crate::shaders::{corpus, ALL};

#[test]
fn generated_bindings_match_the_snapshot() {
    let code = include_str!(concat!(env!("OUT_DIR"), "/shaders.rs"));
    insta::assert_snapshot!("generated_shaders", code);
}

#[test]
fn the_vertex_structs_are_laid_out_as_the_buffers() {
    use corpus::vertex::fs_main::{Instance, Vertex, INFO};
    // 3 + 1 + 2 + 4 floats, 1 + 2 + 3 + 4 uints, 1 + 2 + 3 + 4 ints: 30 four-byte fields.
    assert_eq!(std::mem::size_of::<Vertex>(), 30 * 4);
    assert_eq!(std::mem::size_of::<Instance>(), 4 * 4);
    let fieldkit::bind::EntryKind::Render { vertex_buffers, .. } = INFO.kind else {
        panic!("a render entry point");
    };
    let strides: Vec<u64> = vertex_buffers
        .iter()
        .map(|b| b.as_ref().expect("a buffer").array_stride)
        .collect();
    assert_eq!(strides, vec![120, 16]);
}

/// Every pipeline of the crate whose features the adapter has is made from the generated
/// interface (the overrides stage with its required override set); one whose features the
/// adapter lacks is refused with `Error::Unsupported`.
#[test]
fn every_pipeline_is_made_or_refused_for_its_features() {
    let shared = Context::shared();
    let adapter = shared.adapter.as_ref().expect("an adapter");
    let all_features = adapter.features()
        & (wgpu::Features::TEXTURE_BINDING_ARRAY
            | wgpu::Features::STORAGE_RESOURCE_BINDING_ARRAY
            | wgpu::Features::BUFFER_BINDING_ARRAY
            | wgpu::Features::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING
            | wgpu::Features::IMMEDIATES);
    let (device, _queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("golden corpus"),
        required_features: all_features,
        required_limits: wgpu::Limits {
            max_immediate_size: 64,
            max_binding_array_elements_per_shader_stage: 16,
            ..adapter.limits()
        },
        ..Default::default()
    }))
    .expect("a device");
    let mut made = 0;
    for info in ALL {
        let result = if info.stage == "corpus::overrides" {
            corpus::overrides::main::Pipeline::with_overrides(
                &device,
                &corpus::overrides::Overrides {
                    gain: 2.0,
                    enabled: true,
                    bias: 0,
                    lanes: 64,
                    half: None,
                }
                .constants(),
            )
            .map(|_| ())
        } else {
            fieldkit::bind::create_any(&device, info)
        };
        if device.features().contains(info.required_features()) {
            result.unwrap_or_else(|e| panic!("{}::{}: {e}", info.stage, info.entry_point));
            made += 1;
        } else {
            assert!(
                matches!(result, Err(fieldkit::Error::Unsupported { .. })),
                "{}: {:?}",
                info.stage,
                result.err()
            );
        }
    }
    // Everything but the three binding-array pipelines (math::layers, corpus::arrays,
    // corpus::any_layers) runs on lavapipe too.
    assert!(made >= ALL.len() - 3, "{made} of {}", ALL.len());
}
