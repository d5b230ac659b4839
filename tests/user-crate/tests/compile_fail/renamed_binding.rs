// Host code written before `seeds.wgsl` renamed its output binding from `out` to `packed`: the
// generated `Resources` has no `out`, and lacks the `packed` this code does not give.
use fieldkit_user_crate::shaders::math::seeds;

fn demo(grid: &wgpu::Buffer, out: &wgpu::Buffer, unpacked: &wgpu::Buffer) {
    let _ = seeds::main::Resources {
        grid: grid.into(),
        out: out.into(),
        unpacked: unpacked.into(),
    };
}

fn main() {}
