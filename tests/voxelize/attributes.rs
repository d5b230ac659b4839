//! Averaged voxel attributes (`voxelize/attributes`, `voxelize/compact`): a constant colour comes
//! back exactly, colours, normals and triangle counts match the f64 reference
//! (`voxelize::cpu::attribute_sums`), heavy triangles count once, cancelling normals are
//! reported, two runs give identical bytes, and bad attribute arrays get typed errors.

use crate::common;

use common::upload_2d;

use fieldkit::Error;
use fieldkit::gpu::{Context, read_buffer};
use fieldkit::voxelize::{Attributes, Grid, Mesh, VoxelAttributes, Voxelizer, cpu};
use glam::DVec3;

fn sphere_grid() -> Grid {
    Grid {
        origin: DVec3::new(-1.3, -1.25, -1.2),
        voxel: 2.5 / 24.0,
        size: [26, 24, 25],
    }
}

/// A sphere with a colour ramp over its vertices and its exact vertex normals.
fn painted_sphere() -> Mesh {
    let mut mesh = Mesh::uv_sphere(DVec3::new(0.02, -0.03, 0.01), 1.0, 20, 11);
    mesh.colors = mesh
        .positions
        .iter()
        .map(|p| {
            let q = (*p + 1.0) * 0.5 * 255.0;
            [q.x as u8, q.y as u8, q.z as u8, 255 - q.x as u8]
        })
        .collect();
    mesh.normals = mesh
        .positions
        .iter()
        .map(|p| *p - DVec3::new(0.02, -0.03, 0.01))
        .collect();
    mesh
}

fn run(ctx: &Context, mesh: &Mesh, grid: &Grid) -> (Attributes, Vec<VoxelAttributes>) {
    let v = Voxelizer::new(&ctx.device).unwrap();
    let a = ctx
        .block_on(v.attributes(&ctx.device, &ctx.queue, mesh, grid))
        .unwrap();
    let read = a.read(&ctx.device, &ctx.queue).wait(ctx).unwrap();
    (a, read)
}

/// Every voxel of the list against the reference: the same voxels in the same order, the same
/// triangle counts (integers, exactly), colours within one 8-bit level and normals within
/// `normal_tolerance` radians.
fn check_against_reference(
    mesh: &Mesh,
    grid: &Grid,
    got: &[VoxelAttributes],
    normal_tolerance: f32,
) {
    let local = mesh.to_grid(grid).unwrap();
    let want = cpu::attribute_sums(mesh, &local, grid.size);
    check_sums(grid, got, &want, 1, normal_tolerance);
}

/// `check_against_reference` against the sums `want` of a mesh drawn `copies` times over itself:
/// the same voxels, `copies` times the triangle counts, the same means.
fn check_sums(
    grid: &Grid,
    got: &[VoxelAttributes],
    want: &std::collections::BTreeMap<u64, cpu::AttributeSum>,
    copies: u32,
    normal_tolerance: f32,
) {
    let [nx, ny, _] = grid.size.map(u64::from);
    let got_index: Vec<u64> = got
        .iter()
        .map(|v| (v.voxel[2] as u64 * ny + v.voxel[1] as u64) * nx + v.voxel[0] as u64)
        .collect();
    let want_index: Vec<u64> = want.keys().copied().collect();
    let first = got_index.iter().zip(&want_index).position(|(g, w)| g != w);
    assert!(
        got_index == want_index,
        "voxels or their order differ from the reference: {} against {}, first at {first:?}: {:?}",
        got_index.len(),
        want_index.len(),
        first.map(|i| (got_index[i], want_index[i]))
    );
    let (mut worst_colour, mut worst_normal) = (0.0f64, 0.0f32);
    for (g, w) in got.iter().zip(want.values()) {
        assert_eq!(
            g.triangles,
            copies * w.triangles,
            "triangle count at voxel {:?}",
            g.voxel
        );
        for ch in 0..4 {
            let mean = w.color[ch] / w.triangles as f64;
            worst_colour = worst_colour.max((g.color[ch] as f64 - mean).abs());
        }
        let n = g.normal.expect("these meshes' normals do not cancel");
        let angle = n.angle_between(w.normal.normalize().as_vec3());
        worst_normal = worst_normal.max(angle);
    }
    // Rounding to the nearest level is 0.5 off at most, the sums' 1/16-level steps add 1/32
    // per contribution at most, f32 barycentrics a little more (llvmpipe: 0.531).
    assert!(worst_colour <= 0.55, "colour off by {worst_colour} levels");
    eprintln!("worst colour {worst_colour} levels, normal {worst_normal} rad");
    assert!(
        worst_normal <= normal_tolerance,
        "normal off by {worst_normal} rad"
    );
}

