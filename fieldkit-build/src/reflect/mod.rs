//! Reflection of one linked stage, read from naga's IR and validation info. Codegen, `xtask reflect`
//! and the lints all work from this one description.

use naga::valid::GlobalUse;
use naga::{AddressSpace, ImageClass, ScalarKind, ShaderStage, TypeInner};
use serde::Serialize;

use super::Stage;

mod types;
pub(crate) mod vertex;

use types::{access_name, dim_name, scalar_class};
pub use types::{host_name, rust_type, storage_format_wgsl, wgsl_type};
pub(crate) use types::{located_args, located_outputs};

#[derive(Debug, Clone, Serialize)]
pub struct Reflection {
    pub stage: String,
    pub path: String,
    pub entry_points: Vec<EntryPoint>,
    pub bindings: Vec<Binding>,
    pub structs: Vec<StructInfo>,
    pub overrides: Vec<Override>,
    /// The `var<immediate>` block, if the module declares one.
    pub immediate: Option<Immediate>,
    /// `wgpu::Features` the module needs (constant names, e.g. "TEXTURE_BINDING_ARRAY").
    pub features: Vec<String>,
}

/// A module's `var<immediate>` (push constants): its host type and size in bytes.
#[derive(Debug, Clone, Serialize)]
pub struct Immediate {
    pub name: String,
    pub ty: String,
    pub rust: String,
    pub size: u32,
}

#[derive(Debug, Clone, Serialize)]
pub struct Binding {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub kind: BindingKind,
    /// WGSL spelling of the bound type.
    pub ty: String,
    /// A binding array's length (`binding_array<T, N>`); `None` for one resource or an unsized
    /// array.
    pub count: Option<u32>,
    /// An unsized binding array (`binding_array<T>`): its length is given when the pipeline is
    /// made.
    pub unsized_array: bool,
    /// Its layout takes a dynamic offset (buffers the build script names).
    pub dynamic_offset: bool,
    /// Declared in a module of the folder's `shared/` (its module and its name there): a
    /// group all of whose bindings one such module declares is a shared group.
    pub shared: Option<SharedRef>,
    /// Source line of the declaration in the linked text (for lints).
    #[serde(skip)]
    pub linked_offset: usize,
}

