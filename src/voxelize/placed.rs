//! Meshes that stay on the GPU: uploaded once, then voxelized wherever a model matrix puts
//! them. The surface stage moves each vertex by the matrix as it loads it, so a moving mesh, or
//! several instances of one, cost a 64-byte uniform per pass instead of a new triangle buffer.

use glam::{DMat4, DVec3, Vec4};

use super::{
    CHUNK, Error, GpuListing, Grid, KeptWork, LIGHT, MAX_CHUNKS, MAX_GIANTS, Mesh, STAGE,
    Separation, Surface, SurfaceRun, Voxelizer, check_grid, check_model, check_work_list,
    giant_blocks_bound, giant_count, mark_giants, most_chunks, zeroed_bitset,
};
use crate::gpu::Record;

// `ChunkBound::chunks`'s threshold assumes LIGHT = 16.
const _: () = assert!(LIGHT == 16);

/// A mesh's triangles in a GPU buffer, ready for [`Voxelizer::encode_surface_placed`].
///
/// Positions are stored in f32 relative to the centre of the mesh's bounds (so a mesh far from
/// the origin keeps its precision); the move into a grid is composed in f64 on the host and
/// applied on the GPU. Zero-area triangles are left out at upload (an invertible matrix gives
/// them no area either).
///
/// ```
/// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
/// use fieldkit::voxelize::{GpuMesh, Grid, Mesh, Separation, Voxelizer};
/// use fieldkit::glam::{DMat4, DVec3};
/// let v = Voxelizer::new(device)?;
/// let ball = GpuMesh::upload(device, &Mesh::uv_sphere(DVec3::ZERO, 0.5, 16, 8))?;
/// let grid = Grid { origin: DVec3::splat(-2.0), voxel: 0.125, size: [32, 32, 32] };
/// for frame in 0..3 {
///     let t = frame as f64 * 0.1;
///     let left = DMat4::from_translation(DVec3::new(-1.0, t, 0.0));
///     let right = DMat4::from_translation(DVec3::new(1.0, -t, 0.0)) * DMat4::from_scale(DVec3::splat(0.8));
///     let mut encoder = device.create_command_encoder(&Default::default());
///     let surface = v.encode_surface_placed(
///         device, &mut encoder, &[(&ball, left), (&ball, right)], &grid, Separation::Conservative,
///     )?;
///     queue.submit([encoder.finish()]);
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
    bound: ChunkBound,
}

/// Each kept triangle's box diagonal, largest first, and their running sums and sums of
/// squares: enough to bound the heavy triangles' work under any matrix without a pass over the
/// triangles.
struct ChunkBound {
    diameters: Vec<f64>,
    /// The triangles of the [`MAX_GIANTS`] largest diameters, largest first (ties by index):
    /// those a pass may make giant ([`mark_giants`]).
    largest: Vec<u32>,
    sums: Vec<f64>,
    squares: Vec<f64>,
}

/// The diagonal of the box of a triangle as the GPU stores it (f32, relative to the anchor).
fn box_diagonal(v: &[glam::Vec3; 3]) -> f64 {
    let lo = v[0].min(v[1]).min(v[2]).as_dvec3();
    let hi = v[0].max(v[1]).max(v[2]).as_dvec3();
    (hi - lo).length()
}

/// The largest and second-largest stretch of `linear` along the grid's axes (the lengths of
/// its rows): a segment of length d spans at most row_i · d voxels along axis i.
fn axis_stretches(linear: glam::DMat3) -> (f64, f64) {
    let mut rows = [0, 1, 2].map(|i| linear.row(i).length());
    rows.sort_by(|a, b| b.total_cmp(a));
    (rows[0], rows[1])
}

impl ChunkBound {
    fn new(mut diameters: Vec<f64>) -> Self {
        let mut order: Vec<u32> = (0..diameters.len() as u32).collect();
        order.sort_by(|&i, &j| diameters[j as usize].total_cmp(&diameters[i as usize]));
        order.truncate(MAX_GIANTS as usize);
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
        Self {
            diameters,
            largest: order,
            sums,
            squares,
        }
    }

