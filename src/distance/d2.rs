//! The 2D front: [`Distance2d`] runs the exact transform by default and JFA on request, from
//! the same seed textures and options.

use super::buffers::Pool;
use super::exact::Exact;
use super::resolve::Resolver;
use super::{Inside, Jfa2d, JfaSettings2d, SeedRule, Settings3d, Variant};
use crate::error::Error;
use crate::gpu::{Readback, readback_buffer, readback_texture};

use std::sync::Arc;

/// How [`Distance2d`] computes a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Method2d {
    /// The exact Euclidean transform (rows, then banded lower envelopes along columns): no
    /// wrong texels, and faster than every JFA variant at every size measured. Sides up to
    /// [`MAX_SIDE_2D_EXACT`](super::MAX_SIDE_2D_EXACT).
    #[default]
    Exact,
    /// Jump flooding with the given variant.
    Jfa(Variant),
}

/// What [`Distance2d::encode`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Settings2d {
    /// Exact (default) or a JFA variant.
    pub method: Method2d,
    /// Treat the mask as inside (seed texels) and produce signed distance, negative inside.
    ///
    /// **Convention:** distances are between texel centres, and a signed field takes half a
    /// texel off so that zero lies between the last inside and the first outside texel: an
    /// outside texel holds (its distance to the nearest inside texel − ½) × `texel_size`, an
    /// inside texel −(its distance to the nearest outside texel − ½) × `texel_size`. A texel
    /// beside the boundary reads ±0.5 texel, not 1 or 0. Unsigned fields (`false`) hold the
    /// plain distance to the nearest seed texel's centre (0 on a seed).
    pub signed: bool,
    /// World units per texel; distances are multiplied by it.
    pub texel_size: f32,
    /// Which texels are seeds: red above 0 by default; [`SeedRule::seed`] takes every
    /// non-black texel, as the source's tool does.
    #[cfg_attr(feature = "serde", serde(default))]
    pub seeds: SeedRule,
}

impl Default for Settings2d {
    fn default() -> Self {
        Self {
            method: Method2d::Exact,
            signed: false,
            texel_size: 1.0,
            seeds: SeedRule::default(),
        }
    }
}

impl Settings2d {
    /// The defaults with a signed field, negative inside:
    /// `Settings2d { signed: true, ..Settings2d::default() }`.
    pub fn signed() -> Self {
        Self {
            signed: true,
            ..Self::default()
        }
    }
}

/// Nearest seeds of a 2D field, packed as [`pack_seed`](super::pack_seed) does (0 = none): an `R32Uint` texture
/// from JFA, a row-major `u32` buffer from the exact transform.
#[derive(Debug)]
pub enum Nearest2d {
    /// `R32Uint` texture (JFA).
    Texture(wgpu::Texture),
    /// `u32` per texel, x fastest (exact transform).
    Buffer(wgpu::Buffer),
}

impl Nearest2d {
    /// The packed seeds, x fastest, once the encoder that made them was submitted.
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        len: usize,
    ) -> Readback<Vec<u32>> {
        match self {
            Nearest2d::Texture(t) => readback_texture(device, queue, t),
            Nearest2d::Buffer(b) => readback_buffer(device, queue, b)
                .then(move |bytes| Ok(bytemuck::cast_slice::<u8, u32>(&bytes)[..len].to_vec())),
        }
    }
}

