//! A crate outside the workspace that depends on fieldkit by path with default features, as a
//! user's would: it must build on this toolchain on editions 2021 and 2024 (edition 2021 uses
//! resolver 2, which picks the newest compatible versions: an unpinned wesl sibling once
//! resolved to a release needing a newer rustc), and fieldkit's runtime tree must stay within
//! the dependency budget the README states.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Crates `cargo tree -e normal` lists under fieldkit with default features (the README's
/// number; 114 before naga and wesl left the runtime tree).
const BUDGET: usize = 70;

const MAIN: &str = r#"
//! Uses the public API with a device the application owns (compiled, not run).
#[allow(dead_code)]
fn distance(
    device: &fieldkit::wgpu::Device,
    queue: &fieldkit::wgpu::Queue,
    mask: &[u8],
) -> Result<fieldkit::gpu::Readback<Vec<u32>>, fieldkit::Error> {
    let distance = fieldkit::distance::Distance2d::new(device)?;
    let seeds = fieldkit::distance::upload_mask(device, queue, mask, 2, 2)?;
    let mut encoder = device.create_command_encoder(&Default::default());
    let field = distance.encode(device, &mut encoder, &seeds, &Default::default())?;
    queue.submit([encoder.finish()]);
    Ok(field.read_nearest(device, queue))
}

fn main() {}
"#;

/// A crate that builds its own shaders and needs only the runtime of generated bindings.
const RUNTIME_MAIN: &str = r#"
//! Uses the runtime of generated bindings alone (compiled, not run).
#[allow(dead_code)]
fn needs(info: &fieldkit::bind::EntryInfo) -> fieldkit::wgpu::Features {
    info.required_features()
}

fn main() {}
"#;

fn cargo() -> Command {
    Command::new(env!("CARGO"))
}

fn consumer(root: &Path, edition: &str) -> PathBuf {
    let dir = root.join(format!("edition{edition}"));
    std::fs::create_dir_all(dir.join("src")).unwrap();
    let fieldkit = env!("CARGO_MANIFEST_DIR").replace('\\', "/");
    std::fs::write(
        dir.join("Cargo.toml"),
        format!(
            "[package]\nname = \"consumer{edition}\"\nversion = \"0.0.0\"\nedition = \"{edition}\"\n\
             publish = false\n\n[dependencies]\nfieldkit = {{ path = \"{fieldkit}\" }}\n\n\
             # Its own workspace, not fieldkit's.\n[workspace]\n"
        ),
    )
    .unwrap();
    std::fs::write(dir.join("src/main.rs"), MAIN).unwrap();
    // Resolve afresh, as a new user's crate does.
    std::fs::remove_file(dir.join("Cargo.lock")).ok();
    dir
}

fn run(mut command: Command, what: &str) -> String {
    let output = command.output().unwrap_or_else(|e| panic!("{what}: {e}"));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{what} failed:\n{stderr}");
    String::from_utf8_lossy(&output.stdout).into_owned()
}

#[test]
fn a_user_crate_builds_on_both_editions_within_the_dependency_budget() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("consumer");
    // One target directory for both editions: the second reuses the first's dependencies.
    let target = root.join("target");
    for edition in ["2021", "2024"] {
        let dir = consumer(&root, edition);
        let mut check = cargo();
        check
            .current_dir(&dir)
            .env("CARGO_TARGET_DIR", &target)
            .args(["check", "--quiet"]);
        run(
            check,
            &format!("cargo check of an edition-{edition} crate using fieldkit"),
        );

        let mut tree = cargo();
        tree.current_dir(&dir)
            .args(["tree", "-e", "normal", "--prefix", "none", "-p", "fieldkit"]);
        let listed = run(tree, "cargo tree");
        let mut crates: Vec<&str> = listed
            .lines()
            .map(|l| l.trim_end_matches(" (*)"))
            .filter(|l| !l.is_empty())
            .collect();
        crates.sort_unstable();
        crates.dedup();
        eprintln!(
            "edition {edition}: {} crates in fieldkit's runtime tree",
            crates.len()
        );
        // No shader compiler of fieldkit's own at run time (wgpu brings its naga), and the
        // optional helpers stay off by default.
        let mut direct = cargo();
        direct.current_dir(&dir).args([
            "tree", "-e", "normal", "--prefix", "none", "--depth", "1", "-p", "fieldkit",
        ]);
        let direct = run(direct, "cargo tree --depth 1");
        for banned in ["naga ", "wesl", "image ", "tobj ", "pollster "] {
            assert!(
                !direct.lines().any(|c| c.starts_with(banned)),
                "{banned:?} is a direct runtime dependency with default features:\n{direct}"
            );
        }
        assert!(
            crates.len() <= BUDGET,
            "{} crates (budget {BUDGET}): {crates:#?}",
            crates.len()
        );
    }
}

/// With default features off, fieldkit is the runtime of generated bindings alone (`bind`,
/// `error`, `gpu`): no technique is compiled and no stage of fieldkit's own is built.
#[test]
fn the_runtime_alone_builds_without_the_techniques() {
    // The editions' target directory: the dependencies they share are built once.
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("consumer");
    let dir = root.join("runtime");
    std::fs::create_dir_all(dir.join("src")).unwrap();
    let fieldkit = env!("CARGO_MANIFEST_DIR").replace('\\', "/");
    std::fs::write(
        dir.join("Cargo.toml"),
        format!(
            "[package]\nname = \"runtime\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n\
             [dependencies]\nfieldkit = {{ path = \"{fieldkit}\", default-features = false, features = [\"vulkan\"] }}\n\n\
             [workspace]\n"
        ),
    )
    .unwrap();
    std::fs::write(dir.join("src/main.rs"), RUNTIME_MAIN).unwrap();
    std::fs::remove_file(dir.join("Cargo.lock")).ok();
    let mut check = cargo();
    check
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", root.join("target"))
        .args(["check", "--quiet"]);
    run(
        check,
        "cargo check of a crate using fieldkit's runtime alone",
    );
    // The technique modules are gone: using one fails to compile.
    std::fs::write(
        dir.join("src/main.rs"),
        format!("{RUNTIME_MAIN}\n#[allow(dead_code)]\nfn technique() {{ let _ = fieldkit::distance::Distance2d::new; }}\n"),
    )
    .unwrap();
    let mut check = cargo();
    check
        .current_dir(&dir)
        .env("CARGO_TARGET_DIR", root.join("target"))
        .args(["check", "--quiet"]);
    let output = check.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !output.status.success() && stderr.contains("distance"),
        "fieldkit::distance compiled without the techniques feature:\n{stderr}"
    );
}
