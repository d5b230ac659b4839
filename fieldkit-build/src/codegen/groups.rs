//! Bind groups declared once in a module of `shared/` and used by several pipelines: which
//! groups are shared, and the one `Group` type generated for each.

use std::fmt::Write;

use super::{PipelineDesc, pipelines, resource_field_type, stage_bits, wgpu_binding_type};
use crate::Stage;
use crate::reflect::{BindingKind, Reflection, SampleKind, reflect};

/// A shared group: the bindings of one `@group` that a module of the folder's `shared/`
/// declares, as every pipeline that uses them binds them (the union of their uses).
pub struct SharedGroupInfo {
    pub(super) module: String,
    pub(super) group: u32,
    /// Per binding: the binding, the stages that use it anywhere, its host type path.
    pub(super) bindings: Vec<(crate::reflect::Binding, Vec<String>, String)>,
}

/// The groups of a pipeline that a shared module declares whole: every binding of the group
/// the pipeline uses comes from that one module.
pub(super) fn shared_groups_of<'r>(r: &'r Reflection, p: &PipelineDesc) -> Vec<(u32, &'r str)> {
    let mut groups: Vec<(u32, Option<&str>)> = Vec::new();
    for b in &r.bindings {
        let used = p.entries.iter().any(|e| {
            e.uses
                .iter()
                .any(|u| u.group == b.group && u.binding == b.binding)
        });
        if !used {
            continue;
        }
        let module = b.shared.as_ref().map(|s| s.module.as_str());
        match groups.iter_mut().find(|(g, _)| *g == b.group) {
            Some((_, m)) => {
                if *m != module {
                    *m = None;
                }
            }
            None => groups.push((b.group, module)),
        }
    }
    groups
        .into_iter()
        .filter_map(|(g, m)| m.map(|m| (g, m)))
        .collect()
}

/// Every shared group of the folder, its bindings merged over all stages that use them.
pub fn shared_groups(stages: &[Stage]) -> Vec<SharedGroupInfo> {
    let mut out: Vec<SharedGroupInfo> = Vec::new();
    for st in stages {
        let r = reflect(st);
        for p in pipelines(&r, &[]) {
            for (group, module) in shared_groups_of(&r, &p) {
                let i = match out
                    .iter()
                    .position(|s| s.module == module && s.group == group)
                {
                    Some(i) => i,
                    None => {
                        out.push(SharedGroupInfo {
                            module: module.to_string(),
                            group,
                            bindings: Vec::new(),
                        });
                        out.len() - 1
                    }
                };
                for b in r.bindings.iter().filter(|b| b.group == group) {
                    let stages: Vec<String> =
                        p.stages_using(b).into_iter().map(String::from).collect();
                    let path = format!("super::super::{}::", st.file.id());
                    let rust = qualify(&r, rust_of(&b.kind), &path);
                    let shared = &mut out[i];
                    match shared
                        .bindings
                        .iter_mut()
                        .find(|(o, ..)| o.binding == b.binding)
                    {
                        Some((o, used, _)) => {
                            // A texture sampled through a filtering sampler by any user is
                            // filterable for all.
                            if let (
                                BindingKind::Texture {
                                    sample: SampleKind::Float { filterable: a },
                                    ..
                                },
                                BindingKind::Texture {
                                    sample: SampleKind::Float { filterable: b },
                                    ..
                                },
                            ) = (&mut o.kind, &b.kind)
                            {
                                *a |= *b;
                            }
                            for s in stages {
                                if !used.contains(&s) {
                                    used.push(s);
                                }
                            }
                        }
                        None => shared.bindings.push((b.clone(), stages, rust)),
                    }
                }
            }
        }
    }
    for s in &mut out {
        s.bindings.sort_by_key(|(b, ..)| b.binding);
    }
    out
}

pub(super) fn rust_of(kind: &BindingKind) -> &str {
    match kind {
        BindingKind::Uniform { rust, .. } | BindingKind::Storage { rust, .. } => rust,
        _ => "",
    }
}

/// `rust` with each of the stage's struct names (whole words) reached through `path`.
pub(super) fn qualify(r: &Reflection, rust: &str, path: &str) -> String {
    let mut out = String::new();
    let mut word = String::new();
    let flush = |word: &mut String, out: &mut String| {
        if r.structs
            .iter()
            .any(|st| st.name == *word && st.host_shareable)
        {
            out.push_str(path);
        }
        out.push_str(word);
        word.clear();
    };
    for c in rust.chars() {
        if c.is_alphanumeric() || c == '_' {
            word.push(c);
        } else {
            flush(&mut word, &mut out);
            out.push(c);
        }
    }
    flush(&mut word, &mut out);
    out
}

