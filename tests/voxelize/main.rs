//! Mesh voxelization: surface, solid, placed grids, attributes, listings, OBJ loading and views.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;

mod attributes;
mod listing;
mod obj;
mod placed;
mod solid;
mod surface;
mod touch;
mod view;