/// A 2D distance field from [`Distance2d`], on the GPU.
#[derive(Debug)]
pub struct Field2d {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `R32Float`, texel (x, y) at column x, row y (row 0 the mask's first): distance to the
    /// nearest seed texel's centre times `texel_size` (world units); signed fields are negative
    /// inside and half a texel closer to zero than the centre distance (see
    /// [`Settings2d::signed`]). [`FAR`](super::FAR) where there is no seed.
    pub distance: wgpu::Texture,
    /// Nearest seed per texel (signed: nearest *inside* texel).
    pub nearest: Nearest2d,
    /// Signed fields: nearest *outside* texel.
    pub nearest_outside: Option<Nearest2d>,
}

impl Field2d {
    /// Read [`Field2d::nearest`] back (see [`Nearest2d::read`]).
    pub fn read_nearest(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<u32>> {
        self.nearest
            .read(device, queue, self.width as usize * self.height as usize)
    }
}

/// The 2D distance API: the exact transform by default, JFA on request. Create once, encode
/// many times.
///
/// ```no_run
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, mask: &wgpu::Texture) -> Result<(), fieldkit::Error> {
/// use fieldkit::distance::{Distance2d, Settings2d};
/// let distance = Distance2d::new(device)?; // once
/// let mut encoder = device.create_command_encoder(&Default::default());
/// let field = distance.encode(device, &mut encoder, mask, &Settings2d { signed: true, ..Default::default() })?;
/// queue.submit([encoder.finish()]);
/// // field.distance: R32Float, negative inside (see `Settings2d::signed` for the ½-texel rule).
/// # let _ = field; Ok(()) }
/// ```
pub struct Distance2d {
    jfa: Jfa2d,
    exact: Exact,
    /// The exact transform's fields handed back ([`Distance2d::recycle`]).
    pool: Arc<Pool>,
}

impl Distance2d {
    /// Create the 2D pipelines (both methods).
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        let pool = Arc::new(Pool::default());
        Ok(Self {
            jfa: Jfa2d::new(device)?,
            exact: Exact::new(device, pool.clone(), Arc::new(Resolver::new(device)?))?,
            pool,
        })
    }

    /// Hand a field of the exact transform back (its nearest-seed buffers and distance
    /// texture): the next [`Self::encode`] of the same size takes them instead of making new
    /// ones, so a tool that recomputes its field every frame allocates nothing (on NVIDIA's
    /// driver a new buffer of tens of megabytes costs the CPU milliseconds). The next field's
    /// passes overwrite every texel, and commands run in the order recorded, so a field may be
    /// handed back as soon as the passes that read it are recorded. A JFA field is dropped.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue, mask: &wgpu::Texture) -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance2d, Settings2d};
    /// let distance = Distance2d::new(device)?;
    /// let mut last = None;
    /// for _frame in 0..3 {
    ///     if let Some(field) = last.take() {
    ///         distance.recycle(field);
    ///     }
    ///     let mut encoder = device.create_command_encoder(&Default::default());
    ///     last = Some(distance.encode(device, &mut encoder, mask, &Settings2d::default())?);
    ///     queue.submit([encoder.finish()]);
    /// }
    /// # Ok(()) }
    /// ```
    pub fn recycle(&self, field: Field2d) {
        let Nearest2d::Buffer(nearest) = field.nearest else {
            return;
        };
        let nearest_outside = match field.nearest_outside {
            Some(Nearest2d::Buffer(b)) => Some(b),
            _ => None,
        };
        self.pool.recycle_2d(super::FieldBuf2d {
            width: field.width,
            height: field.height,
            nearest,
            nearest_outside,
            distance: field.distance,
        });
    }

    /// Make the pipelines [`Self::encode`] needs for a mask of `size` with `options`, which it
    /// would otherwise make on its first call with them (the exact transform specialises its
    /// passes by the sign and the plan of a size): call it ahead, on any thread, so that no
    /// frame waits for a pipeline. It records the transform of a blank mask into an encoder it
    /// drops unsubmitted, and hands the field back ([`Self::recycle`]) for the next encode of
    /// that size.
    ///
    /// ```no_run
    /// # fn f(device: &wgpu::Device) -> Result<(), fieldkit::Error> {
    /// use fieldkit::distance::{Distance2d, Settings2d};
    /// let distance = std::sync::Arc::new(Distance2d::new(device)?);
    /// let (d, dev) = (distance.clone(), device.clone());
    /// let signed = Settings2d { signed: true, ..Default::default() };
    /// // On a worker, while frames draw the unsigned field.
    /// std::thread::spawn(move || d.prepare(&dev, [512, 512], &signed)).join().unwrap()?;
    /// # Ok(()) }
    /// ```
    pub fn prepare(
        &self,
        device: &wgpu::Device,
        size: [u32; 2],
        options: &Settings2d,
    ) -> Result<(), Error> {
        super::seeds::check_size(device, size[0], size[1])?;
        let mask = crate::gpu::texture(
            device,
            "distance 2d prepare mask",
            [size[0], size[1], 1],
            wgpu::TextureDimension::D2,
            wgpu::TextureFormat::R8Unorm,
            wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let mut encoder = device.create_command_encoder(&Default::default());
        let field = self.encode(device, &mut encoder, &mask, options)?;
        self.recycle(field);
        Ok(())
    }

    /// The distance field of `mask` (any colour format read as float; `options.seeds` says
    /// which texels are seeds, red above 0 by default),
    /// recorded into `rec` (a command encoder, or [`crate::gpu::Profiler::record`] to time each
    /// pass).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        mask: &wgpu::Texture,
        options: &Settings2d,
    ) -> Result<Field2d, Error> {
        if !(options.texel_size.is_finite() && options.texel_size > 0.0) {
            return Err(Error::Invalid {
                stage: "distance::d2",
                what: format!(
                    "texel_size {} must be finite and positive",
                    options.texel_size
                ),
            });
        }
        match options.method {
            Method2d::Exact => {
                let f = self.exact.encode_exact_2d_with(
                    device,
                    rec,
                    mask,
                    &Settings3d {
                        signed: options.signed,
                        voxel_size: options.texel_size,
                        inside: Inside::Mask,
                        ..Settings3d::default()
                    },
                    &options.seeds,
                )?;
                Ok(Field2d {
                    width: f.width,
                    height: f.height,
                    distance: f.distance,
                    nearest: Nearest2d::Buffer(f.nearest),
                    nearest_outside: f.nearest_outside.map(Nearest2d::Buffer),
                })
            }
            Method2d::Jfa(variant) => {
                let f = self.jfa.encode(
                    device,
                    rec,
                    mask,
                    &JfaSettings2d {
                        variant,
                        signed: options.signed,
                        texel_size: options.texel_size,
                        seeds: options.seeds,
                    },
                )?;
                Ok(Field2d {
                    width: f.width,
                    height: f.height,
                    distance: f.distance,
                    nearest: Nearest2d::Texture(f.nearest),
                    nearest_outside: f.nearest_outside.map(Nearest2d::Texture),
                })
            }
        }
    }
}
