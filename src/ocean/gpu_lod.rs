//! The ocean's patches chosen on the GPU (`ocean/lod`): the quadtree of [`select`](super::select)
//! run in three compute dispatches that leave indirect draws, so a frame's CPU side is a few
//! uniforms and a fixed list of draws whatever the camera sees.
//!
//! The host's share: the height error of each level's spacing at each quad count (a table kept
//! while the waves, the height layers and the settings hold), the frustum planes, and per level
//! the window of nodes that may be visited: a node is visited only where its parent split, and
//! a parent splits only where the eye is nearer its bounds than that level's split radius
//! (`height error × pixels per tangent ÷ max error`), so each level's candidates lie in a
//! rectangle around the eye. The GPU decides every candidate's fate as the CPU walk would.

use std::sync::Mutex;

use glam::{DMat4, DVec2, DVec3, UVec4};

use super::Waves;
use super::lod::{LodSettings, MAX_LOD_NODES, check_select, height_error, planes, reach};
use super::look::Look;
use super::patches::{Patch, patch_indices};
use super::render::OceanCamera;
use crate::bind::{ComputePipeline, KeptBound};
use crate::error::Error;
use crate::gpu::{Recorder, Uploads, kept_buffer, storage_buffer};
use crate::shaders::ocean::lod::{
    self as stage, LodParams, PatchInstance, place_draws, select_patches, write_instances,
};

/// Levels `LodParams::levels` holds: the deepest level allowed (24), the root, and one entry
/// past the last level for the total.
const MAX_LEVELS: usize = 26;
/// Bytes of one `draw_indexed_indirect` argument set.
const DRAW_ARGS: u64 = 20;

/// The pipelines and the buffers kept from frame to frame.
pub(super) struct GpuLod {
    select: ComputePipeline<select_patches::Entry>,
    place: ComputePipeline<place_draws::Entry>,
    write: ComputePipeline<write_instances::Entry>,
    /// The height-error table and what it was made from.
    table: Mutex<Option<(TableKey, Vec<f32>)>>,
    params: Mutex<Option<wgpu::Buffer>>,
    errors: Mutex<Option<wgpu::Buffer>>,
    counts: Mutex<Option<wgpu::Buffer>>,
    cursors: Mutex<Option<wgpu::Buffer>>,
    draws: Mutex<Option<wgpu::Buffer>>,
    leaves: Mutex<Option<wgpu::Buffer>>,
    instances: Mutex<Option<wgpu::Buffer>>,
    /// Every quad count's indices, from the fewest up, for the `patch_quads` they were made for.
    indices: Mutex<Option<(u32, wgpu::Buffer)>>,
    select_bound: KeptBound<select_patches::Entry>,
    place_bound: KeptBound<place_draws::Entry>,
    write_bound: KeptBound<write_instances::Entry>,
}

/// What the height-error table depends on.
struct TableKey {
    waves: Waves,
    height_layers: Vec<super::Layer>,
    size: f64,
    max_depth: u32,
    patch_quads: u32,
}

/// The draws one frame's selection leaves: `count` indirect draws in `draws`, of `instances`
/// with `indices`.
pub(super) struct Chosen {
    pub(super) drawn: LodDraws,
    pub(super) indices: wgpu::Buffer,
}

impl Chosen {
    /// Offset in `draws` of draw `i`'s arguments.
    pub(super) fn offset(i: u32) -> u64 {
        i as u64 * DRAW_ARGS
    }
}

