//! The mesh a voxelizer takes ([`Mesh`]), the grid it voxelizes into ([`Grid`]) and the mesh
//! in the grid's local f32 coordinates ([`GridMesh`]).

use glam::{DVec3, Vec4};

use super::{MAX_SPARSE_SIDE, STAGE, check_grid, check_model, check_sides};
use crate::error::Error;
use crate::grid::Grid;

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

// The fitting of a grid to a mesh lives with the mesh; the grid itself is the crate's shared
// `crate::Grid`.
impl Grid {
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

    /// [`Mesh::to_grid`] for a grid that is never held densely ([`Voxelizer::encode_fragments`](super::Voxelizer::encode_fragments)
    /// and the octree): sides up to [`MAX_SPARSE_SIDE`], any number of voxels.
    pub fn to_sparse_grid(&self, grid: &Grid) -> Result<GridMesh, Error> {
        check_sides(grid, MAX_SPARSE_SIDE)?;
        self.local(grid)
    }

    pub(super) fn local(&self, grid: &Grid) -> Result<GridMesh, Error> {
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
    pub(super) fn check(&self) -> Result<(), Error> {
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
