//! The live viewer (`examples/viewer`): its scenes offscreen and in a window, and its panels driven as a user would.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;
#[path = "../../examples/viewer/main.rs"]
#[allow(dead_code, unused_imports)]
mod viewer;

mod panels;
mod scenes;
