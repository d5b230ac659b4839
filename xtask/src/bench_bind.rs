//! `cargo xtask bench bind`: the CPU cost of binding one stage's resources (`Pipeline::bind`,
//! what every `encode_*` does per pass), as shipped and as it was before binding stopped
//! opening error scopes: two scopes pushed, the bind groups made, both scopes popped with a
//! blocking wait. Both run in the same process on the same pipeline, interleaved, so the ratio
//! holds on any machine. Median, fastest and slowest of `--reps` runs of 1000 binds each.

use std::time::Instant;

use fieldkit::bind::ComputePipeline;
use fieldkit::gpu::Context;
use fieldkit::shaders::distance::jfa_step::{self, jump};

/// Binds per timed run.
const BINDS: u32 = 1000;

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args.reps.max(20), args.warmup)
}

fn texture(ctx: &Context) -> wgpu::TextureView {
    fieldkit::gpu::texture(
        &ctx.device,
        "bind bench",
        [64, 64, 1],
        wgpu::TextureDimension::D2,
        wgpu::TextureFormat::R32Uint,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
    )
    .create_view(&Default::default())
}

/// Nanoseconds per bind over one run of [`BINDS`].
fn time(mut bind: impl FnMut() -> Result<(), String>) -> Result<f64, String> {
    let start = Instant::now();
    for _ in 0..BINDS {
        bind()?;
    }
    Ok(start.elapsed().as_nanos() as f64 / BINDS as f64)
}

fn spread(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

fn bench(reps: usize, warmup: usize) -> Result<(), String> {
    let ctx = Context::new().map_err(|e| e.to_string())?;
    println!("adapter: {}", ctx.adapter_name());
    let pipeline = ComputePipeline::<jump::Entry>::new(&ctx.device).map_err(|e| e.to_string())?;
    let params = fieldkit::gpu::uniform_buffer(
        &ctx.device,
        "bind bench",
        &jfa_step::JumpParams {
            size: glam::uvec2(64, 64),
            step: 1,
        },
    );
    let (src, dst) = (texture(&ctx), texture(&ctx));
    let resources = jump::Resources {
        params: (&params).into(),
        src: (&src).into(),
        dst: (&dst).into(),
    };
    let now = || {
        pipeline
            .bind(&ctx.device, &resources)
            .map(drop)
            .map_err(|e| e.to_string())
    };
    // What `bind` did before: the same checks and bind groups inside two error scopes, popped
    // with a blocking wait.
    let scoped = || {
        let oom = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let bound = pipeline.bind(&ctx.device, &resources);
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        if let Some(e) = v.or(o) {
            return Err(e.to_string());
        }
        bound.map(drop).map_err(|e| e.to_string())
    };
    for _ in 0..warmup.max(3) {
        time(now)?;
        time(scoped)?;
    }
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        a.push(time(now)?);
        b.push(time(scoped)?);
        // Dropped bind groups are freed when the device is polled, as a frame loop does.
        let _ = ctx.device.poll(wgpu::PollType::Poll);
    }
    let (a, b) = (spread(a), spread(b));
    println!("| bind of distance/jfa_step::jump (3 resources) | median µs | fastest | slowest |");
    println!("|---|---|---|---|");
    println!(
        "| as shipped (fieldkit's checks, no error scope) | {:.2} | {:.2} | {:.2} |",
        a.0 / 1e3,
        a.1 / 1e3,
        a.2 / 1e3
    );
    println!(
        "| before: inside two error scopes, popped blocking | {:.2} | {:.2} | {:.2} |",
        b.0 / 1e3,
        b.1 / 1e3,
        b.2 / 1e3
    );
    println!("ratio (before / now, medians): {:.2}", b.0 / a.0);
    Ok(())
}
