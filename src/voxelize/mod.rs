//! Mesh voxelization (`shaders/voxelize/`): conservative surface voxels of a triangle mesh in an
//! occupancy bitset, exact against the 13-axis separating-axis test ([`cpu::conservative`]).
//!
//! Meshes come in world units and are moved into grid-local coordinates (origin 0, voxels of
//! edge 1) on the CPU in f64 before they are rounded to f32, so a mesh 100 km from the origin
//! voxelizes as well as one at it.
//!
//! ```
//! # fn f(ctx: &fieldkit::gpu::Context) -> Result<(), fieldkit::Error> {
//! use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
//! use glam::DVec3;
//! let mesh = Mesh::uv_sphere(DVec3::new(0.1, 0.2, -0.3), 1.0, 24, 12);
//! let grid = Grid { origin: DVec3::splat(-1.5), voxel: 3.0 / 32.0, size: [32, 32, 32] };
//! let v = Voxelizer::new(&ctx.device)?;
//! let mut encoder = ctx.encoder("voxelize");
//! let surface = v.encode_surface(&ctx.device, &mut encoder, &mesh, &grid)?;
//! ctx.submit_and_wait("voxelize", encoder)?;
//! let occupied = surface.read(&ctx.device, &ctx.queue).wait(ctx)?; // one bool per voxel, x fastest
//! # let _ = occupied; Ok(()) }
//! ```
//!
#![doc = include_str!("../../docs/voxelize.md")]

mod attributes;
pub mod cpu;
pub mod export;
mod fragments;
mod obj;
mod placed;
mod view;

pub use view::{ColourBy, Light, VoxelView};

pub use attributes::{
    AttributeVolumes, Attributes, PendingAttributes, VoxelAttributes, occupied_bound,
};
pub use fragments::{FragmentAttributes, Fragments, fragment_estimate};
pub use placed::GpuMesh;

use glam::{DVec3, Vec4};

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Readback, Record, readback_buffer, uniform_buffer as uniform};
use crate::shaders::voxelize::occupancy_volume::{self as volume_stage, VolumeParams};
use crate::shaders::voxelize::raster::{self as raster_stage, RasterParams};
use crate::shaders::voxelize::solid::{self as solid_stage, SolidParams};
use crate::shaders::voxelize::surface::{self as stage, SurfaceParams};

const STAGE: &str = stage::STAGE;

/// Largest side of a voxel grid.
pub const MAX_SIDE: u32 = 4096;

/// Most voxels in a grid: the shaders index voxels with u32.
pub const MAX_VOXELS: u64 = 1 << 32;

/// Largest side of a grid that is never held densely (voxel fragments, the octree): 2¹³, as
/// fragments store a coordinate in 16 bits and the octree's levels stay within 13.
pub const MAX_SPARSE_SIDE: u32 = 8192;

/// Relative slack on the GPU's tests: a few f32 ulp, so rounding only ever adds voxels within
/// about this fraction of the coordinates' size.
pub const SLACK: f32 = 4.0 * f32::EPSILON;

/// A triangle mesh in world units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Counter-clockwise triangles (outward normals), indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex RGBA8 colours, or empty (white) when the mesh has none.
    pub colors: Vec<[u8; 4]>,
    /// Per-vertex normals, or empty when the mesh has none (each triangle's own normal is
    /// used). Need not be unit length.
    pub normals: Vec<DVec3>,
    /// Texture coordinates per triangle corner (one `[uv; 3]` per triangle, as OBJ files give
    /// them, seams included), or empty. OBJ's convention: v up, so an albedo image with its
    /// first row at the top is sampled at (u, 1 − v).
    pub texcoords: Vec<[glam::Vec2; 3]>,
}

/// Where the voxels are: the world position of voxel (0, 0, 0)'s min corner, the voxel edge and
/// the number of voxels per axis.
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
    /// Voxels in the grid.
    pub fn voxels(&self) -> u64 {
        self.size.iter().map(|&n| n as u64).product()
    }

    /// A cube-voxel grid of about `n` voxels along the mesh's longest side, fitted to its
    /// bounds with one voxel of margin on each side. An empty mesh, a non-finite position, a
    /// mesh with no extent or `n` below 3 is refused ([`Error::Invalid`]).
    pub fn fit(mesh: &Mesh, n: u32) -> Result<Grid, Error> {
        if mesh.positions.is_empty() {
            return Err(Error::invalid(STAGE, "cannot fit a grid to an empty mesh"));
        }
        if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::invalid(
                STAGE,
                format!("vertex {i} is {}", mesh.positions[i]),
            ));
        }
        if n < 3 {
            // Not `Error::Size`, whose message says "between 1 and …": 1 and 2 are refused too.
            return Err(Error::invalid(
                STAGE,
                format!(
                    "a fitted grid needs at least 3 voxels along the longest side (the mesh and one \
                 voxel of margin each side), not {n}"
                ),
            ));
        }
        let lo = mesh
            .positions
            .iter()
            .fold(DVec3::splat(f64::MAX), |a, &p| a.min(p));
        let hi = mesh
            .positions
            .iter()
            .fold(DVec3::splat(f64::MIN), |a, &p| a.max(p));
        let extent = (hi - lo).max_element();
        if extent <= 0.0 {
            return Err(Error::invalid(
                STAGE,
                format!("the mesh has no extent (every vertex at {lo})"),
            ));
        }
        let voxel = extent / (n - 2) as f64;
        // Saturating: with n near u32::MAX the side plus margin would overflow.
        let size = ((hi - lo) / voxel)
            .ceil()
            .as_uvec3()
            .saturating_add(glam::UVec3::splat(2));
        Ok(Grid {
            origin: lo - DVec3::splat(voxel),
            voxel,
            size: size
                .min(glam::UVec3::splat(n))
                .max(glam::UVec3::ONE)
                .to_array(),
        })
    }
}

/// A mesh moved into a grid's local coordinates and rounded to f32, as the GPU sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct GridMesh {
    /// Three vertices per triangle (w = 0), zero-area triangles left out.
    pub vertices: Vec<Vec4>,
    /// Triangles left out for having no area (after rounding).
    pub degenerate: usize,
    /// For each triangle kept, its index in the mesh.
    pub source: Vec<u32>,
}

