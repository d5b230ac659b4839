//! Hot reload (fieldkit's `hot-reload` feature) of the user's own stage: a changed body is
//! relinked from the file and runs; a file that no longer validates, or whose interface no
//! longer matches the compiled-in bindings, is refused with a typed error saying why.

mod common;

use std::path::{Path, PathBuf};

use fieldkit::gpu::Context;
use fieldkit_user_crate::shaders::math::scale;

/// A copy of the crate's `shaders/` in a fresh folder, with `scale.wgsl` rewritten by `edit`.
fn shaders_with(tag: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let root = std::env::temp_dir().join(format!("fieldkit-reload-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    for dir in ["shaders/math", "shaders/shared"] {
        std::fs::create_dir_all(root.join(dir)).unwrap();
        for entry in std::fs::read_dir(here.join(dir)).unwrap() {
            let path = entry.unwrap().path();
            let rel = path.strip_prefix(here).unwrap();
            std::fs::copy(&path, root.join(rel)).unwrap();
        }
    }
    let file = root.join("shaders/math/scale.wgsl");
    let text = std::fs::read_to_string(&file).unwrap();
    let edited = edit(&text);
    assert_ne!(edited, text, "the edit must change the file");
    std::fs::write(&file, edited).unwrap();
    root
}

fn run(ctx: &Context, pipeline: &scale::main::Pipeline) -> Vec<f32> {
    let params = common::uniform(
        ctx,
        "params",
        &scale::Params {
            factor: 3.0,
            count: 16,
        },
    );
    let values: Vec<f32> = (0..16).map(|i| i as f32).collect();
    let buffer = common::storage(ctx, "values", &values);
    let mut encoder = ctx.encoder("reload");
    pipeline
        .record(
            &ctx.device,
            &mut encoder,
            &scale::main::Resources {
                params: (&params).into(),
                values: (&buffer).into(),
            },
            [1, 1, 1],
            "reload",
        )
        .expect("binds");
    ctx.submit_and_wait("reload", encoder).unwrap();
    common::read_f32(ctx, &buffer)
}

#[test]
fn a_changed_body_reloads_and_a_changed_interface_is_refused() {
    let ctx = Context::shared();
    // The body changed: every value gets 100 more. Same bindings, same workgroup size.
    let root = shaders_with("body", |t| {
        t.replace(
            "scaled(values[id.x], params.factor) + OFFSET",
            "scaled(values[id.x], params.factor) + OFFSET + 100.0",
        )
    });
    let reloaded =
        scale::main::Pipeline::reload(&ctx.device, &root, &[]).expect("a body change reloads");
    let compiled = scale::main::Pipeline::new(&ctx.device).unwrap();
    for (i, (new, old)) in run(&ctx, &reloaded)
        .iter()
        .zip(run(&ctx, &compiled))
        .enumerate()
    {
        // Small integers times 3, plus 100: exact in f32.
        assert_eq!(old, i as f32 * 3.0, "compiled, value {i}");
        assert_eq!(*new, i as f32 * 3.0 + 100.0, "reloaded, value {i}");
    }
    std::fs::remove_dir_all(&root).unwrap();

    // A shader error: refused with its file and line.
    let root = shaders_with("broken", |t| t.replace("+ OFFSET", "+ OFFSET + 1u"));
    match scale::main::Pipeline::reload(&ctx.device, &root, &[]) {
        Err(fieldkit::Error::Reload { what, .. }) => {
            assert!(what.contains("shaders/math/scale.wgsl:"), "{what}")
        }
        other => panic!("expected Error::Reload, got {:?}", other.err()),
    }
    std::fs::remove_dir_all(&root).unwrap();

    // The interface changed: another workgroup size and a new binding.
    let root = shaders_with("interface", |t| {
        t.replace("@workgroup_size(64)", "@workgroup_size(32)")
            .replace(
                "override OFFSET",
                "@group(0) @binding(2) var<storage, read> bias: array<f32>;\n\noverride OFFSET",
            )
            .replace("+ OFFSET;", "+ OFFSET + bias[0];")
    });
    match scale::main::Pipeline::reload(&ctx.device, &root, &[]) {
        Err(fieldkit::Error::Reload { what, .. }) => assert!(
            what.contains("workgroup size is [32, 1, 1], was [64, 1, 1]")
                && what.contains("binding `bias` (@group(0) @binding(2)) is new"),
            "{what}"
        ),
        other => panic!("expected Error::Reload, got {:?}", other.err()),
    }
    std::fs::remove_dir_all(&root).unwrap();
}