/// Where a binding of a shared module comes from.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SharedRef {
    /// The module's path under `shared/`, `_` between levels.
    pub module: String,
    /// The binding's name in the module.
    pub name: String,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum BindingKind {
    Uniform {
        min_size: u32,
        rust: String,
    },
    Storage {
        read_only: bool,
        min_size: u32,
        rust: String,
    },
    Texture {
        dim: String,
        sample: SampleKind,
        multisampled: bool,
    },
    StorageTexture {
        dim: String,
        format: String,
        access: String,
    },
    Sampler {
        comparison: bool,
        filtering: bool,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SampleKind {
    Float { filterable: bool },
    Uint,
    Sint,
    Depth,
}

#[derive(Debug, Clone, Serialize)]
pub struct BindingUse {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    /// "read", "write" or "read_write", from what the entry point really does.
    pub access: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct EntryPoint {
    pub name: String,
    pub stage: String,
    /// `@workgroup_size`, with a dimension set by an `override` at that override's default.
    pub workgroup_size: [u32; 3],
    /// Per dimension, the `override` that sets it (`@workgroup_size(BLOCK)`), if one does.
    pub workgroup_size_overrides: [Option<String>; 3],
    /// The `@location`s between stages: those a vertex entry writes, those a fragment entry
    /// reads (a vertex and a fragment entry make a pipeline where the first covers the second).
    pub stage_io: Vec<u32>,
    /// Bytes of `var<workgroup>` the entry point uses (array lengths from overrides at their
    /// defaults).
    pub workgroup_storage: u32,
    /// What it asks of a device's limits.
    pub needs: Needs,
    pub uses: Vec<BindingUse>,
    pub vertex_inputs: Vec<VertexInput>,
    pub fragment_outputs: Vec<FragmentOutput>,
    /// It reads the module's `var<immediate>`.
    pub uses_immediate: bool,
}

/// The device limits an entry point (or a pipeline, field by field the larger of its entry
/// points') needs, named as `wgpu::Limits` names them. The build-time twin of fieldkit's
/// `bind::Needs` (this crate cannot depend on fieldkit, which builds with it): generated code
/// fills the runtime one field by field, so a field that drifts is a compile error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Needs {
    pub max_storage_buffers_per_shader_stage: u32,
    pub max_storage_textures_per_shader_stage: u32,
    pub max_sampled_textures_per_shader_stage: u32,
    pub max_samplers_per_shader_stage: u32,
    pub max_uniform_buffers_per_shader_stage: u32,
    pub max_bind_groups: u32,
    pub max_uniform_buffer_binding_size: u32,
    pub max_compute_workgroup_storage_size: u32,
    pub max_compute_invocations_per_workgroup: u32,
}

impl Needs {
    /// Field by field, the larger of the two.
    pub fn max(self, o: Needs) -> Needs {
        Needs {
            max_storage_buffers_per_shader_stage: self
                .max_storage_buffers_per_shader_stage
                .max(o.max_storage_buffers_per_shader_stage),
            max_storage_textures_per_shader_stage: self
                .max_storage_textures_per_shader_stage
                .max(o.max_storage_textures_per_shader_stage),
            max_sampled_textures_per_shader_stage: self
                .max_sampled_textures_per_shader_stage
                .max(o.max_sampled_textures_per_shader_stage),
            max_samplers_per_shader_stage: self
                .max_samplers_per_shader_stage
                .max(o.max_samplers_per_shader_stage),
            max_uniform_buffers_per_shader_stage: self
                .max_uniform_buffers_per_shader_stage
                .max(o.max_uniform_buffers_per_shader_stage),
            max_bind_groups: self.max_bind_groups.max(o.max_bind_groups),
            max_uniform_buffer_binding_size: self
                .max_uniform_buffer_binding_size
                .max(o.max_uniform_buffer_binding_size),
            max_compute_workgroup_storage_size: self
                .max_compute_workgroup_storage_size
                .max(o.max_compute_workgroup_storage_size),
            max_compute_invocations_per_workgroup: self
                .max_compute_invocations_per_workgroup
                .max(o.max_compute_invocations_per_workgroup),
        }
    }

    /// `(name, value)` per field, in declaration order.
    pub fn fields(&self) -> [(&'static str, u32); 9] {
        [
            (
                "max_storage_buffers_per_shader_stage",
                self.max_storage_buffers_per_shader_stage,
            ),
            (
                "max_storage_textures_per_shader_stage",
                self.max_storage_textures_per_shader_stage,
            ),
            (
                "max_sampled_textures_per_shader_stage",
                self.max_sampled_textures_per_shader_stage,
            ),
            (
                "max_samplers_per_shader_stage",
                self.max_samplers_per_shader_stage,
            ),
            (
                "max_uniform_buffers_per_shader_stage",
                self.max_uniform_buffers_per_shader_stage,
            ),
            ("max_bind_groups", self.max_bind_groups),
            (
                "max_uniform_buffer_binding_size",
                self.max_uniform_buffer_binding_size,
            ),
            (
                "max_compute_workgroup_storage_size",
                self.max_compute_workgroup_storage_size,
            ),
            (
                "max_compute_invocations_per_workgroup",
                self.max_compute_invocations_per_workgroup,
            ),
        ]
    }
}

/// What an entry point using `uses` of `bindings` needs.
fn needs_of(
    bindings: &[Binding],
    uses: &[BindingUse],
    workgroup_storage: u32,
    workgroup_size: [u32; 3],
    compute: bool,
) -> Needs {
    let used: Vec<&Binding> = uses
        .iter()
        .filter_map(|u| {
            bindings
                .iter()
                .find(|b| b.group == u.group && b.binding == u.binding)
        })
        .collect();
    // A binding array counts as its length against the per-stage limits, as wgpu counts it.
    let count = |f: &dyn Fn(&BindingKind) -> bool| {
        used.iter()
            .filter(|b| f(&b.kind))
            .map(|b| b.count.unwrap_or(1))
            .sum::<u32>()
    };
    Needs {
        max_storage_buffers_per_shader_stage: count(&|k| matches!(k, BindingKind::Storage { .. })),
        max_storage_textures_per_shader_stage: count(&|k| {
            matches!(k, BindingKind::StorageTexture { .. })
        }),
        max_sampled_textures_per_shader_stage: count(&|k| matches!(k, BindingKind::Texture { .. })),
        max_samplers_per_shader_stage: count(&|k| matches!(k, BindingKind::Sampler { .. })),
        max_uniform_buffers_per_shader_stage: count(&|k| matches!(k, BindingKind::Uniform { .. })),
        max_bind_groups: used.iter().map(|b| b.group + 1).max().unwrap_or(0),
        max_uniform_buffer_binding_size: used
            .iter()
            .filter_map(|b| match b.kind {
                BindingKind::Uniform { min_size, .. } => Some(min_size),
                _ => None,
            })
            .max()
            .unwrap_or(0),
        max_compute_workgroup_storage_size: workgroup_storage,
        max_compute_invocations_per_workgroup: if compute {
            workgroup_size.iter().product()
        } else {
            0
        },
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct VertexInput {
    pub location: u32,
    pub name: String,
    pub ty: String,
    /// `wgpu::VertexFormat` variant name.
    pub format: String,
    /// The host field's type (`[f32; 3]`, `[u8; 4]`).
    pub rust: String,
    /// Bytes in the buffer.
    pub size: u32,
    /// Read per instance (from the second buffer), not per vertex.
    pub instance: bool,
}

#[derive(Debug, Clone, Serialize)]
pub struct FragmentOutput {
    pub location: u32,
    pub ty: String,
    /// "float", "uint" or "sint": the texture formats it may be written to.
    pub scalar: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct StructInfo {
    pub name: String,
    /// Its name in the linked WGSL (mangled where it was imported).
    pub linked: String,
    pub size: u32,
    pub align: u32,
    pub members: Vec<Member>,
    /// Used as (part of) a uniform or storage binding: gets a host type.
    pub host_shareable: bool,
}

#[derive(Debug, Clone, Serialize)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    pub size: u32,
    pub ty: String,
    pub rust: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct Override {
    pub name: String,
    pub id: Option<u16>,
    pub ty: String,
    pub has_default: bool,
    /// The default where it is a literal (`override ROWS: u32 = 1u;`), as f64 (bool: 0 or 1);
    /// `None` where there is none or it is an expression the shader computes.
    pub default: Option<f64>,
}

/// A literal initializer's value, as f64.
fn literal_value(
    module: &naga::Module,
    init: Option<naga::Handle<naga::Expression>>,
) -> Option<f64> {
    use naga::Literal as L;
    match module.global_expressions[init?] {
        naga::Expression::Literal(l) => Some(match l {
            L::F64(v) => v,
            L::F32(v) => v as f64,
            L::F16(v) => f64::from(v),
            L::U32(v) => v as f64,
            L::I32(v) => v as f64,
            L::U64(v) => v as f64,
            L::I64(v) => v as f64,
            L::U16(v) => v as f64,
            L::I16(v) => v as f64,
            L::Bool(v) => v as u32 as f64,
            L::AbstractInt(v) => v as f64,
            L::AbstractFloat(v) => v,
        }),
        _ => None,
    }
}

fn fragment_outputs(module: &naga::Module, func: &naga::Function) -> Vec<FragmentOutput> {
    let Some(result) = &func.result else {
        return vec![];
    };
    let mut out = Vec::new();
    match &result.binding {
        Some(naga::Binding::Location { location, .. }) => out.push(FragmentOutput {
            location: *location,
            ty: wgsl_type(module, result.ty),
            scalar: scalar_class(module, result.ty),
        }),
        Some(_) => {}
        None => {
            if let TypeInner::Struct { members, .. } = &module.types[result.ty].inner {
                for m in members {
                    if let Some(naga::Binding::Location { location, .. }) = m.binding {
                        out.push(FragmentOutput {
                            location,
                            ty: wgsl_type(module, m.ty),
                            scalar: scalar_class(module, m.ty),
                        });
                    }
                }
            }
        }
    }
    out.sort_by_key(|o| o.location);
    out
}

/// Mark every struct reachable from a host-shareable binding.
fn mark_shareable(
    module: &naga::Module,
    ty: naga::Handle<naga::Type>,
    out: &mut Vec<naga::Handle<naga::Type>>,
) {
    match &module.types[ty].inner {
        TypeInner::Struct { members, .. } => {
            if !out.contains(&ty) {
                out.push(ty);
            }
            for m in members {
                mark_shareable(module, m.ty, out);
            }
        }
        TypeInner::Array { base, .. } => mark_shareable(module, *base, out),
        _ => {}
    }
}

pub fn reflect(stage: &Stage) -> Reflection {
    let module = &stage.module;
    let mut layouter = naga::proc::Layouter::default();
    layouter
        .update(module.to_ctx())
        .expect("validated module has a layout");
    let mut shareable = Vec::new();
    let (mut bindings, handles) = reflect_bindings(stage, &layouter, &mut shareable);
    let entry_points = module
        .entry_points
        .iter()
        .enumerate()
        .map(|(i, ep)| reflect_entry(stage, i, ep, &bindings, &handles))
        .collect();
    // The immediate block is host data like a uniform: its struct is generated.
    let immediate = module
        .global_variables
        .iter()
        .find(|(_, v)| v.space == AddressSpace::Immediate)
        .map(|(_, v)| {
            mark_shareable(module, v.ty, &mut shareable);
            Immediate {
                name: v.name.clone().unwrap_or_default(),
                ty: wgsl_type(module, v.ty),
                rust: rust_type(module, v.ty).unwrap_or_default(),
                size: layouter[v.ty].size,
            }
        });

    let structs = reflect_structs(module, &layouter, &shareable);
    let overrides = module
        .overrides
        .iter()
        .map(|(_, o)| Override {
            name: o.name.clone().unwrap_or_default(),
            id: o.id,
            ty: wgsl_type(module, o.ty),
            has_default: o.init.is_some(),
            default: literal_value(module, o.init),
        })
        .collect();

    bindings.sort_by_key(|b| (b.group, b.binding));
    Reflection {
        stage: stage.file.id(),
        path: stage.file.rel_path.clone(),
        entry_points,
        bindings,
        structs,
        overrides,
        immediate,
        features: stage.features.clone(),
    }
}

/// Every bound global of the stage's module, described for the host (in declaration order),
/// with its handle; the types bound as uniforms or storage are marked host-shareable.
fn reflect_bindings(
    stage: &Stage,
    layouter: &naga::proc::Layouter,
    shareable: &mut Vec<naga::Handle<naga::Type>>,
) -> (Vec<Binding>, Vec<naga::Handle<naga::GlobalVariable>>) {
    let module = &stage.module;
    // Which sampled textures are ever sampled through a sampler (they must be filterable).
    let mut sampled_images = Vec::new();
    let mut sampled_samplers = Vec::new();
    for (i, _) in module.entry_points.iter().enumerate() {
        for key in &stage.info.get_entry_point(i).sampling_set {
            sampled_images.push(key.image);
            sampled_samplers.push(key.sampler);
        }
    }

    let mut bindings = Vec::new();
    let mut handles = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        // A binding array is described by its element, with its length beside it (an
        // unsized one's is given when the pipeline is made).
        let (elem, count, unsized_array) = match &module.types[var.ty].inner {
            TypeInner::BindingArray {
                base,
                size: naga::ArraySize::Constant(n),
            } => (*base, Some(n.get()), false),
            TypeInner::BindingArray { base, .. } => (*base, None, true),
            _ => (var.ty, None, false),
        };
        let ty_inner = &module.types[elem].inner;
        let kind = match (var.space, ty_inner) {
            (AddressSpace::Uniform, _) => {
                mark_shareable(module, elem, shareable);
                BindingKind::Uniform {
                    min_size: layouter[elem].size,
                    rust: rust_type(module, elem).unwrap_or_default(),
                }
            }
            (AddressSpace::Storage { access }, _) => {
                mark_shareable(module, elem, shareable);
                BindingKind::Storage {
                    read_only: !access.contains(naga::StorageAccess::STORE),
                    min_size: layouter[elem].size,
                    rust: rust_type(module, elem).unwrap_or_default(),
                }
            }
            (
                _,
                TypeInner::Image {
                    dim,
                    arrayed,
                    class,
                },
            ) => match class {
                ImageClass::Sampled { kind, multi } => BindingKind::Texture {
                    dim: dim_name(*dim, *arrayed),
                    sample: match kind {
                        ScalarKind::Uint => SampleKind::Uint,
                        ScalarKind::Sint => SampleKind::Sint,
                        _ => SampleKind::Float {
                            filterable: sampled_images.contains(&handle),
                        },
                    },
                    multisampled: *multi,
                },
                ImageClass::Depth { multi } => BindingKind::Texture {
                    dim: dim_name(*dim, *arrayed),
                    sample: SampleKind::Depth,
                    multisampled: *multi,
                },
                ImageClass::Storage { format, access } => BindingKind::StorageTexture {
                    dim: dim_name(*dim, *arrayed),
                    format: format!("{format:?}"),
                    access: access_name(*access).into(),
                },
                ImageClass::External => continue,
            },
            (_, TypeInner::Sampler { comparison }) => BindingKind::Sampler {
                comparison: *comparison,
                filtering: !*comparison && sampled_samplers.contains(&handle),
            },
            _ => continue,
        };
        let linked_offset = module
            .global_variables
            .get_span(handle)
            .to_range()
            .map(|r| r.start)
            .unwrap_or(0);
        bindings.push(Binding {
            group: rb.group,
            binding: rb.binding,
            name: var.name.clone().unwrap_or_default(),
            kind,
            ty: wgsl_type(module, var.ty),
            count,
            unsized_array,
            dynamic_offset: stage
                .dynamic_offsets
                .iter()
                .any(|d| Some(d.as_str()) == var.name.as_deref()),
            shared: stage
                .shared
                .iter()
                .find(|d| Some(d.linked.as_str()) == var.name.as_deref())
                .map(|d| SharedRef {
                    module: d.module.clone(),
                    name: d.name.clone(),
                }),
            linked_offset,
        });
        handles.push(handle);
    }

    (bindings, handles)
}

/// Entry point `i` of the stage: its stage, workgroup, what it binds and how, its vertex inputs
/// or fragment outputs, and the limits it needs.
fn reflect_entry(
    stage: &Stage,
    i: usize,
    ep: &naga::EntryPoint,
    bindings: &[Binding],
    handles: &[naga::Handle<naga::GlobalVariable>],
) -> EntryPoint {
    let module = &stage.module;
    let fi = stage.info.get_entry_point(i);
    let mut uses = Vec::new();
    for (b, &h) in bindings.iter().zip(handles) {
        let u = fi[h];
        if u.is_empty() {
            continue;
        }
        let r = u.intersects(GlobalUse::READ | GlobalUse::QUERY);
        let w = u.contains(GlobalUse::WRITE);
        let access = match (r, w) {
            (_, true) if u.contains(GlobalUse::READ) => "read_write",
            (_, true) => "write",
            _ => "read",
        };
        uses.push(BindingUse {
            group: b.group,
            binding: b.binding,
            name: b.name.clone(),
            access: access.into(),
        });
    }
    let stage_name = match ep.stage {
        ShaderStage::Compute => "compute",
        ShaderStage::Vertex => "vertex",
        ShaderStage::Fragment => "fragment",
        _ => "other",
    };
    let vertex_inputs = if ep.stage == ShaderStage::Vertex {
        // The build refused the stage where this fails.
        vertex::inputs(&stage.original, module, ep).unwrap_or_default()
    } else {
        vec![]
    };
    let fragment_outputs = if ep.stage == ShaderStage::Fragment {
        fragment_outputs(module, &ep.function)
    } else {
        vec![]
    };
    let workgroup_storage = module
        .global_variables
        .iter()
        .filter(|(h, v)| v.space == AddressSpace::WorkGroup && !fi[*h].is_empty())
        .map(|(_, v)| module.types[v.ty].inner.size(module.to_ctx()))
        .sum();
    let uses_immediate = module
        .global_variables
        .iter()
        .any(|(h, v)| v.space == AddressSpace::Immediate && !fi[h].is_empty());
    let (workgroup_size, workgroup_size_overrides) = sized_by_overrides(module, ep);
    let needs = needs_of(
        bindings,
        &uses,
        workgroup_storage,
        workgroup_size,
        ep.stage == ShaderStage::Compute,
    );
    EntryPoint {
        name: ep.name.clone(),
        stage: stage_name.into(),
        workgroup_size,
        workgroup_size_overrides,
        stage_io: match ep.stage {
            ShaderStage::Vertex => located_outputs(module, &ep.function),
            ShaderStage::Fragment => located_args(module, &ep.function)
                .into_iter()
                .map(|a| a.0)
                .collect(),
            _ => Vec::new(),
        },
        workgroup_storage,
        needs,
        uses,
        vertex_inputs,
        fragment_outputs,
        uses_immediate,
    }
}

/// A compute entry's `@workgroup_size` with each dimension an `override` sets at that
/// override's literal default, and per dimension the override's name.
fn sized_by_overrides(
    module: &naga::Module,
    ep: &naga::EntryPoint,
) -> ([u32; 3], [Option<String>; 3]) {
    let mut size = ep.workgroup_size;
    let mut names: [Option<String>; 3] = Default::default();
    for (i, e) in ep.workgroup_size_overrides.iter().flatten().enumerate() {
        let Some(h) = e else { continue };
        if let naga::Expression::Override(o) = module.global_expressions[*h] {
            let o = &module.overrides[o];
            names[i] = o.name.clone();
            if let Some(v) = literal_value(module, o.init) {
                size[i] = v as u32;
            }
        }
    }
    (size, names)
}

/// What makes a compute entry's workgroup size unknowable before its pipeline is made, per
/// entry: a dimension set by an expression of overrides (not one plain `override`), or by an
/// override without a literal default.
pub fn workgroup_size_problems(module: &naga::Module) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for ep in &module.entry_points {
        for (i, e) in ep.workgroup_size_overrides.iter().flatten().enumerate() {
            let Some(h) = e else { continue };
            let axis = ["x", "y", "z"][i];
            let why = match module.global_expressions[*h] {
                naga::Expression::Override(o) => {
                    let o = &module.overrides[o];
                    literal_value(module, o.init).is_none().then(|| {
                        format!(
                            "its {axis} size is the override `{}`, which has no literal default: \
                             give it one (`override {}: u32 = 64u;`) so the generated \
                             `WORKGROUP_SIZE` and `needs` hold a size",
                            o.name.as_deref().unwrap_or("?"),
                            o.name.as_deref().unwrap_or("?")
                        )
                    })
                }
                _ => Some(format!(
                    "its {axis} size is an expression of overrides: size it by one plain \
                     `override` with a literal default, so the generated \
                     `workgroup_size(&Overrides)` can say it"
                )),
            };
            if let Some(why) = why {
                out.push((ep.name.clone(), why));
            }
        }
    }
    out
}

/// The module's named memory-layout structs (entry-point interface structs left out).
fn reflect_structs(
    module: &naga::Module,
    layouter: &naga::proc::Layouter,
    shareable: &[naga::Handle<naga::Type>],
) -> Vec<StructInfo> {
    let mut structs = Vec::new();
    for (handle, ty) in module.types.iter() {
        let TypeInner::Struct { members, span } = &ty.inner else {
            continue;
        };
        let Some(name) = &ty.name else { continue };
        // Entry-point interface structs (locations/builtins) are not memory layouts, unless a
        // buffer holds them too (one struct as vertex input and storage element).
        if members.iter().any(|m| m.binding.is_some()) && !shareable.contains(&handle) {
            continue;
        }
        structs.push(StructInfo {
            name: host_name(name),
            linked: name.clone(),
            size: *span,
            align: layouter[handle].alignment.round_up(1),
            members: members
                .iter()
                .map(|m| Member {
                    name: m.name.clone().unwrap_or_default(),
                    offset: m.offset,
                    size: layouter[m.ty].size,
                    ty: wgsl_type(module, m.ty),
                    rust: rust_type(module, m.ty).unwrap_or_default(),
                })
                .collect(),
            host_shareable: shareable.contains(&handle),
        });
    }

    structs
}

impl Reflection {
    /// The human-readable tables `xtask reflect` prints.
    pub fn to_table(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        writeln!(s, "stage {}  ({})", self.stage, self.path).unwrap();
        for ep in &self.entry_points {
            write!(s, "  entry {} [{}]", ep.name, ep.stage).unwrap();
            if ep.stage == "compute" {
                let [x, y, z] = ep.workgroup_size;
                write!(s, " workgroup_size({x}, {y}, {z})").unwrap();
            }
            writeln!(s).unwrap();
            writeln!(
                s,
                "    {:<5} {:<7} {:<16} {:<15} {:<40} access",
                "group", "binding", "name", "kind", "type"
            )
            .unwrap();
            for u in &ep.uses {
                let b = self
                    .bindings
                    .iter()
                    .find(|b| b.group == u.group && b.binding == u.binding && b.name == u.name)
                    .unwrap();
                let kind = match &b.kind {
                    BindingKind::Uniform { .. } => "uniform",
                    BindingKind::Storage { .. } => "storage",
                    BindingKind::Texture { .. } => "texture",
                    BindingKind::StorageTexture { .. } => "storage_texture",
                    BindingKind::Sampler { .. } => "sampler",
                };
                writeln!(
                    s,
                    "    {:<5} {:<7} {:<16} {:<15} {:<40} {}",
                    b.group, b.binding, b.name, kind, b.ty, u.access
                )
                .unwrap();
            }
            for v in &ep.vertex_inputs {
                writeln!(
                    s,
                    "    vertex input @location({}) {}: {} ({})",
                    v.location, v.name, v.ty, v.format
                )
                .unwrap();
            }
            for o in &ep.fragment_outputs {
                writeln!(
                    s,
                    "    fragment output @location({}): {} ({})",
                    o.location, o.ty, o.scalar
                )
                .unwrap();
            }
        }
        for st in self.structs.iter().filter(|s| s.host_shareable) {
            writeln!(
                s,
                "  struct {} size {} align {}",
                st.name, st.size, st.align
            )
            .unwrap();
            for m in &st.members {
                writeln!(
                    s,
                    "    {:>4}  {:<16} {} (size {})",
                    m.offset, m.name, m.ty, m.size
                )
                .unwrap();
            }
        }
        for o in &self.overrides {
            writeln!(
                s,
                "  override {}: {}{}",
                o.name,
                o.ty,
                if o.has_default { " (has default)" } else { "" }
            )
            .unwrap();
        }
        s
    }
}
