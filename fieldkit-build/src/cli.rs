//! The `fieldkit-build` command (feature `cli`): `check`, `lint` and `reflect` on any shader
//! folder, for a project that uses the published crates (fieldkit's own `cargo xtask lint` and
//! `reflect` run the same code).
//!
//! ```text
//! cargo install fieldkit-build --features cli        # or: cargo run -p fieldkit-build --features cli --
//! fieldkit-build check shaders                       # build as a build script would
//! fieldkit-build lint shaders [--only L] [--allow L] # validation, portability, style lints
//! fieldkit-build reflect shaders [STAGE] [--json]    # what each stage binds
//! ```
//!
//! Every file is reported: a file that fails to parse or validate is an error, and every other
//! file is still linted. Exit codes: 0 nothing found, 1 errors or findings, 2 a usage error
//! (an unknown command, option or lint, a folder that cannot be read).

use std::process::ExitCode;

use crate::lint::{self, LintConfig};
use crate::reflect::reflect;
use crate::{ShaderDir, Stage, build_stage, discover};

/// What a folder holds: the stages that built, and an error for each file that did not.
pub struct Built {
    pub stages: Vec<Stage>,
    pub errors: Vec<String>,
}

/// Build every stage of `shaders`, keeping the ones that build and the errors of the others.
pub fn build_each(shaders: &ShaderDir) -> std::io::Result<Built> {
    let mut out = Built {
        stages: Vec::new(),
        errors: Vec::new(),
    };
    for f in discover(shaders)? {
        match build_stage(shaders, &f) {
            Ok(s) => out.stages.push(s),
            Err(e) => out.errors.push(e),
        }
    }
    out.errors.extend(crate::pair_errors(&out.stages));
    Ok(out)
}

