//! `cargo xtask bench frame`: what a frame of every viewer scene costs the application, at
//! 1920×1080 (640×360 with `--quick`): the viewer's `--frame-cost` mode (see
//! `examples/viewer/frame.rs`), at least 60 frames a scene, written to `frame.csv` in `--out`,
//! and each settings change the viewer's panels offer to `frame_settings.csv`.
//!
//! Twice: first with an empty pipeline cache, then with the one the first run saved, the
//! drivers' own shader caches turned off in both (`__GL_SHADER_DISK_CACHE=0`,
//! `MESA_SHADER_CACHE_DISABLE=true`), so that the two first frames compare a cold start with a
//! start from fieldkit's `PipelineCache` alone; `frame.csv` holds both runs (its
//! `pipeline_cache` column: cold, warm).
//!
//! The viewer is an example, so this runs its binary: `viewer` beside this executable where it
//! is there (as on the GPU machine, where both are carried in `.gpu/bin/`), else
//! `target/release/examples/viewer`, built first.

use std::path::PathBuf;
use std::process::Command;

use crate::crate_root;
use crate::measure::Args;

pub fn run(args: &Args) -> Result<(), String> {
    frame(args)
}

fn frame(args: &Args) -> Result<(), String> {
    let viewer = viewer()?;
    let size = if args.quick { "640x360" } else { "1920x1080" };
    let frames = args.reps.max(60);
    let cache = args.out.join("pipeline-cache");
    let _ = std::fs::remove_dir_all(&cache);
    // Both runs' tables, each under one header: the frame costs and the settings changes.
    let names = ["frame.csv", "frame_settings.csv"];
    let mut tables = [String::new(), String::new()];
    for start in ["cold", "warm"] {
        let out = args.out.join(start);
        let status = Command::new(&viewer)
            .args(["--frame-cost", &frames.to_string(), "--size", size, "--out"])
            .arg(&out)
            .arg("--pipeline-cache")
            .arg(&cache)
            .env("__GL_SHADER_DISK_CACHE", "0")
            .env("MESA_SHADER_CACHE_DISABLE", "true")
            .status()
            .map_err(|e| format!("{}: {e}", viewer.display()))?;
        if !status.success() {
            return Err(format!("{} --frame-cost: {status}", viewer.display()));
        }
        for (name, table) in names.iter().zip(&mut tables) {
            let csv = out.join(name);
            let text =
                std::fs::read_to_string(&csv).map_err(|e| format!("{}: {e}", csv.display()))?;
            let skip = usize::from(!table.is_empty());
            for line in text.lines().skip(skip) {
                table.push_str(line);
                table.push('\n');
            }
        }
    }
    for (name, table) in names.iter().zip(&tables) {
        let path = args.out.join(name);
        std::fs::write(&path, table).map_err(|e| format!("{}: {e}", path.display()))?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The viewer's binary: beside this one, or the release example, built where it is missing.
fn viewer() -> Result<PathBuf, String> {
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let beside = exe.with_file_name("viewer");
    if beside.is_file() {
        return Ok(beside);
    }
    let root = crate_root();
    let status = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args(["build", "--release", "--example", "viewer"])
        .current_dir(&root)
        .status()
        .map_err(|e| format!("cargo build --example viewer: {e}"))?;
    if !status.success() {
        return Err(format!("cargo build --release --example viewer: {status}"));
    }
    Ok(root.join("target/release/examples/viewer"))
}
