//! How fields name a voxel's nearest seed: packed integer seeds (2D's 16/16 bits live with
//! the seed textures, [`super::pack_seed`]), 3D's 11/11/10 bits or wider per axis
//! ([`SeedPacking`]), and keys into a table of sub-voxel points.

use super::NO_SEED;
use super::check::MAX_SIDE_EXACT_3D;

/// Most sub-voxel seeds one table may hold (24-bit index in the key).
pub const MAX_POINTS: u32 = 0xfffffe;

/// Pack a 3D seed as the shaders do: x in 11 bits, y in 11, z in 10, and the whole code + 1 so
/// that 0 is [`NO_SEED`].
pub fn pack_seed3(x: u32, y: u32, z: u32) -> u32 {
    (x | (y << 11) | (z << 22)) + 1
}

/// Unpack a 3D seed; `None` for [`NO_SEED`].
pub fn unpack_seed3(s: u32) -> Option<[u32; 3]> {
    (s != NO_SEED).then(|| {
        let c = s - 1;
        [c & 0x7ff, (c >> 11) & 0x7ff, c >> 22]
    })
}

/// How a 3D field names a voxel's nearest seed: x in the low `x_bits` bits of a code, y in the
/// next `y_bits`, z in the rest, and the whole code + 1, so that 0 is [`NO_SEED`].
/// [`SeedPacking::STANDARD`] (11/11/10, [`pack_seed3`]) for every grid up to 2048 × 2048 × 1024
/// and every method; the exact transform also takes grids past that — any side up to
/// [`MAX_SIDE_EXACT_3D`], as long as the voxels' codes fit 32 bits (64 × 64 × 2048 takes
/// 6/6/20) — with as many bits per axis as its sides need ([`SeedPacking::for_size`]).
///
/// ```
/// use fieldkit::distance::SeedPacking;
/// let tall = SeedPacking::for_size([64, 64, 2048]).unwrap();
/// assert_eq!((tall.x_bits, tall.y_bits), (6, 6));
/// assert_eq!(tall.unpack(tall.pack(63, 5, 2047)), Some([63, 5, 2047]));
/// assert_eq!(SeedPacking::for_size([512, 512, 512]), Some(SeedPacking::STANDARD));
/// assert_eq!(SeedPacking::for_size([2048, 2048, 2048]), None); // 33 bits
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SeedPacking {
    /// Bits of x, the lowest.
    pub x_bits: u32,
    /// Bits of y, above x's; z takes the rest of 32.
    pub y_bits: u32,
}

impl SeedPacking {
    /// 11 bits for x and y, 10 for z: [`pack_seed3`].
    pub const STANDARD: Self = Self {
        x_bits: 11,
        y_bits: 11,
    };

    /// The packing the exact transform gives a grid of `size`: [`Self::STANDARD`] where it
    /// holds every voxel, otherwise the fewest bits for x and y; `None` where a side is 0 or
    /// past [`MAX_SIDE_EXACT_3D`], or the voxels' codes do not fit 32 bits.
    pub fn for_size(size: [u32; 3]) -> Option<Self> {
        if size.iter().any(|&n| n == 0 || n > MAX_SIDE_EXACT_3D) {
            return None;
        }
        if Self::STANDARD.holds(size) {
            return Some(Self::STANDARD);
        }
        let bits = |n: u32| 32 - (n - 1).leading_zeros();
        let tight = Self {
            x_bits: bits(size[0]),
            y_bits: bits(size[1]),
        };
        tight.holds(size).then_some(tight)
    }

    /// Whether every voxel of a grid of `size` gets a code of its own, none of them wrapping to
    /// [`NO_SEED`].
    pub fn holds(&self, size: [u32; 3]) -> bool {
        if self.x_bits + self.y_bits > 31 || size.contains(&0) {
            return false;
        }
        let z_bits = 32 - self.x_bits - self.y_bits;
        size[0] as u64 <= 1 << self.x_bits
            && size[1] as u64 <= 1 << self.y_bits
            && size[2] as u64 <= 1 << z_bits
            && self.code(size[0] - 1, size[1] - 1, size[2] - 1) < u32::MAX as u64
    }

    fn code(&self, x: u32, y: u32, z: u32) -> u64 {
        x as u64 | (y as u64) << self.x_bits | (z as u64) << (self.x_bits + self.y_bits)
    }

    /// The seed at voxel (x, y, z) (the coordinates within the grid the packing holds).
    pub fn pack(&self, x: u32, y: u32, z: u32) -> u32 {
        (self.code(x, y, z) + 1) as u32
    }

    /// The voxel a seed names; `None` for [`NO_SEED`].
    pub fn unpack(&self, s: u32) -> Option<[u32; 3]> {
        (s != NO_SEED).then(|| {
            let c = s - 1;
            [
                c & ((1u32 << self.x_bits) - 1),
                (c >> self.x_bits) & ((1u32 << self.y_bits) - 1),
                c >> (self.x_bits + self.y_bits),
            ]
        })
    }
}

/// The packing of a grid the exact transform runs on (`size` passed [`exact_volume_size`] or
/// [`check_size_3d`]), [`SeedPacking::STANDARD`] for 2D fields (which do not read it).
pub(crate) fn packing_of(size: [u32; 3]) -> SeedPacking {
    SeedPacking::for_size(size).unwrap_or(SeedPacking::STANDARD)
}

/// Table index named by a sub-voxel seed key; `None` for no seed.
pub fn key_index(key: u32) -> Option<u32> {
    (key != NO_SEED).then(|| 0xffffff - (key & 0xffffff))
}