#[test]
fn constant_colour_comes_back_exactly() {
    let ctx = Context::shared();
    let mut mesh = Mesh::uv_sphere(DVec3::ZERO, 1.0, 24, 12);
    let colour = [201, 37, 94, 250];
    mesh.colors = vec![colour; mesh.positions.len()];
    let (a, got) = run(&ctx, &mesh, &sphere_grid());
    let surface = a.surface.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    assert_eq!(got.len(), surface.iter().filter(|&&b| b).count());
    assert_eq!(a.count as usize, got.len());
    assert!(got.len() > 500, "only {} voxels", got.len());
    for v in &got {
        assert_eq!(v.color, colour, "voxel {:?}", v.voxel);
    }
}

#[test]
fn colours_normals_and_counts_match_the_reference() {
    let ctx = Context::shared();
    let mesh = painted_sphere();
    let grid = sphere_grid();
    let (_, got) = run(&ctx, &mesh, &grid);
    // Octahedral snorm16 loses 1e-4 rad; f32 interpolation and the sums' 1/4096 steps more
    // (llvmpipe: 4.9e-4).
    check_against_reference(&mesh, &grid, &got, 1e-3);
    // Face normals when the mesh has none: the averages still point away from the centre.
    let mut flat = mesh.clone();
    flat.normals.clear();
    let (_, got) = run(&ctx, &flat, &grid);
    check_against_reference(&flat, &grid, &got, 1e-3);
}

/// Triangles with more than `LIGHT` (16) columns go through the surface pass's work list; the attribute
/// pass must walk the same list and count each of their voxels once.
#[test]
fn heavy_triangles_count_once() {
    let ctx = Context::shared();
    let (lo, hi) = (DVec3::new(1.3, 2.2, 1.7), DVec3::new(21.6, 19.4, 22.1));
    let mesh = Mesh {
        colors: (0..8)
            .map(|i| [30 * i as u8, 255 - 20 * i as u8, 100, 255])
            .collect(),
        ..Mesh::cuboid(lo, hi)
    };
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [24, 22, 24],
    };
    let (_, got) = run(&ctx, &mesh, &grid);
    // The box's faces carry their own normals: exact up to the encoding (5e-5 rad), except
    // along edges, where two faces' normals are averaged just as the reference does.
    check_against_reference(&mesh, &grid, &got, 1e-3);
    // Edge voxels see both faces' triangles (and the diagonal's two); a face's inner voxels
    // see one or two.
    assert!(got.iter().any(|v| v.triangles >= 3));
}

/// [`common::right_triangle`] with a colour per corner, and `copies` copies of it in one mesh.
fn right_triangles(leg: f64, copies: u32) -> (Mesh, Mesh) {
    let one = Mesh {
        colors: vec![[200, 10, 30, 255], [0, 90, 250, 255], [40, 40, 40, 128]],
        ..common::right_triangle(leg)
    };
    let mesh = common::repeated(&one, copies);
    (one, mesh)
}