impl Mesh {
    /// A closed UV sphere (for tests and examples): `segments` around, `rings` from pole to
    /// pole, one vertex at each pole, triangles facing out.
    pub fn uv_sphere(centre: DVec3, radius: f64, segments: u32, rings: u32) -> Self {
        let point = |theta: f64, phi: f64| {
            centre
                + radius
                    * DVec3::new(
                        theta.sin() * phi.cos(),
                        theta.cos(),
                        theta.sin() * phi.sin(),
                    )
        };
        let mut positions = vec![point(0.0, 0.0)];
        for r in 1..rings {
            let theta = std::f64::consts::PI * r as f64 / rings as f64;
            for s in 0..segments {
                positions.push(point(
                    theta,
                    std::f64::consts::TAU * s as f64 / segments as f64,
                ));
            }
        }
        let south = positions.len() as u32;
        positions.push(point(std::f64::consts::PI, 0.0));
        let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
        let mut triangles = Vec::new();
        for s in 0..segments {
            triangles.push([0, at(1, s + 1), at(1, s)]);
            triangles.push([south, at(rings - 1, s), at(rings - 1, s + 1)]);
        }
        for r in 1..rings - 1 {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                triangles.push([a, b, c]);
                triangles.push([b, d, c]);
            }
        }
        Self {
            positions,
            triangles,
            ..Self::default()
        }
    }

    /// A torus around the y axis through `centre` (for tests and examples): tube radius
    /// `minor` around a circle of radius `major`.
    pub fn torus(centre: DVec3, major: f64, minor: f64, segments: u32, sides: u32) -> Self {
        let mut positions = Vec::new();
        for s in 0..segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            for k in 0..sides {
                let theta = std::f64::consts::TAU * k as f64 / sides as f64;
                let r = major + minor * theta.cos();
                positions
                    .push(centre + DVec3::new(r * phi.cos(), minor * theta.sin(), r * phi.sin()));
            }
        }
        let at = |s: u32, k: u32| (s % segments) * sides + k % sides;
        let mut triangles = Vec::new();
        for s in 0..segments {
            for k in 0..sides {
                let (a, b, c, d) = (at(s, k), at(s + 1, k), at(s, k + 1), at(s + 1, k + 1));
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        Self {
            positions,
            triangles,
            ..Self::default()
        }
    }

    /// An axis-aligned box from `lo` to `hi` (for tests and examples): 8 vertices, vertex i at
    /// (x of bit 0, y of bit 1, z of bit 2), 12 triangles facing out.
    pub fn cuboid(lo: DVec3, hi: DVec3) -> Self {
        let pick = |bit: bool, a: f64, b: f64| if bit { b } else { a };
        Self {
            positions: (0..8)
                .map(|i| {
                    DVec3::new(
                        pick(i & 1 != 0, lo.x, hi.x),
                        pick(i & 2 != 0, lo.y, hi.y),
                        pick(i & 4 != 0, lo.z, hi.z),
                    )
                })
                .collect(),
            triangles: vec![
                [0, 2, 1],
                [1, 2, 3],
                [4, 5, 6],
                [5, 7, 6],
                [0, 1, 4],
                [1, 5, 4],
                [2, 6, 3],
                [3, 6, 7],
                [0, 4, 2],
                [2, 4, 6],
                [1, 3, 5],
                [3, 7, 5],
            ],
            ..Self::default()
        }
    }

    /// Every triangle split into four at its edges' midpoints: the same surface with four
    /// times the triangles (colours and normals interpolated too). Midpoints are shared
    /// between neighbours, so a closed mesh stays closed.
    pub fn subdivided(&self) -> Self {
        let mut out = self.clone();
        let mut midpoints = std::collections::HashMap::<(u32, u32), u32>::new();
        let mut midpoint = |a: u32, b: u32, out: &mut Mesh| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (i, j) = (a as usize, b as usize);
                out.positions
                    .push((self.positions[i] + self.positions[j]) * 0.5);
                if !self.colors.is_empty() {
                    let (ci, cj) = (self.colors[i], self.colors[j]);
                    out.colors.push(std::array::from_fn(|k| {
                        (ci[k] as u16 + cj[k] as u16).div_ceil(2) as u8
                    }));
                }
                if !self.normals.is_empty() {
                    out.normals.push(self.normals[i] + self.normals[j]);
                }
                out.positions.len() as u32 - 1
            })
        };
        out.triangles = Vec::with_capacity(self.triangles.len() * 4);
        for &[a, b, c] in &self.triangles {
            let ab = midpoint(a, b, &mut out);
            let bc = midpoint(b, c, &mut out);
            let ca = midpoint(c, a, &mut out);
            out.triangles
                .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        out
    }

    /// Whether every edge is shared by exactly two triangles that run along it in opposite
    /// directions (closed and consistently oriented): what solid voxelization needs. Returns
    /// the first offending edge otherwise.
    pub fn open_edge(&self) -> Option<[u32; 2]> {
        let mut uses = std::collections::HashMap::<(u32, u32), i32>::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *uses.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { 1 << 8 };
            }
        }
        let mut bad: Vec<_> = uses
            .into_iter()
            .filter(|&(_, n)| n != 1 + (1 << 8))
            .collect();
        bad.sort();
        bad.first().map(|&((a, b), _)| [a, b])
    }

    /// Volume enclosed by a closed mesh (divergence theorem), in world units cubed; positive
    /// for outward-facing triangles.
    pub fn volume(&self) -> f64 {
        self.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// The mesh placed by `model` (any affine, invertible transform: rotation, scale,
    /// translation): positions transformed, normals by the inverse transpose, triangles
    /// reversed where `model` mirrors so they stay counter-clockwise.
    pub fn transformed(&self, model: glam::DMat4) -> Result<Mesh, Error> {
        let det = check_model(model)?;
        let normal = glam::DMat3::from_mat4(model).inverse().transpose();
        let mut out = self.clone();
        out.positions = self
            .positions
            .iter()
            .map(|&p| model.transform_point3(p))
            .collect();
        out.normals = self.normals.iter().map(|&n| normal * n).collect();
        if det < 0.0 {
            for t in &mut out.triangles {
                t.swap(1, 2);
            }
            for c in &mut out.texcoords {
                c.swap(1, 2);
            }
        }
        Ok(out)
    }

    /// Several meshes, each placed by its model matrix, as one mesh to voxelize into one grid
    /// in one pass. Colours, normals and texture coordinates are kept where every part has
    /// them; where some part lacks colours it is white, texture coordinates (0, 0), and where
    /// some part lacks normals every triangle uses its own.
    pub fn combined(parts: &[(&Mesh, glam::DMat4)]) -> Result<Mesh, Error> {
        let placed: Vec<Mesh> = parts
            .iter()
            .map(|(m, model)| m.transformed(*model))
            .collect::<Result<_, _>>()?;
        let any_colour = placed.iter().any(|m| !m.colors.is_empty());
        let all_normals = placed.iter().all(|m| !m.normals.is_empty());
        let any_uv = placed.iter().any(|m| !m.texcoords.is_empty());
        let mut out = Mesh::default();
        for m in &placed {
            let base = u32::try_from(out.positions.len())
                .map_err(|_| Error::invalid(STAGE, "more than 2³² vertices in all"))?;
            out.positions.extend(&m.positions);
            out.triangles
                .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
            if any_colour {
                if m.colors.is_empty() {
                    out.colors
                        .extend(std::iter::repeat_n([255; 4], m.positions.len()));
                } else {
                    out.colors.extend(&m.colors);
                }
            }
            if all_normals {
                out.normals.extend(&m.normals);
            }
            if any_uv {
                if m.texcoords.is_empty() {
                    out.texcoords.extend(std::iter::repeat_n(
                        [glam::Vec2::ZERO; 3],
                        m.triangles.len(),
                    ));
                } else {
                    out.texcoords.extend(&m.texcoords);
                }
            }
        }
        Ok(out)
    }

    /// Check the mesh and move it into `grid`'s local coordinates in f64, then round to f32.
    pub fn to_grid(&self, grid: &Grid) -> Result<GridMesh, Error> {
        check_grid(grid)?;
        self.local(grid)
    }

    /// [`Mesh::to_grid`] for a grid that is never held densely ([`Voxelizer::encode_fragments`]
    /// and the octree): sides up to [`MAX_SPARSE_SIDE`], any number of voxels.
    pub fn to_sparse_grid(&self, grid: &Grid) -> Result<GridMesh, Error> {
        check_sides(grid, MAX_SPARSE_SIDE)?;
        self.local(grid)
    }

    fn local(&self, grid: &Grid) -> Result<GridMesh, Error> {
        self.check()?;
        let mut vertices = Vec::with_capacity(self.triangles.len() * 3);
        let mut degenerate = 0;
        let mut source = Vec::with_capacity(self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            let v =
                tri.map(|i| ((self.positions[i as usize] - grid.origin) / grid.voxel).as_vec3());
            if (v[1] - v[0]).cross(v[2] - v[0]).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            vertices.extend(v.iter().map(|p| p.extend(0.0)));
            source.push(t as u32);
        }
        Ok(GridMesh {
            vertices,
            degenerate,
            source,
        })
    }

    /// A mesh the voxelizer can take: triangles, finite positions, indices in range.
    fn check(&self) -> Result<(), Error> {
        if self.triangles.is_empty() {
            return Err(Error::Size {
                stage: STAGE,
                what: "number of triangles",
                got: 0,
                max: u32::MAX as u64 / 3,
            });
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::invalid(
                STAGE,
                format!("vertex {i} is not finite: {}", self.positions[i]),
            ));
        }
        let n = u32::try_from(self.positions.len()).unwrap_or(u32::MAX);
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i >= n) {
                return Err(Error::invalid(
                    STAGE,
                    format!("triangle {t} names vertex {bad}, the mesh has {n}"),
                ));
            }
        }
        Ok(())
    }
}

