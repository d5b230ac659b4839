// Host code written for a JumpParams with a `stride` field: the WGSL struct has `step`.
use fieldkit::shaders::distance::jfa_step::JumpParams;

fn main() {
    let _ = JumpParams { size: glam::UVec2::new(8, 8), stride: 1 };
}
