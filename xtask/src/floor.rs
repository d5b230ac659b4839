//! What a pass costs before it does any work: `bench voxelize --modes empty,zeroed,cleared`
//! times an empty compute pass the way every other row is timed (`Stamps::time_after`: encoder
//! timestamps around everything recorded), with as many threads as the mesh has triangles.
//! `empty` binds a buffer made once. `zeroed` binds a new buffer of the grid's bitset size each
//! run, as `encode_surface` does: wgpu zero-fills it at submission in a command buffer of its
//! own ahead of the recorded one, so outside the timestamps (on the H100 `zeroed` reads the
//! same at 1024³, a 103 MB bitset, as at 128³). `cleared` records the clear
//! (`clear_buffer`) before the pass, inside them: what that zeroing costs the GPU. `loaded`
//! binds the buffer made once, and each thread reads one word of it (as each surface thread
//! reads its list entry) and writes nothing. A surface row minus `empty` is the surface pass's
//! own work; `empty` itself is what no single-pass voxelizer through wgpu gets under on that
//! adapter. `FIELDKIT_BENCH_FLOOR_THREADS=174000` gives the floor rows that many threads
//! instead of one a triangle (the surface pass at 256³ runs one a light triangle and one a
//! heavy triangle's chunk: 174 k on the Stanford bunny). `scripts/cuda_launch_floor.py` times the
//! same empty kernel through CUDA the way the peers' README times cuda_voxelizer (CUDA events,
//! median of 40 after 20 warm-ups), with and without a memset of the bitset.

use fieldkit::gpu::Context;

/// A bench utility, like the heater's spin kernel, not a library stage.
const EMPTY: &str = r#"
@group(0) @binding(0) var<storage, read_write> words: array<u32>;

@compute @workgroup_size(64)
fn empty(@builtin(global_invocation_id) id: vec3<u32>) {
    // Never true for the threads dispatched; keeps the binding.
    if id.x == 0xffffffffu {
        words[0] = 1u;
    }
}

@compute @workgroup_size(64)
fn loaded(@builtin(global_invocation_id) id: vec3<u32>) {
    // One word a thread (threads past the buffer's end read its last word); the buffer is
    // zeroed, so never true.
    if words[min(id.x, arrayLength(&words) - 1u)] == 0xffffffffu {
        words[0] = 1u;
    }
}
"#;

pub(crate) struct EmptyPass {
    empty: wgpu::ComputePipeline,
    loaded: wgpu::ComputePipeline,
}

impl EmptyPass {
    pub(crate) fn new(ctx: &Context) -> Self {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("bench empty pass"),
                source: wgpu::ShaderSource::Wgsl(EMPTY.into()),
            });
        let pipeline = |entry: &str| {
            ctx.device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some("bench empty pass"),
                    layout: None,
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
        };
        Self {
            empty: pipeline("empty"),
            loaded: pipeline("loaded"),
        }
    }

    /// A storage buffer of `bytes` (at least 4), new and so zero-filled by wgpu at its first
    /// use.
    pub(crate) fn buffer(ctx: &Context, bytes: u64) -> wgpu::Buffer {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bench empty pass words"),
            size: bytes.max(4).next_multiple_of(4),
            // COPY_DST: `cleared` clears it.
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// One pass of `threads` threads (in workgroups of 64, at most 65535 of them) that binds
    /// `words` and does nothing, or with `load` reads one word of it a thread.
    pub(crate) fn record(
        &self,
        ctx: &Context,
        enc: &mut wgpu::CommandEncoder,
        words: &wgpu::Buffer,
        threads: u64,
        load: bool,
    ) -> Result<(), String> {
        let pipeline = if load { &self.loaded } else { &self.empty };
        let groups = threads.div_ceil(64).max(1);
        if groups > 65535 {
            return Err(format!(
                "empty pass: {threads} threads need {groups} workgroups, over 65535"
            ));
        }
        let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bench empty pass"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: words.as_entire_binding(),
            }],
        });
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bench empty pass"),
            timestamp_writes: None,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups(groups as u32, 1, 1);
        Ok(())
    }
}
