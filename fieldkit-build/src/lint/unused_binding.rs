use super::{Lint, Violation, locate_binding};
use crate::{Stage, reflect::Reflection};

/// Every declared binding is used by some entry point.
pub struct UnusedBinding;

impl Lint for UnusedBinding {
    fn name(&self) -> &'static str {
        "unused-binding"
    }
    fn summary(&self) -> &'static str {
        "every binding is used by at least one entry point"
    }
    fn explanation(&self) -> &'static str {
        "An unused binding still appears to callers as something to provide; generated layouts leave it out, so it only misleads."
    }
    fn check(&self, stage: &Stage, r: &Reflection) -> Vec<Violation> {
        r.bindings
            .iter()
            .filter(|b| {
                !r.entry_points.iter().any(|e| {
                    e.uses
                        .iter()
                        .any(|u| u.group == b.group && u.binding == b.binding)
                })
            })
            .map(|b| {
                let (line, column) = locate_binding(&stage.original, &b.name);
                Violation {
                    lint: self.name(),
                    file: stage.file.rel_path.clone(),
                    line,
                    column,
                    message: format!(
                        "binding `{}` (@group({}) @binding({})) is used by no entry point",
                        b.name, b.group, b.binding
                    ),
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    #[test]
    fn flags_unused_only() {
        let s = stage(
            "@group(0) @binding(0) var<uniform> a: u32;\n@group(0) @binding(1) var<uniform> b: u32;\n@compute @workgroup_size(1) fn main() { _ = a; }",
        );
        let v = UnusedBinding.check(&s, &reflect(&s));
        assert_eq!(v.len(), 1);
        assert!(v[0].message.contains("`b`"));
        assert_eq!(v[0].line, 2);
    }
}