/// More chunks than one dispatch row holds (65 535 workgroups of 64): 257 copies of a triangle
/// whose box face holds 256² columns list 257 × 16 384 = 4.21 M chunks of 4 columns (a box face
/// of at most 65 536 columns keeps chunks of 4), so the work list's passes (surface and
/// attributes) run in two rows of workgroups. Every voxel against the reference for one copy:
/// the same voxels in the same order, 257 times its triangle count, its colour and normal.
#[test]
fn more_chunks_than_one_dispatch_row_holds() {
    let ctx = Context::shared();
    let copies = 257u32;
    let (one, mesh) = right_triangles(255.0, copies);
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [256, 256, 2],
    };
    let local = mesh.to_grid(&grid).unwrap();
    // The bound is exact here: each triangle has 256² columns, in chunks of 4.
    let chunks = fieldkit::voxelize::heavy_chunk_bound(&local, grid.size) as u64;
    assert_eq!(chunks, copies as u64 * 256 * 256 / 4);
    assert!(chunks > 65_535 * 64, "{chunks} chunks fit one row");
    let (_, got) = run(&ctx, &mesh, &grid);
    assert!(got.len() > 30_000, "{} voxels", got.len());
    let want = cpu::attribute_sums(&one, &one.to_grid(&grid).unwrap(), grid.size);
    check_sums(&grid, &got, &want, copies, 1e-3);
}

/// One triangle whose box face holds 901² columns (202 951 chunks of 4): a giant on the GPU's
/// list (past `GIANT_MIN_COLUMNS`), so the surface pass records it and the attribute pass walks
/// its 3 172 blocks of 64 chunks a workgroup each. Before giants, it was listed in 16 237
/// chunks of 50 columns; before that one thread listed every chunk of 4, and on lavapipe, whose
/// compiler ends an invocation's loops after 65 535 iterations, the voxels of the chunks past
/// the 65 535th were lost (this test failed there). Every voxel against the reference; fails
/// when the giant pass walks 3 columns per chunk instead of 4.
#[test]
fn one_giant_triangle_lists_every_chunk() {
    let ctx = Context::shared();
    let (one, _) = right_triangles(900.0, 1);
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [904, 904, 2],
    };
    let local = one.to_grid(&grid).unwrap();
    // One giant, triangle 0, and no entries.
    use fieldkit::voxelize::GpuListing;
    assert_eq!(
        GpuListing::exact(&local, grid.size),
        (
            GpuListing {
                capacity: 0,
                giants: 1,
                // 901² columns in chunks of 4, 64 to a block.
                blocks: (901 * 901u64).div_ceil(4).div_ceil(64),
            },
            vec![0]
        )
    );
    let (_, got) = run(&ctx, &one, &grid);
    assert!(got.len() > 400_000, "{} voxels", got.len());
    check_against_reference(&one, &grid, &got, 1e-3);
}

/// A sheet drawn twice with opposite windings: its normals cancel, and the voxels say so.
#[test]
fn cancelling_normals_are_reported() {
    let ctx = Context::shared();
    let p = vec![
        DVec3::new(1.2, 1.3, 3.5),
        DVec3::new(6.7, 1.1, 3.5),
        DVec3::new(3.9, 6.6, 3.5),
    ];
    let mesh = Mesh {
        positions: p,
        triangles: vec![[0, 1, 2], [0, 2, 1]],
        ..Mesh::default()
    };
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [8, 8, 8],
    };
    let (_, got) = run(&ctx, &mesh, &grid);
    assert!(!got.is_empty());
    for v in &got {
        assert_eq!(v.normal, None, "voxel {:?}", v.voxel);
        assert_eq!(v.triangles, 2);
    }
}

#[test]
fn two_runs_give_identical_bytes() {
    let ctx = Context::shared();
    let mesh = painted_sphere();
    let grid = sphere_grid();
    let (a, _) = run(&ctx, &mesh, &grid);
    let (b, _) = run(&ctx, &mesh, &grid);
    assert_eq!(
        read_buffer(&ctx, &a.voxels).unwrap(),
        read_buffer(&ctx, &b.voxels).unwrap()
    );
}

