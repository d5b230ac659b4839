//! GPU time of passes from timestamp queries.

use super::Context;
use crate::error::Error;

/// Timestamp pairs around passes. Make one per measurement, hand `compute_pass_writes(i)` to the
/// i-th pass, then [`Timer::resolve`] and [`Timer::read_ms`].
pub struct Timer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    count: u32,
    period_ns: f32,
}

impl Timer {
    /// `None` when the adapter has no timestamp queries.
    pub fn new(ctx: &Context, passes: u32) -> Option<Self> {
        if !ctx
            .device
            .features()
            .contains(wgpu::Features::TIMESTAMP_QUERY)
            || passes == 0
        {
            return None;
        }
        let count = passes * 2;
        let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("fieldkit timer"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let resolve = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fieldkit timer resolve"),
            size: count as u64 * 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(Self {
            set,
            resolve,
            count,
            period_ns: ctx.queue.get_timestamp_period(),
        })
    }

    /// Timestamp writes for pass `i` (start and end).
    pub fn compute_pass_writes(&self, i: u32) -> wgpu::ComputePassTimestampWrites<'_> {
        wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        }
    }

    pub fn render_pass_writes(&self, i: u32) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        }
    }

    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.set, 0..self.count, &self.resolve, 0);
    }

    /// Milliseconds from the start of the first pass to the end of the last one.
    pub fn read_ms(&self, ctx: &Context) -> Result<f64, Error> {
        let bytes = super::read_buffer(ctx, &self.resolve)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let first = ticks[0];
        let last = ticks[ticks.len() - 1];
        Ok(last.saturating_sub(first) as f64 * self.period_ns as f64 / 1e6)
    }
}

/// Optional per-pass timing, threaded through the encode functions.
pub type Prof<'a, 'b> = &'a mut Option<&'b mut Profiler>;

/// Named GPU time per pass: hand [`Profiler::next`] to each compute pass as it is recorded; passes
/// past the capacity go untimed. Used by `cargo xtask bench`.
pub struct Profiler {
    timer: Timer,
    capacity: u32,
    names: Vec<String>,
}

impl Profiler {
    /// `None` when the adapter has no timestamp queries.
    pub fn new(ctx: &Context, capacity: u32) -> Option<Self> {
        Some(Self {
            timer: Timer::new(ctx, capacity)?,
            capacity,
            names: Vec::new(),
        })
    }

    /// Timestamp writes for the next pass, recorded under `name`.
    pub fn next(
        &mut self,
        name: impl Into<String>,
    ) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = self.names.len() as u32;
        if i >= self.capacity {
            return None;
        }
        self.names.push(name.into());
        Some(self.timer.compute_pass_writes(i))
    }

    /// Resolve the passes recorded so far; call once, after the last pass, before submitting.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let used = self.names.len() as u32 * 2;
        if used > 0 {
            encoder.resolve_query_set(&self.timer.set, 0..used, &self.timer.resolve, 0);
        }
    }

    /// After the submission finished: (name, milliseconds) per pass, and the total from the first
    /// pass's start to the last one's end (gaps between passes included). Clears the names.
    pub fn read(&mut self, ctx: &Context) -> Result<(Vec<(String, f64)>, f64), Error> {
        let bytes = super::read_buffer(ctx, &self.timer.resolve)?;
        let ticks: &[u64] = bytemuck::cast_slice(&bytes);
        let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 * self.timer.period_ns as f64 / 1e6;
        let names = std::mem::take(&mut self.names);
        let passes = names
            .into_iter()
            .enumerate()
            .map(|(i, n)| (n, ms(ticks[2 * i], ticks[2 * i + 1])))
            .collect::<Vec<_>>();
        let total = if passes.is_empty() {
            0.0
        } else {
            ms(ticks[0], ticks[2 * passes.len() - 1])
        };
        Ok((passes, total))
    }
}
