// A uniform typed for another stage's struct: `jump` binds `JumpParams`, not `SeedParams`.
use fieldkit::bind::Uniform;
use fieldkit::shaders::distance::{jfa_seed::SeedParams, jfa_step::jump};

fn demo(params: Uniform<'_, SeedParams>, src: &wgpu::TextureView, dst: &wgpu::TextureView) {
    let _ = jump::Resources { params, src: src.into(), dst: dst.into() };
}

fn main() {}
