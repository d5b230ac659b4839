//! The `own_device` example, run as a test: an application's own device with WebGPU's default
//! limits and no optional features drives every technique through the public API, and what it
//! computes is checked against CPU references (not only that it runs).

use crate::own_device;

use fieldkit::distance::cpu;

fn report() -> own_device::Report {
    let (device, queue, adapter) =
        own_device::open_device().unwrap_or_else(|e| panic!("this test needs a GPU adapter: {e}"));
    own_device::run(&device, &queue, adapter).expect("every technique runs on default limits")
}

#[test]
fn own_device_runs_every_technique_and_matches_the_references() {
    let r = report();
    eprintln!("adapter: {}", r.adapter);

    // 2D: the exact transform (the default) against the CPU's exact transform. Distances are
    // square roots of integers, so only the last bit of `sqrt` may differ between adapters.
    let [w, h] = own_device::MASK;
    let inside: Vec<bool> = r.mask.iter().map(|&m| m != 0).collect();
    let want = cpu::signed_2d(&inside, w as usize, h as usize);
    let mut worst = 0.0f64;
    for (i, (&got, &want)) in r.distance_2d.iter().zip(&want).enumerate() {
        let err = (got as f64 - want).abs();
        assert!(
            err <= 1e-5 * want.abs().max(1.0),
            "texel {i}: {got} against {want}"
        );
        worst = worst.max(err);
    }
    eprintln!(
        "2D exact: worst |error| {worst:.2e} over {} texels",
        want.len()
    );

    // Voxelize → SDF: the exact 3D transform of the solid voxels the GPU made, against the
    // CPU's transform of the same voxels; and the voxels themselves are a torus: the voxel at
    // the ring's centre line is solid, the hole's centre is not.
    let size = r.grid.size.map(|s| s as usize);
    assert_eq!(r.solid.len(), size.iter().product::<usize>());
    let want = cpu::signed_3d(&r.solid, size);
    let voxel = r.grid.voxel;
    for (i, (&got, &want)) in r.sdf.iter().zip(&want).enumerate() {
        let want = want * voxel;
        assert!(
            (got as f64 - want).abs() <= 1e-5 * want.abs().max(voxel),
            "voxel {i}: {got} against {want}"
        );
    }
    let index = |p: glam::DVec3| {
        let v = ((p - r.grid.origin) / voxel).floor().as_uvec3();
        ((v.z as usize * size[1]) + v.y as usize) * size[0] + v.x as usize
    };
    assert!(
        r.solid[index(glam::DVec3::new(1.0, 0.0, 0.0))],
        "the ring is solid"
    );
    assert!(!r.solid[index(glam::DVec3::ZERO)], "the hole is empty");
    // The hole's centre is 0.6 from the torus. Its voxel's centre lies within half a voxel
    // diagonal of it, the conservative surface voxels reach up to another half diagonal past
    // the surface, and the resolve takes half a voxel off.
    let hole = r.sdf[index(glam::DVec3::ZERO)] as f64;
    let (lo, hi) = (
        0.6 - 3f64.sqrt() * voxel - voxel / 2.0,
        0.6 + 3f64.sqrt() / 2.0 * voxel,
    );
    assert!(
        (lo..hi).contains(&hole),
        "the hole's centre is 0.6 from the surface: got {hole}, want {lo:.3}..{hi:.3}"
    );

    // The mesh's own field is the distance to the torus's triangles: against the analytic
    // torus (about the y axis, ring radius 1, tube 0.4; its 48 × 24 facets lie within
    // 1.4 · (1 − cos 3.75°) + 0.4 · (1 − cos 7.5°) ≈ 0.007 of it) within the band, where the
    // voxel-centre field above is off by up to a voxel.
    let band = 4.0 * voxel;
    let mut in_band = 0;
    for (i, &got) in r.mesh_sdf.iter().enumerate() {
        let v = [
            i % size[0],
            (i / size[0]) % size[1],
            i / (size[0] * size[1]),
        ];
        let p = r.grid.voxel_centre(v.map(|c| c as u32));
        let ring = (glam::DVec2::new(p.x, p.z).length() - 1.0).hypot(p.y);
        let analytic = ring - 0.4;
        if analytic.abs() < band - 0.05 {
            in_band += 1;
            assert!(
                (got as f64 - analytic).abs() < 0.02,
                "voxel {v:?}: mesh field {got} against the torus's {analytic}"
            );
        } else if analytic.abs() > band + 0.05 {
            // ±band, as the shader rounds it to f32.
            let want = band.copysign(analytic);
            assert!(
                (got as f64 - want).abs() < 1e-6,
                "voxel {v:?} beyond the band: {got}"
            );
        }
    }
    assert!(in_band > 1000, "{in_band} voxels in the band");

    // The frame: the island and the sea wrote depth (the sea covers the lower half of the
    // frame, the sky stays at the clear depth in the top rows), and the cloud changed pixels
    // above the island without touching the depth buffer.
    let [fw, fh] = own_device::FRAME;
    let row_covered = |y: u32| {
        (0..fw)
            .filter(|&x| r.depth[(y * fw + x) as usize] < 1.0)
            .count()
    };
    assert_eq!(row_covered(0), 0, "the top row is sky");
    for y in fh / 2..fh {
        assert_eq!(
            row_covered(y),
            fw as usize,
            "row {y} is covered by the sea or the island"
        );
    }
    // Every pixel the cloud changed lies in its box's screen rectangle, and it changed a fair
    // part of that rectangle (llvmpipe: 2601 of the rectangle's 8176 pixels; the box's corners
    // project wider than the cloud inside, so a fifth is the least an adapter may show).
    let (camera_view, (lo, hi)) = (own_device::camera().1, own_device::CLOUD);
    let [x0, y0, x1, y1] =
        fieldkit::view::screen_rect(&camera_view, glam::Mat4::IDENTITY, lo, lo + hi);
    let mut inside = 0;
    for (i, (a, b)) in r.colour.iter().zip(&r.colour_without_cloud).enumerate() {
        if a != b {
            let (x, y) = (i as u32 % fw, i as u32 / fw);
            assert!(
                (x0..x1).contains(&x) && (y0..y1).contains(&y),
                "the cloud changed pixel ({x}, {y}), outside its rectangle {:?}",
                [x0, y0, x1, y1]
            );
            inside += 1;
        }
    }
    let area = ((x1 - x0) * (y1 - y0)) as usize;
    eprintln!("the cloud changed {inside} of its rectangle's {area} pixels");
    assert!(
        inside * 5 > area,
        "the cloud changed {inside} of {area} pixels"
    );
}
