use super::{Violation, locate_binding};
use crate::{Stage, reflect::Reflection};

/// Its name in findings, `--only` and allow comments.
pub(super) const NAME: &str = "unused-binding";

/// Every declared binding is used by some entry point.
pub(super) fn check(stage: &Stage, r: &Reflection) -> Vec<Violation> {
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
                lint: NAME,
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
#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    #[test]
    fn flags_unused_only() {
        let s = stage(
            "@group(0) @binding(0) var<uniform> a: u32;\n@group(0) @binding(1) var<uniform> b: u32;\n@compute @workgroup_size(1) fn main() { _ = a; }",
        );
        let v = check(&s, &reflect(&s));
        assert_eq!(v.len(), 1);
        assert!(v[0].message.contains("`b`"));
        assert_eq!(v[0].line, 2);
    }
}