    /// Work-list entries the heavy triangles can need when moved into a grid of `size` by a
    /// matrix whose rows' largest lengths are `a` ≥ `b` (`axis_stretches`): a triangle of box
    /// diagonal d spans at most a · d and b · d voxels along two axes, so its box's largest face
    /// has at most (a · d + 3)(b · d + 3) columns (one more each way for closed boxes and one
    /// for rounding: the GPU grows the box by at most [`MOST_MOVED`] each way), and it is heavy
    /// only when that exceeds `LIGHT`.
    ///
    /// The first `skip` (the pass's giants) list nothing. No triangle lists more than
    /// [`MAX_CHUNKS`]: those whose bound is larger (up to `capped`) count that many.
    fn chunks(&self, a: f64, b: f64, size: [u32; 3], skip: usize) -> u64 {
        // (a · d + 3)(b · d + 3) ≤ (a · d + 3)² ≤ LIGHT = 16 when a · d ≤ 1.
        let heavy = self.diameters.partition_point(|&d| a * d > 1.0).max(skip);
        let cap = MAX_CHUNKS as f64;
        let capped = self.diameters[..heavy]
            .partition_point(|&d| (a * d + 3.0) * (b * d + 3.0) / CHUNK as f64 > cap)
            .max(skip);
        let k = (heavy - capped) as f64;
        let columns = a * b * (self.squares[heavy] - self.squares[capped])
            + 3.0 * (a + b) * (self.sums[heavy] - self.sums[capped])
            + 9.0 * k;
        let by_size = (columns / CHUNK as f64 + k + (capped - skip) as f64 * cap).ceil();
        let [x, y, z] = size.map(|n| n as u64);
        let most = (x * y).max(y * z).max(z * x);
        let by_grid = (heavy - skip) as u64 * most_chunks(most);
        if by_size.is_finite() {
            (by_size as u64).min(by_grid)
        } else {
            by_grid
        }
    }

    /// The pass's listing under the same matrix: its giants from the bounds of the
    /// [`MAX_GIANTS`] + 1 largest triangles (each clamped to the grid's largest face;
    /// [`giant_count`]), and the others' entries ([`ChunkBound::chunks`]).
    fn listing(&self, a: f64, b: f64, size: [u32; 3]) -> GpuListing {
        let [x, y, z] = size.map(|n| n as u64);
        let most = (x * y).max(y * z).max(z * x);
        let heavy = self.diameters.partition_point(|&d| a * d > 1.0);
        let bounds: Vec<u64> = self.diameters[..heavy.min(MAX_GIANTS as usize + 1)]
            .iter()
            .map(|&d| ((a * d + 3.0) * (b * d + 3.0)).min(most as f64).ceil() as u64)
            .collect();
        let giants = giant_count(&bounds);
        GpuListing {
            capacity: self.chunks(a, b, size, giants),
            giants: giants as u32,
            blocks: bounds[..giants]
                .iter()
                .map(|&c| giant_blocks_bound(c))
                .sum(),
        }
    }
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
            diameters.push(box_diagonal(&v));
            radius = v.iter().fold(radius, |r, q| r.max(q.as_dvec3().length()));
            vertices.extend(v.iter().map(|q| q.extend(0.0)));
        }
        if !radius.is_finite() || radius > f32::MAX as f64 / 4.0 {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the mesh spans {} units around its centre, more than f32 can place",
                    radius
                ),
            ));
        }
        let count = (vertices.len() / 3) as u32;
        let bound = ChunkBound::new(diameters);
        mark_giants(&mut vertices, &bound.largest);
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
            bound,
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
}

/// The most, in voxels, that f32 rounding may move a placed mesh's vertex (its bound,
/// `moved`, grows with the mesh's distance from the grid's origin: half a voxel at about
/// 524 000 voxels): the GPU grows each triangle's box by the bound, and past this a placement
/// is refused rather than voxelized with voxels the rounding could drop.
const MOST_MOVED: f64 = 0.5;

