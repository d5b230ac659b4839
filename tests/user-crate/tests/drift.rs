//! Host code cannot drift from the shaders it binds: code written against a different
//! interface (a renamed binding, a uniform field the shader does not have, a resource of the
//! wrong kind) fails to compile, for the user's own shaders (`tests/compile_fail`) and for
//! fieldkit's (`tests/compile_fail/fieldkit`).
//!
//! Both sets run here, in one trybuild project: trybuild builds every dev-dependency of the
//! crate under test, and fieldkit's (eframe, winit, the DICOM crates, proptest, …) made the
//! same check in fieldkit's own tests take six minutes of a cold CI run on top of this one.

#[test]
fn drifted_host_code_does_not_compile() {
    // trybuild's project builds the crate's dependency tree again, in cargo's default dev
    // profile: full debug info made it 1.4 GB of a cold CI run's target. The compiler errors it
    // compares need none. (The only test of this binary: no other thread reads the variable.)
    std::env::set_var("CARGO_PROFILE_DEV_DEBUG", "false");
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/compile_fail/*.rs");
    t.compile_fail("tests/compile_fail/fieldkit/*.rs");
}
