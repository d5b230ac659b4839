//! The convenience layer: a headless device of fieldkit's choosing (or one you already have),
//! the uncaptured-error sink, and blocking helpers. For tests, demos and benches; a renderer
//! passes its own `&wgpu::Device` and `&wgpu::Queue` to every stage instead.

use std::sync::{Arc, Mutex};

use super::{Readback, readback_buffer, readback_texture};
use crate::error::Error;

/// Environment variable choosing the adapter by (case-insensitive) substring of its name,
/// e.g. `FIELDKIT_ADAPTER=llvmpipe` or `FIELDKIT_ADAPTER=nvidia`.
pub const ADAPTER_ENV: &str = "FIELDKIT_ADAPTER";

/// A device and queue with the errors wgpu reported that no scope caught.
#[derive(Clone)]
pub struct Context {
    /// The adapter the device came from (`None` when wrapping a device made elsewhere).
    pub adapter: Option<wgpu::Adapter>,
    /// The device every stage is created on.
    pub device: wgpu::Device,
    /// The queue uploads and submissions go to.
    pub queue: wgpu::Queue,
    /// Errors no scope caught (they would otherwise panic); drained by [`Context::take_uncaptured`].
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("adapter", &self.adapter.as_ref().map(|a| a.get_info()))
            .finish()
    }
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.backend, info.device_type)
}

impl Context {
    /// Open the default adapter: the one named by `FIELDKIT_ADAPTER` if set, else the highest
    /// performance one. Software adapters (lavapipe) are allowed.
    pub fn new() -> Result<Self, Error> {
        pollster::block_on(Self::new_async(std::env::var(ADAPTER_ENV).ok().as_deref()))
    }

    /// The default adapter ([`Context::new`]), opened once per process and shared: what tests
    /// and demos use. Panics, saying how to get an adapter, when there is none: GPU tests fail
    /// rather than skip.
    pub fn shared() -> Self {
        static CTX: std::sync::OnceLock<Result<Context, Error>> = std::sync::OnceLock::new();
        match CTX.get_or_init(Context::new) {
            Ok(c) => c.clone(),
            Err(e) => panic!("this needs a GPU adapter: {e}"),
        }
    }

    /// wgpu's noop backend: accepts every call and runs nothing. Enough to prove that pipelines
    /// and layouts are valid without a GPU.
    pub fn noop() -> Result<Self, Error> {
        Self::noop_limited(None)
    }

    /// [`Context::noop`] with a device of `limits` (the noop adapter otherwise offers the
    /// largest values): to test what a stage does on a device with smaller ones.
    pub fn noop_with_limits(limits: wgpu::Limits) -> Result<Self, Error> {
        Self::noop_limited(Some(limits))
    }

