//! Copy buffers and 2D/3D textures back to the CPU without blocking.
//!
//! Two ways, which differ in what they see:
//!
//! - [`readback_texture_in`] and [`readback_buffer_in`] record the copy into **your encoder**,
//!   after what you recorded there, and map it when you submit that encoder: the copy sees
//!   everything recorded before it, submitted or not. Use these for what a pass of yours (or a
//!   fieldkit stage recorded into your encoder) writes.
//! - [`readback_texture`] and [`readback_buffer`] record the copy into an encoder of their own
//!   and **submit it at once**: they see what was submitted before the call, and nothing that is
//!   still only recorded in an encoder you have not submitted (a texture written there reads as
//!   it was before, often zeros).
//!
//! Both return a [`Readback`], which is a `Future`: it completes once the mapping is done,
//! which needs the device to be polled (wgpu polls on its own on the web; natively, call
//! `device.poll(wgpu::PollType::Poll)` each frame, as a render loop does anyway). Nothing here
//! waits. [`Readback::try_take`] asks without a waker, for a frame loop that checks once a
//! frame; the `context` feature adds a blocking `wait`, which is an error, not a hang, for a
//! readback whose encoder was never submitted.

use std::future::Future;
use std::pin::Pin;
use std::sync::{Arc, Mutex};
use std::task::{Context as TaskContext, Poll, Waker};

use crate::error::Error;

type Convert<T> = Box<dyn FnOnce(&[u8]) -> Result<T, Error> + Send>;

#[derive(Default)]
struct MapState {
    /// The mapping's outcome, once wgpu called back for every staging buffer (or for the first
    /// that failed).
    done: Option<Result<(), String>>,
    /// Staging buffers whose mapping has not called back yet.
    pending: usize,
    waker: Option<Waker>,
}

/// Data on its way back from the GPU: a `Future` of `Result<T, Error>`.
///
/// ```no_run
/// # async fn f(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &wgpu::Buffer)
/// #     -> Result<(), fieldkit::Error> {
/// let bytes: Vec<u8> = fieldkit::gpu::readback_buffer(device, queue, buffer).await?;
/// # Ok(()) }
/// ```
#[must_use = "a readback does nothing unless polled, awaited or taken"]
pub struct Readback<T> {
    /// The staging buffers the copy fills, in order (several where one buffer cannot hold it).
    staging: Vec<wgpu::Buffer>,
    state: Arc<Mutex<MapState>>,
    convert: Option<Convert<T>>,
    /// An outcome known before any mapping (a refused copy, or a value computed on the CPU).
    early: Option<Result<T, Error>>,
    submission: Option<wgpu::SubmissionIndex>,
}

impl<T: 'static> std::fmt::Debug for Readback<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Readback")
            .field("staging", &self.staging)
            .field("ready", &self.is_ready())
            .finish()
    }
}

