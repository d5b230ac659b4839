//! The sparse voxel octree's build (`octree/build`) against the dense voxelization of the
//! same mesh (`voxelize/surface`, itself tested against the 13-axis SAT) and against the tree
//! the CPU builds from those voxels ([`OctreeData::from_voxels`]): leaves exact, inner nodes
//! flagging exactly the children that hold voxels, identical bytes on every build; and the
//! build's failure modes, each a test.

use crate::common;

use common::octree::*;
use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::octree::{OctreeBuilder, OctreeData};
use fieldkit::voxelize::{Grid, Mesh, Separation, Voxelizer};
use glam::DVec3;

/// The GPU tree holds exactly the dense voxels, and is byte for byte the CPU's tree of them.
fn check_against_dense(ctx: &Context, mesh: &Mesh, grid: &Grid, separation: Separation) {
    let want = dense(ctx, mesh, grid, separation);
    let (_, tree) = build(ctx, mesh, grid, separation);
    let got = tree.voxels();
    let wrong = got.iter().zip(&want).filter(|(a, b)| a != b).count();
    let occupied = want.iter().filter(|&&o| o).count();
    assert!(occupied > 0, "the mesh must touch the grid");
    assert_eq!(
        wrong, 0,
        "{separation:?}: {wrong} of {occupied} voxels differ from the dense voxelization"
    );
    let reference = OctreeData::from_voxels(&want, grid.size).unwrap();
    assert_eq!(
        tree.nodes_per_level(),
        reference.nodes_per_level(),
        "nodes per level"
    );
    assert!(tree == reference, "the GPU's pool differs from the CPU's");
}

#[test]
fn leaves_and_nodes_equal_the_dense_voxelization() {
    let ctx = Context::shared();
    // A grid that is not a power of two, a sphere off the cells' centres, and a torus whose
    // hole leaves empty nodes inside occupied ones.
    let sphere = Mesh::uv_sphere(DVec3::new(20.3, 17.7, 21.1), 13.37, 40, 20);
    let torus = Mesh::torus(DVec3::new(24.5, 23.2, 20.9), 14.0, 5.3, 48, 16);
    for separation in [Separation::Conservative, Separation::Six] {
        check_against_dense(&ctx, &sphere, &unit_grid([41, 37, 44]), separation);
        check_against_dense(&ctx, &torus, &unit_grid([48, 48, 48]), separation);
    }
}

/// 256³ with a torus of 25 k triangles (seven times the npm bunny's; [`the_bunny_at_256`] is the
/// bunny), its voxels still held by the dense path (2 MiB of bits) to compare with.
#[test]
fn a_256_grid_equals_the_dense_voxelization() {
    let ctx = Context::shared();
    let torus = Mesh::torus(DVec3::new(128.3, 127.6, 128.9), 80.0, 30.0, 256, 96);
    let grid = unit_grid([256, 256, 256]);
    let want = dense(&ctx, &torus, &grid, Separation::Conservative);
    let (octree, tree) = build(&ctx, &torus, &grid, Separation::Conservative);
    let got = tree.voxels();
    let wrong = got.iter().zip(&want).filter(|(a, b)| a != b).count();
    assert_eq!(wrong, 0);
    let occupied = want.iter().filter(|&&o| o).count();
    println!(
        "256³ torus: {occupied} voxels, nodes per level {:?}, {} KiB (dense bits {} KiB), pool capacity {}",
        tree.nodes_per_level(),
        tree.bytes() / 1024,
        256u64.pow(3) / 8 / 1024,
        octree.capacity
    );
    assert!(
        tree.bytes() < 256u64.pow(3) / 8,
        "the tree is larger than the bitset"
    );
}

#[test]
fn two_builds_give_identical_bytes() {
    let ctx = Context::shared();
    let sphere = Mesh::uv_sphere(DVec3::new(16.3, 15.7, 16.1), 11.37, 48, 24);
    let grid = unit_grid([32, 32, 32]);
    let (_, a) = build(&ctx, &sphere, &grid, Separation::Conservative);
    let (_, b) = build(&ctx, &sphere, &grid, Separation::Conservative);
    assert_eq!(
        bytemuck::cast_slice::<[u32; 2], u8>(&a.pool),
        bytemuck::cast_slice::<[u32; 2], u8>(&b.pool)
    );
}

