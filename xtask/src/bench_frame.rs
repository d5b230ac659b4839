//! `cargo xtask bench frame`: what a frame of every viewer scene costs the application, at
//! 1920×1080 (640×360 with `--quick`): the viewer's `--frame-cost` mode (see
//! `examples/viewer/frame.rs`), at least 60 frames a scene, written to `frame.csv` in `--out`.
//!
//! The viewer is an example, so this runs its binary: `viewer` beside this executable where it
//! is there (as on the GPU machine, where both are carried in `.gpu/bin/`), else
//! `target/release/examples/viewer`, built first.

use std::path::PathBuf;
use std::process::{Command, ExitCode};

use crate::crate_root;
use crate::measure::Args;

pub fn run(args: &Args) -> ExitCode {
    match frame(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("bench frame: {e}");
            ExitCode::FAILURE
        }
    }
}

fn frame(args: &Args) -> Result<(), String> {
    let viewer = viewer()?;
    let size = if args.quick { "640x360" } else { "1920x1080" };
    let frames = args.reps.max(60);
    let status = Command::new(&viewer)
        .args(["--frame-cost", &frames.to_string(), "--size", size, "--out"])
        .arg(&args.out)
        .status()
        .map_err(|e| format!("{}: {e}", viewer.display()))?;
    if !status.success() {
        return Err(format!("{} --frame-cost: {status}", viewer.display()));
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