#[test]
fn bad_attribute_arrays_get_typed_errors() {
    let ctx = Context::shared();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let grid = sphere_grid();
    let mut mesh = painted_sphere();
    mesh.colors.pop();
    let err = ctx
        .block_on(v.attributes(&ctx.device, &ctx.queue, &mesh, &grid))
        .err()
        .expect("short colours");
    assert!(
        matches!(&err, Error::Invalid { what, .. } if what.contains("colors")),
        "{err}"
    );
    let mut mesh = painted_sphere();
    mesh.normals[3] = DVec3::new(f64::NAN, 0.0, 1.0);
    let err = ctx
        .block_on(v.attributes(&ctx.device, &ctx.queue, &mesh, &grid))
        .err()
        .expect("NaN normal");
    assert!(
        matches!(&err, Error::Invalid { what, .. } if what.contains("normal 3")),
        "{err}"
    );
    let empty = Mesh::default();
    assert!(matches!(
        ctx.block_on(v.attributes(&ctx.device, &ctx.queue, &empty, &grid)),
        Err(Error::Size { .. })
    ));
}

/// The dense volumes other stages sample (`voxelize/attribute_volume`): every listed voxel's
/// colour exactly and its normal to snorm8 precision, zero everywhere else.
#[test]
fn attribute_volumes_hold_the_list() {
    let ctx = Context::shared();
    let mesh = painted_sphere();
    let grid = sphere_grid();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let a = ctx
        .block_on(v.attributes(&ctx.device, &ctx.queue, &mesh, &grid))
        .unwrap();
    let list = a.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let mut enc = ctx.encoder("volumes");
    let volumes = v
        .encode_attribute_volumes(&ctx.device, &mut enc, &a)
        .unwrap();
    ctx.submit_and_wait("volumes", enc).unwrap();
    let colour: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, &volumes.colour).unwrap();
    let normal: Vec<[i8; 4]> = fieldkit::gpu::read_texture(&ctx, &volumes.normal).unwrap();
    let [nx, ny, _] = grid.size.map(|n| n as usize);
    let mut listed = vec![false; colour.len()];
    for voxel in &list {
        let [x, y, z] = voxel.voxel.map(|c| c as usize);
        let i = (z * ny + y) * nx + x;
        listed[i] = true;
        assert_eq!(colour[i], voxel.color, "colour at {:?}", voxel.voxel);
        let n = voxel.normal.unwrap();
        let got = glam::Vec3::new(
            normal[i][0] as f32,
            normal[i][1] as f32,
            normal[i][2] as f32,
        ) / 127.0;
        // snorm8: Vulkan lets a store return either of the two nearest levels ("should
        // round to nearest"), so one step, 1/127, per component; the GPU's octahedral decode
        // (f32, with or without fused multiply-adds) adds a few f32 roundings, under 1e-5.
        // Measured: llvmpipe within half a step; the H100 0.55 steps off at [9, 9, 2]
        // (x: −0.3228 stored for −0.3271).
        assert!(
            (got - n).abs().max_element() <= 1.0 / 127.0 + 1e-5,
            "normal at {:?}: {got} vs {n}",
            voxel.voxel
        );
        assert_eq!(normal[i][3], 127);
    }
    for (i, &l) in listed.iter().enumerate() {
        if !l {
            assert_eq!(
                (colour[i], normal[i]),
                ([0; 4], [0; 4]),
                "texel {i} holds no voxel"
            );
        }
    }
}

