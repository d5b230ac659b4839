//! The octree's attributes (`octree/attributes`): voxel colours and normals equal to the
//! dense attribute list, albedo sampled as the voxelizer samples it, nodes the mean of their
//! children, and batches that give the same bytes as one pass.

use crate::common;

use common::upload_2d;

use common::octree::*;
use fieldkit::Error;
use fieldkit::gpu::Context;
use fieldkit::octree::{OctreeBuilder, OctreeData};
use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
use glam::DVec3;

fn octahedral(packed: u32) -> Option<glam::Vec3> {
    if packed == 0x8000_8000 {
        return None;
    }
    let s = |v: u32| ((v & 0xffff) as u16 as i16 as f32 / 32767.0).max(-1.0);
    let (x, y) = (s(packed), s(packed >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * x.signum(), (1.0 - x.abs()) * y.signum())
    } else {
        (x, y)
    };
    Some(glam::Vec3::new(x, y, z).normalize())
}

fn build_with_attributes(ctx: &Context, mesh: &Mesh, grid: &Grid) -> OctreeData {
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let octree = ctx
        .block_on(builder.voxelize_with_attributes(&ctx.device, &ctx.queue, &voxelizer, mesh, grid))
        .unwrap();
    octree.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()
}

/// Every voxel's colour and normal in the tree's bricks are the dense attribute list's, byte
/// for byte (the same sums of the same contributions), and two builds give the same bytes.
#[test]
fn voxel_attributes_equal_the_dense_list() {
    let ctx = Context::shared();
    let mesh = painted_torus();
    let grid = unit_grid([48, 48, 44]);
    let tree = build_with_attributes(&ctx, &mesh, &grid);
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let dense = ctx
        .block_on(voxelizer.attributes(&ctx.device, &ctx.queue, &mesh, &grid))
        .unwrap();
    let raw: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(
        &fieldkit::gpu::readback_buffer(&ctx.device, &ctx.queue, &dense.voxels)
            .wait(&ctx)
            .unwrap(),
    );
    let raw = &raw[..dense.count as usize];
    assert_eq!(tree.voxel_attributes.len(), raw.len(), "occupied voxels");
    let [nx, ny, _] = grid.size;
    let mut colours = std::collections::HashSet::new();
    for &[i, colour, normal, _] in raw {
        let v = [i % nx, i / nx % ny, i / (nx * ny)];
        assert_eq!(
            tree.voxel_attribute(v),
            Some([colour, normal]),
            "voxel {v:?}"
        );
        colours.insert(colour);
    }
    assert!(colours.len() > 100, "the colours vary: {}", colours.len());
    let again = build_with_attributes(&ctx, &mesh, &grid);
    assert!(again.voxel_attributes == tree.voxel_attributes);
    assert!(again.node_attributes == tree.node_attributes);
}

