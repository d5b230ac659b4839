//! `cargo xtask gpu-tests`: the whole test suite on a hardware adapter that has no Rust
//! toolchain (the GPU machine). Here: build every test binary in release, strip them, pack them
//! with xz into `.gpu/tests.tar.xz` with a runner script. There, in the checkout:
//!
//! ```sh
//! . .gpu/env.sh && sh .gpu/run-tests.sh H100 $OUT [SECONDS]
//! ```
//!
//! Each binary may run SECONDS (120 by default): one that runs past it is stopped and the
//! tests it never finished are named, so one hang does not cost the rest of the suite (two
//! first runs on freshly started H100 machines ran out of whole 240 s commands with no word of
//! which binary held them; with the limit, the next such run passed every binary in 70 s).
//! Each binary's log is copied to `$OUT/logs` as it ends.
//!
//! The binaries find `tests/` (snapshots, reference images) through `CARGO_MANIFEST_DIR`, the
//! path they were built in; the runner links that path to the checkout when it differs. Each
//! binary runs with `CI=true INSTA_UPDATE=no FIELDKIT_ADAPTER=<adapter>`, so a snapshot that
//! differs fails instead of being rewritten, and with `INSTA_WORKSPACE_ROOT` set to the
//! checkout (there is no cargo there to find it, and the user crate's snapshots are named
//! from the workspace root). Tests that need what that machine lacks are left
//! out by name: cargo (the consumer tests and the user crate's drift test build crates) and Xvfb
//! (the window tests). The user crate's tests (`tests/user-crate`) run too.

use std::path::Path;
use std::process::{Command, ExitCode};

/// Test binaries (by target name) that cannot run without a toolchain (the user crate's drift
/// test builds crates).
const NEEDS_CARGO: [&str; 1] = ["drift"];
/// Tests (binary, name filter) left out there: the consumer tests build crates with cargo, the
/// window tests need a display.
const SKIPPED: [(&str, &str); 3] = [
    ("api", "consumer::"),
    ("window", "window_screenshot_matches_the_offscreen_frame"),
    (
        "viewer",
        "every_scene_in_a_window_matches_the_offscreen_render",
    ),
];