/// The source records its whole voxelization at once: `encode_attributes_in_one` sizes the
/// list by a bound the CPU knows and leaves the true count on the GPU. The list reads back
/// identical to the two-submission path's, the bound holds the count, the attribute volumes
/// are the same bytes, and the view draws only the occupied voxels.
#[test]
fn one_encoder_gives_the_same_attributes() {
    let ctx = Context::shared();
    let mesh = painted_sphere();
    let grid = sphere_grid();
    let v = Voxelizer::new(&ctx.device).unwrap();
    let (two, want) = run(&ctx, &mesh, &grid);
    let mut enc = ctx.encoder("one encoder");
    let one = v
        .encode_attributes_in_one(&ctx.device, &mut enc, &mesh, &grid)
        .unwrap();
    let vol_one = v
        .encode_attribute_volumes(&ctx.device, &mut enc, &one)
        .unwrap();
    let vol_two = v
        .encode_attribute_volumes(&ctx.device, &mut enc, &two)
        .unwrap();
    ctx.submit_and_wait("one encoder", enc).unwrap();
    let got = one.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    assert_eq!(got, want);
    // The bound: at least the occupied voxels, at most the grid's.
    let total: u32 = bytemuck::pod_read_unaligned(&read_buffer(&ctx, &one.occupied).unwrap()[..4]);
    assert_eq!(total as usize, want.len());
    assert!(
        one.count >= total && (one.count as u64) <= grid.voxels(),
        "{} vs {total}",
        one.count
    );
    println!(
        "one encoder: {total} occupied, list sized {} ({:.1}×)",
        one.count,
        one.count as f64 / total as f64
    );
    for (a, b) in [
        (&vol_one.colour, &vol_two.colour),
        (&vol_one.normal, &vol_two.normal),
    ] {
        let a: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, a).unwrap();
        let b: Vec<[u8; 4]> = fieldkit::gpu::read_texture(&ctx, b).unwrap();
        assert_eq!(a, b);
    }
    // The view draws the same picture from either list (the spare entries are not drawn).
    use fieldkit::view::Targets;
    use fieldkit::voxelize::{ColourBy, VoxelView};
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let view = VoxelView::new(&ctx.device, format, wgpu::TextureFormat::Depth32Float).unwrap();
    let proj = glam::camera::rh::proj::directx::perspective(0.9, 1.0, 0.1, 20.0);
    let view_proj = proj
        * glam::camera::rh::view::look_at_mat4(
            glam::Vec3::new(1.5, 2.0, 3.0),
            glam::Vec3::ZERO,
            glam::Vec3::Y,
        );
    let draw = |a: &Attributes| {
        let t = Targets::new(
            &ctx.device,
            [48, 48],
            format,
            wgpu::TextureFormat::Depth32Float,
        );
        let mut enc = ctx.encoder("view");
        t.clear(&mut enc, wgpu::Color::BLACK, 1.0);
        view.encode(
            &ctx.device,
            &mut enc,
            &t.colour_view,
            &t.depth_view,
            a,
            &grid,
            view_proj,
            glam::Vec3::Y,
            ColourBy::Colour,
        )
        .unwrap();
        ctx.submit_and_wait("view", enc).unwrap();
        fieldkit::gpu::read_texture::<[u8; 4]>(&ctx, &t.colour).unwrap()
    };
    let (p1, p2) = (draw(&one), draw(&two));
    assert_eq!(p1, p2);
    assert!(p1.iter().filter(|p| p[..3] != [0, 0, 0]).count() > 300);
}

/// The bound is the sum of each triangle's box, widened by the GPU's slack, clipped to the grid.
#[test]
fn the_bound_counts_each_triangle_box() {
    use fieldkit::voxelize::occupied_bound;
    let mesh = Mesh {
        positions: vec![
            DVec3::new(0.5, 0.5, 0.5),
            DVec3::new(2.5, 0.5, 0.5),
            DVec3::new(0.5, 1.5, 0.5),
            // Out past the grid's corner: clipped.
            DVec3::new(3.5, 3.5, 3.5),
            DVec3::new(9.5, 3.5, 3.5),
            DVec3::new(3.5, 9.5, 3.5),
        ],
        triangles: vec![[0, 1, 2], [3, 4, 5]],
        ..Mesh::default()
    };
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [5, 5, 5],
    };
    let local = mesh.to_grid(&grid).unwrap();
    // 3 × 2 × 1 voxels, then x 3..5 × y 3..5 × z 3: 2 × 2 × 1.
    assert_eq!(occupied_bound(&local, grid.size), 6 + 4);
}

