//! The runtime side of the generated bindings: resource wrappers that say what may be bound,
//! pipelines built from the static interface tables in [`crate::shaders`], and the checks that
//! turn a wrong resource into a [`BindingError`] naming the stage and binding instead of a wgpu
//! validation panic.
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, params: &wgpu::Buffer, src: &wgpu::TextureView, dst: &wgpu::TextureView) -> Result<(), fieldkit::Error> {
//! use fieldkit::shaders::distance::jfa_step::{JumpParams, jump};
//! let pipeline = jump::Pipeline::new(device)?;
//! let bound = pipeline.bind(device, &jump::Resources {
//!     params: params.into(),
//!     src: src.into(),
//!     dst: dst.into(),
//! })?;
//! # Ok(()) }
//! ```

use std::marker::PhantomData;

use crate::error::{BindingError, Error};

/// One `@group/@binding` of an entry point, as the shader declares and uses it.
#[derive(Debug, Clone, Copy)]
pub struct Slot {
    /// Its `@group`.
    pub group: u32,
    /// Its `@binding`.
    pub binding: u32,
    /// The variable's name in the shader.
    pub name: &'static str,
    /// WGSL spelling of the bound type.
    pub wgsl: &'static str,
    /// Stages that really use it.
    pub visibility: wgpu::ShaderStages,
    /// The binding type the layout declares (from real use: access, sample type, size); for a
    /// binding array, the type of each element.
    pub ty: wgpu::BindingType,
    /// A binding array's length (`binding_array<T, N>`); `None` for a single resource.
    pub count: Option<std::num::NonZeroU32>,
}

/// Scalar class of a fragment output: which colour target formats it can write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScalarClass {
    /// `f32` outputs: float and normalized formats.
    Float,
    /// `u32` outputs: unsigned integer formats.
    Uint,
    /// `i32` outputs: signed integer formats.
    Sint,
}

#[derive(Debug, Clone, Copy)]
/// One fragment output: its location and what kind of values it writes.
pub struct TargetKind {
    /// Its `@location`.
    pub location: u32,
    /// What it writes.
    pub scalar: ScalarClass,
}

#[derive(Debug, Clone, Copy)]
/// What kind of pipeline an entry point makes.
pub enum EntryKind {
    /// A compute entry point.
    Compute {
        /// Its `@workgroup_size`.
        workgroup_size: [u32; 3],
    },
    /// A fragment entry point with the vertex entry point it pairs with.
    Render {
        /// The vertex entry point paired with the fragment entry point.
        vertex: &'static str,
        /// Vertex buffer layouts from the vertex stage's inputs.
        vertex_buffers: &'static [Option<wgpu::VertexBufferLayout<'static>>],
        /// The fragment outputs.
        targets: &'static [TargetKind],
    },
}

/// Everything the shader says about one pipeline's interface (generated).
#[derive(Debug)]
pub struct EntryInfo {
    /// `room::stage`.
    pub stage: &'static str,
    /// The shader file, relative to the crate.
    pub path: &'static str,
    /// Compute entry point, or the fragment entry point of a render pipeline.
    pub entry_point: &'static str,
    /// The linked WGSL the pipeline is created from.
    pub source: &'static str,
    /// Compute or render.
    pub kind: EntryKind,
    /// Every binding the entry point uses, ascending.
    pub slots: &'static [Slot],
    /// Names of the module's `override` constants.
    pub overrides: &'static [&'static str],
    /// Every loop of the shader is known to end: its module is built without wgpu's loop
    /// bounding ([`stage_checks`]). True for fieldkit's own stages; set it for a shader of your
    /// own only where you know the same of it.
    pub loops_end: bool,
    /// The device limits the pipeline needs.
    pub needs: Needs,
    /// The device features the pipeline needs (binding arrays and their non-uniform indexing,
    /// immediates), one flag each, as the build found them by validating the shader without
    /// each; [`EntryInfo::required_features`] is their union.
    pub features: &'static [wgpu::Features],
    /// Bytes of `var<immediate>` data the pipeline layout holds (0: none). Set them with
    /// `set_immediates` on the pass; the device needs `Features::IMMEDIATES`.
    pub immediate_size: u32,
    /// Groups bound as a whole from a [`Group`] (a shared module's bindings), not binding by
    /// binding: their slots are the shared module's, with the visibility of every user.
    pub shared_groups: &'static [u32],
}

/// The device limits a pipeline needs, as the build reflected them from its shader (named as
/// `wgpu::Limits` names them; per-stage counts are the larger of its entry points'; workgroup
/// memory has override-sized arrays at their defaults).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Needs {
    /// Storage buffers bound in one shader stage.
    pub max_storage_buffers_per_shader_stage: u32,
    /// Storage textures bound in one shader stage.
    pub max_storage_textures_per_shader_stage: u32,
    /// Sampled textures bound in one shader stage.
    pub max_sampled_textures_per_shader_stage: u32,
    /// Samplers bound in one shader stage.
    pub max_samplers_per_shader_stage: u32,
    /// Uniform buffers bound in one shader stage.
    pub max_uniform_buffers_per_shader_stage: u32,
    /// Bind groups (the highest group used + 1).
    pub max_bind_groups: u32,
    /// Bytes of the largest uniform binding.
    pub max_uniform_buffer_binding_size: u32,
    /// Bytes of `var<workgroup>` memory.
    pub max_compute_workgroup_storage_size: u32,
    /// Invocations per workgroup (compute).
    pub max_compute_invocations_per_workgroup: u32,
}

