//! `cargo xtask lint`: naga validation, translation to every wgpu backend language, style lints.

use std::path::Path;
use std::process::ExitCode;

use crate::toolchain::{Stage, lint, reflect::reflect};

/// Translate a stage to each backend language; `Err` names the language and why.
pub fn translate_all(stage: &Stage) -> Vec<(&'static str, Result<usize, String>)> {
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
    let hlsl_result = (|| {
        let mut s = String::new();
        let opts = hlsl::Options::default();
        let popts = hlsl::PipelineOptions::default();
        hlsl::Writer::new(&mut s, &opts, &popts)
            .write(module, info, None)
            .map_err(|e| e.to_string())?;
        Ok(s.len())
    })();
    out.push(("HLSL", hlsl_result));
    // GLSL is written one entry point at a time.
    let glsl_result = (|| {
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
    })();
    out.push(("GLSL", glsl_result));
    out
}

pub fn run(root: &Path) -> ExitCode {
    let Some(stages) = crate::stages(root) else {
        return ExitCode::FAILURE;
    };
    let mut failures = 0;
    for stage in &stages {
        let r = reflect(stage);
        let mut langs = Vec::new();
        for (lang, result) in translate_all(stage) {
            match result {
                Ok(_) => langs.push(lang),
                Err(e) => {
                    failures += 1;
                    println!(
                        "{}:1:1: [portability] cannot translate to {lang}: {e}",
                        stage.file.rel_path
                    );
                }
            }
        }
        let violations = lint::run(stage, &r);
        for v in &violations {
            println!("{v}");
        }
        failures += violations.len();
        eprintln!(
            "  {:<28} valid; {}; {} lint finding(s)",
            stage.file.id(),
            langs.join(", "),
            violations.len()
        );
    }
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
