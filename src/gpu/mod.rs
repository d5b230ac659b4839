//! What every stage needs from the GPU beyond wgpu itself: readback that does not block
//! ([`Readback`]), pass timing from timestamp queries ([`Timer`], [`Profiler`]) and uniform
//! buffers laid out by encase. With the `context` feature, also a headless `Context` of
//! fieldkit's choosing with blocking helpers, for tests, demos and benches; nothing a renderer
//! calls needs it.

#[cfg(feature = "techniques")]
mod albedo;
mod alloc;
mod cache;
#[cfg(feature = "context")]
mod context;
mod readback;
mod targets;
mod timing;
mod upload;

#[cfg(feature = "techniques")]
pub(crate) use albedo::AlbedoBinding;
pub(crate) use alloc::kept_buffer;
#[cfg(feature = "techniques")]
pub(crate) use alloc::{KeptView, Leased, storage_buffer, volume_texture};
pub use alloc::{Lease, texture};
pub use cache::PipelineCache;
pub(crate) use cache::installed as installed_pipeline_cache;
#[cfg(feature = "context")]
pub use context::{ADAPTER_ENV, Context, read_buffer, read_texture};
pub use readback::{
    Readback, readback_buffer, readback_buffer_in, readback_buffers, readback_texture,
    readback_texture_in,
};
pub use targets::{GBUFFER_FORMATS, clear_depth, depth_cleared, target_bytes_per_sample};
pub(crate) use targets::{check_screen, check_target_bytes, screen_fits, screen_rounded};
pub use timing::{Profiler, Record, Recorder, Timer};
pub use upload::RING_UPLOADS;
#[cfg(feature = "techniques")]
pub(crate) use upload::Uploads;

use crate::error::Error;

/// Run `f` inside validation and out-of-memory error scopes; any error wgpu reports becomes
/// [`Error::Wgpu`] naming `stage`. Used where objects are made (pipelines, uploads), never per
/// frame. It does not wait: on native backends a popped scope is ready at once; where it is not
/// (the web), the error goes to the device's uncaptured-error handler instead.
pub(crate) fn scoped<T>(
    device: &wgpu::Device,
    stage: &'static str,
    f: impl FnOnce() -> T,
) -> Result<T, Error> {
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    let v = ready_now(validation.pop()).flatten();
    let o = ready_now(oom.pop()).flatten();
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
    uniform_of(device, label, &uniform_bytes(value))
}

/// `value` laid out by encase as a uniform.
pub(crate) fn uniform_bytes<T: encase::ShaderType + encase::internal::WriteInto>(
    value: &T,
) -> Vec<u8> {
    let mut bytes = encase::UniformBuffer::new(Vec::new());
    bytes
        .write(value)
        .expect("a generated uniform struct always encodes");
    bytes.into_inner()
}

/// A uniform buffer holding `bytes`.
fn uniform_of(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytes,
        usage: wgpu::BufferUsages::UNIFORM,
    })
}

/// One uniform buffer kept from call to call: [`KeptUniform::get`] hands back the buffer it
/// made last while the value is the same, and makes a new one only when the value changes (the
/// old one lives on in any command still using it). A renderer drawn every frame with the same
/// parameters then makes no buffer a frame, and its bind group can be kept too.
// Used by the techniques.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
#[derive(Default)]
pub(crate) struct KeptUniform(std::sync::Mutex<Option<(Vec<u8>, wgpu::Buffer)>>);

#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl KeptUniform {
    /// The buffer holding `value` (see [`uniform_buffer`]).
    pub(crate) fn get<T: encase::ShaderType + encase::internal::WriteInto>(
        &self,
        device: &wgpu::Device,
        label: &str,
        value: &T,
    ) -> wgpu::Buffer {
        let bytes = uniform_bytes(value);
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((held, buffer)) = kept.as_ref()
            && *held == bytes
        {
            return buffer.clone();
        }
        let buffer = uniform_of(device, label, &bytes);
        *kept = Some((bytes, buffer.clone()));
        buffer
    }
}

/// Poll `f` once: its output if it is ready, else `None`. Never waits.
pub(crate) fn ready_now<F: std::future::Future>(f: F) -> Option<F::Output> {
    let mut f = std::pin::pin!(f);
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    match f.as_mut().poll(&mut cx) {
        std::task::Poll::Ready(v) => Some(v),
        std::task::Poll::Pending => None,
    }
}
