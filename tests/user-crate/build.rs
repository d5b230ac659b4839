fn main() {
    fieldkit_build::Builder::new("shaders")
        // One uniform for several dispatches, each at its own offset (tests/stage.rs).
        .dynamic_offset("math::scale::params")
        .build_or_exit();
}
