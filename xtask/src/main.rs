//! `cargo xtask <command>`: a thin command layer over fieldkit and its toolchain.

use fieldkit_build as toolchain;

mod bench_bind;
mod bench_build;
mod bench_distance;
mod bench_frame;
mod bench_grazing;
mod bench_mesh_sdf;
mod bench_metaball;
mod bench_ocean;
mod bench_octree;
mod bench_volume;
mod bench_voxelize;
mod chart;
mod floor;
mod gpu_tests;
mod heater;
mod lint;
mod measure;
mod shader_stats;

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
    /// Validate every stage with naga, translate it to SPIR-V, MSL, HLSL and GLSL, and run the
    /// style lints. Exits non-zero on any finding, each printed as `file:line:col: [lint] ...`.
    /// A file turns a lint off for itself with a line `// lint: allow(name): why`.
    Lint {
        /// A shader folder laid out as fieldkit's `shaders/` (a folder per technique, helpers in
        /// `shared/`), instead of fieldkit's own.
        #[arg(long)]
        shaders: Option<PathBuf>,
        /// Run only this lint (repeatable).
        #[arg(long)]
        only: Vec<String>,
        /// Do not run this lint (repeatable).
        #[arg(long)]
        allow: Vec<String>,
    },
    /// Print each stage's bindings, structs, workgroup sizes and overrides.
    Reflect {
        /// Only stages whose `room::name` contains this.
        stage: Option<String>,
        /// JSON instead of tables.
        #[arg(long)]
        json: bool,
        /// A shader folder laid out as fieldkit's `shaders/`, instead of fieldkit's own.
        #[arg(long)]
        shaders: Option<PathBuf>,
    },
    /// What the Vulkan driver made of each compute entry point (registers, spills, ...), through
    /// VK_KHR_pipeline_executable_properties.
    ShaderStats {
        /// Only stages whose `room::name` contains this.
        stage: Option<String>,
        /// Values for `override` constants, NAME=value (repeatable).
        #[arg(long = "override")]
        overrides: Vec<String>,
        /// The runtime checks naga writes into the SPIR-V: `wgpu` (as wgpu's Vulkan backend
        /// writes them: clamped indices, bounded loops), `no-loop-bounding`, or `none`.
        #[arg(long, default_value = "wgpu")]
        checks: String,
        /// The shader files of the checkout it runs in (or the one it was built from) instead
        /// of the linked WGSL built into this binary, which its benches run: so two builds sent
        /// to the GPU machine each report their own shaders.
        #[arg(long)]
        checkout: bool,
    },
    /// Render every technique to PNG on the default adapter (FIELDKIT_ADAPTER picks another).
    Gallery {
        #[arg(long, default_value = "gallery")]
        out: PathBuf,
    },
    /// Run each animated technique for many frames (release viewer, offscreen), sampling
    /// resident memory and GPU allocations after every frame; fails on any error or growth
    /// after warm-up.
    Soak {
        /// Frames per technique.
        #[arg(long, default_value_t = 10_000)]
        frames: u32,
        /// Offscreen size, WxH.
        #[arg(long, default_value = "320x240")]
        size: String,
        /// One scene only (actor, ocean, volume, voxelizer).
        #[arg(long)]
        scene: Option<String>,
        /// The voxelizer's mesh (OBJ path, `torus` or `sphere`).
        #[arg(long)]
        mesh: Option<String>,
    },
    /// Pack the release test binaries for the GPU machine (`.gpu/tests.tar.xz` and
    /// `.gpu/run-tests.sh`); there: `. .gpu/env.sh && sh .gpu/run-tests.sh H100 $OUT`.
    GpuTests,
    /// Time against accuracy for a technique, charted (release build; GPU timestamp queries).
    Bench {
        technique: Technique,
        #[command(flatten)]
        args: measure::Args,
    },
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Technique {
    /// The CPU cost of binding a stage's resources (not a technique; `--reps` runs of 1000).
    Bind,
    /// fieldkit-build's time on a 45-stage folder with one stage touched (a build script's cost).
    Build,
    Distance,
    Metaball,
    /// Metaballs at grazing angles: every way of drawing them graded per pixel against an f64
    /// reference (by incidence, on the silhouette's rim or off it) and timed.
    Grazing,
    Volume,
    Ocean,
    Voxelize,
    /// A mesh's signed distance field against an f64 reference, the voxel-centre path and
    /// the CPU crate mesh_to_sdf: time against error.
    MeshSdf,
    /// The sparse voxel octree against the dense grid: memory, build and render time.
    Octree,
    /// What a frame of every viewer scene costs the app: CPU record + submit, submit → done,
    /// GPU compute, the loop's floor, the first frame and a resize (the viewer's `--frame-cost`).
    Frame,
}