/// Visit every field of [`Needs`] with the same-named field of `wgpu::Limits`.
macro_rules! each_need {
    ($m:ident) => {
        $m!(max_storage_buffers_per_shader_stage);
        $m!(max_storage_textures_per_shader_stage);
        $m!(max_sampled_textures_per_shader_stage);
        $m!(max_samplers_per_shader_stage);
        $m!(max_uniform_buffers_per_shader_stage);
        $m!(max_bind_groups);
        $m!(max_uniform_buffer_binding_size);
        $m!(max_compute_workgroup_storage_size);
        $m!(max_compute_invocations_per_workgroup);
    };
}

impl Needs {
    /// `limits` raised wherever this needs more: what to ask `request_device` for (fold it over
    /// every pipeline the application makes).
    ///
    /// ```
    /// use fieldkit::shaders::distance::edt_rows;
    /// let limits = edt_rows::rows::INFO.needs.raise(wgpu::Limits::downlevel_defaults());
    /// assert!(limits.max_compute_workgroup_storage_size >= 11264);
    /// ```
    pub fn raise(&self, mut limits: wgpu::Limits) -> wgpu::Limits {
        macro_rules! up {
            ($f:ident) => {
                limits.$f = limits.$f.max(self.$f.into());
            };
        }
        each_need!(up);
        limits
    }

    /// The first limit of `limits` this needs more of: its name, what is needed, what is
    /// offered.
    pub fn lacking(&self, limits: &wgpu::Limits) -> Option<(&'static str, u64, u64)> {
        macro_rules! check {
            ($f:ident) => {
                if u64::from(self.$f) > u64::from(limits.$f) {
                    return Some((stringify!($f), self.$f.into(), limits.$f.into()));
                }
            };
        }
        each_need!(check);
        None
    }
}

impl EntryInfo {
    /// Groups used, ascending.
    pub fn groups(&self) -> Vec<u32> {
        let mut g: Vec<u32> = self.slots.iter().map(|s| s.group).collect();
        g.sort_unstable();
        g.dedup();
        g
    }

    /// `@workgroup_size`, for compute entries.
    pub fn workgroup_size(&self) -> Option<[u32; 3]> {
        match self.kind {
            EntryKind::Compute { workgroup_size } => Some(workgroup_size),
            _ => None,
        }
    }

    fn layouts(&self, device: &wgpu::Device) -> Vec<(u32, wgpu::BindGroupLayout)> {
        self.groups()
            .into_iter()
            .map(|g| {
                let slots: Vec<Slot> = self
                    .slots
                    .iter()
                    .filter(|s| s.group == g)
                    .copied()
                    .collect();
                let label = format!("{}::{} group {g}", self.stage, self.entry_point);
                (g, layout_of(device, &slots, &label))
            })
            .collect()
    }

    fn pipeline_layout(
        &self,
        device: &wgpu::Device,
        layouts: &[(u32, wgpu::BindGroupLayout)],
    ) -> wgpu::PipelineLayout {
        // Groups must be contiguous from 0 in a pipeline layout; fill gaps with empty layouts.
        let max = layouts.iter().map(|(g, _)| *g + 1).max().unwrap_or(0);
        let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: None,
            entries: &[],
        });
        let ordered: Vec<Option<&wgpu::BindGroupLayout>> = (0..max)
            .map(|g| {
                Some(
                    layouts
                        .iter()
                        .find(|(i, _)| *i == g)
                        .map(|(_, l)| l)
                        .unwrap_or(&empty),
                )
            })
            .collect();
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(self.stage),
            bind_group_layouts: &ordered,
            immediate_size: self.immediate_size,
        })
    }

    /// [`Error::Unsupported`] where the device lacks a feature the shader needs (checked before
    /// a pipeline is made, where wgpu would otherwise report a validation error).
    pub fn check_features(&self, device: &wgpu::Device) -> Result<(), Error> {
        let needed = self.required_features();
        let missing = needed - device.features();
        if missing.is_empty() {
            return Ok(());
        }
        Err(Error::Unsupported {
            stage: self.stage,
            what: format!("features {missing:?} (the shader needs {needed:?})"),
        })
    }

    /// Every device feature the pipeline needs: ask for these (and [`Needs::raise`]'s limits)
    /// in the `wgpu::DeviceDescriptor`.
    pub fn required_features(&self) -> wgpu::Features {
        self.features
            .iter()
            .fold(wgpu::Features::empty(), |all, f| all | *f)
    }

    fn check_overrides(&self, overrides: &[(&str, f64)]) -> Result<(), Error> {
        for (name, value) in overrides {
            if !self.overrides.contains(name) {
                return Err(Error::Invalid {
                    stage: self.stage,
                    what: format!(
                        "override `{name}`: the shader declares no such override (it has {:?})",
                        self.overrides
                    ),
                });
            }
            if !value.is_finite() {
                return Err(Error::Invalid {
                    stage: self.stage,
                    what: format!("override `{name}` is {value}"),
                });
            }
        }
        Ok(())
    }
}

/// A generated entry point: its interface table and its parameter struct.
pub trait Entry: 'static {
    /// The entry point's parameter struct: one typed field per binding.
    type Resources<'a>;
    /// The entry point's interface table.
    const INFO: &'static EntryInfo;
    /// The resources in slot order (slots of shared groups left out).
    fn resources<'a>(r: &Self::Resources<'a>) -> Vec<Resource<'a>>;
    /// The bind groups of [`EntryInfo::shared_groups`], made once from a [`Group`].
    fn groups<'a>(_r: &Self::Resources<'a>) -> Vec<(u32, &'a wgpu::BindGroup)> {
        Vec::new()
    }
}

