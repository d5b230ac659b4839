//! A triangle mesh's signed distance field (`shaders/mesh_sdf/`): every voxel's distance to its
//! nearest *triangle*, exact inside a band around the surface, signed by a vote of rows of
//! voxels that holds for open meshes too, into an `R32Float` 3D texture over any [`Grid`].
//!
#![doc = include_str!("../../docs/mesh_sdf.md")]

pub mod cpu;
mod normals;

use wgpu::util::DeviceExt;

use crate::bind::ComputePipeline;
use crate::error::Error;
use crate::gpu::{Record, kept_buffer, storage_buffer, uniform_buffer, volume_texture};
pub use crate::grid::Grid;
use crate::shaders::mesh_sdf::mesh_sdf::{self as stage, SdfParams};
pub use crate::voxelize::Mesh;

const STAGE: &str = stage::STAGE;

/// Most triangles one field takes: a key holds a triangle's index in its low bits and keeps at
/// least 8 bits for the distance above them.
pub const MAX_TRIANGLES: u64 = 1 << 24;

/// Widest band, voxels.
pub const MAX_BAND: f32 = 4096.0;

/// What a mesh's field holds.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Settings {
    /// Half-width of the band around the surface in which every distance is exact, voxels
    /// (default 4). Beyond it the field holds ±`band` (in world units), signed as everywhere.
    /// The cost grows with the band's volume around each triangle.
    pub band: f32,
    /// Negative inside (default); `false` gives the unsigned distance and skips the sign's pass.
    pub signed: bool,
    /// Also write [`MeshField::march`], the field as fieldkit's SDF march reads it (default
    /// false: 8 more bytes a voxel and one more pass).
    pub march: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            band: 4.0,
            signed: true,
            march: false,
        }
    }
}

impl Settings {
    /// [`Error::Invalid`] unless the band is finite and from above 0 to [`MAX_BAND`] voxels.
    pub fn check(&self) -> Result<(), Error> {
        if !(self.band.is_finite() && self.band > 0.0 && self.band <= MAX_BAND) {
            return Err(Error::invalid(
                STAGE,
                format!(
                    "the band must be finite and above 0 up to {MAX_BAND} voxels, got {}",
                    self.band
                ),
            ));
        }
        Ok(())
    }
}

/// A mesh's distance field on the GPU.
#[derive(Debug)]
pub struct MeshField {
    /// `R32Float` 3D texture of `grid.size`, world units, negative inside when signed; sampled
    /// (`TEXTURE_BINDING`), copied out (`COPY_SRC`) or written again (`STORAGE_BINDING`).
    pub texture: wgpu::Texture,
    /// Where the voxels sit: voxel (i, j, k)'s centre is `grid.voxel_centre([i, j, k])`.
    pub grid: Grid,
    /// With [`Settings::march`]: an `Rgba16Float` 3D texture of the same voxels, red the signed
    /// distance in voxels and green its negation, which `metaball::Raymarcher::encode_march_field`
    /// draws (as a `metaball::MarchField` with threshold 0 and `band` × `grid.voxel`).
    pub march: Option<wgpu::Texture>,
    /// The settings it was made with.
    pub settings: Settings,
    /// Triangles left out for having no area once in the grid's frame.
    pub degenerate: usize,
}

/// Makes mesh distance fields: create once beside your renderer, then
/// [`encode`](Self::encode) for each mesh or grid.
pub struct MeshSdf {
    per_triangle: ComputePipeline<stage::per_triangle::Entry>,
    cross: ComputePipeline<stage::cross_triangles::Entry>,
    layout: stage::Overrides,
    resolve: ComputePipeline<stage::resolve::Entry>,
    march: ComputePipeline<stage::march_texture::Entry>,
    // Scratch kept for the next field of the same size: the keys and the parity rows.
    keys: std::sync::Mutex<Option<wgpu::Buffer>>,
    parity: std::sync::Mutex<Option<wgpu::Buffer>>,
}

/// Where the parity bits of each axis lie in the one parity buffer, words.
struct ParityLayout {
    rows: [u32; 3],
    totals: [u32; 3],
    words: u64,
}

