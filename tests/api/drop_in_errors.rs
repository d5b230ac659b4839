//! Bad input to the drop-in API gets a typed error naming what was wrong: fitting a grid to an
//! unusable mesh, a 2D distance with a bad texel size, reading back a buffer that cannot be
//! copied, taking a readback twice, a command buffer wgpu rejects at submission (its message,
//! not a lost device).

use fieldkit::Error;
use fieldkit::distance::{Distance2d, Method2d, Settings2d, Variant, upload_mask};
use fieldkit::gpu::{Context, readback_buffer};
use fieldkit::voxelize::{Grid, Mesh};
use glam::DVec3;

#[test]
fn grid_fit_refuses_meshes_it_cannot_fit() {
    let invalid = |r: Result<Grid, Error>, needle: &str| match r {
        Err(Error::Invalid { what, .. }) => assert!(what.contains(needle), "{what}"),
        other => panic!("expected an Invalid error naming {needle:?}, got {other:?}"),
    };
    invalid(Grid::fit(&Mesh::default(), 32), "empty mesh");
    let mut nan = Mesh::cuboid(DVec3::ZERO, DVec3::ONE);
    nan.positions[3].y = f64::NAN;
    invalid(Grid::fit(&nan, 32), "vertex 3");
    let mut flat = Mesh::cuboid(DVec3::ZERO, DVec3::ONE);
    flat.positions
        .iter_mut()
        .for_each(|p| *p = DVec3::splat(2.0));
    invalid(Grid::fit(&flat, 32), "no extent");
    for n in [0, 1, 2] {
        invalid(
            Grid::fit(&Mesh::cuboid(DVec3::ZERO, DVec3::ONE), n),
            &format!(
                "needs at least 3 voxels along the longest side (the mesh and one voxel of margin each side), not {n}"
            ),
        );
    }
    assert!(Grid::fit(&Mesh::cuboid(DVec3::ZERO, DVec3::ONE), 3).is_ok());
    // A fitted grid holds the mesh with a voxel of margin and at most n voxels a side.
    let mesh = Mesh::cuboid(DVec3::new(-1.0, 0.0, 2.0), DVec3::new(3.0, 1.0, 2.5));
    let g = Grid::fit(&mesh, 20).unwrap();
    assert_eq!(g.size[0], 20);
    assert!(
        g.size.iter().all(|&s| (1..=20).contains(&s)),
        "{:?}",
        g.size
    );
    let hi = g.origin + DVec3::from(g.size.map(f64::from)) * g.voxel;
    for p in &mesh.positions {
        assert!(
            (p.cmpge(g.origin + g.voxel * 0.999) & p.cmple(hi - g.voxel * 0.999)).all(),
            "{p} in {g:?}"
        );
    }
}

#[test]
fn distance_2d_refuses_bad_texel_sizes_for_both_methods() {
    let ctx = Context::shared();
    let distance = Distance2d::new(&ctx.device).unwrap();
    let mask = upload_mask(&ctx.device, &ctx.queue, &[255, 0, 0, 0], 2, 2).unwrap();
    for method in [Method2d::Exact, Method2d::Jfa(Variant::JfaPlus2)] {
        for texel_size in [f32::NAN, 0.0, -1.0, f32::INFINITY] {
            let mut enc = ctx.encoder("bad texel size");
            let err = distance
                .encode(
                    &ctx.device,
                    &mut enc,
                    &mask,
                    &Settings2d {
                        method,
                        signed: false,
                        texel_size,
                        ..Settings2d::default()
                    },
                )
                .err()
                .unwrap_or_else(|| panic!("{method:?} accepted texel_size {texel_size}"));
            assert!(
                matches!(&err, Error::Invalid { what, .. } if what.contains("texel_size")),
                "{err}"
            );
        }
    }
}

#[test]
fn readbacks_say_what_is_wrong() {
    let ctx = Context::shared();
    let no_copy = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("storage only"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let err = readback_buffer(&ctx.device, &ctx.queue, &no_copy)
        .wait(&ctx)
        .unwrap_err();
    assert!(
        matches!(&err, Error::Readback(m) if m.contains("COPY_SRC")),
        "{err}"
    );

    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("copyable"),
        size: 8,
        usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    ctx.queue
        .write_buffer(&buffer, 0, &[1, 2, 3, 4, 5, 6, 7, 8]);
    let mut readback = readback_buffer(&ctx.device, &ctx.queue, &buffer);
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let first = readback.try_take().expect("mapped after the poll");
    assert_eq!(first.unwrap(), vec![1, 2, 3, 4, 5, 6, 7, 8]);
    assert!(matches!(readback.try_take(), Some(Err(Error::Readback(_)))));
}

/// What each readback sees of a texture written in an encoder not yet submitted: the copy
/// recorded into that encoder (`readback_texture_in`) sees the write; the one that submits its
/// own copy at once (`readback_texture`) sees the texture as it was (zeros), as documented; and
/// waiting for a readback whose encoder is never submitted is an error, not a hang.
#[test]
fn readbacks_see_what_their_encoder_order_says() {
    use fieldkit::gpu::{readback_texture, readback_texture_in};
    let ctx = Context::shared();
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("written later"),
        size: wgpu::Extent3d {
            width: 3,
            height: 2,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let write = |encoder: &mut wgpu::CommandEncoder| {
        let view = texture.create_view(&Default::default());
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("write 9.875"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                resolve_target: None,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 9.875,
                        g: 0.0,
                        b: 0.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
    };
    let mut encoder = ctx.encoder("user's frame");
    write(&mut encoder);
    let in_encoder = readback_texture_in::<f32>(&ctx.device, &mut encoder, &texture);
    let submitted_before = readback_texture::<f32>(&ctx.device, &ctx.queue, &texture);
    ctx.queue.submit([encoder.finish()]);
    assert_eq!(in_encoder.wait(&ctx).unwrap(), vec![9.875; 6]);
    assert_eq!(submitted_before.wait(&ctx).unwrap(), vec![0.0; 6]);

    let mut never = ctx.encoder("never submitted");
    write(&mut never);
    let orphan = readback_texture_in::<f32>(&ctx.device, &mut never, &texture);
    drop(never);
    match orphan.wait(&ctx) {
        Err(Error::Readback(m)) => assert!(m.contains("never submitted"), "{m}"),
        other => panic!("expected a readback error, got {other:?}"),
    }
}

#[test]
fn a_rejected_submission_reports_wgpu_s_message_not_a_lost_device() {
    // A device of its own: the uncaptured error below must not reach the other tests' waits.
    let ctx = Context::new().expect(
        "no GPU adapter: install a Vulkan driver (on Debian: apt-get install mesa-vulkan-drivers)",
    );
    let no_clear = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("storage only"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    // clear_buffer needs COPY_DST: wgpu rejects the command buffer at submission.
    let mut enc = ctx.encoder("clear without COPY_DST");
    enc.clear_buffer(&no_clear, 0, None);
    let err = ctx.submit_and_wait("test clear", enc).unwrap_err();
    assert!(
        matches!(&err, Error::Wgpu { stage: "test clear", message } if message.contains("COPY_DST")),
        "{err}"
    );
    // Nothing is left over for the next wait, and the device still works.
    let enc = ctx.encoder("empty");
    ctx.submit_and_wait("test empty", enc).unwrap();
}