/// With an albedo texture (the mesh's texture coordinates, a 4 × 4 texture of 16 colours), every
/// voxel's colour and normal in the tree are the dense attribute list's with the same albedo,
/// byte for byte, and differ from the untextured tree's; an albedo without texture coordinates
/// or in a format that cannot be filtered is a typed error.
#[test]
fn albedo_attributes_equal_the_dense_list() {
    let ctx = Context::shared();
    let mut mesh = painted_torus();
    let uv = |p: DVec3| {
        let d = p - DVec3::new(24.5, 23.2, 20.9);
        glam::Vec2::new(
            (d.y.atan2(d.x) / std::f64::consts::TAU) as f32 * 3.0,
            (d.z / 5.3) as f32 * 0.5 + 0.5,
        )
    };
    mesh.texcoords = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| uv(mesh.positions[i as usize])))
        .collect();
    let grid = unit_grid([48, 48, 44]);
    let texels: Vec<u8> = (0..16u32)
        .flat_map(|i| {
            [
                (i * 53 % 256) as u8,
                (i * 97 % 256) as u8,
                (i * 31 % 256) as u8,
                255,
            ]
        })
        .collect();
    let albedo = upload_2d(&ctx, [4, 4], wgpu::TextureFormat::Rgba8Unorm, &texels);
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let tree = ctx
        .block_on(builder.voxelize_with_albedo(
            &ctx.device,
            &ctx.queue,
            &voxelizer,
            &mesh,
            &grid,
            &albedo,
        ))
        .unwrap()
        .read(&ctx.device, &ctx.queue)
        .wait(&ctx)
        .unwrap();
    let mut enc = ctx.encoder("dense albedo");
    let dense = voxelizer
        .encode_attributes_in_one_with(&ctx.device, &mut enc, &mesh, &grid, Some(&albedo))
        .unwrap();
    ctx.submit_and_wait("dense albedo", enc).unwrap();
    let count = dense.count.min(dense.voxels.size() as u32 / 16);
    let raw: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(
        &fieldkit::gpu::readback_buffer(&ctx.device, &ctx.queue, &dense.voxels)
            .wait(&ctx)
            .unwrap(),
    );
    let plain = build_with_attributes(&ctx, &mesh, &grid);
    let [nx, ny, _] = grid.size;
    let mut textured = 0;
    let mut listed = 0;
    for &[i, colour, normal, triangles] in &raw[..count as usize] {
        if triangles == 0 {
            continue;
        }
        listed += 1;
        let v = [i % nx, i / nx % ny, i / (nx * ny)];
        assert_eq!(
            tree.voxel_attribute(v),
            Some([colour, normal]),
            "voxel {v:?}"
        );
        textured += (plain.voxel_attribute(v).map(|a| a[0]) != Some(colour)) as usize;
    }
    assert_eq!(listed, tree.voxel_attributes.len(), "occupied voxels");
    assert!(
        textured * 2 > listed,
        "only {textured} of {listed} voxels changed colour with the albedo"
    );

    let bare = Mesh {
        texcoords: vec![],
        ..mesh.clone()
    };
    let e = ctx.block_on(builder.voxelize_with_albedo(
        &ctx.device,
        &ctx.queue,
        &voxelizer,
        &bare,
        &grid,
        &albedo,
    ));
    assert!(
        matches!(&e, Err(Error::Invalid { what, .. }) if what.contains("texture coordinates")),
        "{:?}",
        e.err()
    );
    let integer = crate::common::sampled(&ctx, [4, 4, 1], wgpu::TextureFormat::Rgba8Uint);
    let e = ctx.block_on(builder.voxelize_with_albedo(
        &ctx.device,
        &ctx.queue,
        &voxelizer,
        &mesh,
        &grid,
        &integer,
    ));
    assert!(matches!(e, Err(Error::Format { .. })), "{:?}", e.err());
}

/// Each brick holds the mean of its voxels' attributes and each inner node the mean of its
/// children's: colours the integer mean rounded to nearest (exact), normals the direction of
/// the sum (to the octahedral code's precision).
#[test]
fn nodes_hold_the_mean_of_their_children() {
    let ctx = Context::shared();
    let tree = build_with_attributes(&ctx, &painted_torus(), &unit_grid([48, 48, 44]));
    let mean = |items: &[[u32; 2]]| -> ([u32; 4], Option<glam::Vec3>) {
        let n = items.len() as u32;
        let mut c = [0u32; 4];
        let mut normal = glam::Vec3::ZERO;
        for &[colour, packed] in items {
            for (k, b) in colour.to_le_bytes().into_iter().enumerate() {
                c[k] += b as u32;
            }
            if let Some(d) = octahedral(packed) {
                normal += d;
            }
        }
        (
            c.map(|s| (s + n / 2) / n),
            (normal.length_squared() > 0.0).then(|| normal.normalize()),
        )
    };
    let check = |e: usize, want: ([u32; 4], Option<glam::Vec3>)| {
        let [colour, packed] = tree.node_attributes[e];
        assert_eq!(
            colour.to_le_bytes().map(|b| b as u32),
            want.0,
            "entry {e}'s colour"
        );
        match (octahedral(packed), want.1) {
            (Some(a), Some(b)) => assert!(a.dot(b) > 0.9999, "entry {e}: {a} against {b}"),
            (None, None) => {}
            other => panic!("entry {e}: {other:?}"),
        }
    };
    let leaf = tree.leaf_level as usize;
    let mut checked = 0;
    for e in tree.starts[leaf] as usize..tree.starts[leaf + 1] as usize {
        let [lo, hi] = tree.pool[e];
        let n = (lo.count_ones() + hi.count_ones()) as usize;
        let first = tree.brick_voxels[e] as usize;
        check(e, mean(&tree.voxel_attributes[first..first + n]));
        checked += 1;
    }
    for e in 0..tree.starts[leaf] as usize {
        let [mask, first] = tree.pool[e];
        let n = mask.count_ones() as usize;
        let children: Vec<[u32; 2]> =
            tree.node_attributes[first as usize..first as usize + n].to_vec();
        check(e, mean(&children));
        checked += 1;
    }
    assert_eq!(checked, tree.pool.len());
}

