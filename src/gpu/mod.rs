//! Headless GPU context, error capture, readback and timing.

mod readback;
mod timing;

pub use readback::{read_buffer, read_texture};
pub use timing::{Prof, Profiler, Timer};

use std::sync::{Arc, Mutex};

use crate::error::Error;

/// Environment variable choosing the adapter by (case-insensitive) substring of its name,
/// e.g. `FIELDKIT_ADAPTER=llvmpipe` or `FIELDKIT_ADAPTER=nvidia`.
pub const ADAPTER_ENV: &str = "FIELDKIT_ADAPTER";

/// A device and queue with what the stages need to know about them.
#[derive(Clone)]
pub struct Context {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// Errors no scope caught (they would otherwise panic); drained by [`Context::take_uncaptured`].
    uncaptured: Arc<Mutex<Vec<String>>>,
}

impl std::fmt::Debug for Context {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Context")
            .field("adapter", &self.adapter.get_info())
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

    /// wgpu's noop backend: accepts every call and runs nothing. Enough to prove that pipelines
    /// and layouts are valid without a GPU.
    pub fn noop() -> Result<Self, Error> {
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
        pollster::block_on(Self::from_instance(instance, wgpu::Backends::NOOP, None))
    }

    pub async fn new_async(name: Option<&str>) -> Result<Self, Error> {
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        Self::from_instance(instance, backends, name).await
    }

    async fn from_instance(
        instance: wgpu::Instance,
        backends: wgpu::Backends,
        name: Option<&str>,
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
        // Optional: timing, wireframe for the debug cubes, trilinear R32Float volumes. Used where
        // the adapter has them.
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::POLYGON_MODE_LINE
            | wgpu::Features::FLOAT32_FILTERABLE;
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("fieldkit"),
                required_features: adapter.features() & wanted,
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| Error::Device {
                adapter: describe(&info),
                detail: e.to_string(),
            })?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap().push(e.to_string());
        }));
        Ok(Self {
            instance,
            adapter,
            device,
            queue,
            uncaptured,
        })
    }

    /// "name (backend, type)".
    pub fn adapter_name(&self) -> String {
        describe(&self.adapter.get_info())
    }

    pub fn is_software(&self) -> bool {
        self.adapter.get_info().device_type == wgpu::DeviceType::Cpu
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
            .map_err(|_| Error::DeviceLost { stage })?;
        if let Some(message) = self.take_uncaptured().into_iter().next() {
            return Err(Error::Wgpu { stage, message });
        }
        Ok(())
    }

    pub fn encoder(&self, label: &str) -> wgpu::CommandEncoder {
        self.device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) })
    }
}

/// Run `f` inside validation and out-of-memory error scopes; any error wgpu reports becomes
/// [`Error::Wgpu`] naming `stage`.
pub fn scoped<T>(
    device: &wgpu::Device,
    stage: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T, Error> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    let v = pollster::block_on(validation.pop());
    let o = pollster::block_on(oom.pop());
    match v.or(o) {
        Some(e) => Err(Error::Wgpu {
            stage,
            message: e.to_string(),
        }),
        None => Ok(out),
    }
}

/// A uniform buffer holding `value`, laid out by encase as the shader's struct (use the
/// generated `fieldkit::shaders::…` type).
pub fn uniform_buffer<T: encase::ShaderType + encase::internal::WriteInto>(
    device: &wgpu::Device,
    label: &str,
    value: &T,
) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    let mut bytes = encase::UniformBuffer::new(Vec::new());
    bytes
        .write(value)
        .expect("a generated uniform struct always encodes");
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &bytes.into_inner(),
        usage: wgpu::BufferUsages::UNIFORM,
    })
}
