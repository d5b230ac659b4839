//! Timestamp queries through `gpu::Profiler` (built on `gpu::Timer`): the mechanism the
//! benchmarks use, reached through the same `encode*` functions a renderer calls, with
//! `Profiler::record` in place of the bare encoder. This checks that timing works, names the
//! passes it timed and orders its numbers sensibly; it does not judge speed (that is
//! `xtask bench`).

use crate::common;

use common::seed_pair;
use fieldkit::distance::{Jfa2d, upload_mask};
use fieldkit::gpu::{Context, Profiler};

#[test]
fn profiler_times_the_passes_recorded_through_it() {
    let ctx = Context::shared();
    let Some(mut profiler) = Profiler::new(&ctx.device, &ctx.queue, 2) else {
        panic!(
            "{} offers no timestamp queries; lavapipe and the H100 both do",
            ctx.adapter_name()
        );
    };
    let jfa = Jfa2d::new(&ctx.device).unwrap();
    let seeds = upload_mask(&ctx.device, &ctx.queue, &vec![0u8; 256 * 256], 256, 256).unwrap();
    let mut enc = ctx.encoder("timed");
    // Recorded into the bare encoder: not timed.
    let (a, b) = seed_pair(&ctx, &jfa, &mut enc, &seeds);
    {
        let mut rec = profiler.record(&mut enc);
        jfa.encode_jump(&ctx.device, &mut rec, &a, &b, 64).unwrap();
        jfa.encode_jump(&ctx.device, &mut rec, &b, &a, 32).unwrap();
        // Past the profiler's capacity: recorded, not timed.
        jfa.encode_jump(&ctx.device, &mut rec, &a, &b, 16).unwrap();
    }
    profiler.resolve(&mut enc);
    ctx.submit_and_wait("timed", enc).unwrap();
    let (passes, total) = profiler.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let names: Vec<&str> = passes.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["jump 64", "jump 32"]);
    for (name, ms) in &passes {
        assert!(ms.is_finite() && *ms >= 0.0, "{name} took {ms} ms");
    }
    let sum: f64 = passes.iter().map(|(_, ms)| ms).sum();
    assert!(
        total.is_finite() && total > 0.0 && total >= sum * 0.999,
        "two passes over 256² took {total} ms in all, {sum} ms summed"
    );
}
