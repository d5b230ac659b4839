//! How reflected types are named: WGSL spellings, the Rust types codegen writes for them, and
//! vertex formats.

use naga::{ImageClass, ImageDimension, ScalarKind, TypeInner};

pub(super) fn scalar_name(s: naga::Scalar) -> String {
    match (s.kind, s.width) {
        (ScalarKind::Float, 4) => "f32".into(),
        (ScalarKind::Float, 2) => "f16".into(),
        (ScalarKind::Float, 8) => "f64".into(),
        (ScalarKind::Uint, 4) => "u32".into(),
        (ScalarKind::Sint, 4) => "i32".into(),
        (ScalarKind::Bool, _) => "bool".into(),
        (k, w) => format!("{k:?}{}", w * 8).to_lowercase(),
    }
}

pub(super) fn dim_name(dim: ImageDimension, arrayed: bool) -> String {
    let d = match dim {
        ImageDimension::D1 => "1d",
        ImageDimension::D2 => "2d",
        ImageDimension::D3 => "3d",
        ImageDimension::Cube => "cube",
    };
    if arrayed {
        format!("{d}_array")
    } else {
        d.into()
    }
}

/// The name a struct imported through WESL is known by: the linker spells
/// `package::shared::gerstner::GerstnerWave` as `package_shared_gerstner_GerstnerWave` (and
/// `fieldkit::gerstner::GerstnerWave`, from fieldkit's package, as
/// `fieldkit_gerstner_GerstnerWave`), and the host code should say `GerstnerWave`. Names with
/// escaped underscores are left alone.
pub fn host_name(name: &str) -> String {
    let package = format!("{}_", fieldkit_wesl::PACKAGE.root.name);
    match name
        .strip_prefix("package_")
        .or_else(|| name.strip_prefix(package.as_str()))
    {
        Some(rest) if !rest.contains("__") => rest.rsplit('_').next().unwrap_or(rest).to_string(),
        _ => name.to_string(),
    }
}

/// WGSL spelling of a type.
pub fn wgsl_type(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let t = &module.types[ty];
    if let Some(name) = &t.name {
        return host_name(name);
    }
    match &t.inner {
        TypeInner::Scalar(s) => scalar_name(*s),
        TypeInner::Vector { size, scalar } => {
            format!("vec{}<{}>", *size as u8, scalar_name(*scalar))
        }
        TypeInner::Matrix {
            columns,
            rows,
            scalar,
        } => {
            format!(
                "mat{}x{}<{}>",
                *columns as u8,
                *rows as u8,
                scalar_name(*scalar)
            )
        }
        TypeInner::Atomic(s) => format!("atomic<{}>", scalar_name(*s)),
        TypeInner::Array { base, size, .. } => match size {
            naga::ArraySize::Constant(n) => format!("array<{}, {n}>", wgsl_type(module, *base)),
            _ => format!("array<{}>", wgsl_type(module, *base)),
        },
        TypeInner::BindingArray { base, size } => match size {
            naga::ArraySize::Constant(n) => {
                format!("binding_array<{}, {n}>", wgsl_type(module, *base))
            }
            _ => format!("binding_array<{}>", wgsl_type(module, *base)),
        },
        TypeInner::Image {
            dim,
            arrayed,
            class,
        } => match class {
            ImageClass::Sampled { kind, multi } => format!(
                "texture_{}{}<{}>",
                if *multi { "multisampled_" } else { "" },
                dim_name(*dim, *arrayed),
                scalar_name(naga::Scalar {
                    kind: *kind,
                    width: 4
                })
            ),
            ImageClass::Depth { multi } => {
                format!(
                    "texture_depth_{}{}",
                    if *multi { "multisampled_" } else { "" },
                    dim_name(*dim, *arrayed)
                )
            }
            ImageClass::Storage { format, access } => {
                format!(
                    "texture_storage_{}<{}, {}>",
                    dim_name(*dim, *arrayed),
                    storage_format_wgsl(*format),
                    access_name(*access)
                )
            }
            ImageClass::External => "texture_external".into(),
        },
        TypeInner::Sampler { comparison } => if *comparison {
            "sampler_comparison"
        } else {
            "sampler"
        }
        .into(),
        other => format!("{other:?}"),
    }
}

