use super::{Violation, locate};
use crate::Stage;
use crate::reflect::{BindingKind, Reflection};

/// WebGPU's default limits (what `wgpu::Limits::default()` asks of a device), per shader stage
/// where the limit is per stage.
pub const STORAGE_BUFFERS: u32 = 8;
pub const STORAGE_TEXTURES: u32 = 4;
pub const SAMPLED_TEXTURES: u32 = 16;
pub const SAMPLERS: u32 = 16;
pub const UNIFORM_BUFFERS: u32 = 12;
pub const BIND_GROUPS: u32 = 4;
pub const WORKGROUP_STORAGE: u32 = 16384;
pub const UNIFORM_BINDING: u32 = 65536;
/// Storage texture formats WebGPU allows `read_write` without a feature.
pub const READ_WRITE_FORMATS: &[&str] = &["r32float", "r32uint", "r32sint"];

/// Its name in findings, `--only` and allow comments.
pub(super) const NAME: &str = "webgpu-limits";

/// Each entry point fits WebGPU's default limits, so it runs on every adapter wgpu supports.
pub(super) fn check(stage: &Stage, r: &Reflection) -> Vec<Violation> {
    let mut out = Vec::new();
    for ep in &r.entry_points {
        let (line, column) = locate(&stage.original, &format!("fn {}", ep.name));
        let mut say = |message: String| {
            out.push(Violation {
                lint: NAME,
                file: stage.file.rel_path.clone(),
                line,
                column,
                message: format!("`{}`: {message}", ep.name),
            })
        };
        // Binding arrays and immediates are native features, not WebGPU.
        let native: Vec<&str> = r
            .features
            .iter()
            .map(String::as_str)
            .filter(|_| {
                ep.uses_immediate
                    || ep.uses.iter().any(|u| {
                        r.bindings.iter().any(|b| {
                            b.group == u.group && b.binding == u.binding && b.count.is_some()
                        })
                    })
            })
            .collect();
        if !native.is_empty() {
            say(format!(
                "needs the native features {} (binding arrays, immediates), which WebGPU lacks",
                native.join(", ")
            ));
        }
        let n = ep.needs;
        let counts = [
            (
                "storage buffers",
                n.max_storage_buffers_per_shader_stage,
                STORAGE_BUFFERS,
            ),
            (
                "storage textures",
                n.max_storage_textures_per_shader_stage,
                STORAGE_TEXTURES,
            ),
            (
                "sampled textures",
                n.max_sampled_textures_per_shader_stage,
                SAMPLED_TEXTURES,
            ),
            ("samplers", n.max_samplers_per_shader_stage, SAMPLERS),
            (
                "uniform buffers",
                n.max_uniform_buffers_per_shader_stage,
                UNIFORM_BUFFERS,
            ),
        ];
        for (what, got, max) in counts {
            if got > max {
                say(format!(
                    "{got} {what} in one stage, past WebGPU's default {max}"
                ));
            }
        }
        if n.max_bind_groups > BIND_GROUPS {
            say(format!(
                "bind group {} needs {} bind groups, past WebGPU's default {BIND_GROUPS}",
                n.max_bind_groups - 1,
                n.max_bind_groups
            ));
        }
        if n.max_compute_workgroup_storage_size > WORKGROUP_STORAGE {
            say(format!(
                "{} bytes of workgroup memory, past WebGPU's default {WORKGROUP_STORAGE}",
                n.max_compute_workgroup_storage_size
            ));
        }
        let used = ep.uses.iter().filter_map(|u| {
            r.bindings
                .iter()
                .find(|b| b.group == u.group && b.binding == u.binding)
        });
        for b in used {
            match &b.kind {
                BindingKind::Uniform { min_size, .. } if *min_size > UNIFORM_BINDING => {
                    say(format!(
                        "uniform `{}` is {min_size} bytes, past WebGPU's default {UNIFORM_BINDING}",
                        b.name
                    ))
                }
                BindingKind::StorageTexture { format, access, .. }
                    if access == "read_write"
                        && !READ_WRITE_FORMATS.contains(&format.to_ascii_lowercase().as_str()) =>
                {
                    let format = format.to_ascii_lowercase();
                    say(format!(
                        "storage texture `{}` is read_write in {format}, which WebGPU allows only for r32float, r32uint and r32sint without a native feature",
                        b.name
                    ))
                }
                _ => {}
            }
        }
    }
    out
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::{lint::test_util::stage, reflect::reflect};

    #[test]
    fn flags_what_webgpu_defaults_refuse() {
        let bad = stage(
            "var<workgroup> big: array<u32, 5000>;
@group(4) @binding(0) var<storage, read_write> a: array<u32>;
@group(0) @binding(1) var img: texture_storage_2d<rgba8unorm, read_write>;
@compute @workgroup_size(64) fn main(@builtin(local_invocation_index) i: u32) {
    big[i] = a[i];
    a[i] = big[63u - i];
    textureStore(img, vec2<u32>(i, 0u), textureLoad(img, vec2<u32>(0u, i)));
}",
        );
        let v = check(&bad, &reflect(&bad));
        let text: Vec<_> = v.iter().map(|v| v.message.clone()).collect();
        assert_eq!(v.len(), 3, "{text:#?}");
        assert!(
            text[0].contains("bind group 4 needs 5 bind groups"),
            "{text:#?}"
        );
        assert!(
            text[1].contains("20000 bytes of workgroup memory"),
            "{text:#?}"
        );
        assert!(
            text[2].contains("`img` is read_write in rgba8unorm"),
            "{text:#?}"
        );
        let good = stage(
            "var<workgroup> small: array<u32, 4096>;
@group(3) @binding(0) var<storage, read_write> a: array<u32>;
@group(0) @binding(1) var img: texture_storage_2d<r32float, read_write>;
@compute @workgroup_size(64) fn main(@builtin(local_invocation_index) i: u32) {
    small[i] = a[i];
    a[i] = small[63u - i];
    textureStore(img, vec2<u32>(i, 0u), textureLoad(img, vec2<u32>(0u, i)));
}",
        );
        let v = check(&good, &reflect(&good));
        assert!(v.is_empty(), "{v:#?}");
    }

    /// Binding arrays and immediates need native features: flagged per entry point that uses
    /// them, with the features named.
    #[test]
    fn flags_native_features() {
        let native = stage(
            "struct Push { scale: f32, }
var<immediate> push: Push;
@group(0) @binding(0) var<storage, read_write> a: array<f32>;
@compute @workgroup_size(64) fn uses(@builtin(local_invocation_index) i: u32) {
    a[i] = push.scale;
}
@compute @workgroup_size(64) fn plain(@builtin(local_invocation_index) i: u32) {
    a[i] = 1.0;
}",
        );
        let v = check(&native, &reflect(&native));
        let text: Vec<_> = v.iter().map(|v| v.message.clone()).collect();
        assert_eq!(v.len(), 1, "{text:#?}");
        assert!(
            text[0].starts_with("`uses`") && text[0].contains("IMMEDIATES"),
            "{text:#?}"
        );
    }
}
