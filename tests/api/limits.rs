//! Allocations at and past the device's limits: the largest grid the limits allow is made, one
//! larger is a typed error naming the limit, several of the largest at once are made and run,
//! and afterwards the device still answers a small request correctly.
//!
//! (A real out-of-memory on the device cannot be provoked on lavapipe, which allocates from
//! the host's memory; what is tested is that fieldkit refuses what the limits forbid before
//! wgpu sees it, and that nothing it refused or allocated leaves the device unusable.)

use fieldkit::Error;
use fieldkit::distance::{Distance3d, Settings3d, check_size_3d, cpu, upload_volume};
use fieldkit::gpu::Context;

/// The largest cube side `check_size_3d` accepts on this device.
fn largest_cube(device: &wgpu::Device) -> u32 {
    let (mut lo, mut hi) = (1u32, 2047u32);
    assert!(check_size_3d(device, [1; 3]).is_ok());
    while lo + 1 < hi {
        let mid = (lo + hi) / 2;
        if check_size_3d(device, [mid; 3]).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn the_largest_grid_runs_one_larger_is_refused_and_the_device_stays_usable() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let n = largest_cube(&ctx.device);
    let limits = ctx.device.limits();
    eprintln!(
        "largest exact-distance cube on {}: {n}³ (storage binding {} MiB)",
        ctx.adapter_name(),
        limits.max_storage_buffer_binding_size >> 20
    );

    // One larger: the next cube is refused by its bytes (one binding, what JFA needs), and on
    // each axis (the others 1) the longest side accepted plus one is refused by the side limit
    // — typed, before wgpu. The upload takes any side the exact transform takes (2048 on every
    // axis, `SeedPacking`) and refuses one past that.
    let refused = |size: [u32; 3], upload: bool| {
        match check_size_3d(&ctx.device, size) {
            // A zero side is out of range too (got 0 against the minimum of 1).
            Err(Error::Size { got, max, .. }) => {
                assert!(got > max || got == 0, "{size:?}: {got} ≤ {max}")
            }
            other => panic!("{size:?}: {other:?}"),
        }
        if upload {
            match upload_volume(&ctx.device, &ctx.queue, &[0], size) {
                Err(Error::Size { .. }) => {}
                other => panic!("upload of {size:?}: {other:?}"),
            }
        }
    };
    refused([n + 1; 3], false);
    // Its sides are in range: the upload checks them, not a field's bytes (the exact transform
    // splits a field larger than one binding), so here only the data's length is wrong.
    match upload_volume(&ctx.device, &ctx.queue, &[0], [n + 1; 3]) {
        Err(Error::Invalid { what, .. }) => assert!(what.contains("bytes"), "{what}"),
        other => panic!("upload of {:?}: {other:?}", [n + 1; 3]),
    }
    for axis in 0..3 {
        let side = |m: u32| {
            let mut size = [1; 3];
            size[axis] = m;
            size
        };
        let (mut lo, mut hi) = (1u32, 1 << 20);
        while lo + 1 < hi {
            let mid = (lo + hi) / 2;
            if check_size_3d(&ctx.device, side(mid)).is_ok() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        eprintln!("axis {axis}: longest side {lo}");
        refused(side(lo + 1), false);
        refused(side(0), true);
        let exact = fieldkit::distance::MAX_SIDE_EXACT_3D.min(limits.max_texture_dimension_3d);
        match upload_volume(&ctx.device, &ctx.queue, &[0], side(exact + 1)) {
            Err(Error::Size { got, max, .. }) => {
                assert_eq!((got, max), (exact as u64 + 1, exact as u64))
            }
            other => panic!("upload of {:?}: {other:?}", side(exact + 1)),
        }
    }

    // The largest, three at once, in one submission: each made and recorded without error.
    let mut mask = vec![0u8; (n as usize).pow(3)];
    mask[0] = 1;
    let volume = upload_volume(&ctx.device, &ctx.queue, &mask, [n; 3]).unwrap();
    drop(mask);
    let mut enc = ctx.encoder("largest");
    let fields: Vec<_> = (0..3)
        .map(|_| {
            d3.encode(&ctx.device, &mut enc, &volume, &Settings3d::default())
                .expect("the largest grid the limits allow")
        })
        .collect();
    ctx.submit_and_wait("largest", enc).unwrap();
    assert!(ctx.take_uncaptured().is_empty());
    drop(fields);
    drop(volume);

    // Then a small request, checked against the CPU.
    let size = [7usize, 5, 6];
    let small: Vec<u8> = (0..7 * 5 * 6).map(|i| u8::from(i % 23 == 4)).collect();
    let volume = upload_volume(&ctx.device, &ctx.queue, &small, [7, 5, 6]).unwrap();
    let mut enc = ctx.encoder("small after");
    let f = d3
        .encode(&ctx.device, &mut enc, &volume, &Settings3d::default())
        .unwrap();
    ctx.submit_and_wait("small after", enc).unwrap();
    let words = f.nearest.read(&ctx.device, &ctx.queue).wait(&ctx).unwrap();
    let want = cpu::edt_3d_squared(&small.iter().map(|&m| m != 0).collect::<Vec<_>>(), size);
    for (i, (&w, &d2)) in words.iter().zip(&want).enumerate() {
        let [x, y, z] = fieldkit::distance::unpack_seed3(w).expect("every voxel has a seed");
        let p = [i % 7, (i / 7) % 5, i / 35];
        let got = (x as i64 - p[0] as i64).pow(2)
            + (y as i64 - p[1] as i64).pow(2)
            + (z as i64 - p[2] as i64).pow(2);
        assert_eq!(got as u64, d2, "voxel {p:?}");
    }
    assert!(ctx.take_uncaptured().is_empty());
}