/// What [`OceanRenderer::encode_lod`](super::OceanRenderer::encode_lod) drew from on the GPU,
/// to read back and see which patches it chose ([`LodDraws::patches`]).
#[derive(Clone, Debug)]
pub struct LodDraws {
    /// The patches' instances, 32 bytes each: the square's smallest (x, z) corner then its
    /// largest, relative to `origin` (four f32), then its quads (four u32, the first used).
    pub instances: wgpu::Buffer,
    /// `draw_indexed_indirect` arguments, 5 u32 a draw: one draw of grids per quad count from
    /// `fewest_quads` up, then one draw of skirts per quad count and edge (the edge order of
    /// [`Patch::skirts`](super::Patch::skirts)). The instance count is the second word, the
    /// first instance the fifth.
    pub draws: wgpu::Buffer,
    /// Draws in `draws`.
    pub draw_count: u32,
    /// The fewest quads a patch is drawn with.
    pub fewest_quads: u32,
    /// The eye's world (x, z), which the instances are relative to.
    pub origin: DVec2,
}

impl LodDraws {
    /// The patches drawn, from the bytes of [`Self::draws`] and [`Self::instances`] read back,
    /// in the order of the grid draws.
    pub fn patches(&self, draws: &[u8], instances: &[u8]) -> Vec<Patch> {
        let words: &[u32] = bytemuck::cast_slice(draws);
        let squares: &[[f32; 8]] = bytemuck::cast_slice(instances);
        let quad_counts = self.draw_count / 5;
        let mut out: Vec<Patch> = Vec::new();
        let mut at = std::collections::HashMap::new();
        for d in 0..self.draw_count {
            let args = &words[5 * d as usize..5 * d as usize + 5];
            let (count, first) = (args[1] as usize, args[4] as usize);
            for sq in &squares[first..first + count] {
                let key: [u32; 4] = bytemuck::cast([sq[0], sq[1], sq[2], sq[3]]);
                if d < quad_counts {
                    at.insert(key, out.len());
                    out.push(Patch {
                        corner: self.origin + DVec2::new(sq[0] as f64, sq[1] as f64),
                        size: (sq[2] - sq[0]) as f64,
                        quads: sq[4].to_bits(),
                        skirts: 0,
                    });
                } else if let Some(&i) = at.get(&key) {
                    out[i].skirts |= 1 << ((d - quad_counts) % 4);
                }
            }
        }
        out
    }
}

/// Whether `device` can draw the GPU's selection: the draws start at the instance the GPU
/// wrote, which indirect draws take only with [`wgpu::Features::INDIRECT_FIRST_INSTANCE`].
pub(super) fn supported(device: &wgpu::Device) -> bool {
    device
        .features()
        .contains(wgpu::Features::INDIRECT_FIRST_INSTANCE)
}

/// The fewest quads a patch is drawn with (half of `patch_quads`, rounded up).
fn fewest_quads(patch_quads: u32) -> u32 {
    patch_quads.div_ceil(2)
}