/// A group of bindings declared once in a module of the shader folder's `shared/` and used by
/// several pipelines (generated as `shaders::groups::<module>`): bound once as a [`Group`]
/// and handed to every pipeline that uses it.
pub trait SharedGroup: 'static {
    /// The module (`shared/<module>.wesl`).
    const MODULE: &'static str;
    /// Its `@group`.
    const GROUP: u32;
    /// Its bindings, with the visibility of every pipeline that uses them.
    const SLOTS: &'static [Slot];
    /// One typed field per binding.
    type Resources<'a>;
    /// The resources in slot order.
    fn resources<'a>(r: &Self::Resources<'a>) -> Vec<Resource<'a>>;
}

/// The bind group of a [`SharedGroup`], made once and set on every pipeline that uses it
/// (their `Resources` take a `&Group`).
pub struct Group<G> {
    /// The wgpu bind group.
    pub bind_group: wgpu::BindGroup,
    _g: PhantomData<G>,
}

impl<G: SharedGroup> Group<G> {
    /// The group's layout (equal, entry for entry, to the one each pipeline that uses it makes).
    pub fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        layout_of(device, G::SLOTS, G::MODULE)
    }

    /// Check every resource against the module's slots (as a pipeline's `bind` does) and make
    /// the bind group.
    pub fn new(device: &wgpu::Device, resources: &G::Resources<'_>) -> Result<Self, Error> {
        let layout = Self::layout(device);
        let res = G::resources(resources);
        let bind_group = make_group(
            device,
            &layout,
            G::SLOTS,
            &res,
            G::MODULE,
            "(shared group)",
            G::GROUP,
        )?;
        Ok(Self {
            bind_group,
            _g: PhantomData,
        })
    }
}

/// A bind group layout for `slots` (one group's).
fn layout_of(device: &wgpu::Device, slots: &[Slot], label: &str) -> wgpu::BindGroupLayout {
    let entries: Vec<_> = slots
        .iter()
        .map(|s| wgpu::BindGroupLayoutEntry {
            binding: s.binding,
            visibility: s.visibility,
            ty: s.ty,
            count: s.count,
        })
        .collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

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

fn view_dimension_of(t: &wgpu::Texture) -> wgpu::TextureViewDimension {
    match t.dimension() {
        wgpu::TextureDimension::D1 => wgpu::TextureViewDimension::D1,
        wgpu::TextureDimension::D2 if t.depth_or_array_layers() > 1 => {
            wgpu::TextureViewDimension::D2Array
        }
        wgpu::TextureDimension::D2 => wgpu::TextureViewDimension::D2,
        wgpu::TextureDimension::D3 => wgpu::TextureViewDimension::D3,
    }
}

/// Whether some view of `t` can have dimension `want`: a 2D texture's views are 2D arrays at
/// any layer count (one layer included), 2D with one layer, cubes with six.
fn view_fits(t: &wgpu::Texture, want: wgpu::TextureViewDimension) -> bool {
    use wgpu::TextureViewDimension as V;
    let layers = t.depth_or_array_layers();
    match (t.dimension(), want) {
        (wgpu::TextureDimension::D2, V::D2Array) => true,
        (wgpu::TextureDimension::D2, V::Cube) => layers == 6,
        (wgpu::TextureDimension::D2, V::CubeArray) => layers.is_multiple_of(6),
        _ => view_dimension_of(t) == want,
    }
}

/// Check one resource against its slot. `Err(problem)` says what is wrong, in words. A
/// binding array takes exactly its count of elements, each checked as a single resource.
fn check(slot: &Slot, res: &Resource<'_>, device: &wgpu::Device) -> Result<(), String> {
    let elements: Option<Vec<Resource<'_>>> = match res {
        Resource::Buffers(b) => Some(b.iter().cloned().map(Resource::Buffer).collect()),
        Resource::Textures(v) => Some(v.iter().map(|v| Resource::Texture(v)).collect()),
        Resource::StorageTextures(v) => {
            Some(v.iter().map(|v| Resource::StorageTexture(v)).collect())
        }
        Resource::Samplers(v) => Some(v.iter().map(|v| Resource::Sampler(v)).collect()),
        _ => None,
    };
    match (slot.count, elements) {
        (None, None) => check_one(slot, res, device),
        (Some(count), Some(elements)) => {
            if elements.len() != count.get() as usize {
                return Err(format!(
                    "{} resources bound, the shader's `{}` holds {count}",
                    elements.len(),
                    slot.wgsl
                ));
            }
            for (i, e) in elements.iter().enumerate() {
                check_one(slot, e, device).map_err(|p| format!("element {i}: {p}"))?;
            }
            Ok(())
        }
        (Some(_), None) => Err(format!(
            "one resource bound, the shader's `{}` is a binding array",
            slot.wgsl
        )),
        (None, Some(_)) => Err(format!(
            "a binding array bound, the shader's `{}` is one resource",
            slot.wgsl
        )),
    }
}

