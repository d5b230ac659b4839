//! The user's host code cannot drift from the user's shaders: code written against a different
//! interface (a renamed binding, a uniform field the shader does not have) fails to compile,
//! as fieldkit's own `tests/compile_fail` shows for fieldkit's shaders.

#[test]
fn drifted_host_code_does_not_compile() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/compile_fail/*.rs");
}