impl<T: 'static> Readback<T> {
    /// A readback that is already finished with `result` (used for errors found before any copy).
    pub fn ready(result: Result<T, Error>) -> Self {
        Self {
            staging: Vec::new(),
            state: Arc::default(),
            convert: None,
            early: Some(result),
            submission: None,
        }
    }

    /// Map `staging` (which a submitted copy, `submission`, fills) and turn its bytes, buffer
    /// after buffer, into `T`.
    fn map(
        staging: Vec<wgpu::Buffer>,
        submission: wgpu::SubmissionIndex,
        convert: impl FnOnce(&[u8]) -> Result<T, Error> + Send + 'static,
    ) -> Self {
        let mut this = Self::waiting(staging, convert);
        for buffer in &this.staging {
            buffer.map_async(wgpu::MapMode::Read, .., mapped(&this.state));
        }
        this.submission = Some(submission);
        this
    }

    /// Map `staging` once the caller submits `encoder`, into which the copy that fills it was
    /// recorded.
    fn map_on_submit(
        encoder: &wgpu::CommandEncoder,
        staging: Vec<wgpu::Buffer>,
        convert: impl FnOnce(&[u8]) -> Result<T, Error> + Send + 'static,
    ) -> Self {
        let this = Self::waiting(staging, convert);
        for buffer in &this.staging {
            encoder.map_buffer_on_submit(buffer, wgpu::MapMode::Read, .., mapped(&this.state));
        }
        this
    }

    /// A readback of `staging`, waiting for its mapping.
    fn waiting(
        staging: Vec<wgpu::Buffer>,
        convert: impl FnOnce(&[u8]) -> Result<T, Error> + Send + 'static,
    ) -> Self {
        let state = Arc::new(Mutex::new(MapState {
            pending: staging.len(),
            ..MapState::default()
        }));
        Self {
            staging,
            state,
            convert: Some(Box::new(convert)),
            early: None,
            submission: None,
        }
    }

    /// Convert the result afterwards (e.g. bytes into typed values).
    pub fn then<U: 'static>(
        mut self,
        f: impl FnOnce(T) -> Result<U, Error> + Send + 'static,
    ) -> Readback<U> {
        if let Some(r) = self.early.take() {
            return Readback::ready(r.and_then(f));
        }
        let Some(convert) = self.convert.take() else {
            return Readback::ready(Err(Error::Readback("the result was already taken".into())));
        };
        Readback {
            staging: std::mem::take(&mut self.staging),
            state: self.state.clone(),
            convert: Some(Box::new(move |b| convert(b).and_then(f))),
            early: None,
            submission: self.submission.take(),
        }
    }

    /// The submission that carries the copy (`None` when there was nothing to copy): what a
    /// caller polls the device for.
    pub fn submission(&self) -> Option<&wgpu::SubmissionIndex> {
        self.submission.as_ref()
    }

    /// Whether [`Readback::try_take`] would return the result now.
    pub fn is_ready(&self) -> bool {
        self.early.is_some()
            || self.convert.is_none()
            || self.state.lock().map(|s| s.done.is_some()).unwrap_or(true)
    }

    /// The result if the mapping has finished, else `None` (ask again after the next
    /// `device.poll`). After it returned `Some`, it returns an error.
    pub fn try_take(&mut self) -> Option<Result<T, Error>> {
        if let Some(r) = self.early.take() {
            return Some(r);
        }
        if self.convert.is_none() {
            // Taken before (or an early result taken): say so rather than wait forever.
            return Some(Err(Error::Readback("the result was already taken".into())));
        }
        let done = self
            .state
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .done
            .take()?;
        let staging = std::mem::take(&mut self.staging);
        let Some(convert) = self.convert.take() else {
            return Some(Err(Error::Readback("the result was already taken".into())));
        };
        Some(done.map_err(Error::Readback).and_then(|()| {
            let out = match staging.as_slice() {
                // One buffer: its mapped bytes as they are, no copy.
                [one] => {
                    let view = one
                        .get_mapped_range(..)
                        .map_err(|e| Error::Readback(format!("{e:?}")))?;
                    convert(&view)
                }
                several => {
                    let mut bytes = Vec::new();
                    for b in several {
                        let view = b
                            .get_mapped_range(..)
                            .map_err(|e| Error::Readback(format!("{e:?}")))?;
                        bytes.extend_from_slice(&view);
                    }
                    convert(&bytes)
                }
            };
            for b in &staging {
                b.unmap();
            }
            out
        }))
    }
}

impl<T: Unpin + 'static> Future for Readback<T> {
    type Output = Result<T, Error>;

    fn poll(self: Pin<&mut Self>, cx: &mut TaskContext<'_>) -> Poll<Self::Output> {
        let this = self.get_mut();
        if let Some(r) = this.try_take() {
            return Poll::Ready(r);
        }
        let mut s = this.state.lock().unwrap_or_else(|e| e.into_inner());
        if s.done.is_some() {
            // Finished between the two looks: come back at once.
            cx.waker().wake_by_ref();
        } else {
            s.waker = Some(cx.waker().clone());
        }
        Poll::Pending
    }
}