pub fn run(root: &Path) -> ExitCode {
    match prepare(root) {
        Ok(n) => {
            println!(
                "packed {n} test binaries into .gpu/tests.tar.xz; on the GPU machine:\n  \
                 . .gpu/env.sh && sh .gpu/run-tests.sh H100 $OUT [SECONDS per binary]"
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("gpu-tests: {e}");
            ExitCode::FAILURE
        }
    }
}

fn prepare(root: &Path) -> Result<usize, String> {
    let gpu = root.join(".gpu");
    if !gpu.join("env.sh").exists() {
        return Err("no .gpu/env.sh: run ../shared/device/prepare.sh once first".into());
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = crate::measure::stdout_of(
        Command::new(&cargo).current_dir(root).args([
            "test",
            "--release",
            "-p",
            "fieldkit",
            // The user crate's own stages (binding arrays run where the adapter has them).
            "-p",
            "fieldkit-user-crate",
            "--tests",
            "--no-run",
            "--message-format=json",
        ]),
        "cargo test --no-run",
    )?;
    let staging = gpu.join("tests");
    std::fs::remove_dir_all(&staging).ok();
    std::fs::create_dir_all(&staging).map_err(|e| e.to_string())?;
    let mut names = Vec::new();
    for line in out.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        let (Some(exe), Some(name), Some(kinds)) = (
            v["executable"].as_str(),
            v["target"]["name"].as_str(),
            v["target"]["kind"].as_array(),
        ) else {
            continue;
        };
        // Integration tests only: the library's unit tests have no GPU work.
        if !kinds.iter().any(|k| k == "test") || NEEDS_CARGO.contains(&name) {
            continue;
        }
        let dst = staging.join(name);
        std::fs::copy(exe, &dst).map_err(|e| format!("{exe}: {e}"))?;
        let _ = Command::new("strip").arg(&dst).status();
        names.push(name.to_string());
    }
    names.sort();
    // The viewer's process-level tests (soak, settings files) run its release binary, found
    // beside the test binaries as `examples/viewer`.
    let built = Command::new(&cargo)
        .current_dir(root)
        .args(["build", "--release", "--example", "viewer"])
        .status()
        .map_err(|e| format!("cargo build --example viewer: {e}"))?;
    if !built.success() {
        return Err("cargo build --release --example viewer failed".into());
    }
    std::fs::create_dir_all(staging.join("example-binaries")).map_err(|e| e.to_string())?;
    let viewer = staging.join("example-binaries").join("viewer");
    std::fs::copy(root.join("target/release/examples/viewer"), &viewer)
        .map_err(|e| format!("the viewer example: {e}"))?;
    let _ = Command::new("strip").arg(&viewer).status();
    // The octree test voxelizes the npm bunny (`target/bunny/index.js`, which
    // `scripts/fetch-bunny.sh` fetches); the GPU machine has no network, so it travels along.
    let bunny = root.join("target/bunny/index.js");
    if !bunny.exists() {
        let _ = Command::new("bash")
            .arg(root.join("scripts/fetch-bunny.sh"))
            .status();
    }
    let mut data = Vec::new();
    if bunny.exists() {
        std::fs::create_dir_all(staging.join("data")).map_err(|e| e.to_string())?;
        std::fs::copy(&bunny, staging.join("data/bunny-index.js"))
            .map_err(|e| format!("{}: {e}", bunny.display()))?;
        data.push("data/bunny-index.js");
    } else {
        eprintln!(
            "gpu-tests: no target/bunny/index.js (npm unreachable?): the octree test will fail there"
        );
    }
    let mut skips: Vec<(&str, String)> = Vec::new();
    for (bin, test) in SKIPPED {
        match skips.iter_mut().find(|(b, _)| *b == bin) {
            Some((_, list)) => list.push_str(&format!(" --skip {test}")),
            None => skips.push((bin, format!("--skip {test}"))),
        }
    }
    let skip: String = skips
        .iter()
        .map(|(bin, list)| format!("    {bin}) skip=\"{list}\" ;;\n"))
        .collect();
    let script = format!(
        r#"#!/bin/sh
# Written by `cargo xtask gpu-tests`. Usage: sh .gpu/run-tests.sh ADAPTER OUT_DIR [SECONDS]
# Each binary may run SECONDS (120 if absent); one that runs past it is stopped, and the tests
# it listed but never finished are named. Each binary's log goes to OUT_DIR/logs as it ends.
adapter="$1"; out="${{2:-.}}"; limit="${{3:-120}}"; logs=/tmp/fieldkit-test-logs; mkdir -p "$logs" "$out/logs"
built="{built}"
if [ "$(pwd)" != "$built" ] && [ ! -e "$built" ]; then mkdir -p "$(dirname "$built")"; ln -s "$(pwd)" "$built"; fi
mkdir -p .gpu/bin/tests .gpu/bin/examples && tar -xJf .gpu/tests.tar.xz -C .gpu/bin/tests
cp .gpu/bin/tests/example-binaries/* .gpu/bin/examples/
if [ -f .gpu/bin/tests/data/bunny-index.js ] && [ ! -f "$built/target/bunny/index.js" ]; then
  mkdir -p "$built/target/bunny" && cp .gpu/bin/tests/data/bunny-index.js "$built/target/bunny/index.js"
fi
pass=0; fail=0
for name in {names}; do
  skip=""
  case "$name" in
{skip}  esac
  bin="$(pwd)/.gpu/bin/tests/$name"
  (cd "$built" && CI=true INSTA_UPDATE=no INSTA_WORKSPACE_ROOT="$built" FIELDKIT_ADAPTER="$adapter" timeout "$limit" "$bin" $skip) > "$logs/$name.log" 2>&1
  rc=$?
  cp "$logs/$name.log" "$out/logs/"
  if [ $rc = 0 ]; then
    pass=$((pass+1)); echo "ok   $name: $(grep -h '^test result' "$logs/$name.log" | tail -1)"
  elif [ $rc = 124 ]; then
    fail=$((fail+1)); echo "TIME $name: stopped after ${{limit}} s; unfinished:"
    "$bin" --list 2>/dev/null | sed -n 's/: test$//p' | while read -r t; do
      grep -Eq "^test $t \.\.\. (ok|FAILED|ignored)" "$logs/$name.log" || echo "       $t"
    done
  else
    fail=$((fail+1)); echo "FAIL $name: $(grep -h '^test result' "$logs/$name.log" | tail -1)"
    grep -h -A12 -- '---- .* stdout ----' "$logs/$name.log" | head -60
  fi
done
echo "binaries passed: $pass, failed: $fail"
tar -cJf "$out/test-logs.tar.xz" -C "$logs" .
"#,
        built = root.display(),
        names = names.join(" "),
    );
    std::fs::write(gpu.join("run-tests.sh"), script).map_err(|e| e.to_string())?;
    let status = Command::new("tar")
        .current_dir(&staging)
        .arg("-cJf")
        .arg(gpu.join("tests.tar.xz"))
        .args(&names)
        .arg("example-binaries/viewer")
        .args(&data)
        .status()
        .map_err(|e| format!("tar: {e}"))?;
    if !status.success() {
        return Err("tar -cJf failed".into());
    }
    std::fs::remove_dir_all(&staging).ok();
    Ok(names.len())
}
