//! Allocation helpers every technique shares: textures of one mip and sample, the storage
//! textures stages write volumes into, and storage buffers.

/// A texture of `size` (`[width, height, depth or layers]`), one mip level and one sample: the
/// texture every fieldkit stage makes, and what tests and demos make their targets with.
///
/// ```no_run
/// # fn f(device: &wgpu::Device) {
/// let depth = fieldkit::gpu::texture(
///     device,
///     "depth",
///     [1920, 1080, 1],
///     wgpu::TextureDimension::D2,
///     wgpu::TextureFormat::Depth32Float,
///     wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
/// );
/// # }
/// ```
pub fn texture(
    device: &wgpu::Device,
    label: &str,
    size: [u32; 3],
    dimension: wgpu::TextureDimension,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size[0],
            height: size[1],
            depth_or_array_layers: size[2],
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension,
        format,
        usage,
        view_formats: &[],
    })
}

/// A 3D texture a stage writes (storage) and later stages sample or copy out.
// Used by the techniques.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) fn volume_texture(
    device: &wgpu::Device,
    label: &str,
    size: [u32; 3],
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    texture(
        device,
        label,
        size,
        wgpu::TextureDimension::D3,
        format,
        wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
    )
}

/// A storage buffer of `bytes` with `extra` usages beside `STORAGE`.
// Used by the techniques.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) fn storage_buffer(
    device: &wgpu::Device,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | extra,
        mapped_at_creation: false,
    })
}

/// The buffer kept in `slot` where it holds `bytes` (exactly `bytes` where `exact`, for
/// buffers that passes check to be their field's size), else a new one from `make`, kept for
/// the next call.
pub(crate) fn kept_buffer(
    slot: &std::sync::Mutex<Option<wgpu::Buffer>>,
    bytes: u64,
    exact: bool,
    make: impl FnOnce() -> wgpu::Buffer,
) -> wgpu::Buffer {
    let mut kept = slot.lock().unwrap_or_else(|e| e.into_inner());
    match kept.as_ref() {
        Some(b) if b.size() == bytes || (!exact && b.size() > bytes) => b.clone(),
        _ => {
            let b = make();
            *kept = Some(b.clone());
            b
        }
    }
}

/// A view of the texture given last, kept while the same texture comes again: a stage handed
/// the caller's target every frame makes its view once. Keyed by identity (the kept clone of
/// the texture keeps its identity from being reused).
#[derive(Default)]
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct KeptView(std::sync::Mutex<Option<(wgpu::Texture, wgpu::TextureView)>>);

#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl KeptView {
    /// The view of `texture` made by `make`, or the one kept for it.
    pub(crate) fn get(
        &self,
        texture: &wgpu::Texture,
        make: impl FnOnce(&wgpu::Texture) -> wgpu::TextureView,
    ) -> wgpu::TextureView {
        let mut kept = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((t, v)) = kept.as_ref()
            && t == texture
        {
            return v.clone();
        }
        // The old view goes first, so its texture's memory is free for what comes next.
        *kept = None;
        let view = make(texture);
        *kept = Some((texture.clone(), view.clone()));
        view
    }
}

/// A hold on an output a stage handed out (a `VolumeMarched`, a `LightVolume`, a
/// `MetaballField`): the stage takes the output's buffers and textures back for a later call
/// once every clone of its lease is dropped, so a loop that drops each frame's output before
/// the next frame's call makes none a frame, and one that keeps outputs gets new ones, never
/// its own overwritten. A clone of one of its textures kept past the output sees later values.
#[derive(Clone, Debug, Default)]
pub struct Lease(std::sync::Arc<()>);

/// Outputs a per-frame stage keeps and hands out again: a call takes one the caller no longer
/// holds (every clone of its [`Lease`] dropped) that fits what it needs, else makes one and
/// keeps it. A loop that drops each frame's output before the next frame's call so makes no
/// texture a frame, and one that keeps outputs gets new ones, never its own overwritten.
/// Commands run in the order recorded, so an output may be dropped as soon as the passes that
/// read it are recorded. A clone of one of its textures kept past its output sees later values.
// Used by the techniques' per-frame stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct Leased<T> {
    kept: std::sync::Mutex<Vec<(Lease, T)>>,
}

impl<T> Default for Leased<T> {
    fn default() -> Self {
        Self {
            kept: Default::default(),
        }
    }
}

/// Outputs kept at most per stage: a caller holding more makes new ones, which are not kept.
const LEASED_MAX: usize = 4;

#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl<T: Clone> Leased<T> {
    /// A kept output that `fits` and is free, or `make`'s (kept while there is room, replacing
    /// a free one that does not fit), with its lease.
    pub(crate) fn take(&self, fits: impl Fn(&T) -> bool, make: impl FnOnce() -> T) -> (T, Lease) {
        let free = |l: &Lease| std::sync::Arc::strong_count(&l.0) == 1;
        {
            let mut kept = self.lock();
            if let Some((lease, t)) = kept.iter().find(|(l, t)| free(l) && fits(t)) {
                return (t.clone(), lease.clone());
            }
            // Free outputs of another size are of no more use: dropped before the new one is
            // made, so their memory can hold it.
            kept.retain(|(l, _)| !free(l));
        }
        // Made without the lock: a frame taking a kept output never waits for another thread
        // making a new one (a texture can take the driver milliseconds).
        let t = make();
        let lease = Lease::default();
        let mut kept = self.lock();
        if kept.len() < LEASED_MAX {
            kept.push((lease.clone(), t.clone()));
        }
        (t, lease)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(Lease, T)>> {
        self.kept.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Change the kept output that `lease` holds (what a call learned while filling it).
    pub(crate) fn update(&self, lease: &Lease, f: impl FnOnce(&mut T)) {
        let mut kept = self.lock();
        if let Some((_, t)) = kept
            .iter_mut()
            .find(|(l, _)| std::sync::Arc::ptr_eq(&l.0, &lease.0))
        {
            f(t);
        }
    }
}