/// One triangle, a mesh far from the origin, and triangles lying on node boundaries (the
/// planes x = 16, y = 8 and z = 32 of a 64 grid: closed voxels on both sides hold them).
#[test]
fn single_triangle_far_mesh_and_node_boundaries() {
    let ctx = Context::shared();
    let one = Mesh {
        positions: vec![
            DVec3::new(3.2, 5.1, 9.0),
            DVec3::new(27.7, 8.4, 11.2),
            DVec3::new(10.3, 29.9, 14.6),
        ],
        triangles: vec![[0, 1, 2]],
        ..Mesh::default()
    };
    check_against_dense(
        &ctx,
        &one,
        &unit_grid([32, 32, 32]),
        Separation::Conservative,
    );

    let far = DVec3::new(1.0e5, -2.0e5, 3.0e5);
    let sphere = Mesh::uv_sphere(far, 9.0, 24, 12);
    let grid = Grid {
        origin: far - DVec3::splat(10.0),
        voxel: 20.0 / 24.0,
        size: [24, 24, 24],
    };
    check_against_dense(&ctx, &sphere, &grid, Separation::Conservative);

    let quad = |a: DVec3, b: DVec3, c: DVec3, d: DVec3, base: u32| {
        (
            vec![a, b, c, d],
            vec![[base, base + 1, base + 2], [base, base + 2, base + 3]],
        )
    };
    let planes = [
        quad(
            DVec3::new(16.0, 2.0, 2.0),
            DVec3::new(16.0, 60.0, 2.0),
            DVec3::new(16.0, 60.0, 60.0),
            DVec3::new(16.0, 2.0, 60.0),
            0,
        ),
        quad(
            DVec3::new(2.0, 8.0, 2.0),
            DVec3::new(60.0, 8.0, 2.0),
            DVec3::new(60.0, 8.0, 60.0),
            DVec3::new(2.0, 8.0, 60.0),
            4,
        ),
        quad(
            DVec3::new(2.0, 2.0, 32.0),
            DVec3::new(60.0, 2.0, 32.0),
            DVec3::new(60.0, 60.0, 32.0),
            DVec3::new(2.0, 60.0, 32.0),
            8,
        ),
    ];
    let mut boundaries = Mesh::default();
    for (p, t) in planes {
        boundaries.positions.extend(p);
        boundaries.triangles.extend(t);
    }
    let grid = unit_grid([64, 64, 64]);
    check_against_dense(&ctx, &boundaries, &grid, Separation::Conservative);
    let (_, tree) = build(&ctx, &boundaries, &grid, Separation::Conservative);
    // Both layers of voxels that touch x = 16, in the two root children on either side of it.
    assert!(tree.occupied([15, 30, 30]) && tree.occupied([16, 30, 30]));
    assert!(!tree.occupied([14, 30, 30]) && !tree.occupied([17, 30, 30]));
}

/// A triangle whose box face holds 2101² columns (1.1 M chunks of 4, past the host's budget of
/// 2^20): the host lists it in chunks of 5 columns, and the fragment pass walks each chunk's 5
/// (the length the triangle carries; it failed when it walked 4): the fragments are the voxels
/// whose box meets the triangle, each once.
#[test]
fn a_giant_triangle_gives_every_fragment() {
    let ctx = Context::shared();
    let giant = common::right_triangle(2100.0);
    let grid = unit_grid([2104, 2104, 2]);
    let want = common::right_triangle_voxels(2100, [2104, 2104, 2]);
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("giant fragments");
    let fragments = voxelizer
        .encode_fragments(
            &ctx.device,
            &mut enc,
            &giant,
            &grid,
            Separation::Conservative,
            None,
        )
        .unwrap();
    ctx.submit_and_wait("giant fragments", enc).unwrap();
    let list = fragments.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let mut got = vec![false; want.len()];
    for [x, y, z] in &list {
        got[((z * 2104 + y) * 2104 + x) as usize] = true;
    }
    let occupied = want.iter().filter(|&&o| o).count();
    let wrong = got.iter().zip(&want).filter(|(a, b)| a != b).count();
    assert_eq!(
        wrong, 0,
        "{wrong} of {occupied} voxels differ from the triangle's"
    );
    assert_eq!(list.len(), occupied, "a voxel listed twice");
}

