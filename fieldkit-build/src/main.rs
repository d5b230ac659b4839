//! `fieldkit-build check|lint|reflect DIR`: the toolchain on any shader folder (see
//! `fieldkit_build::cli`).

fn main() -> std::process::ExitCode {
    fieldkit_build::cli::run(std::env::args().skip(1))
}
