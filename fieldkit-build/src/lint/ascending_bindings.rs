use super::{Violation, locate_binding};
use crate::{Stage, reflect::Reflection};

/// Its name in findings, `--only` and allow comments.
pub(super) const NAME: &str = "ascending-bindings";

/// Bindings are declared in ascending `(group, binding)` order (two variables may share a slot
/// where different entry points use them: declared one after the other).
pub(super) fn check(stage: &Stage, r: &Reflection) -> Vec<Violation> {
    // Only the file's own: a group imported from `shared/` is declared where the user cannot
    // reorder it.
    let mut decl_order: Vec<_> = r
        .bindings
        .iter()
        .filter(|b| b.shared.is_none())
        .cloned()
        .collect();
    decl_order.sort_by_key(|b| b.linked_offset);
    let mut out = Vec::new();
    for pair in decl_order.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        if (b.group, b.binding) < (a.group, a.binding) {
            let (line, column) = locate_binding(&stage.original, &b.name);
            out.push(Violation {
                lint: NAME,
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
        let v = check(&bad, &reflect(&bad));
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].line, 2);
        let good = stage(&format!(
            "@group(0) @binding(0) var<uniform> a: u32;\n@group(0) @binding(1) var<uniform> b: u32;\n{BODY}"
        ));
        assert!(check(&good, &reflect(&good)).is_empty());
    }
}