/// `--shapes`: a 3D grid's shape written `XxYxZ`, every side at least 1.
fn parse_shape(s: &str) -> Result<[usize; 3], String> {
    let sides: Vec<usize> = s
        .split('x')
        .map(|t| t.trim().parse::<usize>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("`{s}`: {e} (write a shape as XxYxZ, e.g. 128x128x1024)"))?;
    match sides[..] {
        [x, y, z] if x > 0 && y > 0 && z > 0 => Ok([x, y, z]),
        _ => Err(format!(
            "`{s}`: a shape is three sides of at least 1, written XxYxZ (e.g. 128x128x1024)"
        )),
    }
}

fn crate_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Lint {
            shaders,
            only,
            allow,
        } => lint::run(
            &shader_dir(shaders.as_deref()),
            &toolchain::lint::LintConfig { only, allow },
        ),
        Command::Reflect {
            stage,
            json,
            shaders,
        } => reflect(&shader_dir(shaders.as_deref()), stage.as_deref(), json),
        Command::ShaderStats {
            stage,
            overrides,
            checks,
            checkout,
        } => {
            // The checkout it runs in (a release binary sent to another machine), else the one
            // it was built from.
            let here = std::env::current_dir()
                .ok()
                .filter(|d| d.join("shaders").is_dir() && d.join("build.rs").is_file());
            let root = here.unwrap_or_else(crate_root);
            let source = if checkout {
                shader_stats::Source::Checkout(&root)
            } else {
                shader_stats::Source::Built
            };
            shader_stats::run(source, stage.as_deref(), &overrides, &checks)
        }
        Command::Gallery { out } => gallery(&out),
        Command::GpuTests => gpu_tests::run(&crate_root()),
        Command::Soak {
            frames,
            size,
            scene,
            mesh,
        } => soak(frames, &size, scene.as_deref(), mesh.as_deref()),
        Command::Bench { technique, args } => {
            if cfg!(debug_assertions) && std::env::var_os("FIELDKIT_BENCH_NO_REEXEC").is_none() {
                return rerun_release();
            }
            let (reps, density, band) = (args.reps, args.density, args.band);
            if reps == 0 || !(density > 0.0 && density < 1.0) || !(band.is_finite() && band > 0.0) {
                eprintln!(
                    "bench: --reps must be ≥ 1, --density in (0, 1), --band finite and positive"
                );
                return ExitCode::FAILURE;
            }
            let run = match technique {
                Technique::Bind => bench_bind::run,
                Technique::Build => bench_build::run,
                Technique::Distance => bench_distance::run,
                Technique::Metaball => bench_metaball::run,
                Technique::Grazing => bench_grazing::run,
                Technique::Volume => bench_volume::run,
                Technique::Ocean => bench_ocean::run,
                Technique::Voxelize => bench_voxelize::run,
                Technique::MeshSdf => bench_mesh_sdf::run,
                Technique::Octree => bench_octree::run,
                Technique::Frame => bench_frame::run,
            };
            match run(&args) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    let name = clap::ValueEnum::to_possible_value(&technique)
                        .map_or(String::new(), |v| v.get_name().to_string());
                    eprintln!("bench {name}: {e}");
                    ExitCode::FAILURE
                }
            }
        }
    }
}

