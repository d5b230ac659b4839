//! `cargo xtask bench build`: what a build script pays to run fieldkit-build on a folder of
//! 45 stages (fieldkit's own 34 and the user crate's 11, copied into one folder): link every
//! stage's imports, validate, reflect, lint, generate and write the bindings, as
//! `Builder::build_to` does from a build script. Measured 2026-11-24 on this 2-core machine:
//! median 115 ms (112 to 140 over 20 runs). fieldkit-build keeps no cache between runs,
//! so a run after one shader is touched costs what a first run costs; each timed run touches
//! one stage first. Median, fastest and slowest of `--reps` runs (release build, as cargo
//! builds build scripts here: `[profile.dev.build-override] opt-level = 3`).

use std::path::Path;
use std::time::Instant;

pub fn run(args: &crate::measure::Args) -> Result<(), String> {
    bench(args.reps.max(20), args.warmup)
}

/// Copy every file under `from` into `to`, keeping the tree.
fn copy_tree(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for entry in std::fs::read_dir(from)? {
        let entry = entry?;
        let path = entry.path();
        let dst = to.join(entry.file_name());
        if path.is_dir() {
            copy_tree(&path, &dst)?;
        } else {
            std::fs::copy(&path, &dst)?;
        }
    }
    Ok(())
}

fn bench(reps: usize, warmup: usize) -> Result<(), String> {
    let root = crate::crate_root();
    let scratch = std::env::temp_dir().join(format!("fieldkit-bench-build-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&scratch);
    let shaders = scratch.join("shaders");
    // Rooms and shared helpers of both folders do not collide by name.
    copy_tree(&root.join("shaders"), &shaders).map_err(|e| e.to_string())?;
    copy_tree(&root.join("tests/user-crate/shaders"), &shaders).map_err(|e| e.to_string())?;
    let stages = fieldkit_build::discover(&fieldkit_build::ShaderDir::new(&scratch, "shaders"))
        .map_err(|e| e.to_string())?;
    let touched = stages
        .iter()
        .find(|s| s.rel_path.ends_with("jfa_step.wgsl"))
        .ok_or("no jfa_step stage")?
        .abs_path
        .clone();
    let out = scratch.join("shaders.rs");
    let builder = fieldkit_build::Builder::new("shaders").dynamic_offset("math::scale::params");
    let mut times = Vec::new();
    for i in 0..warmup + reps {
        // Touch one stage: a comment line more each run.
        let mut text = std::fs::read_to_string(&touched).map_err(|e| e.to_string())?;
        text.push_str(&format!("// touched {i}\n"));
        std::fs::write(&touched, text).map_err(|e| e.to_string())?;
        let start = Instant::now();
        builder.build_to(&scratch, &out).map_err(|e| e.join("\n"))?;
        if i >= warmup {
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    times.sort_by(|a, b| a.total_cmp(b));
    let median = times[times.len() / 2];
    println!(
        "fieldkit-build on {} stages, one touched per run: median {median:.1} ms, fastest {:.1}, slowest {:.1} ({} runs)",
        stages.len(),
        times[0],
        times[times.len() - 1],
        times.len()
    );
    std::fs::remove_dir_all(&scratch).ok();
    Ok(())
}
