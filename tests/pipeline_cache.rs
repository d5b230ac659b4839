//! The pipeline cache an app keeps on disk: saved, read back on the next open, and a damaged
//! or foreign file never reaching the driver (an empty cache instead, no error).

use fieldkit::distance::Distance2d;
use fieldkit::gpu::{Context, PipelineCache};

fn open(ctx: &Context, dir: &std::path::Path) -> Option<PipelineCache> {
    let adapter = ctx.adapter.as_ref().expect("a context of fieldkit's own");
    PipelineCache::open(&ctx.device, &adapter.get_info(), dir).expect("the folder is readable")
}

#[test]
fn a_saved_cache_is_read_back_and_a_damaged_one_starts_empty() {
    let ctx = Context::shared();
    let dir = std::env::temp_dir().join(format!("fieldkit-pipeline-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let Some(cache) = open(&ctx, &dir) else {
        // No cache on this device: `open` says so and pipelines are made as before.
        assert!(
            !ctx.device
                .features()
                .contains(wgpu::Features::PIPELINE_CACHE)
                || ctx.adapter.as_ref().unwrap().get_info().backend != wgpu::Backend::Vulkan,
            "a Vulkan device with PIPELINE_CACHE got no cache"
        );
        Distance2d::new(&ctx.device).expect("pipelines without a cache");
        return;
    };
    assert_eq!(cache.loaded_bytes(), 0, "a new folder holds no cache");
    // Pipelines made while the cache is installed go through it.
    Distance2d::new(&ctx.device).expect("pipelines through the cache");
    cache.save().expect("the folder is writable");
    let saved = cache.data().map_or(0, |d| d.len());
    drop(cache);
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
    assert_eq!(files.len(), 1, "one file, named for the adapter: {files:?}");
    let file = files[0].path();

    let again = open(&ctx, &dir).expect("the same device");
    assert_eq!(
        again.loaded_bytes(),
        saved,
        "the next launch starts from what was saved"
    );
    drop(again);

    // Cut short, then one byte changed: an empty cache, no error.
    let whole = std::fs::read(&file).unwrap();
    std::fs::write(&file, &whole[..whole.len() - 1]).unwrap();
    assert_eq!(open(&ctx, &dir).unwrap().loaded_bytes(), 0, "a cut file");
    let mut changed = whole.clone();
    let last = changed.len() - 1;
    changed[last] ^= 0x40;
    std::fs::write(&file, &changed).unwrap();
    assert_eq!(
        open(&ctx, &dir).unwrap().loaded_bytes(),
        0,
        "a changed file"
    );
    std::fs::write(&file, b"not a pipeline cache").unwrap();
    let fresh = open(&ctx, &dir).unwrap();
    assert_eq!(fresh.loaded_bytes(), 0, "a foreign file");
    Distance2d::new(&ctx.device).expect("pipelines through a fresh cache");
    drop(fresh);
    let _ = std::fs::remove_dir_all(&dir);
}
