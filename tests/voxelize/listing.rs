//! How the surface voxelizer lists its work (`voxelize/listing`): heavy triangles cut into
//! chunks, giant triangles walked in blocks, dispatch rows, work-list budgets, each against the
//! voxels of the plain path.

use crate::common;

use common::voxelize::*;
use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::voxelize::{Mesh, Separation, Voxelizer};
use glam::DVec3;

/// More threads than one dispatch row holds (65 535 workgroups of 64): 257 copies of a right
/// triangle whose box face holds 256² columns list 257 × 16 384 = 4.21 M chunks of 4 columns
/// (a box face of at most 65 536 columns keeps chunks of 4), so `surface_listed` runs in two
/// rows of workgroups. The copies set the voxels of one: every one against the SAT.
#[test]
fn more_chunks_than_one_dispatch_row_holds() {
    let ctx = Context::shared();
    let one = common::right_triangle(255.0);
    let copies = 257u32;
    let m = common::repeated(&one, copies);
    let grid = unit_grid([256, 256, 2]);
    let chunks = fieldkit::voxelize::heavy_chunk_bound(&m.to_grid(&grid).unwrap(), grid.size);
    assert_eq!(chunks as u64, copies as u64 * 256 * 256 / 4);
    assert!(chunks > 65_535 * 64, "{chunks} chunks fit one row");
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let (misses, extras, _) = check_against_sat(&gpu, &one, &grid);
    println!("{misses} missed, {extras} extra (each within 1e-3 voxels of the triangle)");
    assert_eq!(misses, 0, "missed voxels");
    assert!(gpu.iter().filter(|&&o| o).count() > 30_000);
}

/// Giant triangles are listed in at most `MAX_CHUNKS` chunks each (longer ones past that) on
/// the GPU (`encode_surface_placed` with a resident mesh), and the host's list
/// (`encode_surface`) is shorter still, so the list for 500 triangles each spanning a 4096²
/// grid holds at most 500 × 16 384 entries (66 MB),
/// which a storage binding of WebGPU's default 128 MiB holds. Before, each counted 4.2 M chunks
/// of 4 (16.8 GB in all) and the mesh was refused by both. The 500 lie past the grid's last
/// layer: the host lists them as light triangles (their box misses the grid), the resident
/// mesh's bound cannot know that (the GPU lists nothing for them); a square of two more, on
/// layer 1, is walked in chunks of 32 (host, 2^20 chunks between the two) or 512 (GPU) columns,
/// and every voxel of that layer is set and none of layer 0.
#[test]
fn giant_triangles_get_a_short_work_list() {
    use fieldkit::voxelize::GpuMesh;
    use glam::DMat4;
    let ctx = Context::shared();
    let n = 4096.0;
    let (mut positions, mut triangles) = square_on_layer_one();
    for k in 0..500u32 {
        let z = 2.5 + k as f64 * 0.001;
        let at = positions.len() as u32;
        positions.extend([
            DVec3::new(0.0, 0.0, z),
            DVec3::new(n, 0.0, z),
            DVec3::new(0.0, n, z),
        ]);
        triangles.push([at, at + 1, at + 2]);
    }
    let m = mesh(positions, triangles);
    let grid = unit_grid([4096, 4096, 2]);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("giant triangles, host-listed");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("giant triangles, host-listed", enc)
        .unwrap();
    check_layer_one(&ctx, &s);
    let resident = GpuMesh::upload(&ctx.device, &m).unwrap();
    let mut enc = ctx.encoder("giant triangles, resident");
    let s = v
        .encode_surface_placed(
            &ctx.device,
            &mut enc,
            &[(&resident, DMat4::IDENTITY)],
            &grid,
            Separation::Conservative,
        )
        .unwrap();
    ctx.submit_and_wait("giant triangles, resident", enc)
        .unwrap();
    check_layer_one(&ctx, &s);
}

/// A triangle whose box face holds 2101² columns (1.1 M chunks of 4, past the host's list
/// budget of 2^20 entries) is listed in chunks of 5 columns, which `surface_listed` walks in
/// full: exactly the voxels whose box meets it.
#[test]
fn a_triangle_past_the_list_budget_is_walked_in_longer_chunks() {
    let ctx = Context::shared();
    let m = common::right_triangle(2100.0);
    let grid = unit_grid([2104, 2104, 2]);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    let s = v.encode_surface(&ctx.device, &mut enc, &m, &grid).unwrap();
    ctx.submit_and_wait("voxelize", enc).unwrap();
    let gpu = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let want = common::right_triangle_voxels(2100, [2104, 2104, 2]);
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "{wrong} voxels wrong");
}

/// A resident giant triangle (2101² columns, past `GIANT_MIN_COLUMNS`) gets a record instead
/// of work-list entries, and `surface_giant` walks it a workgroup per block of 64 chunks of 5
/// columns (its 4.4 M columns over the 2^20 chunks a giant may have): exactly the voxels whose
/// box meets it. Fails when the giant pass walks 4 columns per chunk, or is not recorded.
#[test]
fn a_resident_giant_triangle_is_walked_in_blocks() {
    let ctx = Context::shared();
    let m = common::right_triangle(2100.0);
    let grid = unit_grid([2104, 2104, 2]);
    let gpu = resident_voxels(&ctx, &m, &grid);
    let want = common::right_triangle_voxels(2100, [2104, 2104, 2]);
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "{wrong} voxels wrong");
}

