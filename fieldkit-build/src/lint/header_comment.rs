use super::Violation;
use crate::{Stage, reflect::Reflection};

/// Its name in findings, `--only` and allow comments.
pub(super) const NAME: &str = "header-comment";

/// A stage file opens with a comment saying what it does (and the source it follows).
pub(super) fn check(stage: &Stage, _: &Reflection) -> Vec<Violation> {
    let first = stage.original.lines().next().unwrap_or("");
    if first.trim_start().starts_with("//") && first.trim().len() > 3 {
        return vec![];
    }
    vec![Violation {
        lint: NAME,
        file: stage.file.rel_path.clone(),
        line: 1,
        column: 1,
        message: "no header comment: start the file with `// <what this stage does> (<source>)`"
            .into(),
    }]
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    #[test]
    fn flags_missing_header_and_accepts_present_one() {
        let bad = stage("@compute @workgroup_size(1) fn main() {}");
        assert_eq!(check(&bad, &reflect(&bad)).len(), 1);
        let good = stage("// Does nothing, for tests.\n@compute @workgroup_size(1) fn main() {}");
        assert!(check(&good, &reflect(&good)).is_empty());
    }
}