    fn noop_limited(limits: Option<wgpu::Limits>) -> Result<Self, Error> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::NOOP,
            backend_options: wgpu::BackendOptions {
                noop: wgpu::NoopBackendOptions {
                    enable: true,
                    ..Default::default()
                },
                ..Default::default()
            },
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        pollster::block_on(Self::from_instance(
            instance,
            wgpu::Backends::NOOP,
            None,
            limits,
        ))
    }

    /// [`Context::new`] without blocking: the adapter whose name contains `name`, if given.
    pub async fn new_async(name: Option<&str>) -> Result<Self, Error> {
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        // wgpu's defaults, and its `WGPU_*` variables for the instance's flags (say
        // `WGPU_VALIDATION_INDIRECT_CALL=0`), as an app's own instance may set them.
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
        });
        Self::from_instance(instance, backends, name, None).await
    }

    async fn from_instance(
        instance: wgpu::Instance,
        backends: wgpu::Backends,
        name: Option<&str>,
        limits: Option<wgpu::Limits>,
    ) -> Result<Self, Error> {
        let adapters = instance.enumerate_adapters(backends).await;
        let names: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
        let adapter = match name {
            Some(n) => adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&n.to_lowercase()))
                .ok_or_else(|| Error::NoAdapter {
                    detail: format!("{ADAPTER_ENV}={n} matches none of {names:?}"),
                })?,
            None => {
                let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
                    wgpu::DeviceType::DiscreteGpu => 0,
                    wgpu::DeviceType::IntegratedGpu => 1,
                    wgpu::DeviceType::VirtualGpu => 2,
                    wgpu::DeviceType::Other => 3,
                    wgpu::DeviceType::Cpu => 4,
                };
                let mut adapters = adapters;
                adapters.sort_by_key(rank);
                adapters.into_iter().next().ok_or_else(|| Error::NoAdapter {
                    detail: format!("wgpu enumerated no adapters on {backends:?} (WGPU_BACKEND chooses others)"),
                })?
            }
        };
        let info = adapter.get_info();
        // Optional: timing, wireframe for the debug cubes, trilinear R32Float volumes, a pipeline
        // cache kept on disk (`PipelineCache`), the ocean's patches chosen on the GPU. Used where
        // the adapter has them.
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::INDIRECT_FIRST_INSTANCE
            | wgpu::Features::PIPELINE_CACHE
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::POLYGON_MODE_LINE
            | wgpu::Features::FLOAT32_FILTERABLE;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("fieldkit"),
                required_features: adapter.features() & wanted,
                required_limits: limits.unwrap_or_else(|| adapter.limits()),
                ..Default::default()
            })
            .await
            .map_err(|e| Error::Device {
                adapter: describe(&info),
                detail: e.to_string(),
            })?;
        drop(instance);
        let mut ctx = Self::from_device(device, queue);
        ctx.adapter = Some(adapter);
        Ok(ctx)
    }

    /// Wrap a device and queue the application already has. This installs an uncaptured-error
    /// handler on `device` that collects errors for [`Context::take_uncaptured`] (replacing any
    /// handler set before).
    pub fn from_device(device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(e.to_string());
        }));
        Self {
            adapter: None,
            device,
            queue,
            uncaptured,
        }
    }

    /// "name (backend, type)", or "(device given)" for a wrapped device.
    pub fn adapter_name(&self) -> String {
        self.adapter
            .as_ref()
            .map(|a| describe(&a.get_info()))
            .unwrap_or_else(|| "(device given)".into())
    }

    /// Whether the adapter is a software rasterizer (lavapipe, WARP).
    pub fn is_software(&self) -> bool {
        self.adapter
            .as_ref()
            .is_some_and(|a| a.get_info().device_type == wgpu::DeviceType::Cpu)
    }

    /// Errors that escaped every error scope since the last call.
    pub fn take_uncaptured(&self) -> Vec<String> {
        std::mem::take(&mut *self.uncaptured.lock().unwrap())
    }

    /// Submit, wait, and turn a device loss or an uncaptured error into a typed error.
    pub fn submit_and_wait(
        &self,
        stage: &'static str,
        encoder: wgpu::CommandEncoder,
    ) -> Result<(), Error> {
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|_| self.failed(stage))?;
        if let Some(message) = self.take_uncaptured().into_iter().next() {
            return Err(Error::Wgpu { stage, message });
        }
        Ok(())
    }

    /// Why a wait failed: wgpu's message where a validation error escaped (a command buffer
    /// it rejected at submission is never run, so waiting for it fails as a lost device
    /// would), else a lost device.
    fn failed(&self, stage: &'static str) -> Error {
        match self.take_uncaptured().into_iter().next() {
            Some(message) => Error::Wgpu { stage, message },
            None => Error::DeviceLost { stage },
        }
    }

    /// Block until `readback` is done, turning a device loss or an uncaptured error into a
    /// typed error.
    pub fn wait<T: 'static>(&self, readback: Readback<T>) -> Result<T, Error> {
        readback.wait(self)
    }

    /// Run `future` to completion on this thread, polling the device between tries so that
    /// readbacks inside it finish (for fieldkit's async helpers such as
    /// [`Voxelizer::attributes`](crate::voxelize::Voxelizer::attributes)).
    pub fn block_on<T>(
        &self,
        future: impl std::future::Future<Output = Result<T, Error>>,
    ) -> Result<T, Error> {
        let mut future = std::pin::pin!(future);
        let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
        loop {
            if let std::task::Poll::Ready(v) = future.as_mut().poll(&mut cx) {
                if let Some(message) = self.take_uncaptured().into_iter().next() {
                    return Err(Error::Wgpu {
                        stage: "block_on",
                        message,
                    });
                }
                return v;
            }
            self.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|_| self.failed("block_on"))?;
        }
    }

    /// A command encoder labelled `label`.
    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }
}

impl<T: 'static> Readback<T> {
    /// Block until the data is back (the convenience layer's helper; a render loop polls
    /// [`Readback::try_take`] or awaits instead).
    pub fn wait(mut self, ctx: &Context) -> Result<T, Error> {
        if let Some(index) = self.submission().cloned() {
            ctx.device
                .poll(wgpu::PollType::Wait {
                    submission_index: Some(index),
                    timeout: None,
                })
                .map_err(|_| ctx.failed("readback"))?;
        }
        if let Some(message) = ctx.take_uncaptured().into_iter().next() {
            return Err(Error::Wgpu {
                stage: "readback",
                message,
            });
        }
        // How long an empty queue may go without the mapping arriving: another thread's poll
        // may be running this readback's callback at that moment (tests share one device).
        let grace = std::time::Duration::from_millis(200);
        let mut empty_since: Option<std::time::Instant> = None;
        loop {
            if let Some(r) = self.try_take() {
                return r;
            }
            // The copy finished; the mapping callback runs on the next poll.
            let status = ctx
                .device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| Error::Readback(e.to_string()))?;
            if !status.is_queue_empty() {
                empty_since = None;
                continue;
            }
            // Every callback of finished work ran in a poll, this one or another thread's. A
            // copy submitted by the readback itself is on its way; one recorded into an encoder
            // that was never submitted never comes.
            let since = *empty_since.get_or_insert_with(std::time::Instant::now);
            if self.submission().is_none() && since.elapsed() > grace {
                return self.try_take().unwrap_or_else(|| {
                    Err(Error::Readback(
                        "the copy was never submitted: submit the encoder the readback was \
                         recorded into (`readback_texture_in`, `readback_buffer_in`) before \
                         waiting"
                            .into(),
                    ))
                });
            }
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }
}

/// Read a whole buffer (it needs `COPY_SRC` usage), blocking.
pub fn read_buffer(ctx: &Context, buffer: &wgpu::Buffer) -> Result<Vec<u8>, Error> {
    readback_buffer(&ctx.device, &ctx.queue, buffer).wait(ctx)
}

/// Read mip 0 of a 2D or 3D texture, blocking (see [`readback_texture`]).
pub fn read_texture<T: bytemuck::Pod + Send>(
    ctx: &Context,
    texture: &wgpu::Texture,
) -> Result<Vec<T>, Error> {
    readback_texture(&ctx.device, &ctx.queue, texture).wait(ctx)
}
