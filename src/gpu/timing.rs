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
        if !ctx.device.features().contains(wgpu::Features::TIMESTAMP_QUERY) || passes == 0 {
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
        Some(Self { set, resolve, count, period_ns: ctx.queue.get_timestamp_period() })
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