/// A pool too small is a typed error naming how many entries the levels built need; a
/// fragment list too short, one naming the part's exact count. With those sizes, the tree
/// builds, and a tree of many fragment lists (the split a device's bindings force) is the tree
/// of one.
#[test]
fn a_pool_or_list_too_small_says_what_it_needs() {
    let ctx = Context::shared();
    let sphere = Mesh::uv_sphere(DVec3::splat(16.0), 11.0, 32, 16);
    let grid = unit_grid([32, 32, 32]);
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let (_, full) = build(&ctx, &sphere, &grid, Separation::Conservative);
    let entries = full.pool.len() as u64;

    let mut enc = ctx.encoder("small pool");
    let fragments = voxelizer
        .encode_fragments(
            &ctx.device,
            &mut enc,
            &sphere,
            &grid,
            Separation::Conservative,
            None,
        )
        .unwrap();
    let octree = builder
        .encode(&ctx.device, &mut enc, &fragments, 5)
        .unwrap();
    ctx.submit_and_wait("small pool", enc).unwrap();
    match octree.starts(&ctx.device, &ctx.queue).wait(&ctx) {
        Err(Error::Size { got, max: 5, .. }) => {
            assert!(got > 5 && got <= entries, "needs {got} of {entries}")
        }
        other => panic!("expected a pool-size error, got {other:?}"),
    }
    assert!(matches!(
        octree.read(&ctx.device, &ctx.queue).wait(&ctx),
        Err(Error::Size { .. })
    ));

    // The whole list in one part: the count every split must add up to.
    let mut enc = ctx.encoder("one list");
    let one = voxelizer
        .encode_fragments(
            &ctx.device,
            &mut enc,
            &sphere,
            &grid,
            Separation::Conservative,
            None,
        )
        .unwrap();
    ctx.submit_and_wait("one list", enc).unwrap();
    assert_eq!(one.parts.len(), 1);
    let all = one.count(&ctx.device, &ctx.queue).wait(&ctx).unwrap();

    // Parts of at most 10 fragments: a light triangle alone has more, so some lists are short.
    let mut enc = ctx.encoder("short lists");
    let fragments = voxelizer
        .encode_fragments(
            &ctx.device,
            &mut enc,
            &sphere,
            &grid,
            Separation::Conservative,
            Some(10),
        )
        .unwrap();
    ctx.submit_and_wait("short lists", enc).unwrap();
    assert!(
        fragments.parts.len() > 10,
        "{} parts",
        fragments.parts.len()
    );
    match fragments.count(&ctx.device, &ctx.queue).wait(&ctx) {
        Err(Error::Size { got, max: 10, .. }) => assert!(got > 10),
        other => panic!("expected a fragment-count error, got {other:?}"),
    };
    let totals = fragments
        .totals(&ctx.device, &ctx.queue)
        .wait(&ctx)
        .unwrap();
    assert_eq!(totals.iter().map(|&t| t as u64).sum::<u64>(), all);
    let longest = totals.into_iter().max().unwrap();

    // Every part as long as the longest count: nothing lost, and the tree of the many lists is
    // byte for byte the tree of the one.
    let mut enc = ctx.encoder("long enough");
    let fragments = voxelizer
        .encode_fragments(
            &ctx.device,
            &mut enc,
            &sphere,
            &grid,
            Separation::Conservative,
            Some(longest),
        )
        .unwrap();
    let octree = builder
        .encode(&ctx.device, &mut enc, &fragments, entries as u32)
        .unwrap();
    ctx.submit_and_wait("long enough", enc).unwrap();
    assert!(fragments.parts.len() > 1, "{} parts", fragments.parts.len());
    assert_eq!(
        fragments.count(&ctx.device, &ctx.queue).wait(&ctx).unwrap(),
        all
    );
    assert!(octree.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap() == full);
}