/// [`check`] for a single resource.
fn check_one(slot: &Slot, res: &Resource<'_>, device: &wgpu::Device) -> Result<(), String> {
    use wgpu::BindingType as B;
    match (&slot.ty, res) {
        (
            B::Buffer {
                ty,
                min_binding_size,
                ..
            },
            Resource::Buffer(b),
        ) => check_buffer(slot, *ty, *min_binding_size, b, device),
        (
            B::Texture {
                sample_type,
                view_dimension,
                multisampled,
            },
            Resource::Texture(v),
        ) => check_texture(
            slot,
            *sample_type,
            *view_dimension,
            *multisampled,
            v,
            device,
        ),
        (
            B::StorageTexture {
                format,
                view_dimension,
                ..
            },
            Resource::StorageTexture(v),
        ) => check_storage_texture(slot, *format, *view_dimension, v),
        (B::Sampler(_), Resource::Sampler(_)) => Ok(()),
        _ => Err(format!("wrong kind of resource for `{}`", slot.wgsl)),
    }
}

/// A buffer for a uniform or storage slot: its usage, offset alignment, and size against the
/// shader's minimum and the device's binding limit.
fn check_buffer(
    slot: &Slot,
    ty: wgpu::BufferBindingType,
    min_binding_size: Option<wgpu::BufferSize>,
    b: &wgpu::BufferBinding<'_>,
    device: &wgpu::Device,
) -> Result<(), String> {
    let (usage, align, what) = match ty {
        wgpu::BufferBindingType::Uniform => (
            wgpu::BufferUsages::UNIFORM,
            device.limits().min_uniform_buffer_offset_alignment,
            "UNIFORM",
        ),
        _ => (
            wgpu::BufferUsages::STORAGE,
            device.limits().min_storage_buffer_offset_alignment,
            "STORAGE",
        ),
    };
    if !b.buffer.usage().contains(usage) {
        return Err(format!(
            "buffer lacks {what} usage (has {:?})",
            b.buffer.usage()
        ));
    }
    if b.offset % align as u64 != 0 {
        return Err(format!("offset {} is not a multiple of {align}", b.offset));
    }
    let size = b
        .size
        .map(|s| s.get())
        .unwrap_or(b.buffer.size().saturating_sub(b.offset));
    if let Some(min) = min_binding_size
        && size < min.get()
    {
        return Err(format!(
            "{size} bytes bound, the shader's `{}` needs at least {}",
            slot.wgsl,
            min.get()
        ));
    }
    // wgpu would reject the bind group with a validation error (a panic in an app
    // without an error handler): say which binding and which limit instead.
    let (max, limit) = match ty {
        wgpu::BufferBindingType::Uniform => (
            device.limits().max_uniform_buffer_binding_size,
            "max_uniform_buffer_binding_size",
        ),
        _ => (
            device.limits().max_storage_buffer_binding_size,
            "max_storage_buffer_binding_size",
        ),
    };
    if size > max {
        return Err(format!(
            "{size} bytes bound, more than the device's {limit} ({max})"
        ));
    }
    Ok(())
}

/// A sampled texture: its usage, view dimension, sample count and sample type.
fn check_texture(
    slot: &Slot,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
    multisampled: bool,
    v: &wgpu::TextureView,
    device: &wgpu::Device,
) -> Result<(), String> {
    let t = v.texture();
    if !t.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return Err(format!(
            "texture lacks TEXTURE_BINDING usage (has {:?})",
            t.usage()
        ));
    }
    if !view_fits(t, view_dimension) {
        return Err(format!(
            "{:?} texture bound, the shader reads `{}`",
            view_dimension_of(t),
            slot.wgsl
        ));
    }
    if (t.sample_count() > 1) != multisampled {
        return Err(format!(
            "sample count {} does not suit `{}`",
            t.sample_count(),
            slot.wgsl
        ));
    }
    let features = device.features();
    let fits = |have: Option<wgpu::TextureSampleType>| match (sample_type, have) {
        (
            wgpu::TextureSampleType::Float { filterable: true },
            Some(wgpu::TextureSampleType::Float { filterable }),
        ) => filterable,
        // Depth formats may be read as unfilterable float (textureLoad).
        (
            wgpu::TextureSampleType::Float { filterable: false },
            Some(wgpu::TextureSampleType::Float { .. } | wgpu::TextureSampleType::Depth),
        ) => true,
        (want, Some(h)) => want == h,
        (_, None) => false,
    };
    // A combined depth-stencil format is read through a view of one aspect (the view
    // does not say which): either aspect may fit.
    let ok = match t.format().sample_type(None, Some(features)) {
        Some(have) => fits(Some(have)),
        None => [
            wgpu::TextureAspect::DepthOnly,
            wgpu::TextureAspect::StencilOnly,
        ]
        .into_iter()
        .any(|a| fits(t.format().sample_type(Some(a), Some(features)))),
    };
    if !ok {
        return Err(format!(
            "texture format {:?} cannot be read as `{}` (needs {:?})",
            t.format(),
            slot.wgsl,
            sample_type
        ));
    }
    Ok(())
}

/// A storage texture: its usage, format and view dimension.
fn check_storage_texture(
    slot: &Slot,
    format: wgpu::TextureFormat,
    view_dimension: wgpu::TextureViewDimension,
    v: &wgpu::TextureView,
) -> Result<(), String> {
    let t = v.texture();
    if !t.usage().contains(wgpu::TextureUsages::STORAGE_BINDING) {
        return Err(format!(
            "texture lacks STORAGE_BINDING usage (has {:?})",
            t.usage()
        ));
    }
    if t.format() != format {
        return Err(format!(
            "texture format {:?} bound, the shader's `{}` needs {:?}",
            t.format(),
            slot.wgsl,
            format
        ));
    }
    if !view_fits(t, view_dimension) {
        return Err(format!(
            "{:?} texture bound, the shader writes `{}`",
            view_dimension_of(t),
            slot.wgsl
        ));
    }
    Ok(())
}

