//! A pipeline cache an app keeps on disk, so that its next launch makes fieldkit's pipelines
//! from the driver's compiled code instead of compiling them again.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The caches installed, one per device: every fieldkit pipeline made on the device goes
/// through its cache.
static INSTALLED: Mutex<Vec<(wgpu::Device, wgpu::PipelineCache)>> = Mutex::new(Vec::new());

/// The cache installed for `device`, if any (what fieldkit's pipelines are made through).
pub(crate) fn installed(device: &wgpu::Device) -> Option<wgpu::PipelineCache> {
    let installed = INSTALLED.lock().unwrap_or_else(|e| e.into_inner());
    installed
        .iter()
        .find(|(d, _)| d == device)
        .map(|(_, c)| c.clone())
}

/// What a cache file starts with: a tag, then the length and the FNV-1a hash of what follows,
/// so that a file cut short or changed on disk is never handed to the driver.
const MAGIC: &[u8; 8] = b"fkpipes1";

/// A `wgpu::PipelineCache` installed for one device: while it is kept, every pipeline fieldkit
/// makes on that device (every technique's `new`, every variant made on first use) goes
/// through it, and [`PipelineCache::save`] writes what the driver compiled to disk for the next
/// launch. Dropping it uninstalls it (drop it before the device).
///
/// wgpu tells devices apart by an id that is unique only within their own `wgpu::Instance`:
/// in a process with several instances (tests that each open their own), a cache installed for
/// a device of one instance is found for the device of the same id in another, whose pipelines
/// then fail. Keep to one instance where a cache is installed, or keep such devices apart in
/// time (as `tests/viewer/scenes.rs` does).
///
/// Where the device cannot keep a pipeline cache ([`wgpu::Features::PIPELINE_CACHE`] not
/// enabled, or a backend without one: wgpu has them on Vulkan), [`PipelineCache::open`]
/// returns `None` and pipelines are made as before.
///
/// ```no_run
/// # fn f(adapter: &wgpu::Adapter, device: &wgpu::Device) -> std::io::Result<()> {
/// // Before the app makes its fieldkit objects (the device asked for PIPELINE_CACHE):
/// let cache = fieldkit::gpu::PipelineCache::open(device, &adapter.get_info(), "cache".as_ref())?;
/// let distance = fieldkit::distance::Distance2d::new(device);
/// // … at exit (or after the first frames, when every pipeline was made):
/// if let Some(cache) = &cache {
///     cache.save()?;
/// }
/// # Ok(()) }
/// ```
pub struct PipelineCache {
    device: wgpu::Device,
    cache: wgpu::PipelineCache,
    path: Option<PathBuf>,
    loaded: usize,
}

impl PipelineCache {
    /// The cache kept in `dir` for this adapter and driver (a file named by
    /// `wgpu::util::pipeline_cache_key`), installed for `device`. A missing, damaged or
    /// outdated file starts an empty cache ([`Self::loaded_bytes`] is then 0); only an I/O error
    /// other than "not found" is an error. `None` where the device cannot keep one.
    pub fn open(
        device: &wgpu::Device,
        adapter: &wgpu::AdapterInfo,
        dir: &Path,
    ) -> std::io::Result<Option<Self>> {
        let Some(key) = wgpu::util::pipeline_cache_key(adapter) else {
            return Ok(None);
        };
        if !device.features().contains(wgpu::Features::PIPELINE_CACHE) {
            return Ok(None);
        }
        let path = dir.join(key);
        let data = match std::fs::read(&path) {
            Ok(bytes) => unframe(&bytes).map(<[u8]>::to_vec),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(e) => return Err(e),
        };
        let mut cache = Self::with_data(device, data.as_deref());
        if let Some(c) = &mut cache {
            c.path = Some(path);
        }
        Ok(cache)
    }

    /// A cache holding `data` (what [`Self::data`] returned on an earlier run with the same
    /// adapter and driver; `None` for an empty one), installed for `device`, for an app that
    /// stores it itself. `None` where the device lacks [`wgpu::Features::PIPELINE_CACHE`].
    pub fn with_data(device: &wgpu::Device, data: Option<&[u8]>) -> Option<Self> {
        if !device.features().contains(wgpu::Features::PIPELINE_CACHE) {
            return None;
        }
        // Safety: `data` is what `PipelineCache::get_data` returned for this adapter key (the
        // file is named by it, and checked whole against the hash `save` wrote beside it);
        // wgpu checks its own header and the driver its, and with `fallback` a cache the driver
        // does not take starts empty.
        let cache = unsafe {
            device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                label: Some("fieldkit pipelines"),
                data,
                fallback: true,
            })
        };
        let mut installed = INSTALLED.lock().unwrap_or_else(|e| e.into_inner());
        installed.retain(|(d, _)| d != device);
        installed.push((device.clone(), cache.clone()));
        Some(Self {
            device: device.clone(),
            cache,
            path: None,
            loaded: data.map_or(0, <[u8]>::len),
        })
    }

    /// The bytes the cache started with (0: empty, nothing was loaded).
    pub fn loaded_bytes(&self) -> usize {
        self.loaded
    }

    /// What the driver holds now, to store for the next launch (`None` where it gives nothing).
    pub fn data(&self) -> Option<Vec<u8>> {
        self.cache.get_data()
    }

    /// Write the cache to the file [`Self::open`] read (a new file beside it, then renamed over
    /// it, so a crash never leaves half a cache). Does nothing for a cache made by
    /// [`Self::with_data`] or where the driver gives no data.
    pub fn save(&self) -> std::io::Result<()> {
        let (Some(path), Some(data)) = (&self.path, self.data()) else {
            return Ok(());
        };
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let partial = path.with_extension("partial");
        std::fs::write(&partial, frame(&data))?;
        std::fs::rename(&partial, path)
    }

    /// The wgpu cache itself, for the app's own pipelines.
    pub fn wgpu(&self) -> &wgpu::PipelineCache {
        &self.cache
    }
}

impl Drop for PipelineCache {
    fn drop(&mut self) {
        let mut installed = INSTALLED.lock().unwrap_or_else(|e| e.into_inner());
        installed.retain(|(d, c)| !(d == &self.device && c == &self.cache));
    }
}

/// 64-bit FNV-1a.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// `data` behind [`MAGIC`], its length and its hash.
fn frame(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(data.len() + 24);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&fnv1a(data).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The data of a file [`frame`] wrote, or `None` where it is not one whole.
fn unframe(bytes: &[u8]) -> Option<&[u8]> {
    let rest = bytes.strip_prefix(MAGIC)?;
    let (len, rest) = rest.split_first_chunk::<8>()?;
    let (hash, data) = rest.split_first_chunk::<8>()?;
    (u64::from_le_bytes(*len) == data.len() as u64 && u64::from_le_bytes(*hash) == fnv1a(data))
        .then_some(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_framed_cache_reads_back_and_a_damaged_one_does_not() {
        let data: Vec<u8> = (0..300u32).map(|i| (i * 7 % 251) as u8).collect();
        let framed = frame(&data);
        assert_eq!(unframe(&framed), Some(&data[..]));
        // Cut short, one byte changed, or not a cache at all: nothing reaches the driver.
        assert_eq!(unframe(&framed[..framed.len() - 1]), None);
        let mut flipped = framed.clone();
        flipped[40] ^= 1;
        assert_eq!(unframe(&flipped), None);
        assert_eq!(unframe(b"not a cache"), None);
        assert_eq!(unframe(&[]), None);
    }
}
