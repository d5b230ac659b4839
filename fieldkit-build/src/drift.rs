//! Whether a stage's interface still matches what host code was generated for: the check hot
//! reload makes before it swaps a relinked shader into a pipeline whose layouts, parameter
//! struct and dispatch sizes were compiled from the old one.

use crate::reflect::{Binding, Reflection};

/// What changed between `old` (the interface the host was built for) and `new` (the relinked
/// shader) for the pipeline of `entries` (a compute entry point, or a vertex and a fragment
/// entry point), in words; empty where `new` fits the old layouts.
///
/// `new` may bind less than `old` and use a binding in fewer stages (the old layout still
/// holds it), and its bodies may change freely. Anything else is drift: a binding that is new,
/// or whose group, type, size, access, sample type or array length changed; a binding used
/// in a stage the old layout does not make it visible to; a different workgroup size, set of
/// overrides, immediate size, vertex inputs or fragment outputs; a feature the old shader did
/// not need; an entry point that is gone.
pub fn interface_drift(old: &Reflection, new: &Reflection, entries: &[&str]) -> Vec<String> {
    let mut out = Vec::new();
    let mut old_uses: Vec<(&Binding, &str)> = Vec::new();
    let mut new_uses: Vec<(&Binding, &str)> = Vec::new();
    for &name in entries {
        let (Some(o), Some(n)) = (
            old.entry_points.iter().find(|e| e.name == name),
            new.entry_points.iter().find(|e| e.name == name),
        ) else {
            out.push(format!("entry point `{name}` is gone"));
            continue;
        };
        if o.stage != n.stage {
            out.push(format!(
                "entry point `{name}` is a {} entry point, was {}",
                n.stage, o.stage
            ));
        }
        if o.workgroup_size != n.workgroup_size {
            out.push(format!(
                "`{name}`'s workgroup size is {:?}, was {:?}",
                n.workgroup_size, o.workgroup_size
            ));
        }
        let inputs = |e: &crate::reflect::EntryPoint| -> Vec<(u32, String)> {
            e.vertex_inputs
                .iter()
                .map(|v| (v.location, v.ty.clone()))
                .collect()
        };
        if inputs(o) != inputs(n) {
            out.push(format!("`{name}`'s vertex inputs changed"));
        }
        let outputs = |e: &crate::reflect::EntryPoint| -> Vec<(u32, String)> {
            e.fragment_outputs
                .iter()
                .map(|f| (f.location, f.ty.clone()))
                .collect()
        };
        if outputs(o) != outputs(n) {
            out.push(format!("`{name}`'s fragment outputs changed"));
        }
        if n.uses_immediate && !o.uses_immediate {
            out.push(format!("`{name}` reads immediates it did not"));
        }
        for (r, e, uses) in [(old, o, &mut old_uses), (new, n, &mut new_uses)] {
            for u in &e.uses {
                if let Some(b) = r
                    .bindings
                    .iter()
                    .find(|b| b.group == u.group && b.binding == u.binding)
                {
                    uses.push((b, e.stage.as_str()));
                }
            }
        }
    }
    for (b, stage) in &new_uses {
        let same_slot: Vec<&(&Binding, &str)> = old_uses
            .iter()
            .filter(|(o, _)| o.group == b.group && o.binding == b.binding)
            .collect();
        let Some((o, _)) = same_slot.first() else {
            out.push(format!(
                "binding `{}` (@group({}) @binding({})) is new",
                b.name, b.group, b.binding
            ));
            continue;
        };
        if o.name != b.name || o.kind != b.kind || o.count != b.count || o.ty != b.ty {
            out.push(format!(
                "binding @group({}) @binding({}) is `{}: {}`, was `{}: {}`",
                b.group, b.binding, b.name, b.ty, o.name, o.ty
            ));
        } else if !same_slot.iter().any(|(_, s)| s == stage) {
            out.push(format!(
                "binding `{}` is used in the {stage} stage, which its layout does not reach",
                b.name
            ));
        }
    }
    let names = |r: &Reflection| {
        let mut v: Vec<String> = r.overrides.iter().map(|o| o.name.clone()).collect();
        v.sort();
        v
    };
    if names(old) != names(new) {
        out.push(format!(
            "overrides are {:?}, were {:?}",
            names(new),
            names(old)
        ));
    }
    let size = |r: &Reflection| r.immediate.as_ref().map(|i| i.size);
    if size(old) != size(new) && new.entry_points.iter().any(|e| e.uses_immediate) {
        out.push(format!(
            "the immediate block is {:?} bytes, was {:?}",
            size(new),
            size(old)
        ));
    }
    for f in &new.features {
        if !old.features.contains(f) {
            out.push(format!("it needs the feature {f}, which it did not"));
        }
    }
    out.dedup();
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    const OLD: &str = "struct P { k: f32, }
@group(0) @binding(0) var<uniform> p: P;
@group(0) @binding(1) var<storage, read_write> v: array<f32>;
@group(0) @binding(2) var<storage, read> extra: array<f32>;
override SCALE: f32 = 1.0;
@compute @workgroup_size(64) fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    v[id.x] = v[id.x] * p.k * SCALE + extra[0];
}";

    fn drift(new: &str) -> Vec<String> {
        let (o, n) = (stage(OLD), stage(new));
        interface_drift(&reflect(&o), &reflect(&n), &["main"])
    }

    /// A new body, and a binding no longer used, fit the old layouts; a new binding, a changed
    /// type, workgroup size or set of overrides, or a lost entry point do not.
    #[test]
    fn bodies_change_freely_interfaces_do_not() {
        let body = OLD.replace("* p.k * SCALE + extra[0]", "+ p.k * SCALE + 2.0 * extra[0]");
        assert_eq!(drift(&body), Vec::<String>::new());
        let fewer = OLD.replace(" + extra[0]", "");
        assert_eq!(drift(&fewer), Vec::<String>::new());
        let added = OLD
            .replace(
                "override SCALE",
                "@group(0) @binding(3) var<storage, read> more: array<f32>;\noverride SCALE",
            )
            .replace("+ extra[0]", "+ extra[0] + more[0]");
        assert!(
            drift(&added)[0].contains("binding `more` (@group(0) @binding(3)) is new"),
            "{:?}",
            drift(&added)
        );
        let retyped = OLD.replace("struct P { k: f32, }", "struct P { k: f32, j: f32, }");
        assert!(
            drift(&retyped)[0].contains("@group(0) @binding(0) is `p: P`"),
            "{:?}",
            drift(&retyped)
        );
        let wider = OLD.replace("workgroup_size(64)", "workgroup_size(128)");
        assert!(
            drift(&wider)[0].contains("workgroup size is [128, 1, 1], was [64, 1, 1]"),
            "{:?}",
            drift(&wider)
        );
        let no_override = OLD.replace("override SCALE: f32 = 1.0;", "const SCALE: f32 = 1.0;");
        assert!(
            drift(&no_override)[0].contains("overrides are []"),
            "{:?}",
            drift(&no_override)
        );
        let renamed = OLD.replace("fn main(", "fn main2(");
        assert_eq!(
            drift(&renamed),
            vec!["entry point `main` is gone".to_string()]
        );
    }
}