/// More giant blocks than one dispatch row holds: five giant triangles of 2048² columns, 2^20
/// chunks of 4 each, are 81 920 blocks of 64 chunks, walked in two rows of workgroups; and
/// 64 giants (201² columns) beside 10 smaller triangles (101²) that the resident mesh's bound
/// cannot tell from them, so those are listed in chunks: both exactly the triangles' voxels.
#[test]
fn giant_triangles_fill_two_dispatch_rows_beside_listed_ones() {
    let ctx = Context::shared();
    let (m, want) = right_triangles_on_layers(&[2047; 5], 2048);
    let gpu = resident_voxels(&ctx, &m, &unit_grid([2048, 2048, 5]));
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "five giants: {wrong} voxels wrong");

    let mut legs = vec![200; 64];
    legs.extend([100; 10]);
    let (m, want) = right_triangles_on_layers(&legs, 208);
    let gpu = resident_voxels(&ctx, &m, &unit_grid([208, 208, legs.len() as u32]));
    let wrong = gpu.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "64 giants and 10 listed: {wrong} voxels wrong");
}

/// More giant triangles than the device's storage binding holds chunks for (each lists
/// `MAX_CHUNKS` of 8 bytes): the host sums the chunks before it allocates them and gives a
/// typed error instead, for its own list and for the GPU's list of a resident mesh (the same
/// size: triangles of equal size, none of which the GPU's list makes giant).
#[test]
fn a_chunk_list_too_large_is_refused_before_it_is_made() {
    use fieldkit::voxelize::MAX_CHUNKS;
    let ctx = Context::shared();
    let limit = ctx.device.limits().max_storage_buffer_binding_size;
    let count = (limit / (8 * MAX_CHUNKS as u64) + 1) as u32;
    let n = 4096.0;
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for k in 0..count {
        let z = 0.25 + k as f64 * (1.0 / count as f64);
        positions.extend([
            DVec3::new(0.0, 0.0, z),
            DVec3::new(n, 0.0, z),
            DVec3::new(0.0, n, z),
        ]);
        triangles.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let m = mesh(positions, triangles);
    let v = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("voxelize");
    match v.encode_surface(&ctx.device, &mut enc, &m, &unit_grid([4096, 4096, 2])) {
        Err(Error::Size { what, got, max, .. }) => {
            assert_eq!(what, "heavy-triangle chunk list bytes");
            assert_eq!((got, max), (count as u64 * 8 * MAX_CHUNKS as u64, limit));
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a chunk list past the binding's {limit} bytes was accepted"),
    }
    let resident = fieldkit::voxelize::GpuMesh::upload(&ctx.device, &m).unwrap();
    match v.encode_surface_placed(
        &ctx.device,
        &mut enc,
        &[(&resident, glam::DMat4::IDENTITY)],
        &unit_grid([4096, 4096, 2]),
        Separation::Conservative,
    ) {
        Err(Error::Size { what, got, max, .. }) => {
            assert_eq!(what, "heavy-triangle work list bytes");
            assert_eq!((got, max), (count as u64 * 8 * MAX_CHUNKS as u64, limit));
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a resident list past the binding's {limit} bytes was accepted"),
    }
}

/// However the triangles are cut into threads (light or in chunks, sorted or not, any
/// workgroup size; `Listing::auto` picks per mesh), the voxels are the same, and they are the
/// SAT's: a sphere of small triangles and a few triangles of many columns each.
#[test]
fn every_way_of_cutting_triangles_gives_the_same_voxels() {
    use fieldkit::voxelize::Listing;
    let ctx = Context::shared();
    let mut m = Mesh::uv_sphere(DVec3::new(21.3, 19.8, 17.1), 12.7, 40, 20);
    let base = m.positions.len() as u32;
    m.positions.extend([
        DVec3::new(1.2, 2.3, 3.1),
        DVec3::new(44.7, 6.1, 30.2),
        DVec3::new(9.4, 38.8, 12.6),
        DVec3::new(40.2, 37.9, 2.2),
    ]);
    m.triangles
        .extend([[base, base + 1, base + 2], [base + 1, base + 3, base + 2]]);
    let grid = unit_grid([46, 40, 33]);
    let listings = [
        None,
        Some(Listing::default()),
        Some(Listing::auto(1 << 20)),
        Some(Listing {
            light: 4,
            chunk: 2,
            sort: true,
            workgroup: 32,
        }),
        Some(Listing {
            light: 1,
            chunk: 1,
            sort: false,
            workgroup: 256,
        }),
        Some(Listing {
            light: 64,
            chunk: 16,
            sort: true,
            workgroup: 128,
        }),
    ];
    let mut v = Voxelizer::new(&ctx.device).unwrap();
    for separation in [Separation::Conservative, Separation::Six] {
        let mut first: Option<Vec<bool>> = None;
        for listing in listings {
            v.set_listing(&ctx.device, listing).unwrap();
            let mut enc = ctx.encoder("voxelize");
            let s = v
                .encode_surface_with(&ctx.device, &mut enc, &m, &grid, separation)
                .unwrap();
            ctx.submit_and_wait("voxelize", enc).unwrap();
            let got = s.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
            match &first {
                None => {
                    if separation == Separation::Conservative {
                        let (misses, _, _) = check_against_sat(&got, &m, &grid);
                        assert_eq!(misses, 0, "voxels the SAT has and the GPU missed");
                    }
                    first = Some(got);
                }
                Some(want) => {
                    let differ = got.iter().zip(want).filter(|(a, b)| a != b).count();
                    assert_eq!(differ, 0, "{separation:?}, {listing:?}: voxels differ");
                }
            }
        }
    }
    let bad = Listing {
        chunk: 0,
        ..Listing::default()
    };
    assert!(matches!(
        v.set_listing(&ctx.device, Some(bad)),
        Err(Error::Invalid { .. })
    ));
}
