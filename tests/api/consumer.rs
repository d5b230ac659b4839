//! A crate outside the workspace that depends on fieldkit by path with default features, as a
//! user's would (the README's dependency block), holding every Rust example of the README and
//! the technique pages: it must build on this toolchain on editions 2021 and 2024 (edition 2021 uses
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

/// The pages a user reads first: the README and each technique's page (and the pages for
/// users' own shaders and a frame's cost).
const PAGES: &[&str] = &[
    "README.md",
    "docs/distance.md",
    "docs/metaball.md",
    "docs/mesh_sdf.md",
    "docs/voxelize.md",
    "docs/octree.md",
    "docs/volume.md",
    "docs/ocean.md",
    "docs/shaders.md",
    "docs/frame.md",
];

/// Every Rust block of `text` that rustdoc would compile (a fence with no language or `rust`,
/// not `ignore` or `compile_fail`), its hidden `# ` lines shown, as rustdoc compiles it.
fn rust_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut open: Option<Vec<&str>> = None;
    for line in text.lines() {
        let trimmed = line.trim_start();
        if let Some(info) = trimmed.strip_prefix("```") {
            match open.take() {
                Some(lines) => blocks.push(lines.join("\n")),
                None => {
                    let words: Vec<&str> = info.split(',').map(str::trim).collect();
                    let rust = words[0].is_empty() || words[0] == "rust";
                    let skipped = words.iter().any(|w| *w == "ignore" || *w == "compile_fail");
                    open = Some(Vec::new());
                    if !rust || skipped {
                        // Read to its end and drop it.
                        open = Some(vec!["\u{0}"]);
                    }
                }
            }
            continue;
        }
        if let Some(lines) = open.as_mut() {
            let shown = if trimmed == "#" {
                ""
            } else if let Some(rest) = trimmed.strip_prefix("# ") {
                rest
            } else {
                line
            };
            lines.push(shown);
        }
    }
    blocks.retain(|b| !b.starts_with('\u{0}'));
    blocks
}

/// The pages' Rust blocks as modules of a user's crate, each wrapped in a function where it
/// is statements rather than items (as rustdoc wraps it in `main`).
fn page_examples() -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out = String::new();
    for page in PAGES {
        let text = std::fs::read_to_string(root.join(page)).unwrap();
        for (i, block) in rust_blocks(&text).into_iter().enumerate() {
            let name = page.replace(['/', '.'], "_");
            let items = block.contains("fn ") || block.trim_start().starts_with("use ");
            let body = if items {
                block
            } else {
                format!(
                    "fn example() -> Result<(), Box<dyn std::error::Error>> {{\n{block}\nOk(())\n}}"
                )
            };
            out.push_str(&format!(
                "\n/// `{page}`, Rust block {i}.\n#[allow(dead_code, unused)]\nmod {name}_{i} {{\n{body}\n}}\n"
            ));
        }
    }
    out
}

fn consumer(root: &Path, edition: &str) -> PathBuf {
    let dir = root.join(format!("edition{edition}"));
    std::fs::create_dir_all(dir.join("src")).unwrap();
    let fieldkit = env!("CARGO_MANIFEST_DIR").replace('\\', "/");
    std::fs::write(
        dir.join("Cargo.toml"),
        format!(
            "[package]\nname = \"consumer{edition}\"\nversion = \"0.0.0\"\nedition = \"{edition}\"\n\
             publish = false\n\n[dependencies]\nfieldkit = {{ path = \"{fieldkit}\" }}\n\
             wgpu = \"30\"\n\n\
             # Its own workspace, not fieldkit's.\n[workspace]\n"
        ),
    )
    .unwrap();
    // The README's dependency block (fieldkit and wgpu, default features: no `context`), and
    // the pages' examples compiled in it: an example that needs a feature, a crate or a name
    // the README does not give a user fails here, whatever the workspace's own tests enable.
    std::fs::write(
        dir.join("src/main.rs"),
        format!("{MAIN}{}", page_examples()),
    )
    .unwrap();
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

/// Every text file under `dir`, recursively.
fn text_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            text_files(&path, out);
        } else if path
            .extension()
            .is_some_and(|e| ["md", "txt", "csv", "jsonl"].contains(&e.to_str().unwrap_or("")))
        {
            out.push(path);
        }
    }
}

/// The project's documentation speaks of the project, its API and its measured behaviour, not
/// of how or when the work was done: no page mentions a working session, and no page is dated
/// (a measurement names its adapter, command and commit instead).
#[test]
fn the_docs_are_no_diary() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<PathBuf> = ["README.md", "CHANGELOG.md", "CONTRIBUTING.md"]
        .iter()
        .map(|f| root.join(f))
        .collect();
    text_files(&root.join("docs"), &mut files);
    assert!(files.len() > 20, "found only {files:?}");
    let mut found = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let page = file.extension().is_some_and(|e| e == "md");
        for (n, line) in text.lines().enumerate() {
            let dated = line.as_bytes().windows(10).any(|w| {
                w[..4].iter().all(u8::is_ascii_digit)
                    && w[4] == b'-'
                    && w[5..7].iter().all(u8::is_ascii_digit)
                    && w[7] == b'-'
                    && w[8..].iter().all(u8::is_ascii_digit)
            });
            if line.to_lowercase().contains("session") || (page && dated) {
                found.push(format!("{}:{}: {}", file.display(), n + 1, line.trim()));
            }
        }
    }
    assert!(
        found.is_empty(),
        "documentation that reads as a diary:\n{}",
        found.join("\n")
    );
}
