//! The distance transforms (2D and 3D): stages, accuracy against brute force, seeds, export and errors.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;
#[path = "../../examples/gallery/main.rs"]
#[allow(dead_code)]
mod gallery;

mod accuracy_2d;
mod accuracy_3d;
mod errors_2d;
mod errors_3d;
mod export_2d;
mod fields_3d;
mod jfa_traps_2d;
mod points_3d;
mod seeds_2d;
mod stages_2d;
mod stages_3d;
