//! Per-frame data into buffers kept from frame to frame, without a new buffer a frame and
//! without the hazard of writing one buffer twice before a submission.
//!
//! `Queue::write_buffer` straight into a kept uniform is not enough for a stage drawn several
//! times before its encoder is submitted (two views, a test that records two settings): every
//! write lands at the start of the next submission, so each draw would read the last value.
//! [`Uploads`] writes each call's bytes to a fresh span of a staging ring with the queue and
//! records a copy from that span into the kept buffer in the caller's encoder, ordered with the
//! passes that read it: each draw reads its own bytes. A span is written again only after the
//! ring wraps; the ring holds at least [`RING_UPLOADS`] of the largest upload it has taken (and
//! [`RING_BYTES`]), growing (one new buffer) when a larger one comes, so an encoder may hold
//! that many draws of one object before its submission. One submitted after more would read a
//! later draw's bytes: the bound the renderers' docs state.

use std::sync::Mutex;

/// The staging ring's least size.
pub(crate) const RING_BYTES: u64 = 256 * 1024;

/// How many draws of one renderer ([`OceanRenderer`](crate::ocean::OceanRenderer),
/// [`VolumeRenderer`](crate::volume::VolumeRenderer),
/// [`Raymarcher`](crate::metaball::Raymarcher)) one encoder may hold before it is submitted:
/// each draw stages its parameters in a ring the renderer keeps, which holds at least this many
/// of its largest, and a draw followed by more than this many before its encoder is submitted
/// would read a later draw's parameters. Drawing a renderer once or twice a frame (a view, a
/// reflection) is far within it.
pub const RING_UPLOADS: u64 = 64;

/// A staging ring and the queue that writes it (see the module docs).
// Used by the techniques' per-frame stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct Uploads {
    queue: wgpu::Queue,
    /// The ring and the offset of its next free byte.
    ring: Mutex<Option<(wgpu::Buffer, u64)>>,
}

#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl Uploads {
    pub(crate) fn new(queue: &wgpu::Queue) -> Self {
        Self {
            queue: queue.clone(),
            ring: Mutex::new(None),
        }
    }

    /// The buffer kept in `slot` (made there with `label` and `usage` + `COPY_DST` when there is
    /// none or it is too small, with room to grow) holding `bytes` from the copy recorded now
    /// into `encoder` on: a per-frame uniform or instance list, no buffer made a frame.
    pub(crate) fn kept(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        slot: &Mutex<Option<wgpu::Buffer>>,
        label: &str,
        usage: wgpu::BufferUsages,
        bytes: &[u8],
    ) -> wgpu::Buffer {
        let len = (bytes.len() as u64).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let buffer = super::kept_buffer(slot, len, false, || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                // Room to grow: a few more patches next frame make no new buffer.
                size: len.next_power_of_two().max(256),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        self.write(device, encoder, &buffer, bytes);
        buffer
    }

    /// [`Self::kept`] for a uniform holding `value` (laid out by encase).
    pub(crate) fn uniform<T: encase::ShaderType + encase::internal::WriteInto>(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        slot: &Mutex<Option<wgpu::Buffer>>,
        label: &str,
        value: &T,
    ) -> wgpu::Buffer {
        let bytes = super::uniform_bytes(value);
        self.kept(
            device,
            encoder,
            slot,
            label,
            wgpu::BufferUsages::UNIFORM,
            &bytes,
        )
    }

    /// Record into `encoder` a copy of `bytes` to the start of `dst` (which has `COPY_DST` and
    /// room for them), staged through the ring. Bytes are padded to the copy alignment (4).
    pub(crate) fn write(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        dst: &wgpu::Buffer,
        bytes: &[u8],
    ) {
        if bytes.is_empty() {
            return;
        }
        let align = wgpu::COPY_BUFFER_ALIGNMENT;
        let len = (bytes.len() as u64).next_multiple_of(align);
        let mut ring = self.ring.lock().unwrap_or_else(|e| e.into_inner());
        let want = RING_BYTES.max(len * RING_UPLOADS);
        if ring.as_ref().is_none_or(|(b, _)| b.size() < want) {
            let size = want.next_power_of_two();
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("fieldkit upload ring"),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            *ring = Some((buffer, 0));
        }
        let (buffer, next) = ring.as_mut().expect("made above");
        if *next + len > buffer.size() {
            *next = 0;
        }
        let at = *next;
        *next += len;
        if len == bytes.len() as u64 {
            self.queue.write_buffer(buffer, at, bytes);
        } else {
            let mut padded = bytes.to_vec();
            padded.resize(len as usize, 0);
            self.queue.write_buffer(buffer, at, &padded);
        }
        encoder.copy_buffer_to_buffer(buffer, at, dst, 0, len);
    }
}
