//! Where a volume sits in the world, shared by every technique that has voxels: the distance
//! transforms, the metaball field, the voxelizer and the octree all place their voxels by one
//! [`Grid`]. Placement is f64 (a grid a million voxels from the origin keeps its sub-voxel
//! placement); the stages take it to f32 in their own local frame.
//!
//! ```
//! use fieldkit::Grid;
//! use glam::DVec3;
//! let grid = Grid { origin: DVec3::new(-1.0, 0.0, 0.0), voxel: 0.5, size: [4, 4, 2] };
//! assert_eq!(grid.voxels(), 32);
//! assert_eq!(grid.voxel_centre([0, 0, 0]), DVec3::new(-0.75, 0.25, 0.25));
//! assert_eq!(grid.to_voxel(DVec3::new(-0.75, 0.25, 0.25)), DVec3::ZERO);
//! grid.check("my stage")?;
//! # Ok::<(), fieldkit::Error>(())
//! ```

use glam::{DVec3, Vec3};

use crate::error::Error;

/// Where the voxels are: the world position of voxel (0, 0, 0)'s min corner, the voxel edge and
/// the number of voxels per axis. Voxel `(i, j, k)` has its centre at
/// `origin + (i + ½, j + ½, k + ½) · voxel`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Grid {
    /// World position of the grid's lowest corner.
    pub origin: DVec3,
    /// Edge of a voxel, world units.
    pub voxel: f64,
    /// Voxels per axis.
    pub size: [u32; 3],
}

impl Grid {
    /// A grid of `size` unit voxels with its lowest corner at the origin.
    pub fn new(size: [u32; 3]) -> Self {
        Self {
            origin: DVec3::ZERO,
            voxel: 1.0,
            size,
        }
    }

    /// Voxels in the grid.
    pub fn voxels(&self) -> u64 {
        self.size.iter().map(|&n| n as u64).product()
    }

    /// World position → voxel coordinates (voxel centres at integers).
    pub fn to_voxel(&self, p: DVec3) -> DVec3 {
        (p - self.origin) / self.voxel - DVec3::splat(0.5)
    }

    /// Centre of voxel `v` in the world.
    pub fn voxel_centre(&self, v: [u32; 3]) -> DVec3 {
        self.origin + (DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) + 0.5) * self.voxel
    }

    /// [`Error::Invalid`] naming `stage` unless the origin is finite and the voxel edge finite
    /// and > 0; [`Error::Size`] unless every side is 1 to `u32::MAX`. What a device can hold
    /// each stage checks against its own limits ([`Grid::check_sides`]).
    pub fn check(&self, stage: &'static str) -> Result<(), Error> {
        self.check_sides(stage, u32::MAX)
    }

    /// [`Grid::check`] with sides at most `max_side`: the one check of a grid's placement and
    /// sides that every technique makes.
    pub fn check_sides(&self, stage: &'static str, max_side: u32) -> Result<(), Error> {
        if !(self.origin.is_finite() && self.voxel.is_finite() && self.voxel > 0.0) {
            return Err(Error::invalid(
                stage,
                format!("the grid needs a finite origin and a voxel edge > 0, got {self:?}"),
            ));
        }
        for (what, &n) in ["grid side x", "grid side y", "grid side z"]
            .iter()
            .zip(&self.size)
        {
            if n == 0 || n > max_side {
                return Err(Error::Size {
                    stage,
                    what,
                    got: n as u64,
                    max: max_side as u64,
                });
            }
        }
        Ok(())
    }

    /// The origin and voxel edge in f32, for stages that place their voxels in f32: a typed
    /// error where either is not finite there (or the edge not > 0), as well as in f64.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn as_f32(&self, stage: &'static str) -> Result<(Vec3, f32), Error> {
        self.check(stage)?;
        let (origin, voxel) = (self.origin.as_vec3(), self.voxel as f32);
        if !(origin.is_finite() && voxel.is_finite() && voxel > 0.0) {
            return Err(Error::invalid(
                stage,
                format!("the grid's origin and voxel edge must be finite in f32, got {self:?}"),
            ));
        }
        Ok((origin, voxel))
    }
}
