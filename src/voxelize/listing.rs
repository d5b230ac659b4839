//! How the surface pass's work is listed: triangles sorted by the columns their boxes cover,
//! chunks of heavy triangles, giants handled apart ([`GpuListing`], [`Listing`]).

use glam::Vec4;

use super::{GridMesh, LIGHT, STAGE};
use crate::error::Error;

/// Columns triangle `t` (three grid-local vertices) can have at most: whichever axis is
/// dominant, the largest product of two of its box's sides (clamped to a grid of `size`), and
/// none when the box misses the grid along any axis (as the shaders' `setup` finds from the
/// same box of the same f32 vertices).
pub(super) fn box_columns(t: &[Vec4], size: [u32; 3]) -> u64 {
    let lo = t[0].min(t[1]).min(t[2]).truncate();
    let hi = t[0].max(t[1]).max(t[2]).truncate();
    // Saturating: a vertex far outside the grid (f32 → i64 saturates) clamps to it.
    let side = |a: usize| {
        let l = (lo[a].ceil() as i64).saturating_sub(1).max(0);
        let h = (hi[a].floor() as i64).min(size[a] as i64 - 1);
        h.saturating_sub(l).saturating_add(1).max(0) as u64
    };
    let (x, y, z) = (side(0), side(1), side(2));
    if x == 0 || y == 0 || z == 0 {
        return 0;
    }
    (x * y).max(y * z).max(z * x)
}

/// Chunks the heavy triangles of `local` can need at most in the GPU's work list (see
/// `box_columns`): [`CHUNK`] columns each, but no more than [`MAX_CHUNKS`] for a triangle.
pub fn heavy_chunk_bound(local: &GridMesh, size: [u32; 3]) -> u32 {
    let total: u64 = local
        .vertices
        .chunks(3)
        .map(|t| box_columns(t, size))
        .filter(|&most| most > LIGHT as u64)
        .map(most_chunks)
        .sum();
    total.min(u32::MAX as u64) as u32
}

/// Chunks the host lists in all for the giant triangles of a mesh (those of more than
/// [`MAX_CHUNKS`] chunks, a ground plane or walls; 8 MiB of entries) in `encode_surface` and
/// `encode_solid` before they get chunks longer than the listing's: enough threads to fill a
/// large GPU many times, and a short upload. Smaller triangles keep their chunks. Measured on
/// the H100 (docs/voxelize.md): a square of two triangles at 4096² took 0.52 ms in chunks of 4
/// columns (8.4 M entries, 67 MB), 0.31 in chunks of 32 (1 M entries); a thread walks about
/// 0.65 µs per column, so chunks far longer (1024 columns: 0.76 ms) leave the GPU waiting on a
/// few threads.
pub const LIST_BUDGET: u64 = 1 << 20;

