//! GPU time of passes from timestamp queries.

use super::{Readback, readback_buffer};

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
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, passes: u32) -> Option<Self> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) || passes == 0 {
            return None;
        }
        let count = passes * 2;
        let set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("fieldkit timer"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("fieldkit timer resolve"),
            size: count as u64 * 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(Self {
            set,
            resolve,
            count,
            period_ns: queue.get_timestamp_period(),
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

    /// Timestamp writes for render pass `i` (start and end).
    pub fn render_pass_writes(&self, i: u32) -> wgpu::RenderPassTimestampWrites<'_> {
        wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(2 * i),
            end_of_pass_write_index: Some(2 * i + 1),
        }
    }

    /// Resolve every timestamp into the buffer [`Timer::read_ms`] reads; call once, after the
    /// last pass, before submitting.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.set, 0..self.count, &self.resolve, 0);
    }

    /// Milliseconds from the start of the first pass to the end of the last one, once the
    /// submission that resolved them has finished.
    pub fn read_ms(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<f64> {
        let period = self.period_ns as f64;
        readback_buffer(device, queue, &self.resolve).then(move |bytes| {
            let ticks: &[u64] = bytemuck::cast_slice(&bytes);
            let first = ticks[0];
            let last = ticks[ticks.len() - 1];
            Ok(last.saturating_sub(first) as f64 * period / 1e6)
        })
    }
}

/// Where a stage records its passes: the caller's command encoder, and optionally a
/// [`Profiler`] that times each compute pass. Every `encode*` function takes
/// `&mut impl Record`, so a plain `&mut wgpu::CommandEncoder` is enough; to time the passes,
/// hand it [`Profiler::record`] instead — one code path either way.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, volume: &wgpu::Texture)
/// #     -> Result<(), fieldkit::Error> {
/// use fieldkit::distance::{Distance3d, Settings3d};
/// let distance = Distance3d::new(device)?;
/// let mut encoder = device.create_command_encoder(&Default::default());
/// // Untimed, as a renderer records it:
/// distance.encode(device, &mut encoder, volume, &Settings3d::default())?;
/// // Timed pass by pass:
/// if let Some(mut profiler) = fieldkit::gpu::Profiler::new(device, queue, 64) {
///     distance.encode(device, &mut profiler.record(&mut encoder), volume, &Settings3d::default())?;
///     profiler.resolve(&mut encoder);
/// }
/// # Ok(()) }
/// ```
pub struct Recorder<'a> {
    /// The encoder every pass goes into.
    pub encoder: &'a mut wgpu::CommandEncoder,
    /// Times each compute pass when present.
    pub profiler: Option<&'a mut Profiler>,
}

/// What an `encode*` function records into: a [`wgpu::CommandEncoder`] or a [`Recorder`].
pub trait Record {
    /// A recorder borrowing `self` for one call.
    fn recorder(&mut self) -> Recorder<'_>;
}

impl Record for wgpu::CommandEncoder {
    fn recorder(&mut self) -> Recorder<'_> {
        Recorder {
            encoder: self,
            profiler: None,
        }
    }
}

impl Record for Recorder<'_> {
    fn recorder(&mut self) -> Recorder<'_> {
        Recorder {
            encoder: self.encoder,
            profiler: self.profiler.as_deref_mut(),
        }
    }
}

impl Recorder<'_> {
    /// Begin the render pass `desc`, timed under `name` when profiling (its own
    /// `timestamp_writes` are replaced).
    pub fn render_pass(
        &mut self,
        desc: &wgpu::RenderPassDescriptor<'_>,
        name: &str,
    ) -> wgpu::RenderPass<'_> {
        let timestamp_writes = self.profiler.as_mut().and_then(|p| p.next_render(name));
        self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            timestamp_writes,
            ..desc.clone()
        })
    }

    /// Name the passes recorded from now on `group / pass` when profiling
    /// ([`Profiler::group`]).
    pub fn group(&mut self, group: Option<&str>) {
        if let Some(p) = self.profiler.as_mut() {
            p.group(group);
        }
    }

    /// Begin a compute pass labelled `label`, timed under `name` when profiling.
    pub fn compute_pass(&mut self, label: &str, name: &str) -> wgpu::ComputePass<'_> {
        let timestamp_writes = self.profiler.as_mut().and_then(|p| p.next(name));
        self.encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes,
            })
    }
}

/// Named GPU time per pass: hand [`Profiler::next`] to each compute pass and
/// [`Profiler::next_render`] to each render pass as it is recorded (or record them through
/// [`Recorder::compute_pass`] and [`Recorder::render_pass`]); passes past the capacity go untimed. Used by `cargo xtask bench`.
pub struct Profiler {
    timer: Timer,
    capacity: u32,
    names: Vec<String>,
    group: Option<String>,
}

impl Profiler {
    /// `None` when the adapter has no timestamp queries.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, capacity: u32) -> Option<Self> {
        Some(Self {
            timer: Timer::new(device, queue, capacity)?,
            capacity,
            names: Vec::new(),
            group: None,
        })
    }

    /// A [`Recorder`] that times every compute pass recorded into `encoder` through it.
    pub fn record<'a>(&'a mut self, encoder: &'a mut wgpu::CommandEncoder) -> Recorder<'a> {
        Recorder {
            encoder,
            profiler: Some(self),
        }
    }

    /// Name the passes recorded from now on `group / pass` (`None`: their own names again), so
    /// that the passes of one call add up to its cost: an app comparing two methods in one
    /// frame groups each method's passes under its name.
    pub fn group(&mut self, group: Option<&str>) {
        self.group = group.map(str::to_owned);
    }

    fn named(&self, name: String) -> String {
        match &self.group {
            Some(g) => format!("{g} / {name}"),
            None => name,
        }
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
        let name = self.named(name.into());
        self.names.push(name);
        Some(self.timer.compute_pass_writes(i))
    }

    /// Timestamp writes for the next render pass, recorded under `name`.
    pub fn next_render(
        &mut self,
        name: impl Into<String>,
    ) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let i = self.names.len() as u32;
        if i >= self.capacity {
            return None;
        }
        let name = self.named(name.into());
        self.names.push(name);
        Some(self.timer.render_pass_writes(i))
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
    pub fn read(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Readback<(Vec<(String, f64)>, f64)> {
        let period = self.timer.period_ns as f64;
        let names = std::mem::take(&mut self.names);
        readback_buffer(device, queue, &self.timer.resolve).then(move |bytes| {
            let ticks: &[u64] = bytemuck::cast_slice(&bytes);
            let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 * period / 1e6;
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
        })
    }
}