/// Benchmarks time release code: a debug xtask runs itself again through `cargo run --release`.
fn rerun_release() -> ExitCode {
    eprintln!("bench: running again as a release build");
    let status =
        std::process::Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .args(["run", "--release", "--package", "xtask", "--"])
            .args(std::env::args_os().skip(1))
            .current_dir(crate_root())
            .status();
    match status {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("bench: could not run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Build every stage or print every error.
/// The folder `--shaders` names (as given, relative to the working directory), else fieldkit's
/// own `shaders/`.
fn shader_dir(shaders: Option<&Path>) -> toolchain::ShaderDir {
    match shaders {
        Some(dir) => toolchain::ShaderDir::new(PathBuf::new(), &dir.to_string_lossy()),
        None => toolchain::ShaderDir::new(crate_root(), "shaders"),
    }
}

fn stages(root: &Path) -> Option<Vec<toolchain::Stage>> {
    stages_in(&toolchain::ShaderDir::new(root, "shaders"))
}

fn stages_in(shaders: &toolchain::ShaderDir) -> Option<Vec<toolchain::Stage>> {
    match toolchain::build_dir(shaders) {
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

fn reflect(shaders: &toolchain::ShaderDir, filter: Option<&str>, json: bool) -> ExitCode {
    let Some(stages) = stages_in(shaders) else {
        return ExitCode::FAILURE;
    };
    let text = reflect_text(&stages, filter, json);
    if text.is_empty() {
        eprintln!("no stage matches {:?}", filter.unwrap_or(""));
        return ExitCode::FAILURE;
    }
    print!("{text}");
    ExitCode::SUCCESS
}

fn reflect_text(stages: &[toolchain::Stage], filter: Option<&str>, json: bool) -> String {
    toolchain::cli::reflect_text(stages, filter, json)
}

/// The soak lives in the viewer example (`examples/viewer/soak.rs`), which has the scenes; this
/// runs it in release mode.
fn soak(frames: u32, size: &str, scene: Option<&str>, mesh: Option<&str>) -> ExitCode {
    let mut cmd =
        std::process::Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    cmd.current_dir(crate_root())
        .args(["run", "--release", "--example", "viewer", "--", "--soak"])
        .arg(frames.to_string())
        .args(["--size", size]);
    if let Some(s) = scene {
        cmd.args(["--scene", s]);
    }
    if let Some(m) = mesh {
        cmd.args(["--mesh", m]);
    }
    match cmd.status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: cannot run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The gallery is an example (`examples/gallery/`); this runs it in release mode.
fn gallery(out: &Path) -> ExitCode {
    let status =
        std::process::Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .current_dir(crate_root())
            .args(["run", "--release", "--example", "gallery", "--"])
            .arg(out)
            .status();
    match status {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(_) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: cannot run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--shapes`: three sides of at least 1 written XxYxZ; anything else is an error that
    /// shows how to write one.
    #[test]
    fn shapes_parse_or_say_how_to_write_one() {
        assert_eq!(parse_shape("128x128x1024"), Ok([128, 128, 1024]));
        assert_eq!(parse_shape("1x1x1"), Ok([1, 1, 1]));
        for bad in [
            "128x128",
            "128x128x1024x2",
            "0x1x1",
            "ax1x1",
            "128×128×1024",
            "",
        ] {
            let e = parse_shape(bad).unwrap_err();
            assert!(e.contains("XxYxZ"), "{bad}: {e}");
        }
    }

    /// naga 30's HLSL and GLSL writers panic on binding arrays of buffers: `lint` reports
    /// that as a portability finding for the language and goes on.
    #[test]
    fn a_panicking_backend_writer_is_a_finding() {
        let root = crate_root();
        let stages = toolchain::build_dir(&toolchain::ShaderDir::new(
            &root,
            "tests/user-crate/shaders",
        ))
        .expect("the user crate's stages validate");
        let report = lint::findings(&stages, &Default::default());
        assert!(
            report.lines.iter().any(|l| l.contains("corpus/arrays.wgsl")
                && l.contains("cannot translate to HLSL")
                && l.contains("panicked")),
            "{:#?}",
            report.lines
        );
        let translated = report
            .translated
            .iter()
            .find(|(s, _)| s == "corpus::arrays")
            .map(|(_, l)| l.clone());
        assert_eq!(translated, Some(vec!["SPIR-V", "MSL"]));
    }

    #[test]
    fn reflect_tables_snapshot() {
        let stages = stages(&crate_root()).expect("stages validate");
        insta::assert_snapshot!(
            "reflect_distance",
            reflect_text(&stages, Some("distance::"), false)
        );
    }

    #[test]
    fn reflect_json_names_every_binding() {
        let stages = stages(&crate_root()).expect("stages validate");
        let v: serde_json::Value =
            serde_json::from_str(&reflect_text(&stages, Some("jfa_step"), true)).unwrap();
        let names: Vec<&str> = v[0]["bindings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b["name"].as_str().unwrap())
            .collect();
        assert_eq!(names, ["params", "src", "dst"]);
    }

    #[test]
    fn generated_code_snapshot() {
        let stages = stages(&crate_root()).expect("stages validate");
        let step = stages.iter().find(|s| s.file.name == "jfa_step").unwrap();
        // SOURCE is the linked WGSL; it is checked by naga, not worth a snapshot line.
        let code = toolchain::codegen::format(&toolchain::codegen::stage_module(step));
        let code: String = code
            .lines()
            .filter(|l| !l.contains("pub const SOURCE"))
            .collect::<Vec<_>>()
            .join("\n");
        insta::assert_snapshot!("codegen_jfa_step", code);
    }
}