/// Rust host type for a host-shareable WGSL type (glam for vectors and matrices; encase lays them out).
pub fn rust_type(module: &naga::Module, ty: naga::Handle<naga::Type>) -> Option<String> {
    let t = &module.types[ty];
    Some(match &t.inner {
        TypeInner::Struct { .. } => host_name(t.name.as_deref()?),
        TypeInner::Scalar(s) | TypeInner::Atomic(s) => match (s.kind, s.width) {
            (ScalarKind::Float, 4) => "f32".into(),
            (ScalarKind::Uint, 4) => "u32".into(),
            (ScalarKind::Sint, 4) => "i32".into(),
            _ => return None,
        },
        TypeInner::Vector { size, scalar } => {
            let prefix = match (scalar.kind, scalar.width) {
                (ScalarKind::Float, 4) => "",
                (ScalarKind::Uint, 4) => "U",
                (ScalarKind::Sint, 4) => "I",
                _ => return None,
            };
            format!("glam::{prefix}Vec{}", *size as u8)
        }
        TypeInner::Matrix {
            columns,
            rows,
            scalar,
        } if columns == rows && scalar.kind == ScalarKind::Float => {
            format!("glam::Mat{}", *columns as u8)
        }
        TypeInner::Array { base, size, .. } => {
            let inner = rust_type(module, *base)?;
            match size {
                naga::ArraySize::Constant(n) => format!("[{inner}; {n}]"),
                _ => format!("Vec<{inner}>"),
            }
        }
        _ => return None,
    })
}

pub(super) fn access_name(a: naga::StorageAccess) -> &'static str {
    let r = a.contains(naga::StorageAccess::LOAD);
    let w = a.contains(naga::StorageAccess::STORE);
    match (r, w) {
        (true, true) => "read_write",
        (true, false) => "read",
        _ => "write",
    }
}

/// WGSL texel-format spelling ("r32uint").
pub fn storage_format_wgsl(f: naga::StorageFormat) -> String {
    // naga's Debug names match wgpu's TextureFormat variants; WGSL is their lowercase.
    format!("{f:?}").to_lowercase()
}

pub(super) fn scalar_class(module: &naga::Module, ty: naga::Handle<naga::Type>) -> String {
    let s = match module.types[ty].inner {
        TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } => s,
        _ => return "float".into(),
    };
    match s.kind {
        ScalarKind::Uint => "uint",
        ScalarKind::Sint => "sint",
        _ => "float",
    }
    .into()
}

/// Collect `(location, name, type)` of a function's inputs, flattening struct arguments.
pub(crate) fn located_args(
    module: &naga::Module,
    func: &naga::Function,
) -> Vec<(u32, String, naga::Handle<naga::Type>)> {
    let mut out = Vec::new();
    for arg in &func.arguments {
        match &arg.binding {
            Some(naga::Binding::Location { location, .. }) => {
                out.push((*location, arg.name.clone().unwrap_or_default(), arg.ty))
            }
            Some(_) => {}
            None => {
                if let TypeInner::Struct { members, .. } = &module.types[arg.ty].inner {
                    for m in members {
                        if let Some(naga::Binding::Location { location, .. }) = m.binding {
                            out.push((location, m.name.clone().unwrap_or_default(), m.ty));
                        }
                    }
                }
            }
        }
    }
    out.sort_by_key(|a| a.0);
    out
}

/// The `@location`s a vertex entry writes (its result, or its result struct's members).
pub(crate) fn located_outputs(module: &naga::Module, func: &naga::Function) -> Vec<u32> {
    let Some(result) = &func.result else {
        return Vec::new();
    };
    let mut out = match (&result.binding, &module.types[result.ty].inner) {
        (Some(naga::Binding::Location { location, .. }), _) => vec![*location],
        (None, TypeInner::Struct { members, .. }) => members
            .iter()
            .filter_map(|m| match m.binding {
                Some(naga::Binding::Location { location, .. }) => Some(location),
                _ => None,
            })
            .collect(),
        _ => Vec::new(),
    };
    out.sort_unstable();
    out
}