/// fieldkit's own checks of every resource (kind, format, size, usage, sample type), then the
/// bind groups. No error scope: binding never waits on the device.
fn bind_groups<E: Entry>(
    device: &wgpu::Device,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    resources: &E::Resources<'_>,
) -> Result<Bound<E>, Error> {
    let info = E::INFO;
    let res = E::resources(resources);
    let shared = E::groups(resources);
    // The slots bound one by one: all but the shared groups', in the order `res` lists them.
    let own: Vec<Slot> = info
        .slots
        .iter()
        .filter(|s| !info.shared_groups.contains(&s.group))
        .copied()
        .collect();
    let mut groups = Vec::new();
    for (g, layout) in layouts {
        let dynamic = info
            .slots
            .iter()
            .filter(|s| s.group == *g && has_dynamic_offset(s))
            .count();
        if let Some((_, group)) = shared.iter().find(|(sg, _)| sg == g) {
            groups.push((*g, (*group).clone(), dynamic));
            continue;
        }
        let (slots, group_res): (Vec<Slot>, Vec<&Resource<'_>>) = own
            .iter()
            .zip(&res)
            .filter(|(s, _)| s.group == *g)
            .map(|(s, r)| (*s, r))
            .unzip();
        let group = make_group_refs(
            device,
            layout,
            &slots,
            &group_res,
            info.stage,
            info.entry_point,
            *g,
        )?;
        groups.push((*g, group, dynamic));
    }
    Ok(Bound {
        groups,
        stage: info.stage,
        _e: PhantomData,
    })
}

/// Check each resource against its slot, then make group `g` of them.
fn make_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    res: &[Resource<'_>],
    stage: &'static str,
    entry_point: &'static str,
    g: u32,
) -> Result<wgpu::BindGroup, Error> {
    let refs: Vec<&Resource<'_>> = res.iter().collect();
    make_group_refs(device, layout, slots, &refs, stage, entry_point, g)
}

fn make_group_refs(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    res: &[&Resource<'_>],
    stage: &'static str,
    entry_point: &'static str,
    g: u32,
) -> Result<wgpu::BindGroup, Error> {
    for (slot, r) in slots.iter().zip(res) {
        check(slot, r, device).map_err(|problem| {
            Error::Binding(BindingError {
                stage,
                entry_point,
                binding: slot.name,
                group: slot.group,
                index: slot.binding,
                problem,
            })
        })?;
    }
    let entries: Vec<wgpu::BindGroupEntry> = slots
        .iter()
        .zip(res)
        .map(|(s, r)| wgpu::BindGroupEntry {
            binding: s.binding,
            resource: match r {
                Resource::Buffer(b) => wgpu::BindingResource::Buffer(b.clone()),
                Resource::Texture(v) | Resource::StorageTexture(v) => {
                    wgpu::BindingResource::TextureView(v)
                }
                Resource::Sampler(s) => wgpu::BindingResource::Sampler(s),
                Resource::Buffers(b) => wgpu::BindingResource::BufferArray(b),
                Resource::Textures(v) | Resource::StorageTextures(v) => {
                    wgpu::BindingResource::TextureViewArray(v)
                }
                Resource::Samplers(s) => wgpu::BindingResource::SamplerArray(s),
            },
        })
        .collect();
    let label = format!("{stage}::{entry_point} group {g}");
    Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&label),
        layout,
        entries: &entries,
    }))
}

/// Offset 0 for each of `n` dynamic bindings, without an allocation per pass where `n` is
/// within what any adapter offers (WebGPU's defaults: 8 uniform and 4 storage per layout).
fn zero_offsets(n: usize) -> std::borrow::Cow<'static, [u32]> {
    const ZEROS: [u32; 64] = [0; 64];
    match ZEROS.get(..n) {
        Some(z) => std::borrow::Cow::Borrowed(z),
        None => std::borrow::Cow::Owned(vec![0; n]),
    }
}

/// A bind group's index, the group, and its dynamic offsets.
type GroupOffsets<'s, 'o> = (u32, &'s wgpu::BindGroup, &'o [u32]);

fn has_dynamic_offset(slot: &Slot) -> bool {
    matches!(
        slot.ty,
        wgpu::BindingType::Buffer {
            has_dynamic_offset: true,
            ..
        }
    )
}

/// Bind groups for one dispatch or draw, made by [`ComputePipeline::bind`] / [`RenderPipeline::bind`].
pub struct Bound<E> {
    /// Each group, and how many of its bindings take a dynamic offset.
    groups: Vec<(u32, wgpu::BindGroup, usize)>,
    stage: &'static str,
    _e: PhantomData<E>,
}

impl<E: Entry> Bound<E> {
    /// Set every bind group on a compute pass (a binding with a dynamic offset at offset 0).
    pub fn set_compute(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (g, group, dynamic) in &self.groups {
            pass.set_bind_group(*g, group, &zero_offsets(*dynamic));
        }
    }
    /// Set every bind group on a render pass (a binding with a dynamic offset at offset 0).
    pub fn set_render(&self, pass: &mut wgpu::RenderPass<'_>) {
        for (g, group, dynamic) in &self.groups {
            pass.set_bind_group(*g, group, &zero_offsets(*dynamic));
        }
    }

