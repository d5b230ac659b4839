// Host code that fills the user's `Grid` uniform with a field the shader does not declare
// (`spacing`) and without `every`: the generated struct follows the shader, not this code.
use fieldkit_user_crate::shaders::math::seeds;

fn main() {
    let _ = seeds::Grid {
        size: glam::UVec3::new(4, 4, 4),
        spacing: 2,
    };
}
