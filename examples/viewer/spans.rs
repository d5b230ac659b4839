//! wgpu's own profiling scopes (`CommandEncoder::finish`, `Queue::submit`, `vkQueueSubmit`,
//! barriers, render pass set-up…) timed as tracing spans, their inclusive time summed by name:
//! where the encoder's `finish` and the queue's `submit` spend a frame. Built with the crate's
//! `wgpu-spans` feature and switched on with `FIELDKIT_WGPU_SPANS=1`; `--frame-cost` then
//! prints the spans of each scene's timed frames. Without the feature every call is a no-op.

/// Whether spans are being timed (the feature is built in and the variable set).
pub fn on() -> bool {
    cfg!(feature = "wgpu-spans") && std::env::var_os("FIELDKIT_WGPU_SPANS").is_some()
}

/// Start timing spans, where [`on`].
pub fn install() {
    #[cfg(feature = "wgpu-spans")]
    if on() {
        imp::install();
    }
}

/// Forget what was timed so far.
pub fn reset() {
    #[cfg(feature = "wgpu-spans")]
    imp::reset();
}

/// The spans timed since [`reset`], the most costly first: milliseconds and calls a frame over
/// `frames` frames.
pub fn lines(frames: u32) -> Vec<String> {
    #[cfg(feature = "wgpu-spans")]
    return imp::lines(frames);
    #[cfg(not(feature = "wgpu-spans"))]
    {
        let _ = frames;
        Vec::new()
    }
}

#[cfg(feature = "wgpu-spans")]
mod imp {
    use std::collections::HashMap;
    use std::sync::Mutex;
    use std::time::Instant;

    use tracing::span;
    use tracing_subscriber::Layer;
    use tracing_subscriber::layer::{Context, SubscriberExt};
    use tracing_subscriber::registry::LookupSpan;

    /// Milliseconds and calls by span name.
    static TOTALS: Mutex<Option<HashMap<&'static str, (f64, u64)>>> = Mutex::new(None);

    struct Timing;
    struct Entered(Instant);

    impl<S: tracing::Subscriber + for<'a> LookupSpan<'a>> Layer<S> for Timing {
        fn on_enter(&self, id: &span::Id, ctx: Context<'_, S>) {
            if let Some(span) = ctx.span(id) {
                span.extensions_mut().insert(Entered(Instant::now()));
            }
        }

        fn on_exit(&self, id: &span::Id, ctx: Context<'_, S>) {
            let Some(span) = ctx.span(id) else { return };
            let Some(Entered(t)) = span.extensions_mut().remove::<Entered>() else {
                return;
            };
            let ms = t.elapsed().as_secs_f64() * 1e3;
            let mut totals = TOTALS.lock().unwrap_or_else(|e| e.into_inner());
            let entry = totals
                .get_or_insert_with(HashMap::new)
                .entry(span.metadata().name())
                .or_default();
            entry.0 += ms;
            entry.1 += 1;
        }
    }

    pub fn install() {
        let subscriber = tracing_subscriber::registry().with(Timing);
        if tracing::subscriber::set_global_default(subscriber).is_err() {
            eprintln!("another tracing subscriber is installed: wgpu's spans are not timed");
        }
    }

    pub fn reset() {
        *TOTALS.lock().unwrap_or_else(|e| e.into_inner()) = None;
    }

    pub fn lines(frames: u32) -> Vec<String> {
        let totals = TOTALS.lock().unwrap_or_else(|e| e.into_inner());
        let mut spans: Vec<_> = totals.iter().flatten().collect();
        spans.sort_by(|a, b| b.1.0.total_cmp(&a.1.0));
        let frames = frames.max(1) as f64;
        spans
            .into_iter()
            .take(24)
            .map(|(name, (ms, n))| {
                format!(
                    "{:>8.4} ms {:>5.1} calls  {name}",
                    ms / frames,
                    *n as f64 / frames
                )
            })
            .collect()
    }
}