impl GpuLod {
    pub(super) fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            select: ComputePipeline::new(device)?,
            place: ComputePipeline::new(device)?,
            write: ComputePipeline::new(device)?,
            table: Mutex::new(None),
            params: Mutex::new(None),
            errors: Mutex::new(None),
            counts: Mutex::new(None),
            cursors: Mutex::new(None),
            draws: Mutex::new(None),
            leaves: Mutex::new(None),
            instances: Mutex::new(None),
            indices: Mutex::new(None),
            select_bound: KeptBound::default(),
            place_bound: KeptBound::default(),
            write_bound: KeptBound::default(),
        })
    }

    /// Record the selection for `camera` (a viewport `viewport_height` pixels high) into `rec`:
    /// the draws it leaves for the render pass that follows.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut Recorder<'_>,
        uploads: &Uploads,
        waves: &Waves,
        look: &Look,
        camera: &OceanCamera,
        viewport_height: u32,
        settings: &LodSettings,
    ) -> Result<Chosen, Error> {
        check_select(camera, viewport_height, settings)?;
        let (params, table) = self.params(waves, look, camera, viewport_height, settings)?;
        let draw_count = 5 * (settings.patch_quads - params.fewest_quads + 1);
        let buffers = self.buffers(device, draw_count, params.invocations);
        let enc = &mut *rec.encoder;
        let params_buffer = uploads.uniform(device, enc, &self.params, "ocean lod params", &params);
        let errors = uploads.kept(
            device,
            enc,
            &self.errors,
            "ocean lod errors",
            wgpu::BufferUsages::STORAGE,
            bytemuck::cast_slice(&table),
        );
        let select = self.select.bind_kept(
            device,
            &self.select_bound,
            &select_patches::Resources {
                params: (&params_buffer).into(),
                errors: (&errors).into(),
                counts: (&buffers.counts).into(),
                leaves: (&buffers.leaves).into(),
            },
        )?;
        let place = self.place.bind_kept(
            device,
            &self.place_bound,
            &place_draws::Resources {
                params: (&params_buffer).into(),
                counts: (&buffers.counts).into(),
                cursors: (&buffers.cursors).into(),
                draws: (&buffers.draws).into(),
            },
        )?;
        let write = self.write.bind_kept(
            device,
            &self.write_bound,
            &write_instances::Resources {
                params: (&params_buffer).into(),
                leaves: (&buffers.leaves).into(),
                cursors: (&buffers.cursors).into(),
                instances: (&buffers.instances).into(),
            },
        )?;
        let mut pass = rec.compute_pass(stage::STAGE, "ocean lod");
        let groups =
            ComputePipeline::<select_patches::Entry>::groups_for([params.invocations, 1, 1]);
        self.select.dispatch(&mut pass, &select, groups);
        self.place.dispatch(&mut pass, &place, [1, 1, 1]);
        pass.set_pipeline(&self.write.pipeline);
        write.set_compute(&mut pass);
        pass.dispatch_workgroups_indirect(&buffers.draws, Chosen::offset(draw_count));
        drop(pass);
        Ok(Chosen {
            drawn: LodDraws {
                instances: buffers.instances,
                draws: buffers.draws,
                draw_count,
                fewest_quads: params.fewest_quads,
                origin: DVec2::new(camera.eye().x, camera.eye().z),
            },
            indices: self.indices(device, settings.patch_quads),
        })
    }

    /// The frame's parameters and the height-error table.
    fn params(
        &self,
        waves: &Waves,
        look: &Look,
        camera: &OceanCamera,
        viewport_height: u32,
        settings: &LodSettings,
    ) -> Result<(LodParams, Vec<f32>), Error> {
        let s = settings;
        let table = self.table(waves, look, s);
        let eye = camera.eye();
        let proj = camera.proj.as_dmat4();
        // Positions relative to the eye's (x, z), as the surface draws them.
        let shift = DMat4::from_translation(DVec3::new(eye.x, 0.0, eye.z));
        let frustum = planes(proj * camera.view * shift);
        let px_per_tan = 0.5 * viewport_height as f64 * proj.y_axis.y.abs();
        let (sideways, up) = reach(waves, look);
        let origin = s.centre - DVec2::splat(s.size / 2.0) - DVec2::new(eye.x, eye.z);
        let fewest = fewest_quads(s.patch_quads);
        let per_depth = (s.patch_quads - fewest + 1) as usize;
        // A node at depth d splits where the eye is nearer its bounds than this.
        let split_radius = |d: u32| {
            table[d as usize * per_depth + per_depth - 1] as f64 * px_per_tan / s.max_error_px
        };
        let (levels, invocations) = windows(s, origin, sideways, split_radius)?;
        let params = LodParams {
            planes: frustum.map(|p| p.as_vec4()),
            levels,
            origin: origin.as_vec2(),
            size: s.size as f32,
            eye_y: eye.y as f32,
            sideways: sideways as f32,
            low: (-up - look.skirt as f64) as f32,
            up: up as f32,
            px_per_tan: px_per_tan as f32,
            max_error_px: s.max_error_px as f32,
            max_depth: s.max_depth,
            patch_quads: s.patch_quads,
            fewest_quads: fewest,
            invocations,
        };
        Ok((params, table))
    }

    /// [`height_error`] of every level's spacing at every quad count the settings draw with,
    /// per depth then quad count; kept while its inputs hold (compared in place: a frame
    /// allocates nothing for it).
    fn table(&self, waves: &Waves, look: &Look, s: &LodSettings) -> Vec<f32> {
        let mut kept = self.table.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((k, t)) = kept.as_ref()
            && k.waves == *waves
            && k.height_layers == look.height_layers
            && (k.size, k.max_depth, k.patch_quads) == (s.size, s.max_depth, s.patch_quads)
        {
            return t.clone();
        }
        let fewest = fewest_quads(s.patch_quads);
        let table: Vec<f32> = (0..=s.max_depth)
            .flat_map(|d| {
                let side = s.size / (1u64 << d) as f64;
                (fewest..=s.patch_quads)
                    .map(move |q| height_error(waves, look, side / q as f64) as f32)
            })
            .collect();
        let key = TableKey {
            waves: waves.clone(),
            height_layers: look.height_layers.clone(),
            size: s.size,
            max_depth: s.max_depth,
            patch_quads: s.patch_quads,
        };
        *kept = Some((key, table.clone()));
        table
    }

    /// The buffers the three dispatches share, kept while they are large enough.
    fn buffers(&self, device: &wgpu::Device, draw_count: u32, invocations: u32) -> Buffers {
        let words = |n: u32| (n as u64 + 1) * 4;
        let make = |label: &'static str, bytes: u64, extra: wgpu::BufferUsages| {
            move || storage_buffer(device, label, bytes, extra)
        };
        let none = wgpu::BufferUsages::empty();
        // What `LodDraws` hands out can be read back.
        let readable = wgpu::BufferUsages::COPY_SRC;
        // Counts and cursors are sized exactly: `place_draws` zeroes the counts for the next
        // frame, and a new buffer starts at zero.
        let counts = words(draw_count);
        let draws = Chosen::offset(draw_count) + 12;
        // At most every candidate a leaf, each drawn as a grid and four skirts; room to grow.
        let leaves = (invocations.max(1) as u64 * 16).next_power_of_two();
        let instances = leaves / 16 * 5 * std::mem::size_of::<PatchInstance>() as u64;
        Buffers {
            counts: kept_buffer(
                &self.counts,
                counts,
                true,
                make("ocean lod counts", counts, none),
            ),
            cursors: kept_buffer(
                &self.cursors,
                counts,
                true,
                make("ocean lod cursors", counts, none),
            ),
            draws: kept_buffer(
                &self.draws,
                draws,
                true,
                make(
                    "ocean lod draws",
                    draws,
                    readable | wgpu::BufferUsages::INDIRECT,
                ),
            ),
            leaves: kept_buffer(
                &self.leaves,
                leaves,
                false,
                make("ocean lod leaves", leaves, none),
            ),
            instances: kept_buffer(
                &self.instances,
                instances,
                false,
                make(
                    "ocean lod instances",
                    instances,
                    readable | wgpu::BufferUsages::VERTEX,
                ),
            ),
        }
    }

    /// The index lists of every quad count from the fewest to `patch_quads`, one after another
    /// (the order `place_draws` counts them in), made once for each `patch_quads`.
    fn indices(&self, device: &wgpu::Device, patch_quads: u32) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        let mut kept = self.indices.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((q, b)) = kept.as_ref()
            && *q == patch_quads
        {
            return b.clone();
        }
        let all: Vec<u32> = (fewest_quads(patch_quads)..=patch_quads)
            .flat_map(patch_indices)
            .collect();
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ocean lod indices"),
            contents: bytemuck::cast_slice(&all),
            usage: wgpu::BufferUsages::INDEX,
        });
        *kept = Some((patch_quads, buffer.clone()));
        buffer
    }
}

