//! Bad input to the 3D distance stages: each a typed error naming the problem, never a panic,
//! a wgpu validation error or a lost device.

use fieldkit::Error;
use fieldkit::distance::{ColumnPasses, Variant};
use fieldkit::distance::{
    Distance3d, Grid, Inside, MAX_SIDE_3D, Method, Settings3d, check_size_2d_exact, check_size_3d,
    upload_points, upload_points_with_homes, upload_volume,
};
use fieldkit::gpu::Context;
use glam::Vec3;

#[test]
fn zero_sized_grids() {
    let ctx = Context::shared();
    for (size, what) in [
        ([0, 4, 4], "width"),
        ([4, 0, 4], "height"),
        ([4, 4, 0], "depth"),
    ] {
        let e = upload_volume(&ctx.device, &ctx.queue, &[], size).unwrap_err();
        assert!(
            matches!(e, Error::Size { what: w, got: 0, .. } if w == what),
            "{size:?}: {e}"
        );
    }
    assert!(matches!(
        check_size_2d_exact(&ctx.device, 0, 9),
        Err(Error::Size { what: "width", .. })
    ));
}

#[test]
fn past_the_packing_range() {
    let ctx = Context::shared();
    // x and y have 11 bits, z 10: 2049 across (or 1025 deep) cannot be named.
    let tex = ctx.device.limits().max_texture_dimension_3d;
    for (axis, what) in [(0, "width"), (1, "height"), (2, "depth")] {
        let mut size = [4, 4, 4];
        size[axis] = MAX_SIDE_3D[axis] + 1;
        let e = check_size_3d(&ctx.device, size).unwrap_err();
        let max = MAX_SIDE_3D[axis].min(tex) as u64;
        assert!(
            matches!(e, Error::Size { what: w, max: m, .. } if w == what && m == max),
            "{size:?}: {e}"
        );
    }
    let e = check_size_2d_exact(&ctx.device, 16385, 4).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Size {
                what: "width",
                got: 16385,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn the_one_grid_whose_packing_wraps() {
    let ctx = Context::shared();
    // 2048 × 2048 × 1024: every side is in range, but the last voxel's code + 1 is 2^32.
    let e = check_size_3d(&ctx.device, MAX_SIDE_3D).unwrap_err();
    if ctx.device.limits().max_texture_dimension_3d >= 2048 {
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains("wrap")),
            "{e}"
        );
    } else {
        assert!(matches!(e, Error::Size { .. }), "{e}");
    }
}

#[test]
fn past_the_device_buffer_limit() {
    let ctx = Context::shared();
    // Within the packing, but 2048 × 2048 × 1023 × 4 bytes ≈ 17 GB exceeds every device's
    // storage binding limit: refused before anything is allocated.
    let e = check_size_3d(
        &ctx.device,
        [
            2048.min(ctx.device.limits().max_texture_dimension_3d),
            2048.min(ctx.device.limits().max_texture_dimension_3d),
            1023,
        ],
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            Error::Size {
                what: "field buffer (bytes)",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn bad_seed_points() {
    let ctx = Context::shared();
    let grid = Grid {
        size: [8, 8, 8],
        voxel: 0.5,
        origin: glam::DVec3::new(1.0, 2.0, 3.0),
    };
    let inside = grid.origin.as_vec3() + Vec3::splat(2.0);
    let e = upload_points(
        &ctx.device,
        &ctx.queue,
        &grid,
        &[inside, Vec3::new(f32::NAN, 0.0, 0.0)],
    )
    .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("point 1") && what.contains("not finite")),
        "{e}"
    );
    // The box spans origin .. origin + 4 in each axis.
    let e = upload_points(
        &ctx.device,
        &ctx.queue,
        &grid,
        &[grid.origin.as_vec3() + Vec3::new(4.1, 1.0, 1.0)],
    )
    .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("outside the volume")),
        "{e}"
    );
    assert!(matches!(
        upload_points(&ctx.device, &ctx.queue, &grid, &[]),
        Err(Error::Size {
            what: "number of seed points",
            got: 0,
            ..
        })
    ));
    let e = upload_points_with_homes(&ctx.device, &ctx.queue, &grid, &[inside], &[[8, 0, 0]])
        .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("home voxel")),
        "{e}"
    );
    let e = upload_points_with_homes(&ctx.device, &ctx.queue, &grid, &[inside], &[]).unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("0 homes for 1 points")),
        "{e}"
    );
    let bad_grid = Grid {
        voxel: f64::NAN,
        ..grid
    };
    assert!(matches!(
        upload_points(&ctx.device, &ctx.queue, &bad_grid, &[inside]),
        Err(Error::Invalid { .. })
    ));
}