/// The source's vertex stage passes texture coordinates on: with an albedo texture each
/// voxel's colour is the albedo at the texture coordinates of its centre's closest point on
/// the triangle. One large triangle over the grid with u = ¼ + ½ · x / 8 and a 2 × 1 texture
/// (red, blue): linear filtering between the texel centres gives red · (1 − x/8) + blue · x/8
/// at voxel centre x, written out here.
#[test]
fn albedo_is_sampled_at_each_voxels_texture_coordinates() {
    use glam::Vec2;

    let ctx = Context::shared();
    let u = |x: f64| 0.25 + 0.5 * x / 8.0;
    let corners = [
        DVec3::new(-10.0, -10.0, 1.5),
        DVec3::new(30.0, -10.0, 1.5),
        DVec3::new(-10.0, 30.0, 1.5),
    ];
    let mesh = Mesh {
        positions: corners.to_vec(),
        triangles: vec![[0, 1, 2]],
        texcoords: vec![corners.map(|p| Vec2::new(u(p.x) as f32, 0.5))],
        ..Mesh::default()
    };
    let grid = Grid {
        origin: DVec3::ZERO,
        voxel: 1.0,
        size: [8, 4, 3],
    };
    let albedo = upload_2d(
        &ctx,
        [2, 1],
        wgpu::TextureFormat::Rgba8Unorm,
        &[255, 0, 0, 255, 0, 0, 255, 255],
    );
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("albedo");
    let a = v
        .encode_attributes_in_one_with(&ctx.device, &mut enc, &mesh, &grid, Some(&albedo))
        .unwrap();
    ctx.submit_and_wait("albedo", enc).unwrap();
    let list = a.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    // The plane z = 1.5 runs through the middle of layer 1: that layer alone.
    assert_eq!(list.len(), 8 * 4);
    let mut worst = 0i32;
    for voxel in &list {
        let x = voxel.voxel[0] as f64 + 0.5;
        let want = [255.0 * (1.0 - x / 8.0), 0.0, 255.0 * x / 8.0, 255.0];
        for (got, want) in voxel.color.iter().zip(want) {
            worst = worst.max((*got as i32 - want.round() as i32).abs());
        }
    }
    println!(
        "albedo: {} voxels, colour within {worst} levels of the formula",
        list.len()
    );
    // Linear filtering's weights are held to 8 fractional bits on some GPUs (a level of the
    // red-to-blue ramp), and the mean is rounded: two levels. llvmpipe: 0.
    assert!(worst <= 2, "{worst}");

    // An albedo needs texture coordinates, and a filterable colour format.
    let mut enc = ctx.encoder("bad albedo");
    let bare = Mesh {
        texcoords: vec![],
        ..mesh.clone()
    };
    let e = v
        .encode_attributes_with(&ctx.device, &mut enc, &bare, &grid, Some(&albedo))
        .err()
        .unwrap();
    assert!(e.to_string().contains("texture coordinates"), "{e}");
    let r32 = crate::common::sampled(&ctx, [2, 2, 1], wgpu::TextureFormat::R32Uint);
    assert!(matches!(
        v.encode_attributes_with(&ctx.device, &mut enc, &mesh, &grid, Some(&r32)),
        Err(Error::Format { .. })
    ));
    let short = Mesh {
        texcoords: vec![[Vec2::ZERO; 3]; 2],
        ..mesh.clone()
    };
    let e = v
        .encode_attributes_with(&ctx.device, &mut enc, &short, &grid, Some(&albedo))
        .err()
        .unwrap();
    assert!(e.to_string().contains("texcoords"), "{e}");
}

/// OBJ texture coordinates come through per triangle corner, seams included.
#[test]
fn obj_texture_coordinates_per_corner() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
               vt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n\
               f 1/1 2/2 3/3\nf 2/4 4/2 3/3\n";
    let mesh = Mesh::from_obj(&mut std::io::BufReader::new(obj.as_bytes())).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    let v = |x, y| glam::Vec2::new(x, y);
    assert_eq!(mesh.texcoords[0], [v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)]);
    // Vertex 2 has (1, 0) in the first face and (0.5, 0.5) in the second: a seam.
    assert_eq!(mesh.texcoords[1], [v(0.5, 0.5), v(1.0, 0.0), v(0.0, 1.0)]);
}
