fn main() {
    fieldkit_build::Builder::new("shaders")
        // One uniform for several dispatches, each at its own offset (tests/stage.rs).
        .dynamic_offset("math::scale::params")
        // fieldkit's volume march over a density function of this crate (tests/density.rs).
        .density_march("scene::ramp_march", "shared::ramp")
        .build_or_exit();
}
