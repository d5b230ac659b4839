//! Metaballs: the field, the seeds, the SDF stages, the tracers and the renderer.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;
#[path = "../../examples/gallery/main.rs"]
#[allow(dead_code)]
mod gallery;

mod direct;
mod field;
mod grazing;
mod render;
mod render_failures;
mod render_targets;
mod seed;
mod stages;
