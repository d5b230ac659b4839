//! Links every shader's WESL imports, validates it with naga, and generates the typed host
//! bindings included as `fieldkit::shaders`, through `fieldkit-build` (the same toolchain a
//! user's build script runs). A broken shader fails the build with every error, each named by
//! its original file, line and column.

fn main() {
    fieldkit_build::Builder::new("shaders")
        .runtime("crate")
        .build_or_exit();
}
