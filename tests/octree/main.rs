//! The sparse voxel octree: building, attributes and ray casts.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;

mod attributes;
mod build;
mod cast;