/// Bad input: an empty mesh, a grid past 2¹³ per side, a pool of nothing or past the binding
/// limit, a fragment list of nothing — each a typed error before anything runs.
#[test]
fn bad_input_is_a_typed_error() {
    let ctx = Context::shared();
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let sphere = Mesh::uv_sphere(DVec3::splat(16.0), 11.0, 16, 8);
    let voxelize = |mesh: &Mesh, grid: &Grid| {
        ctx.block_on(builder.voxelize(
            &ctx.device,
            &ctx.queue,
            &voxelizer,
            mesh,
            grid,
            Separation::Conservative,
        ))
    };
    assert!(matches!(
        voxelize(&Mesh::default(), &unit_grid([32, 32, 32])),
        Err(Error::Size {
            what: "number of triangles",
            ..
        })
    ));
    match voxelize(&sphere, &unit_grid([16384, 32, 32])) {
        Err(Error::Size {
            got: 16384,
            max: 8192,
            ..
        }) => {}
        other => panic!("expected a side error, got {:?}", other.err()),
    }
    let mut nan = sphere.clone();
    nan.positions[3].y = f64::NAN;
    assert!(matches!(
        voxelize(&nan, &unit_grid([32, 32, 32])),
        Err(Error::Invalid { .. })
    ));
    let mut enc = ctx.encoder("bad sizes");
    let grid = unit_grid([32, 32, 32]);
    let c = Separation::Conservative;
    assert!(matches!(
        voxelizer.encode_fragments(&ctx.device, &mut enc, &sphere, &grid, c, Some(0)),
        Err(Error::Size { got: 0, .. })
    ));
    let fragments = voxelizer
        .encode_fragments(&ctx.device, &mut enc, &sphere, &grid, c, None)
        .unwrap();
    assert!(matches!(
        builder.encode(&ctx.device, &mut enc, &fragments, 0),
        Err(Error::Size { got: 0, .. })
    ));
    assert!(matches!(
        builder.encode(&ctx.device, &mut enc, &fragments, u32::MAX),
        Err(Error::Size { .. })
    ));
}

/// A mesh wholly outside the grid leaves a tree of one empty root; so does the CPU's tree of
/// an empty grid.
#[test]
fn a_mesh_outside_the_grid_gives_an_empty_root() {
    let ctx = Context::shared();
    let sphere = Mesh::uv_sphere(DVec3::splat(100.0), 5.0, 16, 8);
    let grid = unit_grid([16, 16, 16]);
    let (_, tree) = build(&ctx, &sphere, &grid, Separation::Conservative);
    assert_eq!(tree.pool.len(), 1, "the root alone");
    assert_eq!(tree.pool[0][0], 0, "no child");
    assert_eq!(tree.nodes_per_level(), vec![1, 0, 0]);
    assert!(tree == OctreeData::from_voxels(&vec![false; 16 * 16 * 16], [16, 16, 16]).unwrap());
}

/// Specks scattered through the grid: each a few fragments but a chain of nodes of its own,
/// so the tree needs more entries than the first try's pool estimate; the build tries again
/// and the tree still equals the dense voxels.
#[test]
fn scattered_specks_grow_the_pool() {
    let ctx = Context::shared();
    let mut specks = Mesh::default();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for i in 0..4000u32 {
        let c = DVec3::new(next(), next(), next()) * 250.0 + DVec3::splat(3.0);
        specks.positions.extend([
            c,
            c + DVec3::new(0.3, 0.05, 0.1),
            c + DVec3::new(0.1, 0.3, 0.05),
        ]);
        specks.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let grid = unit_grid([256, 256, 256]);
    let local = specks.to_sparse_grid(&grid).unwrap();
    let first_try = fieldkit::voxelize::fragment_estimate(&local, grid.size) / 8 + 4096;
    let want = dense(&ctx, &specks, &grid, Separation::Conservative);
    let (octree, tree) = build(&ctx, &specks, &grid, Separation::Conservative);
    assert!(
        tree.pool.len() as u64 > first_try,
        "{} entries fit the first try's {first_try}: the test no longer tries again",
        tree.pool.len()
    );
    assert_eq!(
        octree.capacity as usize,
        tree.pool.len(),
        "the pool is shrunk to the tree"
    );
    assert!(tree.voxels() == want);
    assert!(tree == OctreeData::from_voxels(&want, grid.size).unwrap());
}

/// The CPU tree, which the GPU's is compared with, holds what it was given: a random grid
/// (not a power of two, a tenth occupied) read back voxel by voxel.
#[test]
fn the_cpu_tree_holds_its_voxels() {
    let size = [37u32, 29, 41];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let voxels: Vec<bool> = (0..37 * 29 * 41)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state.is_multiple_of(10)
        })
        .collect();
    let tree = OctreeData::from_voxels(&voxels, size).unwrap();
    assert!(tree.voxels() == voxels);
    assert_eq!(tree.log_side, 6);
    assert_eq!(tree.nodes_per_level()[0], 1);
    assert!(!tree.occupied([37, 0, 0]), "outside the grid");
    assert!(matches!(
        OctreeData::from_voxels(&voxels[1..], size),
        Err(Error::Invalid { .. })
    ));
}
