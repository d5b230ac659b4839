//! Distance fields in 2D and 3D.
//!
//! - **2D:** [`Distance2d`] computes the distance to the nearest seed texel of a mask texture,
//!   unsigned or signed. Its default method is the exact Euclidean transform, which is also the
//!   fastest measured; the JFA variants stay selectable ([`Method2d::Jfa`]) and are wrong on
//!   some seed sets (see the crate README's variant table). [`Jfa2d`] runs JFA's stages alone.
//! - **3D:** [`Distance3d`] computes distance fields of occupancy volumes (exact by default),
//!   of sub-voxel points (JFA) and with narrow bands.
//!
#![doc = include_str!("../../docs/distance.md")]

mod buffers;
mod check;
pub mod cpu;
mod d2;
mod d3;
mod exact;
pub mod export;
mod field;
mod jfa2d;
mod jfa3d;
mod options;
mod packing;
mod points;
mod resolve;
mod seeds;
mod upload;

pub use crate::grid::Grid;
pub use check::{
    MAX_SIDE_2D_EXACT, MAX_SIDE_3D, MAX_SIDE_EXACT_3D, VOLUME_FORMATS, check_size_2d_exact,
    check_size_3d,
};
pub use d2::{Distance2d, Field2d, Method2d, Nearest2d, Settings2d};
pub use d3::Distance3d;
pub use exact::Exact;
pub use exact::plan::{
    AUTO_TILE_BAND, AUTO_TILE_MAX_COLUMNS_Y, AUTO_TILE_MAX_LENGTH, AUTO_TILE_MAX_LENGTH_2D,
    AUTO_TILE_MAX_LENGTH_Y, ColumnPasses, MAX_TILE_COLUMNS, MIN_TILE_COLUMNS, tile_columns,
    tile_columns_3d,
};
pub use field::{Field3d, FieldBuf2d, Slabs};
pub use jfa2d::{Jfa2d, JfaField2d, JfaSettings2d, Variant};
pub use jfa3d::Jfa3d;
pub use options::{Inside, Marks, Method, Settings3d, Unreached};
pub use packing::{MAX_POINTS, SeedPacking, key_index, pack_seed3, unpack_seed3};
pub use seeds::{
    Channels, FAR, MAX_PACKED_SIDE, NO_SEED, SEED_FORMATS, SeedRule, check_seed_texture,
    check_size, is_seed_format, pack_seed, unpack_seed, upload_mask,
};
pub use upload::{PointSeeds, upload_points, upload_points_with_homes, upload_volume};

/// The former name of [`Settings3d`].
#[deprecated(note = "renamed to Settings3d: every technique's knobs are its `…Settings`")]
#[doc(hidden)]
pub type Options3d = Settings3d;
/// The former name of [`Settings2d`].
#[deprecated(note = "renamed to Settings2d: every technique's knobs are its `…Settings`")]
#[doc(hidden)]
pub type Options2d = Settings2d;
/// The former name of [`JfaSettings2d`].
#[deprecated(note = "renamed to JfaSettings2d: every technique's knobs are its `…Settings`")]
#[doc(hidden)]
pub type Options = JfaSettings2d;

/// The 3D methods' stage name in their errors.
const STAGE_3D: &str = "distance::d3";
