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

mod check;
mod groups;
mod pipeline;
mod resources;

use std::marker::PhantomData;

pub use groups::*;
pub use pipeline::*;
pub use resources::*;

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
    /// A binding array's length (`binding_array<T, N>`, or an unsized array's as the pipeline
    /// was made); `None` for a single resource.
    pub count: Option<std::num::NonZeroU32>,
    /// An unsized binding array (`binding_array<T>`): its length is given when the pipeline is
    /// made ([`ComputePipeline::with_counts`], [`RenderPipeline::with_counts`]).
    pub unsized_array: bool,
}

/// The lengths of a pipeline's unsized binding arrays, as one typed value: the generated
/// `ArrayCounts` struct of every pipeline with such an array implements it (one field per
/// array), so a renamed array is a compile error.
pub trait Counts {
    /// `(binding name, length)` for each unsized binding array.
    fn counts(&self) -> Vec<(&'static str, u32)>;
}

/// No unsized binding arrays.
impl Counts for () {
    fn counts(&self) -> Vec<(&'static str, u32)> {
        Vec::new()
    }
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
        /// Its `@workgroup_size` (a dimension an override sets, at the override's default).
        workgroup_size: [u32; 3],
        /// Per dimension, the `override` that sets it (`""` where the size is a constant).
        sized_by: [&'static str; 3],
    },
    /// A fragment entry point with the vertex entry point it pairs with.
    Render {
        /// The vertex entry point paired with the fragment entry point.
        vertex: &'static str,
        /// The linked WGSL of the vertex entry's own stage where it lives in another file than
        /// the fragment entry (a `// draw with:` pairing); `None`: both are in `source`.
        vertex_source: Option<&'static str>,
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

    /// `@workgroup_size`, for compute entries (a dimension an override sets, at its default:
    /// [`Self::workgroup_size_with`] gives it for other values).
    pub fn workgroup_size(&self) -> Option<[u32; 3]> {
        match self.kind {
            EntryKind::Compute { workgroup_size, .. } => Some(workgroup_size),
            _ => None,
        }
    }

    /// `@workgroup_size` with `overrides` (by name, as a pipeline is made with them): a
    /// dimension an override sets takes its value there, else its default.
    pub fn workgroup_size_with(&self, overrides: &[(&str, f64)]) -> Option<[u32; 3]> {
        let EntryKind::Compute {
            workgroup_size,
            sized_by,
        } = self.kind
        else {
            return None;
        };
        let mut size = workgroup_size;
        for (i, name) in sized_by.iter().enumerate() {
            if let Some((_, v)) = overrides
                .iter()
                .find(|(n, _)| !name.is_empty() && n == name)
            {
                size[i] = v.max(0.0).min(u32::MAX as f64) as u32;
            }
        }
        Some(size)
    }

    /// The slots with each unsized binding array's length from `counts`; an error naming an
    /// array without a length (or of length 0), a length for no such array, or one past the
    /// device's limits.
    pub(crate) fn slots_with(
        &self,
        device: &wgpu::Device,
        counts: &[(&str, u32)],
    ) -> Result<Vec<Slot>, Error> {
        for (name, _) in counts {
            if !self
                .slots
                .iter()
                .any(|s| s.unsized_array && s.name == *name)
            {
                return Err(Error::invalid(
                    self.stage,
                    format!(
                        "`{}`: no unsized binding array `{name}` to give a length",
                        self.entry_point
                    ),
                ));
            }
        }
        let limits = device.limits();
        self.slots
            .iter()
            .map(|s| {
                if !s.unsized_array {
                    return Ok(*s);
                }
                let n = counts.iter().find(|(name, _)| *name == s.name).map(|c| c.1);
                let Some(count) = n.and_then(std::num::NonZeroU32::new) else {
                    return Err(Error::invalid(
                        self.stage,
                        format!(
                            "`{}`: `{}` is an unsized binding array (`{}`): make the pipeline \
                             with `with_counts`, giving its length (not 0)",
                            self.entry_point, s.name, s.wgsl
                        ),
                    ));
                };
                let (most, limit) = if matches!(s.ty, wgpu::BindingType::Sampler(_)) {
                    (
                        limits.max_binding_array_sampler_elements_per_shader_stage,
                        "max_binding_array_sampler_elements_per_shader_stage",
                    )
                } else {
                    (
                        limits.max_binding_array_elements_per_shader_stage,
                        "max_binding_array_elements_per_shader_stage",
                    )
                };
                if count.get() > most {
                    return Err(Error::Unsupported {
                        stage: self.stage,
                        what: format!(
                            "`{}`: {count} elements of `{}`, past this device's {limit} ({most})",
                            self.entry_point, s.name
                        ),
                    });
                }
                Ok(Slot {
                    count: Some(count),
                    ..*s
                })
            })
            .collect()
    }

    /// One bind group layout per group of `slots`.
    fn layouts(&self, device: &wgpu::Device, slots: &[Slot]) -> Vec<(u32, wgpu::BindGroupLayout)> {
        self.groups()
            .into_iter()
            .map(|g| {
                let slots: Vec<Slot> = slots.iter().filter(|s| s.group == g).copied().collect();
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

impl<G> Clone for Group<G> {
    fn clone(&self) -> Self {
        Self {
            bind_group: self.bind_group.clone(),
            _g: PhantomData,
        }
    }
}

impl<G> std::fmt::Debug for Group<G> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Group")
            .field("bind_group", &self.bind_group)
            .finish()
    }
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
pub(crate) fn layout_of(
    device: &wgpu::Device,
    slots: &[Slot],
    label: &str,
) -> wgpu::BindGroupLayout {
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
