//! `cargo xtask lint`: naga validation, translation to every wgpu backend language, style lints.

use std::process::ExitCode;

use crate::toolchain::lint::{self, LintConfig};
use crate::toolchain::{ShaderDir, Stage, reflect::reflect};

/// Translate a stage to each backend language; `Err` names the language and why. A writer
/// that panics (naga 30's HLSL and GLSL writers reach `unreachable!` on binding arrays of
/// buffers; HLSL wants a bind target for immediates) is a finding for that language, not the
/// end of the run.
pub fn translate_all(stage: &Stage) -> Vec<(&'static str, Result<usize, String>)> {
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let out = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| translate_each(stage)));
    std::panic::set_hook(hook);
    out.unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        vec![(
            "a backend",
            Err(format!("naga panicked translating it: {why}")),
        )]
    })
}

/// [`translate_all`]'s work, each language's writer guarded on its own.
fn translate_each(stage: &Stage) -> Vec<(&'static str, Result<usize, String>)> {
    use naga::back::{glsl, hlsl, msl, spv};
    let mut out = Vec::new();
    // Backends take a module with its overrides already resolved, as wgpu does at pipeline
    // creation; the shader's defaults stand in for the values a pipeline would give.
    let (module, info) = match naga::back::pipeline_constants::process_overrides(
        &stage.module,
        &stage.info,
        None,
        &Default::default(),
    ) {
        Ok(m) => m,
        Err(e) => return vec![("overrides", Err(e.to_string()))],
    };
    let (module, info) = (&*module, &*info);
    out.push((
        "SPIR-V",
        spv::write_vec(module, info, &spv::Options::default(), None)
            .map(|w| w.len() * 4)
            .map_err(|e| e.to_string()),
    ));
    out.push((
        "MSL",
        msl::write_string(
            module,
            info,
            // wgpu's Metal backend writes MSL 2.x (fragment-stage storage writes need ≥ 1.2).
            &msl::Options {
                lang_version: (2, 1),
                ..Default::default()
            },
            &msl::PipelineOptions::default(),
        )
        .map(|(s, _)| s.len())
        .map_err(|e| e.to_string()),
    ));
    let hlsl_result = guarded(|| {
        let mut s = String::new();
        let opts = hlsl::Options::default();
        let popts = hlsl::PipelineOptions::default();
        hlsl::Writer::new(&mut s, &opts, &popts)
            .write(module, info, None)
            .map_err(|e| e.to_string())?;
        Ok(s.len())
    });
    out.push(("HLSL", hlsl_result));
    // GLSL is written one entry point at a time.
    let glsl_result = guarded(|| {
        let mut total = 0;
        for ep in &module.entry_points {
            let mut s = String::new();
            let opts = glsl::Options {
                version: glsl::Version::Desktop(430),
                ..Default::default()
            };
            let popts = glsl::PipelineOptions {
                shader_stage: ep.stage,
                entry_point: ep.name.clone(),
                multiview: None,
            };
            let mut w = glsl::Writer::new(
                &mut s,
                module,
                info,
                &opts,
                &popts,
                naga::proc::BoundsCheckPolicies::default(),
            )
            .map_err(|e| format!("{}: {e}", ep.name))?;
            w.write().map_err(|e| format!("{}: {e}", ep.name))?;
            total += s.len();
        }
        Ok(total)
    });
    out.push(("GLSL", glsl_result));
    out
}

/// Run one writer; a panic in it is an `Err` saying so.
fn guarded(f: impl FnOnce() -> Result<usize, String>) -> Result<usize, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(format!("naga's writer panicked: {why}"))
    })
}

