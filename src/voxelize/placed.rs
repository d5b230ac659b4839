//! Meshes that stay on the GPU: uploaded once, then voxelized wherever a model matrix puts
//! them. The surface stage moves each vertex by the matrix as it loads it, so a moving mesh, or
//! several instances of one, cost a 64-byte uniform per pass instead of a new triangle buffer.

use glam::{DMat4, DVec3, Vec4};

use super::{
    CHUNK, Error, Grid, LIGHT, MAX_CHUNKS, Mesh, Separation, Surface, SurfaceRun, Voxelizer,
    check_grid, check_model, invalid, most_chunks, zeroed_bitset,
};
use crate::gpu::Record;

// `GpuMesh::chunk_bound`'s threshold assumes LIGHT = 16.
const _: () = assert!(LIGHT == 16);

/// A mesh's triangles in a GPU buffer, ready for [`Voxelizer::encode_surface_placed`].
///
/// Positions are stored in f32 relative to the centre of the mesh's bounds (so a mesh far from
/// the origin keeps its precision); the move into a grid is composed in f64 on the host and
/// applied on the GPU. Zero-area triangles are left out at upload (an invertible matrix gives
/// them no area either).
///
/// ```
/// # fn f(ctx: &fieldkit::gpu::Context) -> Result<(), fieldkit::Error> {
/// use fieldkit::voxelize::{GpuMesh, Grid, Mesh, Separation, Voxelizer};
/// use glam::{DMat4, DVec3};
/// let v = Voxelizer::new(&ctx.device)?;
/// let ball = GpuMesh::upload(&ctx.device, &Mesh::uv_sphere(DVec3::ZERO, 0.5, 16, 8))?;
/// let grid = Grid { origin: DVec3::splat(-2.0), voxel: 0.125, size: [32, 32, 32] };
/// for frame in 0..3 {
///     let t = frame as f64 * 0.1;
///     let left = DMat4::from_translation(DVec3::new(-1.0, t, 0.0));
///     let right = DMat4::from_translation(DVec3::new(1.0, -t, 0.0)) * DMat4::from_scale(DVec3::splat(0.8));
///     let mut encoder = ctx.encoder("voxelize");
///     let surface = v.encode_surface_placed(
///         &ctx.device, &mut encoder, &[(&ball, left), (&ball, right)], &grid, Separation::Conservative,
///     )?;
///     ctx.submit_and_wait("voxelize", encoder)?;
///     # let _ = surface;
/// }
/// # Ok(()) }
/// ```
pub struct GpuMesh {
    triangles: wgpu::Buffer,
    count: u32,
    degenerate: usize,
    /// Mesh position of the stored coordinates' origin (the bounds' centre).
    anchor: DVec3,
    /// Largest distance of a vertex from `anchor`.
    radius: f64,
    /// Each kept triangle's box diagonal, largest first, and their running sums and sums of
    /// squares: enough to bound the heavy triangles' work under any matrix without a pass over
    /// the triangles.
    diameters: Vec<f64>,
    sums: Vec<f64>,
    squares: Vec<f64>,
}

impl GpuMesh {
    /// Check `mesh` (triangles, finite positions, indices in range) and copy its positions to a
    /// new GPU buffer. Colours, normals and texture coordinates are not uploaded (the placed
    /// path gives surface voxels).
    pub fn upload(device: &wgpu::Device, mesh: &Mesh) -> Result<GpuMesh, Error> {
        mesh.check()?;
        let used = mesh
            .triangles
            .iter()
            .flatten()
            .map(|&i| mesh.positions[i as usize]);
        let (lo, hi) = used.fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        );
        let anchor = (lo + hi) * 0.5;
        let mut vertices = Vec::with_capacity(mesh.triangles.len() * 3);
        let mut degenerate = 0;
        let mut diameters = Vec::with_capacity(mesh.triangles.len());
        let mut radius: f64 = 0.0;
        for tri in &mesh.triangles {
            let p = tri.map(|i| mesh.positions[i as usize] - anchor);
            if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            let v = p.map(|q| q.as_vec3());
            // The f32 vertices are the triangle the GPU sees: measure those.
            let box_lo = v[0].min(v[1]).min(v[2]).as_dvec3();
            let box_hi = v[0].max(v[1]).max(v[2]).as_dvec3();
            diameters.push((box_hi - box_lo).length());
            radius = v.iter().fold(radius, |r, q| r.max(q.as_dvec3().length()));
            vertices.extend(v.iter().map(|q| q.extend(0.0)));
        }
        if !radius.is_finite() || radius > f32::MAX as f64 / 4.0 {
            return Err(invalid(format!(
                "the mesh spans {} units around its centre, more than f32 can place",
                radius
            )));
        }
        let count = (vertices.len() / 3) as u32;
        diameters.sort_by(|a, b| b.total_cmp(a));
        let running = |f: fn(f64) -> f64| -> Vec<f64> {
            std::iter::once(0.0)
                .chain(diameters.iter().scan(0.0, |acc, &d| {
                    *acc += f(d);
                    Some(*acc)
                }))
                .collect()
        };
        let (sums, squares) = (running(|d| d), running(|d| d * d));
        // One padding vertex keeps the buffer non-empty when every triangle was degenerate.
        if vertices.is_empty() {
            vertices.push(Vec4::ZERO);
        }
        use wgpu::util::DeviceExt;
        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("voxelize resident triangles"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        Ok(GpuMesh {
            triangles,
            count,
            degenerate,
            anchor,
            radius,
            diameters,
            sums,
            squares,
        })
    }

    /// Triangles on the GPU (zero-area ones left out).
    pub fn triangles(&self) -> u32 {
        self.count
    }

