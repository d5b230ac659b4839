use super::{Violation, locate};
use crate::{Stage, reflect::Reflection};

/// WebGPU's default limits: every adapter wgpu supports must accept these.
pub const MAX_X: u32 = 256;
pub const MAX_Y: u32 = 256;
pub const MAX_Z: u32 = 64;
pub const MAX_INVOCATIONS: u32 = 256;

/// Its name in findings, `--only` and allow comments.
pub(super) const NAME: &str = "workgroup-limits";

/// Workgroup sizes stay within WebGPU's default limits.
pub(super) fn check(stage: &Stage, r: &Reflection) -> Vec<Violation> {
    let mut out = Vec::new();
    for ep in r.entry_points.iter().filter(|e| e.stage == "compute") {
        let [x, y, z] = ep.workgroup_size;
        let total = x as u64 * y as u64 * z as u64;
        if x > MAX_X || y > MAX_Y || z > MAX_Z || total > MAX_INVOCATIONS as u64 {
            let (line, column) = locate(&stage.original, &format!("fn {}", ep.name));
            out.push(Violation {
                lint: NAME,
                file: stage.file.rel_path.clone(),
                line,
                column,
                message: format!("`{}` has workgroup size ({x}, {y}, {z}) = {total} invocations, past WebGPU's default limits", ep.name),
            });
        }
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    #[test]
    fn flags_too_many_invocations() {
        let bad = stage("@compute @workgroup_size(32, 16) fn main() {}");
        assert_eq!(check(&bad, &reflect(&bad)).len(), 1);
        let good = stage("@compute @workgroup_size(16, 16) fn main() {}");
        assert!(check(&good, &reflect(&good)).is_empty());
    }
}
