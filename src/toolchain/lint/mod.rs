//! Style and portability lints, each a pass over naga IR (plus the reflection built from it),
//! one file per lint, in the manner of vello's shader lints.

mod ascending_bindings;
mod header_comment;
mod unused_binding;
mod workgroup_limits;

use super::Stage;
use super::reflect::Reflection;

/// One finding, located in the original shader file.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    pub lint: &'static str,
    pub file: String,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}:{}: [{}] {}",
            self.file, self.line, self.column, self.lint, self.message
        )
    }
}

pub trait Lint {
    fn name(&self) -> &'static str;
    /// One line: what the lint wants.
    fn summary(&self) -> &'static str;
    /// Why it matters.
    fn explanation(&self) -> &'static str;
    fn check(&self, stage: &Stage, reflection: &Reflection) -> Vec<Violation>;
}

pub fn all() -> Vec<Box<dyn Lint>> {
    vec![
        Box::new(header_comment::HeaderComment),
        Box::new(ascending_bindings::AscendingBindings),
        Box::new(unused_binding::UnusedBinding),
        Box::new(workgroup_limits::WorkgroupLimits),
    ]
}

/// Run every lint on a stage.
pub fn run(stage: &Stage, reflection: &Reflection) -> Vec<Violation> {
    all()
        .iter()
        .flat_map(|l| l.check(stage, reflection))
        .collect()
}

/// 1-based line and column of the first match of `pat` in the stage file (1:1 if absent).
pub(crate) fn locate(original: &str, pat: &str) -> (usize, usize) {
    match original.find(pat) {
        Some(off) => {
            let before = &original[..off];
            let line = before.matches('\n').count() + 1;
            let col = off - before.rfind('\n').map(|i| i + 1).unwrap_or(0) + 1;
            (line, col)
        }
        None => (1, 1),
    }
}

/// Where `var ... name` is declared in the stage file.
pub(crate) fn locate_binding(original: &str, name: &str) -> (usize, usize) {
    for pat in [
        format!("> {name}:"),
        format!("var {name}:"),
        format!(">{name}:"),
        format!("var {name} :"),
    ] {
        if original.contains(&pat) {
            return locate(original, &pat);
        }
    }
    locate(original, name)
}

#[cfg(test)]
pub(crate) mod test_util {
    use super::super::{Stage, StageFile};

    /// Build a stage from WGSL text (no imports), as the build does.
    pub fn stage(src: &str) -> Stage {
        let module = naga::front::wgsl::parse_str(src).expect("test shader parses");
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::default(),
        )
        .validate(&module)
        .expect("test shader validates");
        Stage {
            file: StageFile {
                room: "test".into(),
                name: "t".into(),
                rel_path: "shaders/test/t.wgsl".into(),
                abs_path: "t.wgsl".into(),
            },
            source: src.into(),
            module,
            info,
            original: src.into(),
        }
    }
}