/// The callback of one staging buffer's mapping: the readback is done once every buffer has
/// called back (or the first failed).
fn mapped(
    state: &Arc<Mutex<MapState>>,
) -> impl FnOnce(Result<(), wgpu::BufferAsyncError>) + Send + 'static {
    let sink = state.clone();
    move |r| {
        let mut s = sink.lock().unwrap_or_else(|e| e.into_inner());
        s.pending -= 1;
        match r {
            Err(e) if s.done.is_none() => s.done = Some(Err(e.to_string())),
            Ok(()) if s.pending == 0 && s.done.is_none() => s.done = Some(Ok(())),
            _ => return,
        }
        if let Some(w) = s.waker.take() {
            w.wake();
        }
    }
}

fn staging(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Read a whole buffer (it needs `COPY_SRC` usage): records and **submits** one copy of its
/// own, so it sees what was submitted before the call and nothing still only recorded in an
/// encoder of yours ([`readback_buffer_in`] records into yours).
pub fn readback_buffer(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffer: &wgpu::Buffer,
) -> Readback<Vec<u8>> {
    readback_buffers(device, queue, &[buffer])
}

/// Read several whole buffers (each needs `COPY_SRC` usage) as one run of bytes, buffer after
/// buffer: one submission, one staging buffer each (so the total may exceed what one buffer
/// holds, as a field split across bindings does). Submitted at once, as [`readback_buffer`].
pub fn readback_buffers(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    buffers: &[&wgpu::Buffer],
) -> Readback<Vec<u8>> {
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("fieldkit readback"),
    });
    match copy_buffers(device, &mut enc, buffers) {
        Ok(staging) => {
            let submission = queue.submit([enc.finish()]);
            Readback::map(staging, submission, |b| Ok(b.to_vec()))
        }
        Err(e) => Readback::ready(Err(e)),
    }
}

/// Read a whole buffer (it needs `COPY_SRC` usage) through `encoder`: the copy is recorded
/// there, after what you recorded, and mapped when you submit the encoder, so it sees every
/// write recorded before it.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, buffer: &wgpu::Buffer) {
/// let mut encoder = device.create_command_encoder(&Default::default());
/// // ... passes that write `buffer` ...
/// let readback = fieldkit::gpu::readback_buffer_in(device, &mut encoder, buffer);
/// queue.submit([encoder.finish()]);
/// // Poll the device (each frame, or `device.poll(wgpu::PollType::wait_indefinitely())`),
/// // then `readback.try_take()` or `.await` it.
/// # let _ = readback; }
/// ```
pub fn readback_buffer_in(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
) -> Readback<Vec<u8>> {
    match copy_buffers(device, encoder, &[buffer]) {
        Ok(staging) => Readback::map_on_submit(encoder, staging, |b| Ok(b.to_vec())),
        Err(e) => Readback::ready(Err(e)),
    }
}

/// Record copies of `buffers` into staging buffers, in `enc`.
fn copy_buffers(
    device: &wgpu::Device,
    enc: &mut wgpu::CommandEncoder,
    buffers: &[&wgpu::Buffer],
) -> Result<Vec<wgpu::Buffer>, Error> {
    if let Some(b) = buffers
        .iter()
        .find(|b| !b.usage().contains(wgpu::BufferUsages::COPY_SRC))
    {
        return Err(Error::Readback(format!(
            "buffer {:?} lacks COPY_SRC usage ({:?})",
            b,
            b.usage()
        )));
    }
    Ok(buffers
        .iter()
        .map(|b| {
            let s = staging(device, "fieldkit readback", b.size());
            enc.copy_buffer_to_buffer(b, 0, &s, 0, b.size());
            s
        })
        .collect())
}