impl Voxelizer {
    /// Surface voxels of several resident meshes, each placed by its model matrix (any
    /// affine, invertible transform: rotation, non-uniform scale, mirror, translation), in
    /// one grid. Nothing is uploaded but the matrices: move the meshes every frame and
    /// voxelize again. The voxels are those of [`Voxelizer::encode_surface_with`] on the
    /// mesh moved in f64 (`Mesh::transformed`), up to the rounding of the move in f32, which
    /// each triangle's box and tests are widened to cover (it can add a voxel within about
    /// 10⁻⁵ voxels of a triangle, never drop one, even one a vertex touches at a single point
    /// on a voxel plane). A mesh so far from the grid's origin that f32 places it only within
    /// more than half a voxel is refused ([`Error::Invalid`]). An empty `parts` gives an empty
    /// surface.
    pub fn encode_surface_placed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        parts: &[(&GpuMesh, DMat4)],
        grid: &Grid,
        separation: Separation,
    ) -> Result<Surface, Error> {
        let runs = placed_runs(device, parts, grid)?;
        let occupancy = zeroed_bitset(device, grid)?;
        self.record_placed(device, rec, &runs, &occupancy, grid, separation)?;
        Ok(Surface::new(
            grid.size,
            occupancy,
            parts.iter().map(|(m, _)| m.degenerate).sum(),
        ))
    }

    /// [`Voxelizer::encode_surface_placed`] into `surface`, a surface made before for a grid
    /// of the same size: its bitset is cleared in `rec` and filled again, and the heavy
    /// triangles' work list is kept with it (made by the first refill, a quarter larger than it
    /// needs, and made again only when a listing outgrows it), so a loop that voxelizes every
    /// frame allocates nothing a frame but the passes' uniforms: not the bitset (16 MiB at 512³,
    /// 128 MiB at 1024³) nor the list (35 MB for the Stanford bunny at 1024³). The voxels are
    /// the same as a new surface's. The clear is recorded into `rec` (a new buffer is zeroed
    /// by wgpu instead, in a command buffer of its own at submission), so the GPU clears the
    /// bitset either way: what this saves is the allocations.
    ///
    /// Refused with [`Error::Invalid`], before anything is recorded: a surface of another size
    /// than `grid`, or whose buffer is too small for it or lacks `STORAGE` or `COPY_DST`; and
    /// whatever `encode_surface_placed` refuses. On an error `surface` is left as it was.
    ///
    /// ```
    /// # fn f(device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(), fieldkit::Error> {
    /// use fieldkit::voxelize::{GpuMesh, Grid, Mesh, Separation, Voxelizer};
    /// use fieldkit::glam::{DMat4, DVec3};
    /// let v = Voxelizer::new(device)?;
    /// let ball = GpuMesh::upload(device, &Mesh::uv_sphere(DVec3::ZERO, 0.5, 16, 8))?;
    /// let grid = Grid { origin: DVec3::splat(-2.0), voxel: 0.125, size: [32, 32, 32] };
    /// let mut surface = None;
    /// for frame in 0..3 {
    ///     let place = [(&ball, DMat4::from_translation(DVec3::new(frame as f64 * 0.1, 0.0, 0.0)))];
    ///     let mut encoder = device.create_command_encoder(&Default::default());
    ///     match surface.as_mut() {
    ///         None => surface = Some(v.encode_surface_placed(
    ///             device, &mut encoder, &place, &grid, Separation::Conservative)?),
    ///         Some(s) => v.encode_surface_placed_into(
    ///             device, &mut encoder, &place, &grid, Separation::Conservative, s)?,
    ///     }
    ///     queue.submit([encoder.finish()]);
    /// }
    /// # Ok(()) }
    /// ```
    pub fn encode_surface_placed_into(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        parts: &[(&GpuMesh, DMat4)],
        grid: &Grid,
        separation: Separation,
        surface: &mut Surface,
    ) -> Result<(), Error> {
        let runs = placed_runs(device, parts, grid)?;
        check_reused(device, surface, grid)?;
        // One work list for every part, kept with the surface: new only where the largest
        // listing has outgrown it.
        let most = runs.iter().map(|r| r.2.capacity).max().unwrap_or(0);
        let kept: &KeptWork = match surface.kept.take() {
            Some(k) if k.heavy.capacity as u64 >= most => surface.kept.insert(k),
            // Within a binding (`placed_runs` checked): a u32 count.
            _ => surface
                .kept
                .insert(Box::new(KeptWork::new(device, most as u32))),
        };
        rec.recorder()
            .encoder
            .clear_buffer(&surface.occupancy, 0, None);
        let pipelines = self.pipelines(separation);
        for run in &runs {
            kept.reset(rec);
            self.surface_pass_with(
                device,
                rec,
                pipelines,
                &surface.occupancy,
                &run_of(run),
                grid,
                &kept.heavy,
            )?;
        }
        surface.degenerate = parts.iter().map(|(m, _)| m.degenerate).sum();
        Ok(())
    }

    /// The surface passes of `runs` into `occupancy`.
    fn record_placed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        runs: &[PlacedRun],
        occupancy: &wgpu::Buffer,
        grid: &Grid,
        separation: Separation,
    ) -> Result<(), Error> {
        let pipelines = self.pipelines(separation);
        for run in runs {
            let _ = self.surface_pass(device, rec, pipelines, occupancy, &run_of(run), grid)?;
        }
        Ok(())
    }
}