    /// Zero-area triangles left out at upload.
    pub fn degenerate(&self) -> usize {
        self.degenerate
    }

    /// The centre of the mesh's bounds and the radius of a ball around it that holds every
    /// triangle: where a model matrix puts the mesh can be bounded from these (to fit a grid
    /// to moving instances, say).
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        (self.anchor, self.radius)
    }

    /// Work-list entries the heavy triangles can need when the triangles are stretched by at
    /// most `stretch` (grid voxels per stored unit) into a grid of `size`: a triangle of box
    /// diagonal d spans at most stretch · d voxels along each axis, so at most
    /// (stretch · d + 3)² columns (one more each way for closed boxes and one for rounding),
    /// and it is heavy only when that exceeds `LIGHT`.
    ///
    /// No triangle lists more than [`MAX_CHUNKS`]: those whose bound is larger (the first
    /// `giant`, where (stretch · d + 3)² / CHUNK passes it) count that many.
    fn chunk_bound(&self, stretch: f64, size: [u32; 3]) -> u64 {
        // (stretch · d + 3)² > LIGHT = 16 only when stretch · d > 1.
        let heavy = self.diameters.partition_point(|&d| stretch * d > 1.0);
        let cap = MAX_CHUNKS as f64;
        let giant = self.diameters[..heavy]
            .partition_point(|&d| (stretch * d + 3.0).powi(2) / CHUNK as f64 > cap);
        let k = (heavy - giant) as f64;
        let columns = stretch * stretch * (self.squares[heavy] - self.squares[giant])
            + 6.0 * stretch * (self.sums[heavy] - self.sums[giant])
            + 9.0 * k;
        let by_size = (columns / CHUNK as f64 + k + giant as f64 * cap).ceil();
        let [x, y, z] = size.map(|n| n as u64);
        let most = (x * y).max(y * z).max(z * x);
        let by_grid = heavy as u64 * most_chunks(most);
        if by_size.is_finite() {
            (by_size as u64).min(by_grid)
        } else {
            by_grid
        }
    }
}

impl Voxelizer {
    /// Surface voxels of several resident meshes, each placed by its model matrix (any
    /// affine, invertible transform: rotation, non-uniform scale, mirror, translation), in
    /// one grid. Nothing is uploaded but the matrices: move the meshes every frame and
    /// voxelize again. The voxels are those of [`Voxelizer::encode_surface_with`] on the
    /// mesh moved in f64 (`Mesh::transformed`), up to the rounding of the move in f32, which
    /// the tests' slack is widened to cover (it can add a voxel within about 10⁻⁵ voxels of a
    /// triangle, never drop one). An empty `parts` gives an empty surface.
    pub fn encode_surface_placed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        parts: &[(&GpuMesh, DMat4)],
        grid: &Grid,
        separation: Separation,
    ) -> Result<Surface, Error> {
        check_grid(grid)?;
        let grid_from_world = DMat4::from_scale(DVec3::splat(1.0 / grid.voxel))
            * DMat4::from_translation(-grid.origin);
        let mut runs = Vec::with_capacity(parts.len());
        for (i, &(mesh, model)) in parts.iter().enumerate() {
            check_model(model).map_err(|e| match e {
                Error::Invalid { stage, what } => Error::Invalid {
                    stage,
                    what: format!("part {i}: {what}"),
                },
                e => e,
            })?;
            let to_grid = grid_from_world * model * DMat4::from_translation(mesh.anchor);
            let linear = glam::DMat3::from_mat4(to_grid);
            // Frobenius norm: at least the largest stretch of any direction.
            let stretch = (linear.x_axis.length_squared()
                + linear.y_axis.length_squared()
                + linear.z_axis.length_squared())
            .sqrt();
            let shift = to_grid.w_axis.truncate();
            // How far f32 rounding can move a vertex, in voxels: the stored position (half an
            // ulp), the matrix's entries (half an ulp each) and the product's three multiplies
            // and adds, each a few ulp of |A|·|p| + |b| — 8 ulp of it bounds them all.
            let rows = linear.transpose();
            let row_sum = [rows.x_axis, rows.y_axis, rows.z_axis]
                .map(|r| r.abs().element_sum())
                .into_iter()
                .fold(0.0, f64::max);
            let size = row_sum * mesh.radius + shift.abs().max_element();
            let moved = 8.0 * f32::EPSILON as f64 * size;
            let placed = to_grid.as_mat4();
            if !placed.is_finite() || !size.is_finite() || size > 1e30 {
                return Err(invalid(format!(
                    "part {i}: the model matrix moves the mesh {size} voxels from the grid, \
                     more than f32 can hold"
                )));
            }
            let capacity =
                u32::try_from(mesh.chunk_bound(stretch, grid.size)).map_err(|_| Error::Size {
                    stage: super::STAGE,
                    what: "heavy-triangle work list entries of one placed mesh",
                    got: mesh.chunk_bound(stretch, grid.size),
                    max: u32::MAX as u64,
                })?;
            runs.push((mesh, placed, capacity, moved as f32));
        }
        let occupancy = zeroed_bitset(device, grid)?;
        let pipelines = match separation {
            Separation::Conservative => &self.surface,
            Separation::Six => &self.surface_six,
        };
        for &(mesh, to_grid, capacity, moved) in &runs {
            let _ = self.surface_pass(
                device,
                rec,
                pipelines,
                &occupancy,
                &SurfaceRun {
                    triangles: &mesh.triangles,
                    count: mesh.count,
                    capacity,
                    to_grid,
                    moved,
                },
                grid,
            )?;
        }
        Ok(Surface {
            size: grid.size,
            occupancy,
            degenerate: parts.iter().map(|(m, _)| m.degenerate).sum(),
        })
    }
}
