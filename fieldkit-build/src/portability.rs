//! Portability (feature `portability`): each stage translated to every language wgpu's backends
//! take (SPIR-V, MSL, HLSL, GLSL), as `cargo xtask lint` and [`crate::Builder::check_portability`]
//! check it.

use crate::Stage;

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
    // creation; the shader's defaults stand in for the values a pipeline would give, and 1
    // (true) for an override without a default, which a pipeline must give.
    let stand_ins: naga::back::PipelineConstants = stage
        .module
        .overrides
        .iter()
        .filter(|(_, o)| o.init.is_none())
        .filter_map(|(_, o)| Some((o.id.map(|i| i.to_string()).or(o.name.clone())?, 1.0)))
        .collect();
    let (module, info) = match naga::back::pipeline_constants::process_overrides(
        &stage.module,
        &stage.info,
        None,
        &stand_ins,
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
    let hlsl_result = guarded("HLSL", || {
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
    let glsl_result = guarded("GLSL", || {
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

/// Run `lang`'s writer; a panic in it is an `Err` saying so and what it means.
fn guarded(lang: &str, f: impl FnOnce() -> Result<usize, String>) -> Result<usize, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(f)).unwrap_or_else(|p| {
        let why = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(format!(
            "naga's {lang} writer panicked ({why}): a limit of that writer rather than an error \
             in the shader; wgpu's backends that take {lang} would fail the same way, the \
             others are unaffected"
        ))
    })
}