/// What `lint` found over a folder.
pub struct Report {
    /// Every finding as `file:line:col: [lint] message` (portability first, per stage).
    pub lines: Vec<String>,
    /// Per stage (`room::name`), the languages it translated to.
    pub translated: Vec<(String, Vec<&'static str>)>,
}

/// Translate every stage to every backend language (with the `portability` feature) and run
/// the lints `config` selects.
pub fn findings(stages: &[Stage], config: &LintConfig) -> Report {
    let mut report = Report {
        lines: Vec::new(),
        translated: Vec::new(),
    };
    for stage in stages {
        #[allow(unused_mut)]
        let mut langs = Vec::new();
        #[cfg(feature = "portability")]
        for (lang, result) in crate::portability::translate_all(stage) {
            match result {
                Ok(_) => langs.push(lang),
                Err(e) => report.lines.push(format!(
                    "{}:1:1: [portability] cannot translate to {lang}: {e}",
                    stage.file.rel_path
                )),
            }
        }
        report.translated.push((stage.file.id(), langs));
        let r = reflect(stage);
        report.lines.extend(
            lint::run_with(stage, &r, config)
                .iter()
                .map(|v| v.to_string()),
        );
    }
    report
}

/// `lint`: the errors of the files that do not build, then the findings of every file that
/// does; failure if there is any.
pub fn lint_folder(shaders: &ShaderDir, config: &LintConfig) -> ExitCode {
    if let Err(e) = config.check() {
        eprintln!("{e}");
        return ExitCode::from(2);
    }
    let built = match reported(shaders) {
        Ok(b) => b,
        Err(code) => return code,
    };
    let report = findings(&built.stages, config);
    for line in &report.lines {
        println!("{line}");
    }
    for (id, langs) in &report.translated {
        eprintln!("  {id:<28} valid; {}", langs.join(", "));
    }
    let problems = report.lines.len() + built.errors.len();
    if problems > 0 {
        eprintln!(
            "{} stage(s) failed to build, {} finding(s) in the {} that built",
            built.errors.len(),
            report.lines.len(),
            built.stages.len()
        );
        return ExitCode::FAILURE;
    }
    let portable = if cfg!(feature = "portability") {
        ", portable to SPIR-V, MSL, HLSL and GLSL"
    } else {
        ""
    };
    eprintln!(
        "{} stages: all valid{portable}, no lint findings",
        built.stages.len()
    );
    for l in lint::all() {
        eprintln!("  lint {:<20} {}", l.name, l.summary);
    }
    ExitCode::SUCCESS
}

/// The reflection of the stages whose `room::name` contains `filter`: tables, or JSON.
#[cfg(feature = "cli")]
pub fn reflect_text(stages: &[Stage], filter: Option<&str>, json: bool) -> String {
    let reflections: Vec<_> = stages
        .iter()
        .filter(|s| filter.is_none_or(|f| s.file.id().contains(f)))
        .map(reflect)
        .collect();
    if reflections.is_empty() {
        return String::new();
    }
    if json {
        serde_json::to_string_pretty(&reflections).unwrap_or_default() + "\n"
    } else {
        reflections
            .iter()
            .map(|r| r.to_table())
            .collect::<Vec<_>>()
            .join("\n")
    }
}

/// [`build_each`], each error printed; a folder that cannot be read is the usage exit code.
fn reported(shaders: &ShaderDir) -> Result<Built, ExitCode> {
    let built = build_each(shaders).map_err(|e| {
        eprintln!("error: cannot read {}: {e}", shaders.root().display());
        ExitCode::from(2)
    })?;
    for e in &built.errors {
        eprintln!("{e}");
    }
    Ok(built)
}

#[cfg(feature = "cli")]
const USAGE: &str = "usage: fieldkit-build <check|lint|reflect> DIR [options]
  check DIR                       build every stage (validation, bindings) as a build script would
  lint DIR [--only L]... [--allow L]...
                                  validation, portability and style lints, every file reported
  reflect DIR [STAGE] [--json]    what each stage (whose room::name contains STAGE) binds
exit codes: 0 nothing found, 1 errors or findings, 2 usage";

/// Run the command line `args` (without the program name).
#[cfg(feature = "cli")]
pub fn run(args: impl IntoIterator<Item = String>) -> ExitCode {
    let args: Vec<String> = args.into_iter().collect();
    let usage = |why: &str| {
        eprintln!("error: {why}\n{USAGE}");
        ExitCode::from(2)
    };
    let (Some(command), Some(dir)) = (args.first(), args.get(1)) else {
        if args.iter().any(|a| a == "--help" || a == "-h") {
            println!("{USAGE}");
            return ExitCode::SUCCESS;
        }
        return usage("a command and a folder are needed");
    };
    let shaders = ShaderDir::new(std::path::PathBuf::new(), dir);
    let rest = &args[2..];
    match command.as_str() {
        "check" => {
            if let Some(extra) = rest.first() {
                return usage(&format!("unexpected `{extra}`"));
            }
            let built = match reported(&shaders) {
                Ok(b) => b,
                Err(code) => return code,
            };
            let code = crate::codegen::generate_for(&built.stages, "::fieldkit");
            if built.errors.is_empty() {
                eprintln!(
                    "{} stages build ({} lines of bindings)",
                    built.stages.len(),
                    code.lines().count()
                );
                ExitCode::SUCCESS
            } else {
                eprintln!("{} stage(s) failed to build", built.errors.len());
                ExitCode::FAILURE
            }
        }
        "lint" => {
            let mut config = LintConfig::default();
            let mut it = rest.iter();
            while let Some(a) = it.next() {
                let list = match a.as_str() {
                    "--only" => &mut config.only,
                    "--allow" => &mut config.allow,
                    other => return usage(&format!("unknown option `{other}`")),
                };
                match it.next() {
                    Some(l) => list.push(l.clone()),
                    None => return usage(&format!("`{a}` needs a lint name")),
                }
            }
            lint_folder(&shaders, &config)
        }
        "reflect" => {
            let json = rest.iter().any(|a| a == "--json");
            let filter = rest.iter().find(|a| !a.starts_with("--"));
            if let Some(bad) = rest.iter().find(|a| a.starts_with("--") && *a != "--json") {
                return usage(&format!("unknown option `{bad}`"));
            }
            let built = match reported(&shaders) {
                Ok(b) => b,
                Err(code) => return code,
            };
            let text = reflect_text(&built.stages, filter.map(String::as_str), json);
            if text.is_empty() {
                eprintln!("no stage matches {:?}", filter.map_or("", |s| s.as_str()));
                return ExitCode::FAILURE;
            }
            print!("{text}");
            if built.errors.is_empty() {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        other => usage(&format!("unknown command `{other}`")),
    }
}