/// A model matrix's determinant, once it is known to be affine, finite and invertible.
fn check_model(model: glam::DMat4) -> Result<f64, Error> {
    let det = glam::DMat3::from_mat4(model).determinant();
    let affine = model.row(3).abs_diff_eq(glam::DVec4::W, 1e-12);
    if !(model.is_finite() && det.is_finite() && det != 0.0 && affine) {
        return Err(Error::invalid(
            STAGE,
            format!(
                "model matrix must be affine, finite and invertible, got {model} (determinant \
             {det})"
            ),
        ));
    }
    Ok(det)
}

/// Refuses a GPU work list for `listing` larger than one binding of `device`.
fn check_work_list(device: &wgpu::Device, listing: &GpuListing) -> Result<(), Error> {
    let limit = device.limits().max_storage_buffer_binding_size;
    if listing.capacity.saturating_mul(8) > limit {
        return Err(Error::Size {
            stage: STAGE,
            what: "heavy-triangle work list bytes",
            got: listing.capacity.saturating_mul(8),
            max: limit,
        });
    }
    Ok(())
}

fn check_grid(grid: &Grid) -> Result<(), Error> {
    check_sides(grid, MAX_SIDE)?;
    // Voxel indices are u32 in the shaders.
    let voxels = grid.voxels();
    if voxels > MAX_VOXELS {
        return Err(Error::Size {
            stage: STAGE,
            what: "voxels in the grid",
            got: voxels,
            max: MAX_VOXELS,
        });
    }
    Ok(())
}

/// A finite origin, a voxel edge > 0 and sides from 1 to `max_side`.
fn check_sides(grid: &Grid, max_side: u32) -> Result<(), Error> {
    if !(grid.origin.is_finite() && grid.voxel.is_finite() && grid.voxel > 0.0) {
        return Err(Error::invalid(
            STAGE,
            format!("the grid needs a finite origin and a voxel edge > 0, got {grid:?}"),
        ));
    }
    for (axis, &n) in ["x", "y", "z"].iter().zip(&grid.size) {
        if n == 0 || n > max_side {
            return Err(Error::Size {
                stage: STAGE,
                what: match *axis {
                    "x" => "grid side x",
                    "y" => "grid side y",
                    _ => "grid side z",
                },
                got: n as u64,
                max: max_side as u64,
            });
        }
    }
    Ok(())
}

/// An empty occupancy bitset for `grid`: a new buffer, which wgpu hands over zeroed (it clears
/// new buffers before their first use, outside the passes that fill them), so no clear is
/// recorded here.
fn zeroed_bitset(device: &wgpu::Device, grid: &Grid) -> Result<wgpu::Buffer, Error> {
    let voxels = grid.voxels();
    let words = voxels.div_ceil(32).max(1);
    let limit = device.limits().max_storage_buffer_binding_size;
    if words * 4 > limit {
        return Err(Error::Size {
            stage: STAGE,
            what: "occupancy bitset bytes",
            got: words * 4,
            max: limit,
        });
    }
    let occupancy = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("voxel occupancy"),
        size: words * 4,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    Ok(occupancy)
}

