//! The patches the ocean draws: a square of grid with its skirts ([`Patch`]), the index list
//! of a patch of n quads, and how a frame's patches become draws (listed on the CPU, grouped by
//! quad count with the skirts last, or the GPU's indirect draws).

use glam::DVec2;

use super::gpu_lod::Chosen;
use crate::shaders::ocean::surface as stage;

/// Quads per side of a patch made with [`Patch::new`].
pub const PATCH_QUADS: u32 = 64;

/// A square of ocean to draw: its world corner (x, z, smallest) and side, in metres, its
/// grid's quads per side (1 to [`MAX_PATCH_QUADS`]; `ocean::lod` picks the fewest that keep
/// its error), and which of its edges hang a skirt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Patch {
    /// World corner (x, z) at the smallest x and z, metres.
    pub corner: DVec2,
    /// Side, metres.
    pub size: f64,
    /// Grid quads per side.
    pub quads: u32,
    /// Edges with a skirt, one bit each: 1 the edge at the smallest z, 2 the largest x, 4 the
    /// largest z, 8 the smallest x (higher bits are ignored). A skirt hides the crack beside a
    /// patch of another vertex spacing; two patches of the same size and quads meet without one.
    pub skirts: u8,
}

/// Every edge of a patch: [`Patch::skirts`].
pub const ALL_SKIRTS: u8 = 0b1111;

impl Patch {
    /// A patch of [`PATCH_QUADS`] quads per side, skirted on every edge.
    pub fn new(corner: DVec2, size: f64) -> Self {
        Self {
            corner,
            size,
            quads: PATCH_QUADS,
            skirts: ALL_SKIRTS,
        }
    }

    /// The same patch with `quads` per side.
    pub fn with_quads(self, quads: u32) -> Self {
        Self { quads, ..self }
    }

    /// Triangles it draws: its grid and its skirts.
    pub fn triangles(&self) -> u64 {
        let n = self.quads as u64;
        2 * n * n + 2 * n * (self.skirts & ALL_SKIRTS).count_ones() as u64
    }
}

/// Most quads per patch side.
pub const MAX_PATCH_QUADS: u32 = 256;

/// Triangle indices of one patch: (n + 1)² grid vertices, x fastest, then the skirt ring under
/// the edges z = 0, x = n, z = n, x = 0 (as `patch_vertex` numbers them).
pub fn patch_indices(n: u32) -> Vec<u32> {
    let row = n + 1;
    let mut out = Vec::with_capacity((6 * n * n + 24 * n) as usize);
    // Columns of STRIP quads, row by row, so a row's lower vertices are still in the GPU's
    // post-transform cache when the next row uses them as its upper ones.
    const STRIP: u32 = 8;
    for i0 in (0..n).step_by(STRIP as usize) {
        for j in 0..n {
            for i in i0..(i0 + STRIP).min(n) {
                let a = j * row + i;
                let (b, c, d) = (a + 1, a + row, a + row + 1);
                out.extend_from_slice(&[a, c, b, b, c, d]);
            }
        }
    }
    let grid = |i: u32, j: u32| j * row + i;
    let skirt_base = row * row;
    for edge in 0..4u32 {
        for t in 0..n {
            let (g0, g1) = match edge {
                0 => (grid(t, 0), grid(t + 1, 0)),
                1 => (grid(n, t), grid(n, t + 1)),
                2 => (grid(t, n), grid(t + 1, n)),
                _ => (grid(0, t), grid(0, t + 1)),
            };
            let s0 = skirt_base + edge * row + t;
            out.extend_from_slice(&[g0, s0, g1, g1, s0, s0 + 1]);
        }
    }
    out
}

/// The patches' draws: listed on the CPU (an index buffer, index range and instance range
/// each), or left by the GPU's selection as indirect draws.
pub(super) enum Draws<'a> {
    Listed(&'a [(wgpu::Buffer, std::ops::Range<u32>, std::ops::Range<u32>)]),
    Indirect(&'a Chosen),
}

impl Draws<'_> {
    pub(super) fn record(&self, pass: &mut wgpu::RenderPass<'_>) {
        match self {
            Draws::Listed(parts) => {
                for (indices, part, range) in parts.iter() {
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(part.clone(), 0, range.clone());
                }
            }
            Draws::Indirect(chosen) => {
                pass.set_index_buffer(chosen.indices.slice(..), wgpu::IndexFormat::Uint32);
                // One command for every draw (a loop of draws where the backend has no
                // multi-draw).
                pass.multi_draw_indexed_indirect(&chosen.drawn.draws, 0, chosen.drawn.draw_count);
            }
        }
    }
}

/// One draw of patches: (quads, first index, index count, instances).
pub(super) type PatchDraw = (u32, u32, u32, std::ops::Range<u32>);

/// The patches' instances and draws: grouped by quad count, one draw of the grids per group
/// (within a group nearest first still), then, after every grid, one draw per group and edge
/// of the skirts that edge needs: the same patches again, listed after the grids. Corners
/// relative to `origin`. The skirts come last so that the depth test drops every skirt
/// fragment a grid covers before it is shaded: drawn after each group's own grids instead,
/// the skirts took 1.19 of the 3.14 ms the viewer's ocean pass took at 1080p on the H200, and
/// last they take 0.17 of 2.15 ms (`docs/bench/frame_ocean_skirts_h200.csv`).
pub(super) fn patch_draws(
    patches: &[Patch],
    origin: DVec2,
) -> (Vec<stage::fs_forward::Instance>, Vec<PatchDraw>) {
    let mut order: Vec<usize> = (0..patches.len()).collect();
    order.sort_by_key(|&i| patches[i].quads);
    let instance = |p: &Patch| {
        // Both corners from f64, so neighbours share their edge's f32 values exactly.
        let lo = p.corner - origin;
        let hi = p.corner + DVec2::splat(p.size) - origin;
        stage::fs_forward::Instance {
            instance_patch: [lo.x as f32, lo.y as f32, hi.x as f32, hi.y as f32],
            instance_quads: [p.quads, 0, 0, 0],
        }
    };
    let mut instances: Vec<stage::fs_forward::Instance> =
        order.iter().map(|&i| instance(&patches[i])).collect();
    // (quads, first index, index count, instances)
    let (mut draws, mut skirts): (Vec<PatchDraw>, Vec<PatchDraw>) = (Vec::new(), Vec::new());
    let mut start = 0;
    while start < order.len() {
        let q = patches[order[start]].quads;
        let end = start
            + order[start..]
                .iter()
                .take_while(|&&i| patches[i].quads == q)
                .count();
        draws.push((q, 0, 6 * q * q, start as u32..end as u32));
        for edge in 0..4u32 {
            let first = instances.len() as u32;
            instances.extend(
                order[start..end]
                    .iter()
                    .filter(|&&i| patches[i].skirts & (1 << edge) != 0)
                    .map(|&i| instance(&patches[i])),
            );
            let last = instances.len() as u32;
            if last > first {
                skirts.push((q, 6 * q * q + edge * 6 * q, 6 * q, first..last));
            }
        }
        start = end;
    }
    draws.extend(skirts);
    (instances, draws)
}