struct Buffers {
    counts: wgpu::Buffer,
    cursors: wgpu::Buffer,
    draws: wgpu::Buffer,
    leaves: wgpu::Buffer,
    instances: wgpu::Buffer,
}

/// Per level, the window of nodes that may be visited, as `LodParams::levels` holds it: first
/// node (i, j), columns, first invocation; the total after the last level. A node at depth
/// d ≥ 1 is visited only where its parent split, and the parent split only where the eye's
/// horizontal distance to its bounds (grown by `sideways`) is below `split_radius(d − 1)`; a
/// node more is taken on each side for the GPU's f32 distances.
fn windows(
    s: &LodSettings,
    origin: DVec2,
    sideways: f64,
    split_radius: impl Fn(u32) -> f64,
) -> Result<([UVec4; MAX_LEVELS], u32), Error> {
    let mut levels = [UVec4::ZERO; MAX_LEVELS];
    let mut first = 0u64;
    for d in 0..=s.max_depth {
        let (lo, hi) = if d == 0 {
            ([0i64; 2], [0i64; 2])
        } else {
            let parents = 1i64 << (d - 1);
            let side = s.size / parents as f64;
            let r = split_radius(d - 1) + sideways;
            let range = |o: f64| {
                let lo = (((-r - side - o) / side).floor() as i64 - 1).max(0);
                let hi = (((r - o) / side).ceil() as i64 + 1).min(parents - 1);
                (2 * lo, 2 * hi + 1)
            };
            let ((i0, i1), (j0, j1)) = (range(origin.x), range(origin.y));
            ([i0, j0], [i1, j1])
        };
        let cols = (hi[0] - lo[0] + 1).max(0) as u64;
        let rows = (hi[1] - lo[1] + 1).max(0) as u64;
        levels[d as usize] = UVec4::new(
            lo[0].max(0) as u32,
            lo[1].max(0) as u32,
            cols.max(1) as u32,
            first.min(u32::MAX as u64) as u32,
        );
        first += cols * rows;
        if first > MAX_LOD_NODES {
            return Err(Error::Size {
                stage: stage::STAGE,
                what: "quadtree nodes a frame may visit (raise max_error_px or lower max_depth)",
                got: first,
                max: MAX_LOD_NODES,
            });
        }
    }
    for l in &mut levels[s.max_depth as usize + 1..] {
        l.w = first as u32;
    }
    Ok((levels, first as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every node the CPU walk visits lies in its level's window.
    #[test]
    fn windows_hold_every_visited_node() {
        let s = LodSettings::default();
        // Splits out to 300 m at the root, 40 at depth 3, nothing below 6.
        let radius = |d: u32| if d < 6 { 300.0 / (1 << d) as f64 } else { 0.0 };
        let origin = DVec2::new(-1000.0, -1500.0);
        let (levels, total) = windows(&s, origin, 2.0, radius).unwrap();
        assert_eq!(levels[0], UVec4::new(0, 0, 1, 0));
        assert_eq!(levels[s.max_depth as usize + 1].w, total);
        // Below depth 7 the radius is 0: no parent splits, nothing to look for.
        for d in 1..=7 {
            let side = s.size / (1u64 << (d - 1)) as f64;
            let n = 1u32 << (d - 1);
            let l = levels[d as usize];
            let rows = (levels[d as usize + 1].w - l.w) / l.z;
            for pi in 0..n {
                for pj in 0..n {
                    let corner = origin + DVec2::new(pi as f64, pj as f64) * side;
                    let lo = corner - DVec2::splat(2.0);
                    let hi = corner + DVec2::splat(side + 2.0);
                    let near = DVec2::ZERO.clamp(lo, hi).length();
                    if near < radius(d - 1) {
                        for (a, b) in [(0, 0), (1, 1)] {
                            let (i, j) = (2 * pi + a, 2 * pj + b);
                            assert!(
                                i >= l.x && i < l.x + l.z && j >= l.y && j < l.y + rows,
                                "depth {d}: node ({i}, {j}) outside {l:?} ({rows} rows)"
                            );
                        }
                    }
                }
            }
        }
    }
}
