//! The `fieldkit-build` command on a user's folder: every file reported (a file that does not
//! parse does not hide the others' findings), and the exit codes it documents.
#![cfg(feature = "cli")]

use std::process::Command;

fn folder(files: &[(&str, &str)]) -> std::path::PathBuf {
    let n = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    let root = std::env::temp_dir().join(format!("fieldkit-cli-{}-{n}", std::process::id()));
    for (path, text) in files {
        let p = root.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    root
}

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_fieldkit-build"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const GOOD: &str = "// Doubles.\n@group(0) @binding(0) var<storage, read_write> v: array<u32>;\n@compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    v[id.x] *= 2u;\n}\n";

#[test]
fn every_file_is_reported_and_the_exit_codes_hold() {
    let root = folder(&[
        (
            "broken.wgsl",
            "// Broken.\n@compute @workgroup_size(1)\nfn main() { let x = ; }\n",
        ),
        (
            "room/plain.wgsl",
            "@compute @workgroup_size(1)\nfn main() {}\n",
        ),
        ("room/good.wgsl", GOOD),
    ]);
    let dir = root.to_string_lossy().into_owned();
    let (code, out, err) = run(&["lint", &dir]);
    assert_eq!(code, 1, "{out}\n{err}");
    assert!(err.contains("broken.wgsl:3:"), "{err}");
    assert!(out.contains("plain.wgsl:1:1: [header-comment]"), "{out}");
    assert!(
        err.contains("1 stage(s) failed to build, 1 finding(s) in the 2 that built"),
        "{err}"
    );
    let (code, out, _) = run(&["reflect", &dir, "good", "--json"]);
    assert_eq!(code, 1, "the broken file still fails the run");
    assert!(out.contains("\"name\": \"v\""), "{out}");
    let (code, _, err) = run(&["check", &dir]);
    assert_eq!(code, 1);
    assert!(err.contains("broken.wgsl:3:"), "{err}");
    for bad in [
        vec!["frobnicate", &dir],
        vec!["lint", &dir, "--only", "no-such-lint"],
        vec!["reflect", &dir, "--yaml"],
        vec!["lint"],
    ] {
        assert_eq!(run(&bad).0, 2, "{bad:?}");
    }
    std::fs::remove_file(root.join("broken.wgsl")).unwrap();
    std::fs::remove_file(root.join("room/plain.wgsl")).unwrap();
    let (code, _, err) = run(&["check", &dir]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&["lint", &dir]);
    assert_eq!(code, 0, "{err}");
    std::fs::remove_dir_all(&root).ok();
}
