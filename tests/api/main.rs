//! The crate as a dependency: generated bindings, consumer crates, drop-in errors, timing, limits, threads, properties and the own-device example.
//!
//! One test binary for the room (a binary per file linked wgpu into each: ~38 MB and a link apiece).

#[path = "../common/mod.rs"]
mod common;
#[path = "../../examples/own_device.rs"]
#[allow(dead_code)]
mod own_device;

mod bindings;
mod consumer;
mod drop_in_errors;
mod examples;
mod gpu_timing;
mod limits;
mod properties;
mod threads;
