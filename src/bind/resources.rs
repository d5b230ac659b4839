//! What may be bound where: the resource wrappers the generated `Resources` fields take.

use super::*;

/// A resource handed to a slot, before it is checked against the slot.
#[derive(Clone)]
pub enum Resource<'a> {
    /// A uniform or storage buffer range.
    Buffer(wgpu::BufferBinding<'a>),
    /// A sampled texture view.
    Texture(&'a wgpu::TextureView),
    /// A storage texture view.
    StorageTexture(&'a wgpu::TextureView),
    /// A sampler.
    Sampler(&'a wgpu::Sampler),
    /// A binding array of uniform or storage buffer ranges.
    Buffers(&'a [wgpu::BufferBinding<'a>]),
    /// A binding array of sampled texture views.
    Textures(&'a [&'a wgpu::TextureView]),
    /// A binding array of storage texture views.
    StorageTextures(&'a [&'a wgpu::TextureView]),
    /// A binding array of samplers.
    Samplers(&'a [&'a wgpu::Sampler]),
}

/// What a generated parameter struct's fields turn into for binding.
pub trait IntoResource<'a> {
    /// The resource to bind.
    fn resource(&self) -> Resource<'a>;
}

macro_rules! buffer_wrapper {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        pub struct $name<'a, T: ?Sized> {
            /// The buffer range bound.
            pub binding: wgpu::BufferBinding<'a>,
            _t: PhantomData<fn() -> Box<T>>,
        }
        impl<'a, T: ?Sized> $name<'a, T> {
            /// A range of a buffer.
            pub fn range(buffer: &'a wgpu::Buffer, offset: u64, size: Option<std::num::NonZeroU64>) -> Self {
                Self { binding: wgpu::BufferBinding { buffer, offset, size }, _t: PhantomData }
            }
        }
        impl<'a, T: ?Sized> From<&'a wgpu::Buffer> for $name<'a, T> {
            fn from(buffer: &'a wgpu::Buffer) -> Self {
                Self::range(buffer, 0, None)
            }
        }
        impl<'a, T: ?Sized> IntoResource<'a> for $name<'a, T> {
            fn resource(&self) -> Resource<'a> {
                Resource::Buffer(self.binding.clone())
            }
        }
    };
}

buffer_wrapper!(
    /// A uniform buffer holding a `T` (the generated struct for the WGSL type).
    Uniform
);
buffer_wrapper!(
    /// A read-only storage buffer holding a `T`.
    StorageRead
);
buffer_wrapper!(
    /// A read-write storage buffer holding a `T`.
    StorageReadWrite
);

macro_rules! view_wrapper {
    ($(#[$doc:meta])* $name:ident, $variant:ident, $inner:ty) => {
        $(#[$doc])*
        #[derive(Clone, Copy)]
        pub struct $name<'a>(pub &'a $inner);
        impl<'a> From<&'a $inner> for $name<'a> {
            fn from(v: &'a $inner) -> Self {
                Self(v)
            }
        }
        impl<'a> IntoResource<'a> for $name<'a> {
            fn resource(&self) -> Resource<'a> {
                Resource::$variant(self.0)
            }
        }
    };
}

view_wrapper!(
    /// A texture read by `textureLoad`/`textureSample` (`texture_2d<f32>` and friends).
    Texture, Texture, wgpu::TextureView
);
view_wrapper!(
    /// A storage texture (`texture_storage_*`).
    StorageTexture, StorageTexture, wgpu::TextureView
);
view_wrapper!(
    /// A sampler.
    Sampler, Sampler, wgpu::Sampler
);

macro_rules! array_wrapper {
    ($(#[$doc:meta])* $name:ident, $variant:ident, $inner:ty) => {
        $(#[$doc])*
        #[derive(Clone, Copy)]
        pub struct $name<'a>(pub &'a [&'a $inner]);
        impl<'a> From<&'a [&'a $inner]> for $name<'a> {
            fn from(v: &'a [&'a $inner]) -> Self {
                Self(v)
            }
        }
        impl<'a, const N: usize> From<&'a [&'a $inner; N]> for $name<'a> {
            fn from(v: &'a [&'a $inner; N]) -> Self {
                Self(v)
            }
        }
        impl<'a> IntoResource<'a> for $name<'a> {
            fn resource(&self) -> Resource<'a> {
                Resource::$variant(self.0)
            }
        }
    };
}

array_wrapper!(
    /// A binding array of sampled textures (`binding_array<texture_2d<f32>, N>`): exactly N views.
    Textures, Textures, wgpu::TextureView
);
array_wrapper!(
    /// A binding array of storage textures: exactly N views.
    StorageTextures, StorageTextures, wgpu::TextureView
);
array_wrapper!(
    /// A binding array of samplers: exactly N.
    Samplers, Samplers, wgpu::Sampler
);

/// A binding array of uniform or storage buffers each holding a `T` (`binding_array<T, N>` in
/// `var<uniform>` or `var<storage>`): exactly N ranges.
pub struct Buffers<'a, T: ?Sized> {
    /// The buffer ranges bound, one per element.
    pub bindings: &'a [wgpu::BufferBinding<'a>],
    _t: PhantomData<fn() -> Box<T>>,
}

impl<'a, T: ?Sized> Buffers<'a, T> {
    /// The ranges bound, one per element of the array.
    pub fn new(bindings: &'a [wgpu::BufferBinding<'a>]) -> Self {
        Self {
            bindings,
            _t: PhantomData,
        }
    }
}

impl<'a, T: ?Sized> From<&'a [wgpu::BufferBinding<'a>]> for Buffers<'a, T> {
    fn from(bindings: &'a [wgpu::BufferBinding<'a>]) -> Self {
        Self::new(bindings)
    }
}

impl<'a, T: ?Sized> IntoResource<'a> for Buffers<'a, T> {
    fn resource(&self) -> Resource<'a> {
        Resource::Buffers(self.bindings)
    }
}
