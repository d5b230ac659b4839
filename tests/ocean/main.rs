//! The ocean: waves, level of detail (CPU and GPU), the renderer and its targets.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;

mod gpu_lod;
mod lod;
mod render;
mod targets;
mod waves;