    /// Bindings that take a dynamic offset (`fieldkit_build::Builder::dynamic_offset`), in
    /// group then binding order: one offset each is expected.
    pub fn dynamic_offsets(&self) -> usize {
        self.groups.iter().map(|(_, _, d)| d).sum()
    }

    /// [`Self::set_compute`] with `offsets`, one per binding that takes a dynamic offset, in
    /// group then binding order; [`Error::Invalid`] for the wrong number of them.
    pub fn set_compute_with_offsets(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offsets: &[u32],
    ) -> Result<(), Error> {
        for (g, group, split) in self.split(offsets)? {
            pass.set_bind_group(g, group, split);
        }
        Ok(())
    }

    /// [`Self::set_render`] with `offsets`, as [`Self::set_compute_with_offsets`] takes them.
    pub fn set_render_with_offsets(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        offsets: &[u32],
    ) -> Result<(), Error> {
        for (g, group, split) in self.split(offsets)? {
            pass.set_bind_group(g, group, split);
        }
        Ok(())
    }

    /// Each group with its share of `offsets`.
    fn split<'s, 'o>(&'s self, offsets: &'o [u32]) -> Result<Vec<GroupOffsets<'s, 'o>>, Error> {
        if offsets.len() != self.dynamic_offsets() {
            return Err(Error::Invalid {
                stage: self.stage,
                what: format!(
                    "{} dynamic offsets given, the pipeline's layouts take {}",
                    offsets.len(),
                    self.dynamic_offsets()
                ),
            });
        }
        let mut rest = offsets;
        Ok(self
            .groups
            .iter()
            .map(|(g, group, d)| {
                let (mine, after) = rest.split_at(*d);
                rest = after;
                (*g, group, mine)
            })
            .collect())
    }
}

/// The runtime checks fieldkit's own stages are built with: wgpu's defaults (indices clamped to
/// their arrays; buffers and images left to the driver's robust access) less *loop bounding*,
/// the 64-bit counter naga adds to every loop so that a loop that never ends cannot be assumed
/// unreachable by the driver's compiler. Every loop in `shaders/` ends by construction (a
/// counted `for`, a step count, a stack that only shrinks, a walk along an array's
/// bounds), and the counter costs a register pair, a compare and a carry per iteration: measured
/// on the H100 (`cargo xtask bench distance --exact-only`, clocks held, one command running a
/// build with it and one without), the exact transform took 0.709 ms without it against 0.873
/// with it at 256³, 6.01 against 6.77 at 512³ and 2.55 against 2.95 at 8192², and the
/// workgroup column pass went from 47 to 41 registers. Entries whose [`EntryInfo::loops_end`]
/// is false (a shader no one has checked) keep every check.
pub const fn stage_checks() -> wgpu::ShaderRuntimeChecks {
    let mut checks = wgpu::ShaderRuntimeChecks::checked();
    checks.force_loop_bounding = false;
    checks
}

/// The shader module of `info`, from its compiled-in source, or from `relinked` (hot reload:
/// every runtime check kept, as no one has read its loops).
fn module(device: &wgpu::Device, info: &EntryInfo, relinked: Option<&str>) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(info.path),
        source: wgpu::ShaderSource::Wgsl(relinked.unwrap_or(info.source).into()),
    };
    if !info.loops_end || relinked.is_some() {
        return device.create_shader_module(desc);
    }
    // SAFETY: `stage_checks` keeps every bounds check and turns off only loop bounding, whose
    // contract is that the shader has no infinite loop: `loops_end` says each loop of this one
    // ends (fieldkit's own stages, see `stage_checks`).
    unsafe { device.create_shader_module_trusted(desc, stage_checks()) }
}

/// A stage's `override` constants as one typed value: the generated `Overrides` struct of
/// every stage that declares overrides implements it, so pipelines are specialised through
/// typed fields and a renamed override is a compile error, never a string that no longer
/// matches.
pub trait Constants: Copy + PartialEq + Send + Sync + 'static {
    /// `(name, value)` for each override to set, as pipelines take them.
    fn constants(&self) -> Vec<(&'static str, f64)>;
}

/// Compute pipelines of one entry point `E` specialised by override values `O` (its stage's
/// generated `Overrides`), each made on first use and kept, keyed on the typed value (for
/// overrides that take many values, such as a workgroup array's length).
// Used by the techniques' stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct Variants<E, O> {
    made: std::sync::Mutex<Vec<(VariantKey<O>, std::sync::Arc<ComputePipeline<E>>)>>,
}

/// The typed overrides and the zero-fill choice.
type VariantKey<O> = (O, bool);

impl<E, O> Default for Variants<E, O> {
    fn default() -> Self {
        Self {
            made: Default::default(),
        }
    }
}

// Used by the techniques' stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl<E: Entry, O: Constants> Variants<E, O> {
    /// The pipeline for `overrides`, made now if it is the first use.
    pub(crate) fn get(
        &self,
        device: &wgpu::Device,
        overrides: &O,
        zero_initialize_workgroup_memory: bool,
    ) -> Result<std::sync::Arc<ComputePipeline<E>>, Error> {
        let key = (*overrides, zero_initialize_workgroup_memory);
        let mut made = self.made.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = made.iter().find(|(k, _)| *k == key) {
            return Ok(p.clone());
        }
        let p = std::sync::Arc::new(ComputePipeline::with_options(
            device,
            &overrides.constants(),
            zero_initialize_workgroup_memory,
        )?);
        made.push((key, p.clone()));
        Ok(p)
    }
}

