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
//! let surface = v.encode_surface(ctx, &mut encoder, &mesh, &grid)?;
//! ctx.submit_and_wait("voxelize", encoder)?;
//! let occupied = surface.read(ctx)?; // one bool per voxel, x fastest
//! # let _ = occupied; Ok(()) }
//! ```

pub mod cpu;

use glam::{DVec3, Vec4};

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Context, read_buffer, uniform_buffer as uniform};
use crate::shaders::voxelize::surface::{self as stage, SurfaceParams};

const STAGE: &str = stage::STAGE;

/// Largest side of a voxel grid.
pub const MAX_SIDE: u32 = 4096;

/// Relative slack on the GPU's tests: a few f32 ulp, so rounding only ever adds voxels within
/// about this fraction of the coordinates' size.
pub const SLACK: f32 = 4.0 * f32::EPSILON;

/// A triangle mesh in world units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Where the voxels are: the world position of voxel (0, 0, 0)'s min corner, the voxel edge and
/// the number of voxels per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    pub origin: DVec3,
    pub voxel: f64,
    pub size: [u32; 3],
}

/// A mesh moved into a grid's local coordinates and rounded to f32, as the GPU sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct GridMesh {
    /// Three vertices per triangle (w = 0), zero-area triangles left out.
    pub vertices: Vec<Vec4>,
    /// Triangles left out for having no area (after rounding).
    pub degenerate: usize,
}

fn invalid(what: String) -> Error {
    Error::Invalid { stage: STAGE, what }
}

impl Mesh {
    /// A UV sphere (for tests and examples): `segments` around, `rings` from pole to pole.
    pub fn uv_sphere(centre: DVec3, radius: f64, segments: u32, rings: u32) -> Self {
        let mut positions = Vec::new();
        for r in 0..=rings {
            let theta = std::f64::consts::PI * r as f64 / rings as f64;
            for s in 0..segments {
                let phi = std::f64::consts::TAU * s as f64 / segments as f64;
                positions.push(
                    centre
                        + radius
                            * DVec3::new(
                                theta.sin() * phi.cos(),
                                theta.cos(),
                                theta.sin() * phi.sin(),
                            ),
                );
            }
        }
        let at = |r: u32, s: u32| r * segments + s % segments;
        let mut triangles = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
                if r > 0 {
                    triangles.push([a, b, c]);
                }
                if r + 1 < rings {
                    triangles.push([b, d, c]);
                }
            }
        }
        Self {
            positions,
            triangles,
        }
    }

    /// Check the mesh and move it into `grid`'s local coordinates in f64, then round to f32.
    pub fn to_grid(&self, grid: &Grid) -> Result<GridMesh, Error> {
        check_grid(grid)?;
        if self.triangles.is_empty() {
            return Err(Error::Size {
                stage: STAGE,
                what: "number of triangles",
                got: 0,
                max: u32::MAX as u64 / 3,
            });
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!(
                "vertex {i} is not finite: {}",
                self.positions[i]
            )));
        }
        let n = self.positions.len() as u32;
        let mut vertices = Vec::with_capacity(self.triangles.len() * 3);
        let mut degenerate = 0;
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&bad) = tri.iter().find(|&&i| i >= n) {
                return Err(invalid(format!(
                    "triangle {t} names vertex {bad}, the mesh has {n}"
                )));
            }
            let v =
                tri.map(|i| ((self.positions[i as usize] - grid.origin) / grid.voxel).as_vec3());
            if (v[1] - v[0]).cross(v[2] - v[0]).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            vertices.extend(v.iter().map(|p| p.extend(0.0)));
        }
        Ok(GridMesh {
            vertices,
            degenerate,
        })
    }
}

fn check_grid(grid: &Grid) -> Result<(), Error> {
    if !(grid.origin.is_finite() && grid.voxel.is_finite() && grid.voxel > 0.0) {
        return Err(invalid(format!(
            "the grid needs a finite origin and a voxel edge > 0, got {grid:?}"
        )));
    }
    for (axis, &n) in ["x", "y", "z"].iter().zip(&grid.size) {
        if n == 0 || n > MAX_SIDE {
            return Err(Error::Size {
                stage: STAGE,
                what: match *axis {
                    "x" => "grid side x",
                    "y" => "grid side y",
                    _ => "grid side z",
                },
                got: n as u64,
                max: MAX_SIDE as u64,
            });
        }
    }
    Ok(())
}

/// Surface voxels on the GPU: one bit per voxel.
pub struct Surface {
    pub size: [u32; 3],
    /// `u32` words; voxel i = (z · ny + y) · nx + x is bit i % 32 of word i / 32.
    pub occupancy: wgpu::Buffer,
    /// Zero-area triangles left out.
    pub degenerate: usize,
}

impl Surface {
    /// One bool per voxel, x fastest.
    pub fn read(&self, ctx: &Context) -> Result<Vec<bool>, Error> {
        let bytes = read_buffer(ctx, &self.occupancy)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        let n = self.size.iter().map(|&s| s as usize).product::<usize>();
        Ok((0..n).map(|i| words[i / 32] >> (i % 32) & 1 == 1).collect())
    }
}

pub struct Voxelizer {
    surface: ComputePipeline<stage::surface::Entry>,
}

impl Voxelizer {
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            surface: ComputePipeline::new(device)?,
        })
    }

    /// Conservative surface voxels of `mesh` in `grid`: every voxel (a closed box) a triangle
    /// touches.
    pub fn encode_surface(
        &self,
        ctx: &Context,
        encoder: &mut wgpu::CommandEncoder,
        mesh: &Mesh,
        grid: &Grid,
    ) -> Result<Surface, Error> {
        let local = mesh.to_grid(grid)?;
        let device = &ctx.device;
        let voxels: u64 = grid.size.iter().map(|&s| s as u64).product();
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
        encoder.clear_buffer(&occupancy, 0, None);
        let count = (local.vertices.len() / 3) as u32;
        if count == 0 {
            return Ok(Surface {
                size: grid.size,
                occupancy,
                degenerate: local.degenerate,
            });
        }
        use wgpu::util::DeviceExt;
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize triangles"),
            contents: bytemuck::cast_slice(&local.vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        // Dispatches of at most 65535 workgroups of 64 triangles.
        let per_dispatch = 65535 * 64;
        let mut first = 0;
        while first < count {
            let n = (count - first).min(per_dispatch);
            let params = uniform(
                device,
                "voxelize params",
                &SurfaceParams {
                    grid: grid.size.into(),
                    first,
                    count: n,
                    slack: SLACK,
                },
            );
            let bound = self.surface.bind(
                device,
                &stage::surface::Resources {
                    params: (&params).into(),
                    triangles: (&triangles).into(),
                    occupancy: (&occupancy).into(),
                },
            )?;
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(STAGE),
                timestamp_writes: None,
            });
            self.surface
                .dispatch(&mut pass, &bound, [n.div_ceil(64), 1, 1]);
            drop(pass);
            first += n;
        }
        Ok(Surface {
            size: grid.size,
            occupancy,
            degenerate: local.degenerate,
        })
    }
}
