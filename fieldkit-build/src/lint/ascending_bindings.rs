use super::{Lint, Violation, locate_binding};
use crate::{Stage, reflect::Reflection};

/// Bindings are declared in ascending `(group, binding)` order.
pub struct AscendingBindings;

impl Lint for AscendingBindings {
    fn name(&self) -> &'static str {
        "ascending-bindings"
    }
    fn summary(&self) -> &'static str {
        "declare bindings in ascending (group, binding) order"
    }
    fn explanation(&self) -> &'static str {
        "Reading the declarations top to bottom then gives the bind-group layout in order, which is how host code and the reflection tables list them."
    }
    fn check(&self, stage: &Stage, r: &Reflection) -> Vec<Violation> {
        let mut decl_order = r.bindings.clone();
        decl_order.sort_by_key(|b| b.linked_offset);
        let mut out = Vec::new();
        for pair in decl_order.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            if (b.group, b.binding) <= (a.group, a.binding) {
                let (line, column) = locate_binding(&stage.original, &b.name);
                out.push(Violation {
                    lint: self.name(),
                    file: stage.file.rel_path.clone(),
                    line,
                    column,
                    message: format!(
                        "`{}` (@group({}) @binding({})) is declared after `{}` (@group({}) @binding({}))",
                        b.name, b.group, b.binding, a.name, a.group, a.binding
                    ),
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    const BODY: &str = "@compute @workgroup_size(1) fn main() { _ = a; _ = b; }";

    #[test]
    fn flags_descending_and_accepts_ascending() {
        let bad = stage(&format!(
            "@group(0) @binding(1) var<uniform> a: u32;\n@group(0) @binding(0) var<uniform> b: u32;\n{BODY}"
        ));
        let v = AscendingBindings.check(&bad, &reflect(&bad));
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].line, 2);
        let good = stage(&format!(
            "@group(0) @binding(0) var<uniform> a: u32;\n@group(0) @binding(1) var<uniform> b: u32;\n{BODY}"
        ));
        assert!(AscendingBindings.check(&good, &reflect(&good)).is_empty());
    }
}