/// `pub mod groups`: per shared group, its typed resources, slots and `Group` type.
pub(super) fn gen_shared_groups(shared: &[SharedGroupInfo], s: &mut String) {
    if shared.is_empty() {
        return;
    }
    writeln!(s, "/// Bind groups declared once in a module of `shared/` and used by several pipelines: make\n/// one `Group` and hand it to each.\n#[allow(non_snake_case, non_camel_case_types)]\npub mod groups {{").unwrap();
    for g in shared {
        let name = if shared.iter().filter(|o| o.module == g.module).count() > 1 {
            format!("{}_{}", g.module, g.group)
        } else {
            g.module.clone()
        };
        writeln!(
            s,
            "/// `@group({})` of `shared/{}`.\npub mod {name} {{\n/// Its `@group`.\npub const GROUP: u32 = {};",
            g.group, g.module, g.group
        )
        .unwrap();
        writeln!(s, "/// Every binding of the group, typed by what may be bound there.\npub struct Resources<'a> {{").unwrap();
        for (b, _, rust) in &g.bindings {
            let name = b
                .shared
                .as_ref()
                .map_or(b.name.as_str(), |r| r.name.as_str());
            let ty = match &b.kind {
                BindingKind::Uniform { rust: r, .. } | BindingKind::Storage { rust: r, .. } => {
                    resource_field_type(&b.kind, b.count.is_some() || b.unsized_array)
                        .replace(r.as_str(), rust)
                }
                _ => resource_field_type(&b.kind, b.count.is_some() || b.unsized_array),
            };
            writeln!(
                s,
                "/// `@binding({})`: `{}`\npub {name}: {ty},",
                b.binding, b.ty
            )
            .unwrap();
        }
        writeln!(s, "}}").unwrap();
        let slots: Vec<String> = g
            .bindings
            .iter()
            .map(|(b, stages, _)| {
                let stages: Vec<&str> = stages.iter().map(String::as_str).collect();
                slot_literal(b, &stages)
            })
            .collect();
        writeln!(s, "/// The group's slots, visible to every stage that uses them in any pipeline.\npub const SLOTS: &[crate::bind::Slot] = &[{}];", slots.join(", ")).unwrap();
        let items: Vec<String> = g
            .bindings
            .iter()
            .map(|(b, ..)| {
                let name = b
                    .shared
                    .as_ref()
                    .map_or(b.name.as_str(), |r| r.name.as_str());
                format!("crate::bind::IntoResource::resource(&r.{name})")
            })
            .collect();
        writeln!(s, "/// Marker type for the group.\npub struct Entry;\nimpl crate::bind::SharedGroup for Entry {{\nconst MODULE: &'static str = \"{}\";\nconst GROUP: u32 = GROUP;\nconst SLOTS: &'static [crate::bind::Slot] = SLOTS;\ntype Resources<'a> = Resources<'a>;\nfn resources<'a>(r: &Self::Resources<'a>) -> Vec<crate::bind::Resource<'a>> {{ vec![{}] }}\n}}", g.module, items.join(", ")).unwrap();
        writeln!(s, "/// The group's bind group: `Group::new(&device, &Resources {{ .. }})`, once.\npub type Group = crate::bind::Group<Entry>;\n}}").unwrap();
    }
    writeln!(s, "}}").unwrap();
}

/// The `Slot` literal of a binding used by `stages`.
pub(super) fn slot_literal(b: &crate::reflect::Binding, stages: &[&str]) -> String {
    format!(
        "crate::bind::Slot {{ group: {}, binding: {}, name: \"{}\", wgsl: \"{}\", visibility: {}, ty: {}, count: {}, unsized_array: {} }}",
        b.group,
        b.binding,
        b.shared
            .as_ref()
            .map_or(b.name.as_str(), |r| r.name.as_str()),
        b.ty,
        stage_bits(stages),
        wgpu_binding_type(&b.kind, b.dynamic_offset),
        b.count.map_or("None".to_string(), |n| format!(
            "core::num::NonZeroU32::new({n})"
        )),
        b.unsized_array
    )
}

/// The module name of shared group (module, group) under `groups`.
pub(super) fn group_module(shared: &[SharedGroupInfo], module: &str, group: u32) -> String {
    if shared.iter().filter(|o| o.module == module).count() > 1 {
        format!("{module}_{group}")
    } else {
        module.to_string()
    }
}
