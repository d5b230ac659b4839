//! Timestamp queries through `gpu::Timer`: the mechanism the benchmarks use. This checks that
//! timing works and orders its numbers sensibly; it does not judge speed (that is `xtask bench`).

use fieldkit::gpu::Context;
use fieldkit::distance::{Jfa2d, upload_mask};
use fieldkit::gpu::Timer;

#[test]
fn timer_measures_jfa_passes() {
    let ctx = Context::shared();
    let Some(timer) = Timer::new(&ctx.device, &ctx.queue, 2) else {
        panic!(
            "{} offers no timestamp queries; lavapipe and the H100 both do",
            ctx.adapter_name()
        );
    };
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let seeds = upload_mask(&ctx.device, &ctx.queue, &vec![0u8; 256 * 256], 256, 256).unwrap();
    let mut enc = ctx.encoder("timed");
    let a = jfa
        .encode_seed(&ctx.device, &mut enc, &seeds, false)
        .unwrap();
    let b = jfa
        .encode_seed(&ctx.device, &mut enc, &seeds, false)
        .unwrap();
    jfa.encode_jump(
        &ctx.device,
        &mut enc,
        &a,
        &b,
        64,
        Some(timer.compute_pass_writes(0)),
    )
    .unwrap();
    jfa.encode_jump(
        &ctx.device,
        &mut enc,
        &b,
        &a,
        32,
        Some(timer.compute_pass_writes(1)),
    )
    .unwrap();
    timer.resolve(&mut enc);
    ctx.submit_and_wait("timed", enc).unwrap();
    let ms = timer.read_ms(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    assert!(
        ms.is_finite() && ms > 0.0,
        "two passes over 256² took {ms} ms"
    );
}