/// A compute pipeline for a generated entry point `E`.
pub struct ComputePipeline<E> {
    /// The wgpu pipeline.
    pub pipeline: wgpu::ComputePipeline,
    layouts: Vec<(u32, wgpu::BindGroupLayout)>,
    _e: PhantomData<E>,
}

impl<E: Entry> ComputePipeline<E> {
    /// Create the pipeline; wgpu validation errors come back as [`Error::Wgpu`].
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Self::with_overrides(device, &[])
    }

    /// The pipeline specialised by `overrides` held in `slot`, made there on first use.
    // Used by the techniques' stages.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn cached<'a>(
        slot: &'a std::sync::OnceLock<Self>,
        device: &wgpu::Device,
        overrides: &[(&str, f64)],
    ) -> Result<&'a Self, Error> {
        if slot.get().is_none() {
            let _ = slot.set(Self::with_overrides(device, overrides)?);
        }
        Ok(slot.get().expect("set above"))
    }

    /// Create the pipeline with the stage's typed `override` values (its generated
    /// `Overrides`).
    pub fn with_constants(
        device: &wgpu::Device,
        overrides: &impl Constants,
    ) -> Result<Self, Error> {
        Self::with_overrides(device, &overrides.constants())
    }

    /// Create the pipeline with values for the shader's `override` constants, by name
    /// ([`Self::with_constants`] takes them typed).
    pub fn with_overrides(device: &wgpu::Device, overrides: &[(&str, f64)]) -> Result<Self, Error> {
        Self::with_options(device, overrides, true)
    }

    /// [`Self::with_overrides`], choosing whether wgpu zero-fills workgroup memory before the
    /// shader runs (`false` only for shaders that write every workgroup cell before reading it).
    pub fn with_options(
        device: &wgpu::Device,
        overrides: &[(&str, f64)],
        zero_initialize_workgroup_memory: bool,
    ) -> Result<Self, Error> {
        Self::make(device, None, overrides, zero_initialize_workgroup_memory)
    }

    pub(crate) fn make(
        device: &wgpu::Device,
        relinked: Option<&str>,
        overrides: &[(&str, f64)],
        zero_initialize_workgroup_memory: bool,
    ) -> Result<Self, Error> {
        let info = E::INFO;
        info.check_overrides(overrides)?;
        info.check_features(device)?;
        crate::gpu::scoped(device, info.stage, || {
            let layouts = info.layouts(device);
            let pipeline = build_compute(
                device,
                info,
                relinked,
                &layouts,
                overrides,
                zero_initialize_workgroup_memory,
            );
            Self {
                pipeline,
                layouts,
                _e: PhantomData,
            }
        })
    }

    /// Check every resource against the shader's slots and make the bind groups.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        bind_groups(device, &self.layouts, resources)
    }

    /// Record one dispatch of `groups` workgroups into `pass`.
    pub fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>, bound: &Bound<E>, groups: [u32; 3]) {
        pass.set_pipeline(&self.pipeline);
        bound.set_compute(pass);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }

    /// Bind `resources` and record one dispatch of `groups` workgroups in a compute pass of its
    /// own, timed under `name` when `rec` carries a profiler.
    pub fn record(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        resources: &E::Resources<'_>,
        groups: [u32; 3],
        name: &str,
    ) -> Result<(), Error> {
        let bound = self.bind(device, resources)?;
        let mut rec = rec.recorder();
        let mut pass = rec.compute_pass(E::INFO.stage, name);
        self.dispatch(&mut pass, &bound, groups);
        Ok(())
    }

    /// Workgroups needed to cover `extent` invocations on each axis.
    pub fn groups_for(extent: [u32; 3]) -> [u32; 3] {
        let ws = E::INFO.workgroup_size().unwrap_or([1, 1, 1]);
        [
            extent[0].div_ceil(ws[0]),
            extent[1].div_ceil(ws[1]),
            extent[2].div_ceil(ws[2]),
        ]
    }
}

/// How a render pipeline draws: the parts the shader cannot say.
#[derive(Debug, Clone, Default)]
pub struct RenderTargets<'a> {
    /// One per fragment output, in location order.
    pub color: &'a [Option<wgpu::ColorTargetState>],
    /// Depth (and stencil) test and write, if the pass has a depth target.
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// Topology, culling and polygon mode.
    pub primitive: wgpu::PrimitiveState,
    /// Sample count and mask.
    pub multisample: wgpu::MultisampleState,
}

/// A render pipeline for a generated vertex + fragment entry pair `E`.
pub struct RenderPipeline<E> {
    /// The wgpu pipeline.
    pub pipeline: wgpu::RenderPipeline,
    layouts: Vec<(u32, wgpu::BindGroupLayout)>,
    _e: PhantomData<E>,
}

impl<E: Entry> RenderPipeline<E> {
    /// Create the pipeline; colour targets are checked against the fragment outputs first.
    pub fn new(device: &wgpu::Device, targets: &RenderTargets<'_>) -> Result<Self, Error> {
        Self::make(device, None, targets)
    }

