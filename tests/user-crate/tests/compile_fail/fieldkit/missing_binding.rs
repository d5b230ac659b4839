// Host code that binds only two of the three resources `jump` uses.
use fieldkit::shaders::distance::jfa_step::jump;

fn demo(params: &wgpu::Buffer, src: &wgpu::TextureView) {
    let _ = jump::Resources { params: params.into(), src: src.into() };
}

fn main() {}