/// The most chunks a heavy triangle may list, given each heavy triangle's count in chunks of
/// the listing's length. Triangles of at most [`MAX_CHUNKS`] are never cut short; the larger
/// ones share [`LIST_BUDGET`]: no cap while they fit it, else the largest cap under which they
/// do (the heaviest shortened first), but never below `MAX_CHUNKS`, so no chunk is longer than
/// `MAX_SIDE² / MAX_CHUNKS` = 1024 columns (past 64 such triangles each lists `MAX_CHUNKS`).
pub(super) fn chunk_cap(chunks: &[u64]) -> u64 {
    let floor = MAX_CHUNKS as u64;
    let giant: Vec<u64> = chunks.iter().copied().filter(|&n| n > floor).collect();
    let fits = |cap: u64| giant.iter().map(|&n| n.min(cap)).sum::<u64>() <= LIST_BUDGET;
    let Some(&most) = giant.iter().max() else {
        return u64::MAX;
    };
    if fits(most) {
        return u64::MAX;
    }
    if !fits(floor) {
        return floor;
    }
    // The largest cap that fits, between the floor (fits) and `most` (does not).
    let (mut lo, mut hi) = (floor, most - 1);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

/// Columns per listed chunk of a heavy triangle of at most `most` columns: `chunk`, or longer
/// where that would take more than `cap` chunks ([`chunk_cap`]).
pub(super) fn listed_chunk(most: u64, chunk: u64, cap: u64) -> u64 {
    chunk.max(most.div_ceil(cap))
}

/// `local`'s triangles sorted for `surface_listed`: the light ones (at most [`LIGHT`] columns
/// by [`box_columns`]) first, then the heavy ones, and each heavy triangle's chunks as
/// (triangle, first column), of `listing.chunk` columns, or longer for the heaviest ones where
/// the giant triangles' chunks would pass [`LIST_BUDGET`] ([`chunk_cap`]); a heavy triangle's first
/// vertex carries its chunks' columns in w (which the shaders read for nothing else). A list
/// larger than `limit` bytes is refused before it is made.
pub(super) fn listed(
    local: &GridMesh,
    size: [u32; 3],
    limit: u64,
    listing: Listing,
) -> Result<Sorted, Error> {
    let chunk = listing.chunk.max(1) as u64;
    let light_most = listing.light as u64;
    let most: Vec<u64> = local
        .vertices
        .chunks(3)
        .map(|t| box_columns(t, size))
        .collect();
    let heavy_chunks: Vec<u64> = most
        .iter()
        .filter(|&&m| m > light_most)
        .map(|&m| m.div_ceil(chunk))
        .collect();
    let cap = chunk_cap(&heavy_chunks);
    // Sized before anything is allocated: many huge triangles can need more entries than a
    // buffer may hold (or the host has memory for).
    let total: u64 = most
        .iter()
        .filter(|&&m| m > light_most)
        .map(|&m| m.div_ceil(listed_chunk(m, chunk, cap)))
        .sum();
    if total.saturating_mul(8) > limit {
        return Err(Error::Size {
            stage: STAGE,
            what: "heavy-triangle chunk list bytes",
            got: total.saturating_mul(8),
            max: limit,
        });
    }
    let mut vertices = Vec::with_capacity(local.vertices.len());
    let mut order = Vec::with_capacity(most.len());
    let mut heavy = Vec::new();
    for (i, &most) in most.iter().enumerate() {
        if most > light_most {
            heavy.push((i, &local.vertices[3 * i..3 * i + 3], most));
        } else {
            order.push(i as u32);
        }
    }
    if listing.sort {
        // Most columns first: threads of a warp then walk about as many columns each.
        order.sort_by_key(|&i| std::cmp::Reverse(most[i as usize]));
    }
    for &i in &order {
        vertices.extend_from_slice(&local.vertices[3 * i as usize..3 * i as usize + 3]);
    }
    let light = (vertices.len() / 3) as u32;
    let mut chunks = Vec::with_capacity(total as usize);
    let mut runs = Vec::with_capacity(heavy.len());
    for (k, (i, t, most)) in heavy.into_iter().enumerate() {
        let columns = listed_chunk(most, chunk, cap);
        // Exact in f32: at most MAX_SIDE² / MAX_CHUNKS (or the listing's chunk) columns.
        vertices.extend_from_slice(t);
        let first = vertices.len() - 3;
        vertices[first].w = columns as f32;
        order.push(i as u32);
        let at = light + k as u32;
        let n = most.div_ceil(columns);
        chunks.extend((0..n).map(|c| [at, (c * columns) as u32]));
        runs.push((n as u32, columns as u32));
    }
    Ok(Sorted {
        vertices,
        light,
        chunks,
        runs,
        order,
    })
}

/// [`listed`]'s result: vertices with the light triangles first, how many are light, the
/// heavy ones' chunks as (triangle, first column) and for each heavy triangle its chunks and
/// their columns, and for each sorted triangle its index in the [`GridMesh`].
pub(super) struct Sorted {
    pub(super) vertices: Vec<Vec4>,
    pub(super) light: u32,
    pub(super) chunks: Vec<[u32; 2]>,
    pub(super) runs: Vec<(u32, u32)>,
    pub(super) order: Vec<u32>,
}

/// Columns per chunk of a heavy triangle (the shader's `CHUNK`).
pub const CHUNK: u32 = 4;

/// Most chunks the GPU lists for one triangle (`fieldkit::triangle_box`'s `MAX_CHUNKS`): a
/// triangle of more than `MAX_CHUNKS` × [`CHUNK`] columns gets longer chunks, so a mesh of
/// many large triangles needs a bounded work list at any grid (the largest [`MAX_GIANTS`] get
/// records instead, [`GpuListing`]). The host's listing for `encode_surface` shortens
/// triangles to fit [`LIST_BUDGET`], but never below this.
pub const MAX_CHUNKS: u32 = 16384;

/// Chunks the GPU's work list can need for a triangle of at most `columns` columns: chunks of
/// [`CHUNK`], and at most [`MAX_CHUNKS`] (the shader's `chunk_columns` keeps a larger triangle
/// to that many, and never lists more for fewer columns).
pub(super) fn most_chunks(columns: u64) -> u64 {
    columns.div_ceil(CHUNK as u64).min(MAX_CHUNKS as u64)
}

/// Most giant triangles in one surface pass on the GPU (`fieldkit::triangle_box`'s
/// `MAX_GIANTS`): the host marks at most this many, the largest (`mark_giants`).
pub const MAX_GIANTS: u32 = 64;

/// The GPU's list makes no triangle of at most this many columns giant: below it, writing a
/// triangle's entries (at most 1 024) costs its workgroup about a microsecond, less than the
/// giants' pass of its own.
pub const GIANT_MIN_COLUMNS: u32 = 4096;

/// Bytes of the giants' buffer: the dispatch arguments, two counts, padding, then four words
/// per record (`fieldkit::triangle_box`'s `GIANT_HEADER`).
pub(super) const GIANT_BYTES: u64 = 4 * (8 + 4 * MAX_GIANTS as u64);

/// How a surface pass on the GPU takes a mesh's heavy triangles: the entries its work list
/// can need, and how many of the largest are giant (a record and a pass of their own instead
/// of entries): those whose first vertex's w the host set to 1 ..= `giants` ([`mark_giants`]).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuListing {
    pub capacity: u64,
    pub giants: u32,
    /// At least the giants' blocks (the giant pass's workgroups).
    pub blocks: u64,
}