/// What `lint` found over a folder.
pub struct Report {
    /// Every finding as `file:line:col: [lint] message` (portability first, per stage).
    pub lines: Vec<String>,
    /// Per stage (`room::name`), the languages it translated to.
    pub translated: Vec<(String, Vec<&'static str>)>,
}

/// Translate every stage to every backend language and run the lints `config` selects.
pub fn findings(stages: &[Stage], config: &LintConfig) -> Report {
    let mut report = Report {
        lines: Vec::new(),
        translated: Vec::new(),
    };
    for stage in stages {
        let mut langs = Vec::new();
        for (lang, result) in translate_all(stage) {
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

pub fn run(shaders: &ShaderDir, config: &LintConfig) -> ExitCode {
    if let Err(e) = config.check() {
        eprintln!("{e}");
        return ExitCode::FAILURE;
    }
    let Some(stages) = crate::stages_in(shaders) else {
        return ExitCode::FAILURE;
    };
    let report = findings(&stages, config);
    for line in &report.lines {
        println!("{line}");
    }
    for (id, langs) in &report.translated {
        eprintln!("  {id:<28} valid; {}", langs.join(", "));
    }
    let failures = report.lines.len();
    if failures > 0 {
        eprintln!("{failures} problem(s)");
        ExitCode::FAILURE
    } else {
        eprintln!(
            "{} stages: all valid, portable to SPIR-V, MSL, HLSL and GLSL, no lint findings",
            stages.len()
        );
        for l in lint::all() {
            eprintln!("  lint {:<20} {}", l.name(), l.summary());
        }
        ExitCode::SUCCESS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_stage_translates_to_every_backend() {
        let stages = crate::stages(&crate::crate_root()).expect("stages validate");
        for s in &stages {
            for (lang, r) in translate_all(s) {
                assert!(r.is_ok(), "{} -> {lang}: {:?}", s.file.id(), r);
            }
        }
    }

    /// A user's folder (any name, anywhere): its stages build, each finding names the file as
    /// given, line and column, a file's allow comment (with a reason) turns a lint off for that
    /// file alone, and `--only` / `--allow` select lints.
    #[test]
    fn any_folder_lints_with_file_line_col_and_allows() {
        let base = std::env::temp_dir().join(format!("fieldkit-lint-{}", std::process::id()));
        let room = base.join("user/shaders/room");
        std::fs::create_dir_all(&room).unwrap();
        std::fs::create_dir_all(base.join("user/shaders/shared")).unwrap();
        std::fs::write(
            base.join("user/shaders/shared/math.wesl"),
            "// Helpers.\n\nfn twice(x: u32) -> u32 {\n    return x * 2u;\n}\n",
        )
        .unwrap();
        let body = "@group(0) @binding(0) var<storage, read_write> data: array<u32>;\n\
                    @group(0) @binding(1) var<uniform> unused: vec4<f32>;\n\n\
                    @compute @workgroup_size(64)\n\
                    fn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    \
                    data[id.x] = twice(data[id.x]);\n}\n";
        let import = "import package::shared::math::twice;\n\n";
        // No header comment, an unused binding.
        std::fs::write(room.join("plain.wgsl"), format!("{import}{body}")).unwrap();
        // The same, allowing both for itself, with a reason.
        std::fs::write(
            room.join("allowed.wgsl"),
            format!(
                "{import}// lint: allow(header-comment, unused-binding): generated by a tool\n{body}"
            ),
        )
        .unwrap();
        // An allow without a reason, and one naming no lint.
        std::fs::write(
            room.join("careless.wgsl"),
            format!("// Doubles.\n// lint: allow(unused-binding)\n// lint: allow(no-such-lint): why\n{import}{body}"),
        )
        .unwrap();
        let dir = ShaderDir::new(&base, "user/shaders/");
        let stages = crate::stages_in(&dir).expect("the user's stages build");
        assert_eq!(stages.len(), 3);
        let all = findings(&stages, &LintConfig::default()).lines;
        let of = |file: &str| -> Vec<&String> {
            all.iter()
                .filter(|l| l.starts_with(&format!("user/shaders/room/{file}.wgsl:")))
                .collect()
        };
        let plain = of("plain");
        assert_eq!(plain.len(), 2, "{all:#?}");
        assert!(plain[0].starts_with("user/shaders/room/plain.wgsl:1:1: [header-comment]"));
        assert!(
            plain[1].starts_with("user/shaders/room/plain.wgsl:4:34: [unused-binding]"),
            "{}",
            plain[1]
        );
        assert!(of("allowed").is_empty(), "{all:#?}");
        let careless = of("careless");
        assert_eq!(careless.len(), 3, "{all:#?}");
        assert!(
            careless[0].starts_with("user/shaders/room/careless.wgsl:2:1: [lint-allow] say why")
        );
        assert!(careless[1].contains(":3:1: [lint-allow] `no-such-lint` is not a lint"));
        assert!(careless[2].contains("[unused-binding]"));
        let only = LintConfig {
            only: vec!["header-comment".into()],
            allow: vec![],
        };
        let lines = findings(&stages, &only).lines;
        assert!(
            lines.iter().all(|l| !l.contains("[unused-binding]")),
            "{lines:#?}"
        );
        assert!(
            lines
                .iter()
                .any(|l| l.contains("plain.wgsl:1:1: [header-comment]"))
        );
        let allow = LintConfig {
            only: vec![],
            allow: vec!["unused-binding".into(), "header-comment".into()],
        };
        let lines = findings(&stages, &allow).lines;
        assert_eq!(
            lines.len(),
            2,
            "only the careless allows are left: {lines:#?}"
        );
        assert!(
            LintConfig {
                only: vec!["nope".into()],
                allow: vec![]
            }
            .check()
            .unwrap_err()
            .contains("`nope` is not a lint")
        );
        std::fs::remove_dir_all(&base).unwrap();
    }

    #[test]
    fn shipped_stages_have_no_lint_findings() {
        let stages = crate::stages(&crate::crate_root()).expect("stages validate");
        let v: Vec<String> = stages
            .iter()
            .flat_map(|s| lint::run(s, &reflect(s)))
            .map(|v| v.to_string())
            .collect();
        assert!(v.is_empty(), "{v:#?}");
    }
}