impl ParityLayout {
    fn new(size: [u32; 3]) -> Self {
        let voxels = size.iter().map(|&n| n as u64).product::<u64>();
        let row_words = voxels.div_ceil(32);
        let mut at = 0u64;
        let mut rows = [0u32; 3];
        for r in &mut rows {
            *r = at as u32;
            at += row_words;
        }
        let mut totals = [0u32; 3];
        for (axis, t) in totals.iter_mut().enumerate() {
            *t = at as u32;
            let columns = size[(axis + 1) % 3] as u64 * size[(axis + 2) % 3] as u64;
            at += columns.div_ceil(32);
        }
        Self {
            rows,
            totals,
            words: at,
        }
    }
}

impl MeshSdf {
    /// Create the pipelines.
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Self::with_layout(device, stage::Overrides::default())
    }

    /// [`Self::new`] with the per-triangle pass laid out otherwise (the shader's `LOAD_FIRST`
    /// and `CROSS_APART`): for `cargo xtask bench mesh-sdf`, which times them side by side.
    /// Every layout gives the same field.
    #[doc(hidden)]
    pub fn with_layout(device: &wgpu::Device, layout: stage::Overrides) -> Result<Self, Error> {
        Ok(Self {
            per_triangle: ComputePipeline::with_constants(device, &layout)?,
            cross: ComputePipeline::with_constants(device, &layout)?,
            layout,
            resolve: ComputePipeline::new(device)?,
            march: ComputePipeline::new(device)?,
            keys: Default::default(),
            parity: Default::default(),
        })
    }

    /// Record the distance field of `mesh` over `grid` into `rec`. Each voxel within
    /// `settings.band` of the surface holds its distance to the nearest triangle (f32 arithmetic
    /// on grid-local coordinates: within about 10⁻⁴ voxels of the f64 answer); the sign comes
    /// from rows of voxel centres along x, y and z (see the module's page for where it fails).
    ///
    /// A bake, made when the mesh or the grid changes and sampled for many frames after: the
    /// mesh is moved into the grid's frame on the CPU in f64 and uploaded (its triangles and
    /// pseudo-normals), and the field is a new texture the caller keeps; the keys and parity
    /// scratch are kept here for the next field of the same size. That CPU work grows with the
    /// mesh (tens of milliseconds for a 69 451-triangle mesh, `docs/frame.md`): an app that
    /// bakes while it draws records the bake on a thread of its own into an encoder of its
    /// own — a `MeshSdf` is `Send + Sync` and its [`MeshField`] `Send` — as the viewer does.
    ///
    /// Errors: an empty mesh, a non-finite vertex or index out of range, a mesh of no area, a
    /// grid over [`crate::voxelize::MAX_SIDE`] or the device's 3D texture and buffer limits,
    /// more than [`MAX_TRIANGLES`], a band that is not finite or not above 0.
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        mesh: &Mesh,
        grid: &Grid,
        settings: &Settings,
    ) -> Result<MeshField, Error> {
        let (local, layout, [groups, cross_groups]) = checked(device, mesh, grid, settings)?;
        let count = local.source.len() as u64;
        let size = grid.size;
        let voxels = grid.voxels();

        let triangles = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("mesh sdf triangles"),
            contents: bytemuck::cast_slice(&local.vertices),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let normals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("mesh sdf pseudo-normals"),
            contents: bytemuck::cast_slice(&normals::pseudo_normals(mesh, &local.source)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let scratch = |slot, label, bytes: u64| {
            kept_buffer(slot, bytes, true, || {
                storage_buffer(device, label, bytes, wgpu::BufferUsages::COPY_DST)
            })
        };
        let keys = scratch(&self.keys, "mesh sdf keys", voxels * 4);
        // Unsigned fields still bind the parity buffer, at its smallest.
        let parity_words = if settings.signed { layout.words } else { 1 };
        let parity = scratch(&self.parity, "mesh sdf parity", parity_words * 4);
        let field = volume_texture(device, "mesh sdf", size, wgpu::TextureFormat::R32Float);
        let view = field.create_view(&Default::default());
        let params = uniform_buffer(
            device,
            "mesh sdf params",
            &SdfParams {
                grid: size.into(),
                count: count as u32,
                band: settings.band,
                id_bits: (u64::BITS - (count - 1).leading_zeros()).max(1),
                voxel: grid.voxel as f32,
                signed: settings.signed as u32,
                rows_y: layout.rows[1],
                rows_z: layout.rows[2],
                totals: layout.totals.into(),
            },
        );
        let mut rec = rec.recorder();
        rec.encoder.clear_buffer(&keys, 0, None);
        rec.encoder.clear_buffer(&parity, 0, None);
        self.per_triangle.record(
            device,
            &mut rec,
            &stage::per_triangle::Resources {
                params: (&params).into(),
                triangles: (&triangles).into(),
                keys: (&keys).into(),
                parity: (&parity).into(),
            },
            groups,
            "mesh sdf per triangle",
        )?;
        if settings.signed && self.layout.cross_apart {
            self.cross.record(
                device,
                &mut rec,
                &stage::cross_triangles::Resources {
                    params: (&params).into(),
                    triangles: (&triangles).into(),
                    parity: (&parity).into(),
                },
                cross_groups,
                "mesh sdf crossings",
            )?;
        }
        self.resolve.record(
            device,
            &mut rec,
            &stage::resolve::Resources {
                params: (&params).into(),
                triangles: (&triangles).into(),
                normals: (&normals).into(),
                keys: (&keys).into(),
                parity: (&parity).into(),
                field: (&view).into(),
            },
            ComputePipeline::<stage::resolve::Entry>::groups_for(size),
            "mesh sdf resolve",
        )?;
        let march = if settings.march {
            let march = volume_texture(
                device,
                "mesh sdf march",
                size,
                wgpu::TextureFormat::Rgba16Float,
            );
            self.march.record(
                device,
                &mut rec,
                &stage::march_texture::Resources {
                    params: (&params).into(),
                    field_in: (&view).into(),
                    march: (&march.create_view(&Default::default())).into(),
                },
                ComputePipeline::<stage::march_texture::Entry>::groups_for(size),
                "mesh sdf march texture",
            )?;
            Some(march)
        } else {
            None
        };
        Ok(MeshField {
            march,
            texture: field,
            grid: *grid,
            settings: *settings,
            degenerate: local.degenerate,
        })
    }
}