/// The surface pass's view of a placed run.
fn run_of<'a>(&(mesh, to_grid, listing, moved): &PlacedRun<'a>) -> SurfaceRun<'a> {
    SurfaceRun {
        triangles: &mesh.triangles,
        count: mesh.count,
        listing,
        to_grid,
        moved,
    }
}

/// One placed mesh as its surface pass takes it: the mesh, its move into the grid in f32, how
/// its heavy triangles are listed, and how far f32 rounding of the move can carry a vertex.
type PlacedRun<'a> = (&'a GpuMesh, glam::Mat4, GpuListing, f32);

/// Check `grid` and every part's matrix, and make each part's [`PlacedRun`], refusing a work
/// list larger than one binding (as `surface_pass` would, but before anything is recorded).
fn placed_runs<'a>(
    device: &wgpu::Device,
    parts: &[(&'a GpuMesh, DMat4)],
    grid: &Grid,
) -> Result<Vec<PlacedRun<'a>>, Error> {
    check_grid(grid)?;
    let grid_from_world =
        DMat4::from_scale(DVec3::splat(1.0 / grid.voxel)) * DMat4::from_translation(-grid.origin);
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
        let (a, b) = axis_stretches(linear);
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
            return Err(Error::invalid(
                STAGE,
                format!(
                    "part {i}: the model matrix moves the mesh {size} voxels from the grid, \
                 more than f32 can hold"
                ),
            ));
        }
        // The GPU grows each triangle's box by `moved` so that a vertex rounded past a voxel
        // plane it lies on still reaches the voxel beyond; the work list's bound allows half a
        // voxel of it each way (`ChunkBound::chunks`).
        if moved > MOST_MOVED {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "part {i}: the mesh reaches {size:.0} voxels from the grid's origin, where \
                     f32 places it only within {moved:.2} voxels (at most {MOST_MOVED} keeps the \
                     placed path conservative): voxelize it with encode_surface (moved in f64)"
                ),
            ));
        }
        let listing = mesh.bound.listing(a, b, grid.size);
        check_work_list(device, &listing)?;
        runs.push((mesh, placed, listing, moved as f32));
    }
    Ok(runs)
}

