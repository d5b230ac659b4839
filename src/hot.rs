//! Hot reload (feature `hot-reload`): a stage relinked from its file at run time, checked
//! against the interface its generated bindings were compiled from.

use std::path::Path;

use crate::bind::{ComputePipeline, Entry, EntryInfo, EntryKind, RenderPipeline, RenderTargets};
use crate::error::Error;

/// The linked WGSL of `info`'s stage read again from `crate_root.join(info.path)` (imports
/// included), where its interface still fits the compiled-in one
/// (`fieldkit_build::drift::interface_drift` between the compiled-in `SOURCE` and the file).
pub(crate) fn relink(info: &EntryInfo, crate_root: &Path) -> Result<String, Error> {
    let refuse = |what: String| Error::Reload {
        stage: info.stage,
        what,
    };
    // `shaders/<room>/<name>.wgsl`: the folder, the room and the stage's name.
    let parts: Vec<&str> = info.path.split('/').collect();
    let [dir, room, file] = parts[..] else {
        return Err(refuse(format!(
            "{} is not laid out as <folder>/<room>/<stage>.wgsl",
            info.path
        )));
    };
    let name = file
        .rsplit_once('.')
        .map_or(file, |(stem, _)| stem)
        .to_string();
    let stage_file = fieldkit_build::StageFile {
        room: room.to_string(),
        name,
        rel_path: info.path.to_string(),
        abs_path: crate_root.join(info.path),
        source: None,
    };
    let shaders = fieldkit_build::ShaderDir::new(crate_root, dir);
    let new = fieldkit_build::build_stage(&shaders, &stage_file).map_err(refuse)?;
    let old = fieldkit_build::stage_from_linked(stage_file, info.source).map_err(refuse)?;
    let entries: Vec<&str> = match info.kind {
        EntryKind::Compute { .. } => vec![info.entry_point],
        EntryKind::Render { vertex, .. } => vec![vertex, info.entry_point],
    };
    let drift = fieldkit_build::drift::interface_drift(
        &fieldkit_build::reflect::reflect(&old),
        &fieldkit_build::reflect::reflect(&new),
        &entries,
    );
    if !drift.is_empty() {
        return Err(refuse(format!(
            "{} no longer matches the compiled-in bindings: {}",
            info.path,
            drift.join("; ")
        )));
    }
    Ok(new.source)
}

// Hot reload lives here, beside `relink`, so that `bind` does not reach back into this module.
impl<E: Entry> ComputePipeline<E> {
    /// The pipeline made again from the stage's file under `crate_root` (`EntryInfo::path`,
    /// its imports relinked), for iterating on a shader while the app runs: [`Error::Reload`]
    /// where the file no longer links or validates (the message has its file:line:col) or
    /// where its interface no longer matches the compiled-in bindings (a new or retyped
    /// binding, another workgroup size or set of overrides); the body may change freely.
    /// Feature `hot-reload`.
    pub fn reload(
        device: &wgpu::Device,
        crate_root: &std::path::Path,
        overrides: &[(&str, f64)],
    ) -> Result<Self, Error> {
        let source = crate::hot::relink(E::INFO, crate_root)?;
        Self::make(device, Some(&source), overrides, &[], true)
    }
}

impl<E: Entry> RenderPipeline<E> {
    /// The pipeline made again from the stage's file under `crate_root`, as
    /// [`ComputePipeline::reload`] makes a compute pipeline. Feature `hot-reload`.
    pub fn reload(
        device: &wgpu::Device,
        crate_root: &std::path::Path,
        targets: &RenderTargets<'_>,
    ) -> Result<Self, Error> {
        let source = crate::hot::relink(E::INFO, crate_root)?;
        Self::make(device, Some(&source), targets, &[])
    }
}
