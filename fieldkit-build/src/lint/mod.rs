//! Style and portability lints, each a pass over naga IR (plus the reflection built from it),
//! one file per lint, in the manner of vello's shader lints.

mod ascending_bindings;
mod header_comment;
mod unused_binding;
mod webgpu_limits;
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

/// A lint: its name (in findings, `--only` and allow comments), what it wants in one line,
/// why it matters, and the pass over a stage that finds what breaks it.
pub struct Lint {
    pub name: &'static str,
    /// One line: what the lint wants.
    pub summary: &'static str,
    /// Why it matters.
    pub explanation: &'static str,
    check: fn(&Stage, &Reflection) -> Vec<Violation>,
}

impl Lint {
    /// What breaks the lint in `stage`.
    pub fn check(&self, stage: &Stage, reflection: &Reflection) -> Vec<Violation> {
        (self.check)(stage, reflection)
    }
}

/// Every lint, in the order they run. Each file holds a lint's pass and its name; what it
/// says about itself is here, in one table.
const LINTS: &[Lint] = &[
    Lint {
        name: header_comment::NAME,
        summary: "a stage file starts with a `//` comment saying what the stage does",
        explanation: "The first line is what a reader and the generated docs see; it names the technique and its source.",
        check: header_comment::check,
    },
    Lint {
        name: ascending_bindings::NAME,
        summary: "declare bindings in ascending (group, binding) order",
        explanation: "Reading the declarations top to bottom then gives the bind-group layout in order, which is how host code and the reflection tables list them.",
        check: ascending_bindings::check,
    },
    Lint {
        name: unused_binding::NAME,
        summary: "every binding is used by at least one entry point",
        explanation: "An unused binding still appears to callers as something to provide; generated layouts leave it out, so it only misleads.",
        check: unused_binding::check,
    },
    Lint {
        name: workgroup_limits::NAME,
        summary: "workgroup size within WebGPU default limits (256 x 256 x 64, 256 invocations)",
        explanation: "Larger workgroups fail pipeline creation on adapters that only offer the default limits (many mobile and web targets).",
        check: workgroup_limits::check,
    },
    Lint {
        name: webgpu_limits::NAME,
        summary: "bindings per stage, bind groups, workgroup memory, uniform size and storage-texture access within WebGPU defaults",
        explanation: "Past WebGPU's default limits a pipeline needs a device created with higher limits or a native feature; browsers and many mobile adapters refuse it. A file that needs more says so with `// lint: allow(webgpu-limits): why` and the host asks for the limit.",
        check: webgpu_limits::check,
    },
];

pub fn all() -> &'static [Lint] {
    LINTS
}

/// Run every lint on a stage (as [`run_with`] with the default configuration: every lint, less
/// those the file allows).
pub fn run(stage: &Stage, reflection: &Reflection) -> Vec<Violation> {
    run_with(stage, reflection, &LintConfig::default())
}

/// Which lints run over a folder: every lint, or only those in `only` where it is not empty,
/// less those in `allow`. A file turns lints off for itself with a comment line
/// `// lint: allow(name, ...): why`; the reason is required.
#[derive(Debug, Clone, Default)]
pub struct LintConfig {
    pub only: Vec<String>,
    pub allow: Vec<String>,
}

impl LintConfig {
    /// `Err` naming the first lint name that is not a lint, and the lints there are.
    pub fn check(&self) -> Result<(), String> {
        for name in self.only.iter().chain(&self.allow) {
            if !is_lint(name) {
                return Err(unknown(name));
            }
        }
        Ok(())
    }

    fn runs(&self, name: &str) -> bool {
        (self.only.is_empty() || self.only.iter().any(|n| n == name))
            && !self.allow.iter().any(|n| n == name)
    }
}

fn is_lint(name: &str) -> bool {
    all().iter().any(|l| l.name == name)
}

fn unknown(name: &str) -> String {
    let names: Vec<_> = all().iter().map(|l| l.name).collect();
    format!("`{name}` is not a lint (lints: {})", names.join(", "))
}

/// The marker of a file's own allow comment.
const ALLOW: &str = "// lint: allow(";

/// The lints a stage file allows for itself, and a finding (lint `lint-allow`) for each allow
/// comment that names no lint, an unknown one, or gives no reason.
fn file_allows(stage: &Stage) -> (Vec<String>, Vec<Violation>) {
    let mut names = Vec::new();
    let mut findings = Vec::new();
    for (i, line) in stage.original.lines().enumerate() {
        let Some(at) = line.find(ALLOW) else {
            continue;
        };
        let rest = &line[at + ALLOW.len()..];
        let mut finding = |message: String| {
            findings.push(Violation {
                lint: "lint-allow",
                file: stage.file.rel_path.clone(),
                line: i + 1,
                column: at + 1,
                message,
            })
        };
        let Some(close) = rest.find(')') else {
            finding("`// lint: allow(` without its `)`".into());
            continue;
        };
        let reason = rest[close + 1..].trim_start_matches(':').trim();
        if reason.is_empty() {
            finding("say why after the allow: `// lint: allow(name): why`".into());
            continue;
        }
        for name in rest[..close].split(',').map(str::trim) {
            if is_lint(name) {
                names.push(name.to_string());
            } else {
                finding(unknown(name));
            }
        }
    }
    (names, findings)
}

/// Run the lints `config` selects on a stage, less those the file allows for itself.
pub fn run_with(stage: &Stage, reflection: &Reflection, config: &LintConfig) -> Vec<Violation> {
    let (allowed, mut findings) = file_allows(stage);
    for l in all() {
        if config.runs(l.name) && !allowed.iter().any(|n| n == l.name) {
            findings.extend(l.check(stage, reflection));
        }
    }
    findings
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
        let (capabilities, features) = crate::needed_features(&module);
        let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .expect("test shader validates");
        Stage {
            file: StageFile {
                room: "test".into(),
                name: "t".into(),
                rel_path: "shaders/test/t.wgsl".into(),
                abs_path: "t.wgsl".into(),
                source: None,
            },
            source: src.into(),
            module,
            info,
            original: src.into(),
            features,
            dynamic_offsets: Vec::new(),
            shared: Vec::new(),
        }
    }
}
