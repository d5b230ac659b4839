//! Volume raymarching: loading (raw, DICOM, functions), lighting and the march.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;

mod dicom;
mod function;
mod light;
mod load;
mod march;