/// Read mip 0 of a 2D or 3D texture into texels of type `T` (e.g. `u32` for `R32Uint`, `f32`
/// for `R32Float` and `Depth32Float`, `[u8; 4]` for `Rgba8Unorm`), rows tightly packed, x
/// fastest, then y, then z. The texture needs `COPY_SRC` usage.
///
/// This records and **submits** a copy of its own: it sees what was submitted before the call,
/// not what an encoder of yours that you have not submitted yet writes (that reads as the
/// texture was before, often zeros). To read what your encoder writes, use
/// [`readback_texture_in`], or submit first.
pub fn readback_texture<T: bytemuck::Pod + Send>(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Readback<Vec<T>> {
    let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("fieldkit texture readback"),
    });
    match copy_texture::<T>(device, &mut enc, texture) {
        Ok((staging, convert)) => {
            let submission = queue.submit([enc.finish()]);
            Readback::map(vec![staging], submission, convert)
        }
        Err(e) => Readback::ready(Err(e)),
    }
}

/// [`readback_texture`] through `encoder`: the copy is recorded there, after what you recorded,
/// and mapped when you submit the encoder, so it sees every write recorded before it.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) {
/// let mut encoder = device.create_command_encoder(&Default::default());
/// // ... a pass (or a fieldkit stage) that writes `texture` ...
/// let readback = fieldkit::gpu::readback_texture_in::<f32>(device, &mut encoder, texture);
/// queue.submit([encoder.finish()]);
/// // Poll the device (each frame, or `device.poll(wgpu::PollType::wait_indefinitely())`),
/// // then `readback.try_take()` or `.await` it.
/// # let _ = readback; }
/// ```
pub fn readback_texture_in<T: bytemuck::Pod + Send>(
    device: &wgpu::Device,
    encoder: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
) -> Readback<Vec<T>> {
    match copy_texture::<T>(device, encoder, texture) {
        Ok((staging, convert)) => Readback::map_on_submit(encoder, vec![staging], convert),
        Err(e) => Readback::ready(Err(e)),
    }
}

/// Record a copy of `texture`'s mip 0 into a staging buffer, in `enc`, with what turns the
/// staging buffer's padded rows into texels.
#[allow(clippy::type_complexity)]
fn copy_texture<T: bytemuck::Pod + Send>(
    device: &wgpu::Device,
    enc: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
) -> Result<
    (
        wgpu::Buffer,
        impl FnOnce(&[u8]) -> Result<Vec<T>, Error> + Send + 'static,
    ),
    Error,
> {
    let format = texture.format();
    // Depth formats are read through their depth aspect (`f32` for `Depth32Float`).
    let aspect = if format.has_depth_aspect() {
        wgpu::TextureAspect::DepthOnly
    } else {
        wgpu::TextureAspect::All
    };
    let Some(texel) = format.block_copy_size(Some(aspect)) else {
        return Err(Error::Readback(format!("{format:?} cannot be copied")));
    };
    if texel as usize != std::mem::size_of::<T>() {
        return Err(Error::Readback(format!(
            "{format:?} has {texel}-byte texels, asked for {}-byte values",
            std::mem::size_of::<T>()
        )));
    }
    if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
        return Err(Error::Readback(format!(
            "texture lacks COPY_SRC usage ({:?})",
            texture.usage()
        )));
    }
    let size = texture.size();
    let row = size.width * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let staging = staging(
        device,
        "fieldkit texture readback",
        padded as u64 * size.height as u64 * size.depth_or_array_layers as u64,
    );
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            aspect,
            ..texture.as_image_copy()
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(size.height),
            },
        },
        size,
    );
    Ok((staging, move |bytes: &[u8]| {
        let mut out =
            Vec::with_capacity((size.width * size.height * size.depth_or_array_layers) as usize);
        for chunk in bytes.chunks(padded as usize) {
            out.extend_from_slice(bytemuck::cast_slice::<u8, T>(&chunk[..row as usize]));
        }
        Ok(out)
    }))
}