/// With attributes the render shades each hit with its cell's filtered colour: a mesh of one
/// colour gives pixels of that hue, lit to varying degrees, at the voxels and at coarse levels;
/// without them, the settings' colour.
#[test]
fn the_render_shades_the_filtered_attributes() {
    use fieldkit::octree::{Lod, OctreeCaster, RenderSettings};
    use glam::Vec3;
    let ctx = Context::shared();
    let mut mesh = painted_torus();
    mesh.colors = vec![[200, 40, 90, 255]; mesh.positions.len()];
    let grid = unit_grid([48, 48, 44]);
    let voxelizer = Voxelizer::new(&ctx.device).unwrap();
    let builder = OctreeBuilder::new(&ctx.device).unwrap();
    let octree = ctx
        .block_on(builder.voxelize_with_attributes(
            &ctx.device,
            &ctx.queue,
            &voxelizer,
            &mesh,
            &grid,
        ))
        .unwrap();
    let view = fieldkit::view::View {
        view_proj: glam::camera::rh::proj::directx::perspective(0.9, 1.0, 1.0, 400.0)
            * glam::camera::rh::view::look_at_mat4(
                Vec3::new(60.0, 80.0, 90.0),
                Vec3::new(24.0, 23.0, 21.0),
                Vec3::Y,
            ),
        viewport: [64, 64],
        reversed_z: false,
        origin: [0, 0],
    };
    let caster = OctreeCaster::new();
    let render = |lod, attributes| {
        let settings = RenderSettings {
            lod,
            attributes,
            colour: Vec3::new(0.2, 0.9, 0.3),
            ..Default::default()
        };
        render_image(&ctx, &caster, &octree, &grid, &view, &settings).0
    };
    for lod in [Lod::Level(octree.log_side), Lod::Level(3)] {
        let px = render(lod, true);
        let hit: Vec<_> = px.iter().filter(|p| p[3] == 255).collect();
        assert!(hit.len() > 200, "{lod:?}: {} pixels", hit.len());
        // 8-bit rounding of r and b: |r·90 − b·200| ≤ ½·90 + ½·200.
        for p in &hit {
            let (r, b) = (p[0] as i32, p[2] as i32);
            assert!(
                (r * 90 - b * 200).abs() <= 145,
                "{lod:?}: pixel {p:?} is not the mesh's hue"
            );
            assert!(p[1] < p[2], "{lod:?}: pixel {p:?}");
        }
        let shades: std::collections::HashSet<u8> = hit.iter().map(|p| p[0]).collect();
        assert!(shades.len() > 10, "{lod:?}: the light does not vary");
    }
    let plain = render(Lod::Level(octree.log_side), false);
    assert!(
        plain.iter().filter(|p| p[3] == 255).all(|p| p[1] > p[0]),
        "the settings' green"
    );
}

/// Where the attribute sums of every voxel (32 bytes each) do not fit one storage binding, they
/// are summed in batches: a device whose bindings hold 8 192 voxels' sums gives the same bytes
/// as the adapter's own limits.
#[test]
fn attributes_in_batches_give_the_same_bytes() {
    let shared = Context::shared();
    let adapter = shared
        .adapter
        .as_ref()
        .expect("Context::shared opens an adapter");
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("small bindings"),
        required_limits: wgpu::Limits {
            max_storage_buffer_binding_size: 256 << 10,
            ..adapter.limits()
        },
        ..Default::default()
    }))
    .expect("smaller limits than the adapter's");
    let small = Context::from_device(device, queue);
    // Large triangles: few fragments per voxel, so the fragment list fits the small bindings.
    let mut mesh = Mesh::uv_sphere(DVec3::new(28.2, 27.9, 28.4), 25.0, 24, 12);
    mesh.colors = mesh
        .positions
        .iter()
        .map(|p| [(p.x * 9.0) as u8, (p.y * 7.0) as u8, (p.z * 5.0) as u8, 255])
        .collect();
    let grid = unit_grid([57, 57, 57]);
    let whole = build_with_attributes(&shared, &mesh, &grid);
    let batched = build_with_attributes(&small, &mesh, &grid);
    assert!(
        whole.voxel_attributes.len() > 8192,
        "{} voxels: one batch would do",
        whole.voxel_attributes.len()
    );
    assert!(batched.voxel_attributes == whole.voxel_attributes);
    assert!(batched.node_attributes == whole.node_attributes);
}
