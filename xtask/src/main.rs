//! `cargo xtask <command>`: a thin command layer over fieldkit and its toolchain.

#[path = "../../src/toolchain/mod.rs"]
mod toolchain;

mod lint;

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "cargo xtask", about = "fieldkit developer commands")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Validate every stage with naga, translate it to SPIR-V, MSL, HLSL and GLSL, and run the style lints.
    Lint,
    /// Print each stage's bindings, structs, workgroup sizes and overrides.
    Reflect {
        /// Only stages whose `room::name` contains this.
        stage: Option<String>,
        /// JSON instead of tables.
        #[arg(long)]
        json: bool,
    },
    /// Render every technique to PNG on the default adapter (FIELDKIT_ADAPTER picks another).
    Gallery {
        #[arg(long, default_value = "gallery")]
        out: PathBuf,
    },
}

fn crate_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Lint => lint::run(&crate_root()),
        Command::Reflect { stage, json } => reflect(&crate_root(), stage.as_deref(), json),
        Command::Gallery { out } => gallery(&out),
    }
}

/// Build every stage or print every error.
fn stages(root: &Path) -> Option<Vec<toolchain::Stage>> {
    match toolchain::build_all(root) {
        Ok(s) => Some(s),
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            eprintln!("{} stage(s) failed to validate", errors.len());
            None
        }
    }
}

fn reflect(root: &Path, filter: Option<&str>, json: bool) -> ExitCode {
    let Some(stages) = stages(root) else { return ExitCode::FAILURE };
    let text = reflect_text(&stages, filter, json);
    if text.is_empty() {
        eprintln!("no stage matches {:?}", filter.unwrap_or(""));
        return ExitCode::FAILURE;
    }
    print!("{text}");
    ExitCode::SUCCESS
}

fn reflect_text(stages: &[toolchain::Stage], filter: Option<&str>, json: bool) -> String {
    let reflections: Vec<_> = stages
        .iter()
        .filter(|s| filter.is_none_or(|f| s.file.id().contains(f)))
        .map(toolchain::reflect::reflect)
        .collect();
    if reflections.is_empty() {
        return String::new();
    }
    if json {
        serde_json::to_string_pretty(&reflections).unwrap() + "\n"
    } else {
        reflections.iter().map(|r| r.to_table()).collect::<Vec<_>>().join("\n")
    }
}

fn gallery(out: &Path) -> ExitCode {
    let ctx = match fieldkit::gpu::Context::new() {
        Ok(c) => c,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
    };
    eprintln!("adapter: {}", ctx.adapter_name());
    match fieldkit::gallery::run(&ctx, out, |step| eprintln!("  {step}")) {
        Ok(files) => {
            for f in files {
                println!("{}", f.display());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_tables_snapshot() {
        let stages = stages(&crate_root()).expect("stages validate");
        insta::assert_snapshot!("reflect_distance", reflect_text(&stages, Some("distance::"), false));
    }

    #[test]
    fn reflect_json_names_every_binding() {
        let stages = stages(&crate_root()).expect("stages validate");
        let v: serde_json::Value = serde_json::from_str(&reflect_text(&stages, Some("jfa_step"), true)).unwrap();
        let names: Vec<&str> = v[0]["bindings"].as_array().unwrap().iter().map(|b| b["name"].as_str().unwrap()).collect();
        assert_eq!(names, ["params", "src", "dst"]);
    }

    #[test]
    fn generated_code_snapshot() {
        let stages = stages(&crate_root()).expect("stages validate");
        let step = stages.iter().find(|s| s.file.name == "jfa_step").unwrap();
        // SOURCE is the linked WGSL; it is checked by naga, not worth a snapshot line.
        let code = toolchain::codegen::format(&toolchain::codegen::stage_module(step));
        let code: String = code.lines().filter(|l| !l.contains("pub const SOURCE")).collect::<Vec<_>>().join("\n");
        insta::assert_snapshot!("codegen_jfa_step", code);
    }
}
