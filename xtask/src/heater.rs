//! Keeps the GPU at full clocks between timed runs whose CPU side leaves it mostly idle.
//!
//! The voxelize benchmark transforms and uploads the mesh on the CPU for every run, so the GPU
//! sits idle most of the time and its clock governor lowers the SM clock: on the H100 it fell
//! from 1980 to 345 MHz within seconds of such a loop (`nvidia-smi`), and the split bunny's
//! surface pass read 0.11 to 0.48 ms by what the process had run before it. The heater runs a
//! spin kernel for a set time, waited for, after the timed run is encoded and before it is
//! submitted, so the timed work starts on a GPU that has just been busy. It is outside the
//! timestamps and does not share the GPU with the timed work.

use fieldkit::gpu::{Context, Timer};

/// A bench utility, not a library stage, so it lives here rather than in `shaders/`.
const SPIN: &str = r#"
@group(0) @binding(0) var<storage, read_write> sink: array<f32>;

@compute @workgroup_size(256)
fn spin(@builtin(global_invocation_id) id: vec3<u32>) {
    var x = f32(id.x) * 1e-7;
    for (var i = 0u; i < 4096u; i++) {
        x = fma(x, 0.99991, 1e-7);
    }
    // Never true; keeps the loop.
    if x == 1234.5 {
        sink[0] = x;
    }
}
"#;

pub(crate) struct Heater {
    pipeline: wgpu::ComputePipeline,
    bind: wgpu::BindGroup,
    /// Workgroups along x and y per run.
    groups: [u32; 2],
}

impl Heater {
    /// A heater of `ms` on a GPU, none on a software adapter (whose clocks are the CPU's).
    pub(crate) fn for_gpu(ctx: &Context, ms: f64) -> Result<Option<Self>, String> {
        if ctx.is_software() {
            return Ok(None);
        }
        Self::new(ctx, ms).map(Some)
    }

    /// A heater whose run takes about `ms` milliseconds of GPU time at full clocks.
    pub(crate) fn new(ctx: &Context, ms: f64) -> Result<Self, String> {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bench heater"),
            source: wgpu::ShaderSource::Wgsl(SPIN.into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("bench heater"),
            layout: None,
            module: &module,
            entry_point: Some("spin"),
            compilation_options: Default::default(),
            cache: None,
        });
        let sink = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bench heater sink"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bench heater"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: sink.as_entire_binding(),
            }],
        });
        const CALIBRATE: u32 = 65535;
        let mut heater = Self {
            pipeline,
            bind,
            groups: [CALIBRATE, 1],
        };
        // Calibrate on a warm GPU: the last of a few timed runs, scaled to `ms`.
        let mut took = 0.0;
        for _ in 0..5 {
            let timer = Timer::new(&ctx.device, &ctx.queue, 1)
                .ok_or("the heater is calibrated with timestamp queries; the adapter has none")?;
            let mut enc = ctx.encoder("bench heater calibration");
            heater.record(&mut enc, Some(timer.compute_pass_writes(0)));
            timer.resolve(&mut enc);
            ctx.submit_and_wait("bench heater", enc)
                .map_err(|e| e.to_string())?;
            took = timer
                .read_ms(&ctx.device, &ctx.queue)
                .wait(ctx)
                .map_err(|e| e.to_string())?;
        }
        let want = (CALIBRATE as f64 * ms / took.max(1e-3))
            .ceil()
            .clamp(1.0, 65535.0 * 64.0) as u32;
        let rows = want.div_ceil(65535);
        heater.groups = [want.div_ceil(rows), rows];
        Ok(heater)
    }

    fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bench heater"),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind, &[]);
        pass.dispatch_workgroups(self.groups[0], self.groups[1], 1);
    }

    /// Run the spin kernel and wait for it.
    pub(crate) fn run(&self, ctx: &Context) -> Result<(), String> {
        let mut enc = ctx.encoder("bench heater");
        self.record(&mut enc, None);
        ctx.submit_and_wait("bench heater", enc)
            .map_err(|e| e.to_string())
    }
}
