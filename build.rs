//! Links every shader's WESL imports, validates it with naga, and generates the typed host
//! bindings included as `fieldkit::shaders`. A broken shader fails the build with every error,
//! each named by its original file, line and column.

#[path = "src/toolchain/mod.rs"]
mod toolchain;

use std::path::PathBuf;

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    // A directory here makes cargo rerun when any file under it changes.
    println!("cargo:rerun-if-changed=shaders");
    println!("cargo:rerun-if-changed=src/toolchain");
    let stages = match toolchain::build_all(&root) {
        Ok(s) => s,
        Err(errors) => {
            for e in &errors {
                for line in e.lines() {
                    println!("cargo:warning={line}");
                }
                eprintln!("{e}");
            }
            eprintln!("{} shader(s) failed to validate", errors.len());
            std::process::exit(1);
        }
    };
    let code = toolchain::codegen::generate(&stages);
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap()).join("shaders.rs");
    // Only touch the file when it changes, so dependents are not rebuilt for nothing.
    if std::fs::read_to_string(&out).ok().as_deref() != Some(code.as_str()) {
        std::fs::write(&out, code).expect("write generated bindings");
    }
}
