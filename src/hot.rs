//! Hot reload (feature `hot-reload`): a stage relinked from its file at run time, checked
//! against the interface its generated bindings were compiled from.

use std::path::Path;

use crate::bind::{EntryInfo, EntryKind};
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