/// Columns triangle `t` (three grid-local vertices) can have at most: whichever axis is
/// dominant, the largest product of two of its box's sides (clamped to a grid of `size`), and
/// none when the box misses the grid along any axis (as the shaders' `setup` finds from the
/// same box of the same f32 vertices).
fn box_columns(t: &[Vec4], size: [u32; 3]) -> u64 {
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
fn chunk_cap(chunks: &[u64]) -> u64 {
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
fn listed_chunk(most: u64, chunk: u64, cap: u64) -> u64 {
    chunk.max(most.div_ceil(cap))
}

/// `local`'s triangles sorted for `surface_listed`: the light ones (at most [`LIGHT`] columns
/// by [`box_columns`]) first, then the heavy ones, and each heavy triangle's chunks as
/// (triangle, first column), of `listing.chunk` columns, or longer for the heaviest ones where
/// the giant triangles' chunks would pass [`LIST_BUDGET`] ([`chunk_cap`]); a heavy triangle's first
/// vertex carries its chunks' columns in w (which the shaders read for nothing else). A list
/// larger than `limit` bytes is refused before it is made.
fn listed(local: &GridMesh, size: [u32; 3], limit: u64, listing: Listing) -> Result<Sorted, Error> {
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
struct Sorted {
    vertices: Vec<Vec4>,
    light: u32,
    chunks: Vec<[u32; 2]>,
    runs: Vec<(u32, u32)>,
    order: Vec<u32>,
}

/// Surface voxels on the GPU: one bit per voxel.
pub struct Surface {
    /// Voxels per axis.
    pub size: [u32; 3],
    /// `u32` words; voxel i = (z · ny + y) · nx + x is bit i % 32 of word i / 32.
    pub occupancy: wgpu::Buffer,
    /// Zero-area triangles left out.
    pub degenerate: usize,
    /// The work list kept for refills (`encode_surface_placed_into`), made by the first.
    kept: Option<Box<KeptWork>>,
}

impl Surface {
    /// A surface of `size` voxels whose bits are in `occupancy`, with no work list kept.
    pub(crate) fn new(size: [u32; 3], occupancy: wgpu::Buffer, degenerate: usize) -> Self {
        Surface {
            size,
            occupancy,
            degenerate,
            kept: None,
        }
    }

    /// One bool per voxel, x fastest, once the encoder that recorded this surface has been
    /// submitted (see [`Readback`] for how to wait or poll).
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Readback<Vec<bool>> {
        let n = self.size.iter().map(|&s| s as usize).product::<usize>();
        readback_buffer(device, queue, &self.occupancy).then(move |bytes| {
            let words: &[u32] = bytemuck::cast_slice(&bytes);
            Ok((0..n).map(|i| words[i / 32] >> (i % 32) & 1 == 1).collect())
        })
    }
}

/// How thick a surface voxelization is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Separation {
    /// Every voxel a triangle touches (closed boxes): no 26-connected path crosses it.
    #[default]
    Conservative,
    /// Thinner: voxels whose inner cross the triangle's plane crosses and whose centre
    /// projects within half a voxel of the triangle: no 6-connected path crosses it.
    Six,
}

/// The entries of one surface variant: triangles (listing the heavy ones' chunks and sizing
/// their indirect dispatch), the heavy triangles' chunks, and both in one pass where the host
/// listed the chunks.
struct SurfacePipelines {
    light: ComputePipeline<stage::surface::Entry>,
    heavy: ComputePipeline<stage::surface_heavy::Entry>,
    giant: ComputePipeline<stage::surface_giant::Entry>,
    listed: ComputePipeline<stage::surface_listed::Entry>,
}

impl SurfacePipelines {
    fn new(device: &wgpu::Device, six: bool) -> Result<Self, Error> {
        let o = stage::Overrides {
            six_separating: six,
            ..Default::default()
        };
        Ok(Self {
            light: ComputePipeline::with_constants(device, &o)?,
            heavy: ComputePipeline::with_constants(device, &o)?,
            giant: ComputePipeline::with_constants(device, &o)?,
            listed: ComputePipeline::with_constants(device, &o)?,
        })
    }
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
fn most_chunks(columns: u64) -> u64 {
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
const GIANT_BYTES: u64 = 4 * (8 + 4 * MAX_GIANTS as u64);

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
fn giant_blocks_bound(columns: u64) -> u64 {
    columns.div_ceil(CHUNK as u64).min(1 << 20).div_ceil(64)
}

/// `groups` workgroups in rows of 65535 (the shaders read `num_workgroups`).
fn in_rows(groups: u64) -> [u32; 3] {
    [groups.min(65535) as u32, groups.div_ceil(65535) as u32, 1]
}

/// How many of the triangles whose columns (or bounds on them) are `sorted`, most first, are
/// giant: those past the [`MAX_GIANTS`]-plus-first's count and past [`GIANT_MIN_COLUMNS`], so
/// at most `MAX_GIANTS`, the largest first.
fn giant_count(sorted: &[u64]) -> usize {
    let threshold = sorted
        .get(MAX_GIANTS as usize)
        .map_or(0, |&c| c)
        .max(GIANT_MIN_COLUMNS as u64);
    sorted.partition_point(|&c| c > threshold)
}

/// Mark the giant triangles `giants` (triangle indices, largest first) for the surface pass:
/// the w of a giant's first vertex is its rank + 1, every other first vertex's 0.
fn mark_giants(vertices: &mut [Vec4], giants: &[u32]) {
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
/// Most columns a triangle walks in its own thread; heavier ones go through the work list (the
/// shader's `LIGHT`).
pub const LIGHT: u32 = 16;

/// The voxelization pipelines. Create once, encode many times.
pub struct Voxelizer {
    surface: SurfacePipelines,
    surface_six: SurfacePipelines,
    solid: ComputePipeline<solid_stage::solid::Entry>,
    to_volume: ComputePipeline<volume_stage::to_volume::Entry>,
    attribute_pipelines: attributes::AttributePipelines,
    fragment_pipelines: fragments::FragmentPipelines,
    raster: std::sync::OnceLock<crate::bind::RenderPipeline<raster_stage::fs_raster::Entry>>,
    listing: Option<Listing>,
}

/// Most workgroups a walk of the GPU's list is dispatched with directly, the host's bound on
/// them, instead of through the arguments the surface pass counted: an indirect dispatch
/// costs the H100 several microseconds more (wgpu validates indirect arguments by default,
/// `InstanceFlags::VALIDATION_INDIRECT_CALL`), and a bound dispatched directly may launch
/// many workgroups that find nothing. Measured on the H100 (docs/voxelize.md, "Giant triangles on the GPU's list"): the
/// resident bunny's heavy pass, bounded by 0.43 M / 0.73 M / 1.6 M / 4.4 M entries at 128³ /
/// 256³ / 512³ / 1024³, took 0.0091 / 0.0121 / 0.0466 / 0.1965 ms direct against 0.0120 /
/// 0.0204 / 0.0491 / 0.1468 indirect; so bounds up to 2^21 invocations go direct.
const DIRECT_GROUPS: u64 = 1 << 15;

/// One compute pass of `pipeline` over at most `most` workgroups: exactly that many, in rows
/// of 65535, up to [`DIRECT_GROUPS`], else as many as `args` (three u32 the surface pass
/// wrote) say.
fn run_walk<E: crate::bind::Entry>(
    rec: &mut impl Record,
    label: &str,
    pipeline: &ComputePipeline<E>,
    bound: &crate::bind::Bound<E>,
    args: &wgpu::Buffer,
    most: u64,
) {
    let mut rec = rec.recorder();
    let mut pass = rec.compute_pass(label, label);
    if most <= DIRECT_GROUPS {
        pipeline.dispatch(&mut pass, bound, in_rows(most));
    } else {
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_compute(&mut pass);
        pass.dispatch_workgroups_indirect(args, 0);
    }
}

/// A 3D texture of `size` that stages sample and write (`TEXTURE_BINDING`, `STORAGE_BINDING`)
/// and tests read back (`COPY_SRC`).

/// Triangles per dispatch: at most 65535 workgroups of 64.
const PER_DISPATCH: u32 = 65535 * 64;

/// `count` triangles as (first, count) runs of at most [`PER_DISPATCH`].
fn batches(count: u32) -> impl Iterator<Item = (u32, u32)> {
    (0..count)
        .step_by(PER_DISPATCH as usize)
        .map(move |first| (first, (count - first).min(PER_DISPATCH)))
}

/// The triangles of one surface pass: a buffer of `count` triangles (three `vec4<f32>` each),
/// the work-list entries their heavy triangles can need, the move into grid-local coordinates
/// and how far its f32 rounding can move a vertex (voxels).
struct SurfaceRun<'a> {
    triangles: &'a wgpu::Buffer,
    count: u32,
    listing: GpuListing,
    to_grid: glam::Mat4,
    moved: f32,
}

/// Triangles sorted on the host for `surface_listed` (see [`listed`]): light ones first, then
/// heavy ones, and the heavy ones' chunks.
struct Listed {
    triangles: wgpu::Buffer,
    chunks: wgpu::Buffer,
    light: u32,
    chunk_count: u32,
    /// Per heavy triangle (in the sorted order): its chunks and their columns.
    runs: Vec<(u32, u32)>,
    /// Per sorted triangle, its index in the [`GridMesh`].
    order: Vec<u32>,
}

impl Listed {
    fn new(
        device: &wgpu::Device,
        local: &GridMesh,
        grid: &Grid,
        listing: Listing,
    ) -> Result<Listed, Error> {
        use wgpu::util::DeviceExt;
        let limit = device.limits().max_storage_buffer_binding_size;
        let Sorted {
            mut vertices,
            light,
            mut chunks,
            runs,
            order,
        } = listed(local, grid.size, limit, listing)?;
        let chunk_count = chunks.len() as u32;
        // Padding keeps the buffers non-empty.
        if vertices.is_empty() {
            vertices.push(Vec4::ZERO);
        }
        if chunks.is_empty() {
            chunks.push([0, 0]);
        }
        let buffer = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        Ok(Listed {
            triangles: buffer("voxelize triangles", bytemuck::cast_slice(&vertices)),
            chunks: buffer("voxelize heavy chunks", bytemuck::cast_slice(&chunks)),
            light,
            chunk_count,
            runs,
            order,
        })
    }
}

/// The heavy triangles' chunks a surface pass listed and the indirect dispatch that walks
/// them, and its giant triangles' records with a bound on their blocks (0: no giants).
struct HeavyWork {
    work: wgpu::Buffer,
    work_count: wgpu::Buffer,
    dispatch: wgpu::Buffer,
    capacity: u32,
    giant_records: wgpu::Buffer,
    giant_blocks: u64,
}

impl HeavyWork {
    /// New buffers for a list of `capacity` entries (at least one): the count zero, both
    /// dispatches' arguments (0, 1, 1) (`surface` raises the count, and the rows of 65535, as
    /// it lists chunks), the giants' counts zero.
    fn new(device: &wgpu::Device, capacity: u32, giant_blocks: u64) -> Self {
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        let arguments = |label, bytes: u64| {
            wgpu::util::DeviceExt::create_buffer_init(
                device,
                &wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: bytemuck::cast_slice(&initial_arguments(bytes)),
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::INDIRECT
                        | wgpu::BufferUsages::COPY_DST,
                },
            )
        };
        HeavyWork {
            work: buffer(
                "voxelize work list",
                capacity.max(1) as u64 * 8,
                wgpu::BufferUsages::empty(),
            ),
            work_count: buffer("voxelize work count", 4, wgpu::BufferUsages::COPY_DST),
            dispatch: arguments("voxelize heavy dispatch", 12),
            capacity,
            // The giant pass's arguments (0, 1, 1), then zeros.
            giant_records: arguments("voxelize giant triangles", GIANT_BYTES),
            giant_blocks,
        }
    }
}

/// Words of `bytes` of indirect dispatch arguments before any work is listed: (0, 1, 1), then
/// zeros.
fn initial_arguments(bytes: u64) -> Vec<u32> {
    let mut words = vec![0u32; bytes as usize / 4];
    words[1..3].copy_from_slice(&[1, 1]);
    words
}

/// A [`HeavyWork`] kept with a refilled [`Surface`] (`encode_surface_placed_into`), and the
/// arguments it starts from, copied over it before each pass that uses it.
struct KeptWork {
    heavy: HeavyWork,
    initial: wgpu::Buffer,
}

impl KeptWork {
    /// Kept buffers for a list of at least `capacity` entries (a quarter more, so that a
    /// listing that grows a little from frame to frame does not make new ones each time).
    fn new(device: &wgpu::Device, capacity: u32) -> Self {
        let initial = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("voxelize initial arguments"),
                contents: bytemuck::cast_slice(&initial_arguments(GIANT_BYTES)),
                usage: wgpu::BufferUsages::COPY_SRC,
            },
        );
        let most = device.limits().max_storage_buffer_binding_size / 8;
        let room = (capacity as u64 + capacity as u64 / 4).min(most) as u32;
        KeptWork {
            heavy: HeavyWork::new(device, room, 0),
            initial,
        }
    }

    /// Record the count's and the arguments' reset, so the next pass lists from nothing.
    fn reset(&self, rec: &mut impl Record) {
        let rec = rec.recorder();
        let h = &self.heavy;
        rec.encoder.clear_buffer(&h.work_count, 0, None);
        rec.encoder
            .copy_buffer_to_buffer(&self.initial, 0, &h.dispatch, 0, 12);
        rec.encoder
            .copy_buffer_to_buffer(&self.initial, 0, &h.giant_records, 0, GIANT_BYTES);
    }
}

impl Voxelizer {
    /// Create the surface, solid and volume pipelines (the rest on first use).
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            surface: SurfacePipelines::new(device, false)?,
            surface_six: SurfacePipelines::new(device, true)?,
            solid: ComputePipeline::new(device)?,
            to_volume: ComputePipeline::new(device)?,
            attribute_pipelines: Default::default(),
            fragment_pipelines: Default::default(),
            raster: Default::default(),
            listing: None,
        })
    }

    /// Bench knob: how the surface pass cuts triangles into threads (see [`Listing`]; `None`:
    /// [`Listing::auto`] per mesh).
    #[doc(hidden)]
    pub fn set_listing(
        &mut self,
        device: &wgpu::Device,
        listing: Option<Listing>,
    ) -> Result<(), Error> {
        let workgroup = listing.map_or(64, |l| l.workgroup);
        if listing.is_some_and(|l| l.chunk == 0) || !workgroup.is_power_of_two() || workgroup > 256
        {
            return Err(Error::invalid(STAGE, format!("listing {listing:?}")));
        }
        for (pipelines, six) in [(&mut self.surface, false), (&mut self.surface_six, true)] {
            pipelines.listed = ComputePipeline::with_constants(
                device,
                &stage::Overrides {
                    six_separating: six,
                    listed_workgroup: workgroup,
                },
            )?;
        }
        self.listing = listing;
        Ok(())
    }

    fn listing_for(&self, local: &GridMesh) -> Listing {
        self.listing
            .unwrap_or_else(|| Listing::auto(local.vertices.len() / 3))
    }

    /// Solid voxels of a closed mesh: every voxel whose centre is inside, by parity along x
    /// (`voxelize/solid`), ORed with the conservative surface so parts thinner than a voxel
    /// survive. A mesh with an open or inconsistently oriented edge is refused (its inside is
    /// not defined). `with_surface: false` gives the parity fill alone.
    pub fn encode_solid(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        with_surface: bool,
    ) -> Result<Surface, Error> {
        if let Some([a, b]) = mesh.open_edge() {
            return Err(Error::Invalid {
                stage: solid_stage::STAGE,
                what: format!(
                    "solid voxelization needs a closed, consistently oriented mesh: the edge \
                     between vertices {a} and {b} is not shared by exactly two triangles running \
                     opposite ways"
                ),
            });
        }
        let local = mesh.to_grid(grid)?;
        let occupancy = zeroed_bitset(device, grid)?;
        // The parity fill takes the triangles in any order: the surface pass's sorted ones.
        let listed = Listed::new(device, &local, grid, self.listing_for(&local))?;
        let triangles = &listed.triangles;
        let count = (local.vertices.len() / 3) as u32;
        for (first, n) in batches(count) {
            let params = uniform(
                device,
                "voxelize solid params",
                &SolidParams {
                    grid: grid.size.into(),
                    first,
                    count: n,
                },
            );
            self.solid.record(
                device,
                rec,
                &solid_stage::solid::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: (&occupancy).into(),
                },
                [n.div_ceil(64), 1, 1],
                solid_stage::STAGE,
            )?;
        }
        if with_surface {
            self.listed_pass(device, rec, &self.surface, &occupancy, &listed, grid)?;
        }
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }

    /// `voxels` as an `R32Float` 3D texture (1 occupied, 0 empty) that the distance stages
    /// read: `Distance3d::encode` with `Inside::Mask` gives the mesh's distance field.
    pub fn encode_volume(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        voxels: &Surface,
    ) -> Result<wgpu::Texture, Error> {
        let volume = crate::gpu::volume_texture(
            device,
            "voxel occupancy volume",
            voxels.size,
            wgpu::TextureFormat::R32Float,
        );
        let view = volume.create_view(&Default::default());
        let params = uniform(
            device,
            "voxel volume params",
            &VolumeParams {
                grid: voxels.size.into(),
            },
        );
        self.to_volume.record(
            device,
            rec,
            &volume_stage::to_volume::Resources {
                params: (&params).into(),
                occupancy: (&voxels.occupancy).into(),
                volume: (&view).into(),
            },
            ComputePipeline::<volume_stage::to_volume::Entry>::groups_for(voxels.size),
            volume_stage::STAGE,
        )?;
        Ok(volume)
    }

    /// A cleared bitset for `grid` and the triangle buffer of `local`, its `giants` marked
    /// ([`mark_giants`]).
    fn bitset(
        &self,
        device: &wgpu::Device,
        local: &GridMesh,
        grid: &Grid,
        giants: &[u32],
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), Error> {
        let occupancy = zeroed_bitset(device, grid)?;
        use wgpu::util::DeviceExt;
        let mut vertices = local.vertices.clone();
        mark_giants(&mut vertices, giants);
        // One padding vertex keeps the buffer non-empty when every triangle was degenerate.
        if vertices.is_empty() {
            vertices.push(Vec4::ZERO);
        }
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize triangles"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Ok((occupancy, triangles))
    }

    /// A surface pass (`pipelines`: conservative or six-separating) over the `count` triangles
    /// of `triangles` (marked for `listing`), ORed into `occupancy`: light triangles one per
    /// thread, heavy ones (more than [`LIGHT`] columns) in chunks of [`CHUNK`] through a work
    /// list and an indirect dispatch, giant ones by blocks. Returns the work list, which the
    /// attribute pass walks again.
    #[allow(clippy::too_many_arguments)]
    fn surface_into(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        triangles: &wgpu::Buffer,
        count: u32,
        listing: GpuListing,
        grid: &Grid,
    ) -> Result<HeavyWork, Error> {
        self.surface_pass(
            device,
            rec,
            pipelines,
            occupancy,
            &SurfaceRun {
                triangles,
                count,
                listing,
                to_grid: glam::Mat4::IDENTITY,
                moved: 0.0,
            },
            grid,
        )
    }

    /// The surface of `listed`'s triangles in one pass (`surface_listed`), ORed into
    /// `occupancy`: a light triangle per thread, then a heavy triangle's chunk per thread.
    fn listed_pass(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        listed: &Listed,
        grid: &Grid,
    ) -> Result<(), Error> {
        let threads = listed.light as u64 + listed.chunk_count as u64;
        if threads == 0 {
            return Ok(());
        }
        let params = uniform(
            device,
            "voxelize params",
            &SurfaceParams {
                to_grid: glam::Mat4::IDENTITY,
                grid: grid.size.into(),
                first: 0,
                count: listed.light,
                slack: SLACK,
                moved: 0.0,
                capacity: listed.chunk_count,
                giants: 0,
            },
        );
        // More than 65535 workgroups: rows of 65535 (the shader reads `num_workgroups`).
        let wg = self.listing.map_or(64, |l| l.workgroup) as u64;
        let groups = threads.div_ceil(wg);
        let rows = groups.div_ceil(65535);
        let wide = groups.min(65535);
        if rows > 65535 {
            return Err(Error::Size {
                stage: STAGE,
                what: "surface threads (triangles and heavy chunks)",
                got: threads,
                max: 65535 * 65535 * wg,
            });
        }
        pipelines.listed.record(
            device,
            rec,
            &stage::surface_listed::Resources {
                params: (&params).into(),
                triangles: (&listed.triangles).into(),
                occupancy: occupancy.into(),
                listed: (&listed.chunks).into(),
            },
            [wide as u32, rows as u32, 1],
            STAGE,
        )
    }

    /// The surface pipelines for `separation`.
    fn pipelines(&self, separation: Separation) -> &SurfacePipelines {
        match separation {
            Separation::Conservative => &self.surface,
            Separation::Six => &self.surface_six,
        }
    }

    /// One surface pass of `run`'s triangles into `occupancy` (see [`Self::surface_into`]),
    /// with a work list of its own.
    fn surface_pass(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        run: &SurfaceRun,
        grid: &Grid,
    ) -> Result<HeavyWork, Error> {
        check_work_list(device, &run.listing)?;
        // Within a binding: a u32 count. New buffers: zeroed by wgpu (the count starts at 0).
        let heavy = HeavyWork::new(device, run.listing.capacity as u32, run.listing.blocks);
        self.surface_pass_with(device, rec, pipelines, occupancy, run, grid, &heavy)?;
        Ok(heavy)
    }

    /// [`Self::surface_pass`] with the work list `heavy`, whose count must be zero and whose
    /// arguments (0, 1, 1) when the pass is recorded, and which holds at least the run's
    /// listing's entries (the pass uses as many as the listing asks for).
    #[allow(clippy::too_many_arguments)]
    fn surface_pass_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        pipelines: &SurfacePipelines,
        occupancy: &wgpu::Buffer,
        run: &SurfaceRun,
        grid: &Grid,
        heavy_work: &HeavyWork,
    ) -> Result<(), Error> {
        let &SurfaceRun {
            triangles,
            count,
            listing,
            to_grid,
            moved,
        } = run;
        debug_assert!(heavy_work.capacity as u64 >= listing.capacity);
        let capacity = listing.capacity as u32;
        let HeavyWork {
            work,
            work_count,
            dispatch,
            giant_records,
            ..
        } = heavy_work;
        if count == 0 {
            return Ok(());
        }
        let params_for = |first, n| {
            uniform(
                device,
                "voxelize params",
                &SurfaceParams {
                    to_grid,
                    grid: grid.size.into(),
                    first,
                    count: n,
                    slack: SLACK,
                    moved,
                    capacity,
                    giants: listing.giants,
                },
            )
        };
        for (first, n) in batches(count) {
            let params = params_for(first, n);
            pipelines.light.record(
                device,
                rec,
                &stage::surface::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: occupancy.into(),
                    work: work.into(),
                    work_count: work_count.into(),
                    heavy_dispatch: dispatch.into(),
                    giants: giant_records.into(),
                },
                [n.div_ceil(64), 1, 1],
                STAGE,
            )?;
        }
        let params = params_for(0, count);
        if listing.giants > 0 {
            let giant = pipelines.giant.bind(
                device,
                &stage::surface_giant::Resources {
                    params: (&params).into(),
                    triangles: triangles.into(),
                    occupancy: occupancy.into(),
                    giant_list: giant_records.into(),
                },
            )?;
            run_walk(
                rec,
                "voxelize giant triangles",
                &pipelines.giant,
                &giant,
                giant_records,
                listing.blocks,
            );
        }
        if capacity == 0 {
            return Ok(());
        }
        let heavy = pipelines.heavy.bind(
            device,
            &stage::surface_heavy::Resources {
                params: (&params).into(),
                triangles: triangles.into(),
                occupancy: occupancy.into(),
                work: work.into(),
                work_count: work_count.into(),
            },
        )?;
        run_walk(
            rec,
            "voxelize heavy triangles",
            &pipelines.heavy,
            &heavy,
            dispatch,
            (capacity as u64).div_ceil(64),
        );
        Ok(())
    }

    /// The conservative surface voxels of [`Voxelizer::encode_surface`], found through the
    /// rasterizer as the write-up did (`voxelize/raster`): each triangle drawn on the plane of
    /// its dominant axis into a square target of the grid's largest side, enlarged by half a
    /// pixel's diagonal so every column it touches gets a fragment, which runs the exact tests.
    /// Kept to compare with the compute path; the voxels are the same.
    pub fn encode_surface_raster(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Surface, Error> {
        let side = grid.size.into_iter().max().unwrap_or(1);
        let max = device.limits().max_texture_dimension_2d;
        if side > max {
            return Err(Error::Size {
                stage: raster_stage::STAGE,
                what: "largest grid side (the raster target's side)",
                got: side as u64,
                max: max as u64,
            });
        }
        let local = mesh.to_grid(grid)?;
        let (occupancy, triangles) = self.bitset(device, &local, grid, &[])?;
        let format = wgpu::TextureFormat::R8Unorm;
        let pipeline = if let Some(p) = self.raster.get() {
            p
        } else {
            let p = crate::bind::RenderPipeline::new(
                device,
                &crate::bind::RenderTargets {
                    color: &[Some(wgpu::ColorTargetState {
                        format,
                        blend: None,
                        write_mask: wgpu::ColorWrites::empty(),
                    })],
                    ..Default::default()
                },
            )?;
            let _ = self.raster.set(p);
            self.raster.get().expect("set above")
        };
        let target = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("voxelize raster target"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let view = target.create_view(&Default::default());
        let params = uniform(
            device,
            "voxelize raster params",
            &RasterParams {
                grid: grid.size.into(),
                side,
                slack: SLACK,
                // Rasterizers snap to 1/256 pixel or finer; 1/64 covers that with room.
                margin: 1.0 / 64.0,
            },
        );
        let bound = pipeline.bind(
            device,
            &raster_stage::fs_raster::Resources {
                params: (&params).into(),
                triangles: (&triangles).into(),
                occupancy: (&occupancy).into(),
            },
        )?;
        let count = (local.vertices.len() / 3) as u32;
        let mut pass = rec
            .recorder()
            .encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(raster_stage::STAGE),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                ..Default::default()
            });
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..count * 3, 0..1);
        drop(pass);
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }

    /// Conservative surface voxels of `mesh` in `grid`: every voxel (a closed box) a triangle
    /// touches.
    pub fn encode_surface(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Surface, Error> {
        self.encode_surface_with(device, rec, mesh, grid, Separation::Conservative)
    }

    /// Surface voxels of `mesh` in `grid`, as thick as `separation` says, recorded into `rec`
    /// (a command encoder, or [`crate::gpu::Profiler::record`] to time each pass).
    pub fn encode_surface_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        separation: Separation,
    ) -> Result<Surface, Error> {
        let local = mesh.to_grid(grid)?;
        let occupancy = zeroed_bitset(device, grid)?;
        let pipelines = self.pipelines(separation);
        let listed = Listed::new(device, &local, grid, self.listing_for(&local))?;
        self.listed_pass(device, rec, pipelines, &occupancy, &listed, grid)?;
        Ok(Surface::new(grid.size, occupancy, local.degenerate))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three vertices of a right triangle at height `z` with legs `leg` from (x0, y0).
    fn right(x0: f32, y0: f32, leg: f32, z: f32) -> [Vec4; 3] {
        [
            Vec4::new(x0, y0, z, 0.0),
            Vec4::new(x0 + leg, y0, z, 0.0),
            Vec4::new(x0, y0 + leg, z, 0.0),
        ]
    }

    fn grid_mesh(triangles: &[[Vec4; 3]]) -> GridMesh {
        GridMesh {
            vertices: triangles.concat(),
            degenerate: 0,
            source: (0..triangles.len() as u32).collect(),
        }
    }

    /// Triangles of more than `MAX_CHUNKS` chunks share `LIST_BUDGET`: while they fit it
    /// every heavy triangle keeps chunks of `CHUNK`; past it the heaviest get longer chunks,
    /// just enough to fit, that start at every multiple of their length up to their columns;
    /// the chunks' columns ride in each heavy triangle's first vertex's w. Smaller triangles
    /// neither get longer chunks nor count against the budget.
    #[test]
    fn the_heaviest_triangles_get_longer_chunks_past_the_budget() {
        let size = [4096, 4096, 2];
        let light = right(0.2, 0.2, 0.5, 0.5); // 1 column
        let heavy = right(0.5, 0.5, 5.0, 0.5); // its box: 6 × 6 = 36 columns
        let list = |triangles: &[[Vec4; 3]]| {
            listed(&grid_mesh(triangles), size, u64::MAX, Listing::default()).unwrap()
        };
        // 512² columns, 65 536 chunks: within the budget.
        let sorted = list(&[light, heavy, right(0.0, 0.0, 511.5, 1.5)]);
        assert_eq!(sorted.runs, [(9, CHUNK), (512 * 512 / 4, CHUNK)]);

        // 4096² and 2048² columns, 2^22 + 2^20 chunks of 4: the largest cap c with
        // min(2^22, c) + min(2^20, c) ≤ 2^20 is 2^19, so chunks of 32 and 8 columns.
        let giant = right(0.0, 0.0, 4096.0, 1.5);
        let sorted = list(&[light, heavy, giant, right(0.0, 0.0, 2047.5, 1.5)]);
        assert_eq!((sorted.light, &sorted.order[..]), (1, &[0, 1, 2, 3][..]));
        assert_eq!(sorted.runs, [(9, CHUNK), (1 << 19, 32), (1 << 19, 8)]);
        assert_eq!(sorted.chunks.len() as u64, 9 + LIST_BUDGET);
        let ws: Vec<f32> = sorted.vertices.iter().map(|p| p.w).collect();
        let mut want_ws = [0.0; 12];
        (want_ws[3], want_ws[6], want_ws[9]) = (4.0, 32.0, 8.0);
        assert_eq!(ws, want_ws);
        for (c, &[t, first]) in sorted.chunks.iter().enumerate() {
            let want = match c {
                0..9 => (1, 4 * c as u32),
                _ if c < 9 + (1 << 19) => (2, 32 * (c - 9) as u32),
                _ => (3, 8 * (c - 9 - (1 << 19)) as u32),
            };
            assert_eq!((t, first), want, "chunk {c}");
        }

        // 70 triangles of 256² columns (16 384 chunks each, 1.15 M in all) and one of 1024²
        // (262 144 chunks, within the budget on its own): every chunk keeps 4 columns.
        let mut many = vec![right(0.0, 0.0, 255.5, 0.5); 70];
        many.push(right(0.0, 0.0, 1023.5, 1.5));
        let sorted = list(&many);
        assert_eq!(sorted.runs.len(), 71);
        assert!(sorted.runs.iter().all(|&(_, columns)| columns == CHUNK));
        assert_eq!(sorted.chunks.len(), 70 * 16_384 + 262_144);
    }

    /// A triangle whose box misses the grid along one axis has no columns, however large its
    /// box is along the other two (a roof above the grid's top layer), so it is listed as light
    /// (one thread, which finds nothing) instead of in chunks; one that touches the grid's
    /// last layer keeps them.
    #[test]
    fn triangles_outside_the_grid_list_no_chunks() {
        let size = [4096, 4096, 2];
        let above = right(0.0, 0.0, 4096.0, 2.5);
        let touching = right(0.0, 0.0, 4096.0, 2.0);
        let below = right(0.0, 0.0, 4096.0, -0.001);
        assert_eq!(box_columns(&above, size), 0);
        assert_eq!(box_columns(&below, size), 0);
        assert_eq!(box_columns(&touching, size), 4096 * 4096);
        let sorted = listed(
            &grid_mesh(&[above, touching, below]),
            size,
            u64::MAX,
            Listing::default(),
        )
        .unwrap();
        assert_eq!((sorted.light, &sorted.order[..]), (2, &[0, 2, 1][..]));
        assert_eq!(sorted.runs, [(1 << 20, 16)]);
    }

    /// More giant triangles than the budget holds at `MAX_CHUNKS` each: each lists exactly
    /// that many (chunks of 1024 columns, no longer), and the list's bytes, counted before
    /// anything is made, are refused past the limit.
    #[test]
    fn giant_triangles_list_at_least_max_chunks_each() {
        let size = [4096, 4096, 2];
        let giants: Vec<[Vec4; 3]> = (0..100)
            .map(|k| right(0.0, 0.0, 4096.0, 0.25 + k as f32 * 0.01))
            .collect();
        let mesh = grid_mesh(&giants);
        let sorted = listed(&mesh, size, u64::MAX, Listing::default()).unwrap();
        assert!(sorted.runs.iter().all(|&run| run == (MAX_CHUNKS, 1024)));
        assert_eq!(sorted.chunks.len(), 100 * MAX_CHUNKS as usize);
        let bytes = 100 * MAX_CHUNKS as u64 * 8;
        assert!(listed(&mesh, size, bytes, Listing::default()).is_ok());
        assert!(matches!(
            listed(&mesh, size, bytes - 1, Listing::default()),
            Err(Error::Size { got, .. }) if got == bytes
        ));
    }

    /// The host's copies of the shader's constants agree with `fieldkit::triangle_box`.
    #[test]
    fn constants_match_the_shader() {
        let src = include_str!("../../fieldkit-wesl/shaders/triangle_box.wesl");
        for (name, value) in [
            ("LIGHT", super::LIGHT),
            ("CHUNK", super::CHUNK),
            ("MAX_CHUNKS", super::MAX_CHUNKS),
            ("MAX_GIANTS", super::MAX_GIANTS),
            // `GIANT_BYTES`' header.
            ("GIANT_HEADER", 8),
        ] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(src.contains(&line), "triangle_box.wesl lacks `{line}`");
        }
    }
}
