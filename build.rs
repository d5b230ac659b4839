//! Links every shader's WESL imports, validates it with naga, and generates the typed host
//! bindings included as `fieldkit::shaders`, through `fieldkit-build` (the same toolchain a
//! user's build script runs). A broken shader fails the build with every error, each named by
//! its original file, line and column.

fn main() {
    // Without the techniques there are no stages of fieldkit's own to build: the crate is the
    // runtime of generated bindings alone.
    if std::env::var_os("CARGO_FEATURE_TECHNIQUES").is_none() {
        return;
    }
    fieldkit_build::Builder::new("shaders")
        .runtime("crate")
        // fieldkit's own stages keep every lint (or say why a file does not).
        .deny_lints()
        // The volume march over the procedural cloud as a function (seed 002).
        .density_march("volume::cloud_march", "shared::fbm_cloud")
        .build_or_exit();
}
