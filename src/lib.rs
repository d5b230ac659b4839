//! fieldkit: GPU shader stages for fields — distance fields, metaball SDFs, voxel grids, volume
//! raymarching, ocean surfaces and mesh voxelization — on wgpu and naga.
//!
//! Every stage is a WGSL file under `shaders/`, validated by naga at build time; its typed host
//! bindings are generated into [`shaders`]. Technique modules (like [`distance`]) compose stages
//! into passes recorded into your own `wgpu::CommandEncoder`.

#![warn(missing_docs)]

pub mod bind;
#[cfg(feature = "techniques")]
pub mod distance;
pub mod error;
pub mod gpu;
pub mod grid;
#[cfg(feature = "harness")]
pub mod harness;
#[cfg(feature = "hot-reload")]
mod hot;
#[cfg(feature = "techniques")]
pub mod mesh_sdf;
#[cfg(feature = "techniques")]
pub mod metaball;
#[cfg(feature = "techniques")]
pub mod ocean;
#[cfg(feature = "techniques")]
pub mod octree;
#[cfg(feature = "techniques")]
pub mod view;
#[cfg(feature = "techniques")]
pub mod volume;
#[cfg(feature = "techniques")]
pub mod voxelize;

pub use error::{BindingError, Error};
/// glam, the vector maths of fieldkit's API (`DVec3` mesh placement, `Mat4` cameras), at the version fieldkit
/// uses: `fieldkit::glam::DVec3` needs no dependency of your own.
pub use glam;
pub use grid::Grid;
pub use wgpu;

/// Generated bindings, one module per stage (`shaders::<room>::<stage>`). See [`bind`].
#[cfg(feature = "techniques")]
#[allow(clippy::all, missing_docs)]
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}

// The README's examples compile as doc tests (each technique's page, docs/<t>.md, is its
// module's documentation, tested there).
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

// So do the pages that are no module's: users' own shaders, and a frame's cost.
#[doc = include_str!("../docs/shaders.md")]
#[cfg(doctest)]
pub struct ShadersDoctests;

#[doc = include_str!("../docs/frame.md")]
#[cfg(doctest)]
pub struct FrameDoctests;
