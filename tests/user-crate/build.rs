fn main() {
    fieldkit_build::Builder::new("shaders").build_or_exit();
}
