// A buffer where the shader declares a storage texture (`dst: texture_storage_2d<r32uint, write>`).
use fieldkit::shaders::distance::jfa_step::jump;

fn demo(params: &wgpu::Buffer, src: &wgpu::TextureView, dst: &wgpu::Buffer) {
    let _ = jump::Resources { params: params.into(), src: src.into(), dst: dst.into() };
}

fn main() {}