/// Whether `surface` can take a surface of `grid` again: the same size, a buffer that holds
/// its bits within one binding, and the usages the clear and the passes need.
fn check_reused(device: &wgpu::Device, surface: &Surface, grid: &Grid) -> Result<(), Error> {
    if surface.size != grid.size {
        return Err(Error::invalid(
            STAGE,
            format!(
                "the surface to refill is {:?} voxels, the grid {:?}; make a new surface for \
             another size",
                surface.size, grid.size
            ),
        ));
    }
    let bytes = grid.voxels().div_ceil(32).max(1) * 4;
    let buffer = &surface.occupancy;
    let limit = device.limits().max_storage_buffer_binding_size;
    if buffer.size() < bytes || buffer.size() > limit {
        return Err(Error::invalid(
            STAGE,
            format!(
                "the surface's occupancy buffer is {} bytes; {} voxels need {bytes}, within the \
             device's binding limit of {limit}",
                buffer.size(),
                grid.voxels()
            ),
        ));
    }
    let needs = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    if !buffer.usage().contains(needs) {
        return Err(Error::invalid(
            STAGE,
            format!(
                "the surface's occupancy buffer has usages {:?}; refilling it needs {needs:?}",
                buffer.usage()
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{ChunkBound, axis_stretches, box_diagonal};
    use crate::voxelize::{GpuListing, LIGHT, MAX_GIANTS, box_columns, most_chunks};
    use glam::{DMat3, DMat4, DVec3, EulerRot, Vec3};
    use proptest::prelude::*;

    /// `ChunkBound::listing` for `stored` (f32 triangles, as `GpuMesh` keeps them) moved by
    /// `to_grid`, and the entries the GPU's list needs for the same triangles moved in f64
    /// (each moved triangle's box columns, themselves at least what the GPU finds) but for the
    /// giants the listing marks (the first `giants` of `ChunkBound::largest`).
    fn listing_and_entries(
        stored: &[[Vec3; 3]],
        to_grid: DMat4,
        size: [u32; 3],
    ) -> (GpuListing, u64) {
        let bound = ChunkBound::new(stored.iter().map(box_diagonal).collect());
        let (a, b) = axis_stretches(DMat3::from_mat4(to_grid));
        let listing = bound.listing(a, b, size);
        let giants = &bound.largest[..listing.giants as usize];
        let moved: Vec<_> = stored
            .iter()
            .flatten()
            .map(|v| to_grid.transform_point3(v.as_dvec3()).as_vec3().extend(0.0))
            .collect();
        let entries = moved
            .chunks(3)
            .zip(0..)
            .filter(|(_, i)| !giants.contains(i))
            .map(|(t, _)| box_columns(t, size))
            .filter(|&c| c > LIGHT as u64)
            .map(most_chunks)
            .sum();
        (listing, entries)
    }

    /// [`listing_and_entries`]: the listing holds every entry, and marks no more giants than
    /// there are records.
    fn check(stored: &[[Vec3; 3]], to_grid: DMat4, size: [u32; 3]) -> (GpuListing, u64) {
        let (listing, entries) = listing_and_entries(stored, to_grid, size);
        assert!(
            listing.capacity >= entries,
            "{listing:?} < {entries} entries"
        );
        assert!(listing.giants <= MAX_GIANTS, "{listing:?}");
        (listing, entries)
    }

    /// One flat right triangle per (leg, height) at the origin.
    fn flat(legs: &[(f32, f32)]) -> Vec<[Vec3; 3]> {
        legs.iter()
            .map(|&(l, z)| {
                [
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(l, 0.0, z),
                    Vec3::new(0.0, l, z),
                ]
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

        /// The bound holds whatever the matrix: rotations, shears, scales from 1/20 to 40
        /// voxels per unit along each axis, mirrors, shifts in and out of grids of any size, triangles
        /// from specks to larger than the grid.
        #[test]
        fn the_bound_holds_under_any_matrix(
            triangles in prop::collection::vec(prop::array::uniform9(-20.0f32..20.0), 1..30),
            scale in prop::array::uniform3(0.05f64..40.0),
            mirror in prop::array::uniform3(any::<bool>()),
            angles in prop::array::uniform3(-3.2f64..3.2),
            shear in prop::array::uniform3(-4.0f64..4.0),
            shift in prop::array::uniform3(-100.0f64..400.0),
            size in prop::array::uniform3(1u32..400),
        ) {
            let stored: Vec<[Vec3; 3]> = triangles
                .iter()
                .map(|t| [0, 1, 2].map(|i| Vec3::new(t[3 * i], t[3 * i + 1], t[3 * i + 2])))
                .collect();
            let signs = DVec3::from_array(mirror.map(|m| if m { -1.0 } else { 1.0 }));
            // A shear as well, so rows can be far from orthogonal.
            let shear = DMat3::from_cols(
                DVec3::X,
                DVec3::new(shear[0], 1.0, 0.0),
                DVec3::new(shear[1], shear[2], 1.0),
            );
            let linear = DMat3::from_euler(EulerRot::XYZ, angles[0], angles[1], angles[2])
                * shear
                * DMat3::from_diagonal(DVec3::from_array(scale) * signs);
            let to_grid = DMat4::from_mat3_translation(linear, DVec3::from_array(shift));
            check(&stored, to_grid, size);
        }
    }

    /// Not loose where it need not be: a flat square in 64 × 64 tiles, unmoved. A tile's
    /// triangles have boxes of up to 66² columns (closed boxes reach a voxel past each integer
    /// edge), 138 368 chunks for the 128; the bound counts (64√2 + 3)² / 4 + 1 = 2 187 each,
    /// 279 938 (2.02 times). The Frobenius norm of the matrix as the stretch of both sides
    /// would count about 6 times.
    #[test]
    fn the_bound_is_within_about_twice_the_count_unmoved() {
        let mut stored = Vec::new();
        for i in 0..8 {
            for j in 0..8 {
                let (x, y) = (64.0 * i as f32, 64.0 * j as f32);
                let c = [(0.0, 0.0), (64.0, 0.0), (64.0, 64.0), (0.0, 64.0)]
                    .map(|(u, v)| Vec3::new(x + u, y + v, 1.5));
                stored.push([c[0], c[1], c[2]]);
                stored.push([c[0], c[2], c[3]]);
            }
        }
        let (listing, count) = check(&stored, DMat4::IDENTITY, [512, 512, 4]);
        // 128 triangles of the same bound: none is giant.
        assert_eq!(listing.giants, 0);
        let bound = listing.capacity;
        assert!(count > 0, "{bound} against {count}");
        assert!(
            (bound as f64) < 2.05 * count as f64,
            "{bound} against {count} chunks"
        );
    }

    /// Giant triangles: the largest (at most `MAX_GIANTS`) whose bounds pass the threshold are
    /// marked and list no entries; the rest keep theirs. Two halves of a square over a 4096²
    /// grid and a small triangle: the two pass `GIANT_MIN_COLUMNS`, the small one (31²
    /// columns, bound 2 064) does not. 64 + 10 large ones: the 64 largest. 70 equal ones: none,
    /// each listed (in `MAX_CHUNKS`).
    #[test]
    fn the_largest_triangles_are_giant() {
        use crate::voxelize::MAX_CHUNKS;
        let size = [4096, 4096, 2];
        let (listing, entries) = check(
            &flat(&[(30.0, 0.5), (4096.0, 0.5), (4096.0, 1.5)]),
            DMat4::IDENTITY,
            size,
        );
        assert_eq!(listing.giants, 2);
        // The small one: 31² columns, 241 chunks of 4; its bound, 2 064 columns, 517.
        assert_eq!((entries, listing.capacity), (241, 517));

        let mut legs = vec![(1000.0, 0.5); 64];
        legs.extend([(200.0, 1.5); 10]);
        let (listing, entries) = check(&flat(&legs), DMat4::IDENTITY, size);
        assert_eq!(listing.giants, 64);
        assert_eq!(entries, 10 * (201 * 201u64).div_ceil(4));

        let (listing, entries) = check(&flat(&[(4096.0, 0.5); 70]), DMat4::IDENTITY, size);
        assert_eq!(listing.giants, 0);
        assert_eq!(entries, 70 * MAX_CHUNKS as u64);
    }
}