/// The mesh in the grid's frame, the parity rows' layout and the triangle workgroups, once
/// every limit holds (see [`MeshSdf::encode`]'s errors).
fn checked(
    device: &wgpu::Device,
    mesh: &Mesh,
    grid: &Grid,
    settings: &Settings,
) -> Result<(crate::voxelize::GridMesh, ParityLayout, [[u32; 3]; 2]), Error> {
    settings.check()?;
    let local = mesh.to_grid(grid)?;
    let count = local.source.len() as u64;
    if count == 0 {
        return Err(Error::invalid(
            STAGE,
            format!(
                "every one of the mesh's {} triangles has no area",
                mesh.triangles.len()
            ),
        ));
    }
    check_count("triangles", count, MAX_TRIANGLES)?;
    let size = grid.size;
    check_count(
        "grid side for a 3D texture",
        size.into_iter().max().unwrap_or(0) as u64,
        device.limits().max_texture_dimension_3d as u64,
    )?;
    let layout = ParityLayout::new(size);
    let voxels = grid.voxels();
    let limit = device.limits().max_storage_buffer_binding_size;
    check_count("key buffer bytes", voxels * 4, limit)?;
    check_count("parity buffer bytes", layout.words * 4, limit)?;
    let groups = wide_groups(device, "rows of triangle workgroups", count)?;
    // A thread a triangle for the crossings apart.
    let cross = ComputePipeline::<stage::cross_triangles::Entry>::groups_for([count as u32, 1, 1]);
    let cross_groups = wide_groups(device, "rows of crossing workgroups", cross[0] as u64)?;
    Ok((local, layout, [groups, cross_groups]))
}

/// [`Error::Size`] where `got` is over `max`.
fn check_count(what: &'static str, got: u64, max: u64) -> Result<(), Error> {
    if got > max {
        return Err(Error::Size {
            stage: STAGE,
            what,
            got,
            max,
        });
    }
    Ok(())
}

/// `count` workgroups (one a triangle, or the crossings' of 64 triangles), in rows of the
/// device's widest dispatch.
fn wide_groups(device: &wgpu::Device, what: &'static str, count: u64) -> Result<[u32; 3], Error> {
    let wide = device.limits().max_compute_workgroups_per_dimension as u64;
    let rows = count.div_ceil(wide);
    check_count(what, rows, wide)?;
    Ok([count.min(wide) as u32, rows as u32, 1])
}
