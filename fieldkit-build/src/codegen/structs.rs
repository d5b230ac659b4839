//! The WGSL structs a stage binds, as Rust types with compile-time proofs of their layout: a
//! stage's own in its module, those declared in a module of `shared/` once, in the generated
//! `shared` module, re-exported by every stage that binds them.

use std::fmt::Write;

use super::super::reflect::{Reflection, reflect};
use crate::Stage;

/// The stage's host-shareable structs: its own defined here, one declared in a module of
/// `shared/` re-exported from the one definition in the file's `shared` module.
pub(super) fn gen_structs(stage: &Stage, r: &Reflection, s: &mut String) {
    let depth = stage.file.room.split('/').filter(|p| !p.is_empty()).count() + 1;
    for st in r.structs.iter().filter(|s| s.host_shareable) {
        match stage.shared.iter().find(|d| d.linked == st.linked) {
            Some(d) => writeln!(
                s,
                "/// WGSL `struct {0}` of `shared/{1}`, declared once for every stage.\npub use {2}shared::{1}::{0};",
                st.name,
                d.module,
                "super::".repeat(depth)
            )
            .unwrap(),
            None => gen_struct(st, s),
        }
    }
}

/// Structs declared in modules of `shared/` that some stage binds: per module, each once (as
/// the first stage that binds it reflects it).
pub(super) fn shared_structs(stages: &[Stage]) -> Vec<(String, super::super::reflect::StructInfo)> {
    let mut out: Vec<(String, super::super::reflect::StructInfo)> = Vec::new();
    for stage in stages {
        let r = reflect(stage);
        for st in r.structs.into_iter().filter(|s| s.host_shareable) {
            if let Some(d) = stage.shared.iter().find(|d| d.linked == st.linked)
                && !out.iter().any(|(m, x)| *m == d.module && x.name == st.name)
            {
                out.push((d.module.clone(), st));
            }
        }
    }
    out.sort_by(|a, b| (&a.0, &a.1.name).cmp(&(&b.0, &b.1.name)));
    out
}

/// The `shared` module: each struct of `shared/` defined once, by module.
pub(super) fn gen_shared_structs(
    structs: &[(String, super::super::reflect::StructInfo)],
    s: &mut String,
) {
    if structs.is_empty() {
        return;
    }
    writeln!(s, "/// Structs declared once in a module of `shared/`: every stage that binds one re-exports\n/// this definition.\n#[allow(non_snake_case, non_camel_case_types)]\npub mod shared {{").unwrap();
    let mut modules: Vec<&str> = structs.iter().map(|(m, _)| m.as_str()).collect();
    modules.dedup();
    for m in modules {
        writeln!(
            s,
            "/// Structs of `shared/{m}`.\npub mod {m} {{\n#[allow(unused_imports)]\nuse super::*;"
        )
        .unwrap();
        for (_, st) in structs.iter().filter(|(x, _)| x == m) {
            gen_struct(st, s);
        }
        writeln!(s, "}}").unwrap();
    }
    writeln!(s, "}}").unwrap();
}

/// One struct, with compile-time proofs of its layout.
fn gen_struct(st: &super::super::reflect::StructInfo, s: &mut String) {
    {
        let runtime = st
            .members
            .last()
            .is_some_and(|m| m.rust.starts_with("Vec<"));
        let derives = if runtime {
            "Debug, Clone, PartialEq, encase::ShaderType"
        } else {
            "Debug, Clone, Copy, PartialEq, Default, encase::ShaderType"
        };
        writeln!(
            s,
            "/// WGSL `struct {}`: {} bytes, align {}.",
            st.name, st.size, st.align
        )
        .unwrap();
        writeln!(s, "#[derive({derives})]\npub struct {} {{", st.name).unwrap();
        for m in &st.members {
            writeln!(s, "/// offset {}, `{}`", m.offset, m.ty).unwrap();
            if m.rust.starts_with("Vec<") {
                writeln!(s, "#[shader(size(runtime))]").unwrap();
            }
            writeln!(s, "pub {}: {},", m.name, m.rust).unwrap();
        }
        writeln!(s, "}}").unwrap();
        // Prove the host layout equals naga's: a change on either side fails the build.
        writeln!(s, "const _: () = {{").unwrap();
        if !runtime {
            writeln!(
                s,
                "assert!(<{0} as encase::ShaderType>::METADATA.min_size().get() == {1}, \"{0}: size does not match WGSL ({1} bytes)\");",
                st.name, st.size
            )
            .unwrap();
        }
        for (i, m) in st.members.iter().enumerate() {
            writeln!(
                s,
                "assert!(<{0} as encase::ShaderType>::METADATA.offset({i}) == {1}, \"{0}.{2}: offset does not match WGSL ({1})\");",
                st.name, m.offset, m.name
            )
            .unwrap();
        }
        writeln!(s, "}};").unwrap();
    }
}