    pub(crate) fn make(
        device: &wgpu::Device,
        relinked: Option<&str>,
        targets: &RenderTargets<'_>,
    ) -> Result<Self, Error> {
        let info = E::INFO;
        info.check_features(device)?;
        let EntryKind::Render {
            targets: outputs, ..
        } = info.kind
        else {
            return Err(Error::Invalid {
                stage: info.stage,
                what: "not a render entry point".into(),
            });
        };
        if targets.color.len() != outputs.len() {
            return Err(Error::Invalid {
                stage: info.stage,
                what: format!(
                    "{} colour targets given, the fragment shader writes {}",
                    targets.color.len(),
                    outputs.len()
                ),
            });
        }
        for (t, o) in targets.color.iter().zip(outputs) {
            let Some(t) = t else { continue };
            let class = match t.format.sample_type(None, None) {
                Some(wgpu::TextureSampleType::Uint) => ScalarClass::Uint,
                Some(wgpu::TextureSampleType::Sint) => ScalarClass::Sint,
                _ => ScalarClass::Float,
            };
            if class != o.scalar {
                return Err(Error::Invalid {
                    stage: info.stage,
                    what: format!(
                        "target @location({}) has format {:?}, the shader writes {:?} values",
                        o.location, t.format, o.scalar
                    ),
                });
            }
        }
        crate::gpu::scoped(device, info.stage, || {
            let layouts = info.layouts(device);
            let pipeline = build_render(device, info, relinked, &layouts, targets);
            Self {
                pipeline,
                layouts,
                _e: PhantomData,
            }
        })
    }

    /// Check every resource against the shader's slots and make the bind groups.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        bind_groups(device, &self.layouts, resources)
    }
}

fn build_compute(
    device: &wgpu::Device,
    info: &EntryInfo,
    relinked: Option<&str>,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    overrides: &[(&str, f64)],
    zero_initialize_workgroup_memory: bool,
) -> wgpu::ComputePipeline {
    let layout = info.pipeline_layout(device, layouts);
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(info.stage),
        layout: Some(&layout),
        module: &module(device, info, relinked),
        entry_point: Some(info.entry_point),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: overrides,
            zero_initialize_workgroup_memory,
        },
        cache: None,
    })
}

/// Build a render pipeline; `info.kind` must be `Render` (checked by the callers).
fn build_render(
    device: &wgpu::Device,
    info: &EntryInfo,
    relinked: Option<&str>,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    targets: &RenderTargets<'_>,
) -> wgpu::RenderPipeline {
    let EntryKind::Render {
        vertex,
        vertex_buffers,
        ..
    } = info.kind
    else {
        unreachable!("callers pass render entries")
    };
    let layout = info.pipeline_layout(device, layouts);
    let module = module(device, info, relinked);
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(info.stage),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: vertex_buffers,
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(info.entry_point),
            compilation_options: Default::default(),
            targets: targets.color,
        }),
        primitive: targets.primitive,
        depth_stencil: targets.depth_stencil.clone(),
        multisample: targets.multisample,
        multiview_mask: None,
        cache: None,
    })
}

/// Create the pipeline for any entry point from its table alone (used to prove every generated
/// pipeline is accepted by wgpu, on the noop backend in tests). Colour targets get a format of
/// each output's scalar class, and a depth target.
pub fn create_any(device: &wgpu::Device, info: &'static EntryInfo) -> Result<(), Error> {
    info.check_features(device)?;
    crate::gpu::scoped(device, info.stage, || {
        let layouts = info.layouts(device);
        match info.kind {
            EntryKind::Compute { .. } => {
                let _ = build_compute(device, info, None, &layouts, &[], true);
            }
            EntryKind::Render { targets, .. } => {
                let color: Vec<_> = targets
                    .iter()
                    .map(|t| {
                        Some(wgpu::ColorTargetState::from(match t.scalar {
                            ScalarClass::Float => wgpu::TextureFormat::Rgba8Unorm,
                            ScalarClass::Uint => wgpu::TextureFormat::R32Uint,
                            ScalarClass::Sint => wgpu::TextureFormat::R32Sint,
                        }))
                    })
                    .collect();
                let _ = build_render(
                    device,
                    info,
                    None,
                    &layouts,
                    &RenderTargets {
                        color: &color,
                        // A depth target, so stages that write `frag_depth` are accepted too.
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: wgpu::TextureFormat::Depth32Float,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(wgpu::CompareFunction::Always),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        ..Default::default()
                    },
                );
            }
        }
    })
}

#[cfg(all(test, feature = "techniques"))]
mod tests {
    /// Every `.rs` file under `dir`, recursively.
    fn rust_files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                rust_files(&path, out);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }

    /// Pipelines are specialised through the generated `Overrides` structs (and
    /// [`super::Constants`]), so a renamed override is a compile error. A string literal naming
    /// an override in the library or in xtask would turn it back into a run-time error: none may.
    #[test]
    fn no_override_is_named_by_a_string() {
        let names: std::collections::BTreeSet<&str> = crate::shaders::ALL
            .iter()
            .flat_map(|info| info.overrides.iter().copied())
            .collect();
        // fieldkit's stages declare 26 distinct override names.
        assert!(names.len() >= 20, "{names:?}");
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = Vec::new();
        for dir in ["src", "xtask/src"] {
            rust_files(&root.join(dir), &mut files);
        }
        assert!(files.len() > 20, "found only {files:?}");
        let mut found = Vec::new();
        for file in &files {
            let text = std::fs::read_to_string(file).unwrap();
            for (n, line) in text.lines().enumerate() {
                for name in &names {
                    if line.contains(&format!("\"{name}\"")) {
                        found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
                    }
                }
            }
        }
        assert!(
            found.is_empty(),
            "override names written as strings (use the stage's generated `Overrides`):\n{}",
            found.join("\n")
        );
    }
}