#[test]
fn bad_options_and_textures() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let volume = upload_volume(&ctx.device, &ctx.queue, &[255; 64], [4, 4, 4]).unwrap();
    let mut enc = ctx.encoder("bad");
    let bad = [
        Settings3d {
            voxel_size: f32::NAN,
            ..Settings3d::default()
        },
        Settings3d {
            voxel_size: -1.0,
            ..Settings3d::default()
        },
        Settings3d {
            band: Some(0.0),
            ..Settings3d::default()
        },
        Settings3d {
            band: Some(f32::INFINITY),
            ..Settings3d::default()
        },
        Settings3d {
            inside: Inside::Threshold(f32::NAN),
            ..Settings3d::default()
        },
    ];
    for o in bad {
        assert!(
            matches!(
                d3.encode(&ctx.device, &mut enc, &volume, &o),
                Err(Error::Invalid { .. })
            ),
            "{o:?}"
        );
    }
    // A 3D texture of a format the stages do not read.
    let rgba = crate::common::sampled(&ctx, [4, 4, 4], wgpu::TextureFormat::Rgba8Unorm);
    let e = d3
        .encode(&ctx.device, &mut enc, &rgba, &Settings3d::default())
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::Format {
                format: wgpu::TextureFormat::Rgba8Unorm,
                ..
            }
        ),
        "{e}"
    );
    // A 2D texture where a volume is expected.
    let flat = fieldkit::distance::upload_mask(&ctx.device, &ctx.queue, &[255; 16], 4, 4).unwrap();
    assert!(matches!(
        d3.encode(&ctx.device, &mut enc, &flat, &Settings3d::default()),
        Err(Error::Invalid { .. })
    ));
    // Sub-voxel seeds with the exact method, and an inside volume of another size.
    let grid = Grid::new([4, 4, 4]);
    let pts = upload_points(&ctx.device, &ctx.queue, &grid, &[Vec3::splat(1.5)]).unwrap();
    let e = d3
        .encode_points(
            &ctx.device,
            &mut enc,
            &pts,
            [4, 4, 4],
            None,
            &Settings3d::default(),
        )
        .unwrap_err();
    assert!(
        matches!(&e, Error::Invalid { what, .. } if what.contains("JFA")),
        "{e}"
    );
    let other = upload_volume(&ctx.device, &ctx.queue, &[0; 27], [3, 3, 3]).unwrap();
    let jfa = Settings3d {
        method: Method::Jfa(Variant::JfaPlus2),
        ..Settings3d::default()
    };
    assert!(matches!(
        d3.encode_points(&ctx.device, &mut enc, &pts, [4, 4, 4], Some(&other), &jfa),
        Err(Error::Invalid { .. })
    ));
    // Column pass on an axis that does not exist.
    let buf = |n| {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: n,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        })
    };
    assert!(matches!(
        d3.exact()
            .encode_column_pass(&ctx.device, &mut enc, &buf(256), &buf(256), [4, 4, 4], 0),
        Err(Error::Invalid { .. })
    ));
    assert!(matches!(
        d3.exact()
            .encode_column_pass(&ctx.device, &mut enc, &buf(256), &buf(128), [4, 4, 4], 1),
        Err(Error::Invalid { .. })
    ));
    // The benchmarks' copies check their buffers as the passes do.
    for axis in [1, 2] {
        let e = d3
            .exact()
            .encode_tile_copy(&ctx.device, &mut enc, &buf(128), [4, 4, 4], axis, None)
            .unwrap_err();
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains("nearest buffer has 128 bytes")),
            "{e}"
        );
        let e = d3
            .exact()
            .encode_global_copy(
                &ctx.device,
                &mut enc,
                &buf(128),
                None,
                [4, 4, 4],
                axis,
                None,
            )
            .unwrap_err();
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains("nearest")),
            "{e}"
        );
        // Words of a 4 × 4 × 4 field: one per row, 8 bytes each.
        let e = d3
            .exact()
            .encode_global_copy(
                &ctx.device,
                &mut enc,
                &buf(256),
                Some(&buf(64)),
                [4, 4, 4],
                axis,
                None,
            )
            .unwrap_err();
        assert!(
            matches!(&e, Error::Invalid { what, .. } if what.contains("words buffer has 64 bytes, [4, 4, 4] needs 128")),
            "{e}"
        );
    }
    assert!(matches!(
        d3.exact()
            .encode_global_copy(&ctx.device, &mut enc, &buf(256), None, [4, 4, 4], 3, None),
        Err(Error::Invalid { .. })
    ));
    // With good buffers the global copies record (a placeholder bound both read-only and
    // read-write in one dispatch would fail wgpu's validation below).
    let mut global = Distance3d::new(&ctx.device).unwrap();
    global.set_column_passes(ColumnPasses::Global);
    for axis in [1, 2] {
        for words in [None, Some(buf(128))] {
            let recorded = global
                .exact()
                .encode_global_copy(
                    &ctx.device,
                    &mut enc,
                    &buf(256),
                    words.as_ref(),
                    [4, 4, 4],
                    axis,
                    None,
                )
                .unwrap();
            assert!(
                recorded.is_some(),
                "axis {axis}: the copy did not run in global memory"
            );
        }
    }
    // The copies along z with the resolving pass's distance store take a 3D R32Float storage
    // texture of the grid's size, and record with one in either memory; a wrong one, or one
    // along y, is a typed error naming what was wrong.
    let texture = |size: [u32; 3], format, dimension| {
        fieldkit::gpu::texture(
            &ctx.device,
            "test texture",
            [size[0], size[1], size[2]],
            dimension,
            format,
            wgpu::TextureUsages::STORAGE_BINDING,
        )
    };
    let d3d = wgpu::TextureDimension::D3;
    let good = texture([4, 4, 4], wgpu::TextureFormat::R32Float, d3d);
    for copier in [&d3, &global] {
        let tile = copier
            .exact()
            .encode_tile_copy(&ctx.device, &mut enc, &buf(256), [4, 4, 4], 2, Some(&good))
            .unwrap();
        let glob = copier
            .exact()
            .encode_global_copy(
                &ctx.device,
                &mut enc,
                &buf(256),
                None,
                [4, 4, 4],
                2,
                Some(&good),
            )
            .unwrap();
        // Exactly one of them runs the pass's memory.
        assert!(tile.is_some() != glob.is_some());
    }
    let bad = [
        (
            texture([4, 4, 5], wgpu::TextureFormat::R32Float, d3d),
            2,
            "the grid [4, 4, 4]",
        ),
        (
            texture([4, 4, 4], wgpu::TextureFormat::R32Uint, d3d),
            2,
            "R32Float",
        ),
        (
            texture(
                [4, 4, 1],
                wgpu::TextureFormat::R32Float,
                wgpu::TextureDimension::D2,
            ),
            2,
            "3D",
        ),
        (good.clone(), 1, "only by the copy along z"),
    ];
    for (t, axis, says) in &bad {
        for e in [
            d3.exact().encode_tile_copy(
                &ctx.device,
                &mut enc,
                &buf(256),
                [4, 4, 4],
                *axis,
                Some(t),
            ),
            global.exact().encode_global_copy(
                &ctx.device,
                &mut enc,
                &buf(256),
                None,
                [4, 4, 4],
                *axis,
                Some(t),
            ),
        ] {
            let e = e.unwrap_err();
            assert!(
                matches!(&e, Error::Invalid { what, .. } if what.contains(says)),
                "{says}: {e}"
            );
        }
    }
    // Nothing bad reached wgpu: the encoder still submits cleanly.
    ctx.submit_and_wait("bad", enc).unwrap();
    assert!(ctx.take_uncaptured().is_empty());
}