/// At least the blocks of a giant of at most `columns` columns: chunks of at least [`CHUNK`]
/// columns, at most `GIANT_CHUNKS` (2^20) of them, 64 to a block.
pub(super) fn giant_blocks_bound(columns: u64) -> u64 {
    columns.div_ceil(CHUNK as u64).min(1 << 20).div_ceil(64)
}

/// `groups` workgroups in rows of 65535 (the shaders read `num_workgroups`).
pub(super) fn in_rows(groups: u64) -> [u32; 3] {
    [groups.min(65535) as u32, groups.div_ceil(65535) as u32, 1]
}

/// How many of the triangles whose columns (or bounds on them) are `sorted`, most first, are
/// giant: those past the [`MAX_GIANTS`]-plus-first's count and past [`GIANT_MIN_COLUMNS`], so
/// at most `MAX_GIANTS`, the largest first.
pub(super) fn giant_count(sorted: &[u64]) -> usize {
    let threshold = sorted
        .get(MAX_GIANTS as usize)
        .map_or(0, |&c| c)
        .max(GIANT_MIN_COLUMNS as u64);
    sorted.partition_point(|&c| c > threshold)
}

/// Mark the giant triangles `giants` (triangle indices, largest first) for the surface pass:
/// the w of a giant's first vertex is its rank + 1, every other first vertex's 0.
pub(super) fn mark_giants(vertices: &mut [Vec4], giants: &[u32]) {
    for first in vertices.iter_mut().step_by(3) {
        first.w = 0.0;
    }
    for (rank, &t) in giants.iter().enumerate() {
        vertices[3 * t as usize].w = rank as f32 + 1.0;
    }
}

impl GpuListing {
    /// The listing for `local` moved by the identity, from each heavy triangle's box columns,
    /// and its giant triangles, largest first (to [`mark_giants`]).
    pub fn exact(local: &GridMesh, size: [u32; 3]) -> (GpuListing, Vec<u32>) {
        let mut heavy: Vec<(u64, u32)> = local
            .vertices
            .chunks(3)
            .zip(0..)
            .map(|(t, i)| (box_columns(t, size), i))
            .filter(|&(c, _)| c > LIGHT as u64)
            .collect();
        heavy.sort_unstable_by(|a, b| b.cmp(a));
        let columns: Vec<u64> = heavy.iter().map(|&(c, _)| c).collect();
        let giants = giant_count(&columns);
        let listing = GpuListing {
            capacity: columns[giants..].iter().map(|&c| most_chunks(c)).sum(),
            giants: giants as u32,
            blocks: columns[..giants]
                .iter()
                .map(|&c| giant_blocks_bound(c))
                .sum(),
        };
        (listing, heavy[..giants].iter().map(|&(_, t)| t).collect())
    }
}

/// How `encode_surface`/`encode_solid` cut the triangles into threads: a triangle whose box
/// has at most `light` columns is one thread, a heavier one is cut into chunks of `chunk`
/// columns; `sort` orders the light ones by columns, most first; `workgroup` invocations per
/// workgroup. Bench knob: by default [`Listing::auto`] picks per mesh.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Listing {
    pub light: u32,
    pub chunk: u32,
    pub sort: bool,
    pub workgroup: u32,
}

impl Default for Listing {
    fn default() -> Self {
        Self {
            light: LIGHT,
            chunk: CHUNK,
            sort: false,
            workgroup: 64,
        }
    }
}

impl Listing {
    /// Fewer triangles than one wave of a large GPU's threads: the pass takes as long as its
    /// slowest warp, so no thread walks more than 4 columns and the light triangles are sorted
    /// by columns (warps of equal work). More: throughput counts, and cutting more triangles
    /// would repeat their setup; the default. Chosen from the H100 measurements in
    /// docs/voxelize.md.
    pub fn auto(triangles: usize) -> Self {
        if triangles <= 1 << 18 {
            Self {
                light: 4,
                sort: true,
                ..Self::default()
            }
        } else {
            Self::default()
        }
    }
}
