//! The ocean's LOD (`fieldkit::ocean::lod`, CPU): the error bound holds for every drawn patch,
//! the view is covered without overlaps, culling keeps what the camera sees, skirts are only
//! where the vertex spacing changes, and the triangle count against the write-up's patches of
//! 256 vertices per row at the same largest error.

use fieldkit::ocean::{LodSettings, height_error, patch_triangles, select, writeup_patches};
use fieldkit::ocean::{Look, OceanCamera, Patch};
use fieldkit::ocean::{Wave, Waves};
use glam::{DVec2, DVec3, DVec4, Vec2};

fn waves() -> Waves {
    Waves::open_sea()
}

/// 1080p, 60° vertical field of view, 12 m above the water looking 8° down, somewhere inside
/// the 2560 m square.
fn camera() -> OceanCamera {
    let eye = DVec3::new(130.0, 12.0, -260.0);
    let dir = DVec3::new(0.6, -0.14, -0.79).normalize();
    OceanCamera::look_at(
        eye,
        eye + dir,
        glam::camera::rh::proj::directx::perspective(60f32.to_radians(), 16.0 / 9.0, 0.5, 5000.0),
    )
}

#[test]
fn every_drawn_patch_meets_the_error_or_the_depth_limit() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    let settings = LodSettings::default();
    let sel = select(&w, &look, &cam, 1080, &settings).unwrap();
    let smallest = settings.size / (1u64 << settings.max_depth) as f64;
    println!(
        "{} patches, {} culled, {} triangles, largest error {:.3} px",
        sel.patches.len(),
        sel.culled,
        sel.triangles,
        sel.max_error_px
    );
    assert!(
        sel.max_error_px <= settings.max_error_px || sel.patches.iter().any(|p| p.size <= smallest)
    );
    assert_eq!(
        sel.triangles,
        sel.patches.iter().map(|p| p.triangles()).sum::<u64>()
    );
    assert!(
        sel.triangles
            < sel
                .patches
                .iter()
                .map(|p| patch_triangles(p.quads))
                .sum::<u64>()
    );
    // Each patch drawn with the fewest quads a side, from 16 down to 8, that keep the error;
    // each count is needed somewhere in this view.
    let q = settings.patch_quads;
    for quads in q / 2..=q {
        assert!(
            sel.patches.iter().any(|p| p.quads == quads),
            "no patch of {quads} quads"
        );
    }
    assert!(sel.patches.iter().all(|p| (q / 2..=q).contains(&p.quads)));
    // Finer patches near the eye, coarser far away.
    let sizes: Vec<f64> = sel.patches.iter().map(|p| p.size).collect();
    let (min, max) = sizes
        .iter()
        .fold((f64::MAX, 0f64), |(a, b), &s| (a.min(s), b.max(s)));
    assert!(max / min >= 16.0, "sizes from {min} to {max}");
}

/// Skirts only where a crack can be: an edge has one exactly when a drawn patch of another size
/// or quad count touches it from across. Checked against every pair of patches.
#[test]
fn skirts_only_where_the_spacing_changes() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    let sel = select(&w, &look, &cam, 1080, &LodSettings::default()).unwrap();
    // Per edge (z low, x high, z high, x low): the line it lies on, the axis along it.
    let edges = |p: &Patch| {
        let (lo, hi) = (p.corner, p.corner + DVec2::splat(p.size));
        [(1, lo.y, 0), (0, hi.x, 1), (1, hi.y, 0), (0, lo.x, 1)]
            .map(|(axis, at, along)| (axis, at, (lo[along], hi[along])))
    };
    let (mut bare, mut skirted) = (0, 0);
    for (i, p) in sel.patches.iter().enumerate() {
        for (e, (axis, at, (a0, a1))) in edges(p).into_iter().enumerate() {
            // Drawn patches across this edge (corners are exact in f64: sums of halvings).
            let across: Vec<&Patch> = sel
                .patches
                .iter()
                .enumerate()
                .filter(|&(k, q)| {
                    let (qlo, qhi) = (q.corner, q.corner + DVec2::splat(q.size));
                    let along = 1 - axis;
                    k != i
                        && (qlo[axis] == at || qhi[axis] == at)
                        && qlo[along] < a1
                        && qhi[along] > a0
                })
                .map(|(_, q)| q)
                .collect();
            let differs = across
                .iter()
                .any(|q| q.size != p.size || q.quads != p.quads);
            let has = p.skirts & (1 << e) != 0;
            assert_eq!(
                has, differs,
                "patch {p:?} edge {e}: skirt {has}, patches across {across:?}"
            );
            if has { skirted += 1 } else { bare += 1 }
        }
    }
    println!("{skirted} edges with skirts, {bare} without");
    assert!(skirted > 0 && bare > 0);
}

/// Every point of the square that the camera sees (on the mean surface, inside the image) lies
/// in exactly one drawn patch.
#[test]
fn the_view_is_covered_once() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    let settings = LodSettings::default();
    let sel = select(&w, &look, &cam, 1080, &settings).unwrap();
    let vp = cam.proj.as_dmat4() * cam.view;
    let (mut seen, mut covered) = (0, 0);
    for j in 0..400 {
        for i in 0..400 {
            let p = DVec2::new(
                -1280.0 + 6.4 * (i as f64 + 0.5),
                -1280.0 + 6.4 * (j as f64 + 0.5),
            );
            let clip = vp * DVec4::new(p.x, 0.0, p.y, 1.0);
            let ndc = clip.truncate() / clip.w;
            if clip.w <= 0.0
                || ndc.x.abs() > 1.0
                || ndc.y.abs() > 1.0
                || !(0.0..=1.0).contains(&ndc.z)
            {
                continue;
            }
            seen += 1;
            let holders = sel
                .patches
                .iter()
                .filter(|q| {
                    p.x >= q.corner.x
                        && p.x < q.corner.x + q.size
                        && p.y >= q.corner.y
                        && p.y < q.corner.y + q.size
                })
                .count();
            assert_eq!(holders, 1, "point {p} is in {holders} patches");
            covered += 1;
        }
    }
    println!("{seen} visible sample points, all covered once");
    assert!(seen > 1000 && covered == seen);
}

/// The goal: the write-up's largest error with at most a tenth of its triangles. Counted
/// against the write-up's patches in view only (a renderer would cull the others), which is
/// the harder comparison.
#[test]
fn fewer_triangles_than_the_writeup_at_its_error() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    let settings = LodSettings::default();
    let writeup = writeup_patches(&w, &look, &cam, 1080, &settings, 255);
    let per_patch = 2 * 255 * 255;
    let ours = select(
        &w,
        &look,
        &cam,
        1080,
        &LodSettings {
            max_error_px: writeup.max_error_px,
            ..settings
        },
    )
    .unwrap();
    let visible = writeup.visible as u64 * per_patch;
    println!(
        "write-up: {} patches of 255² ({} in view), {} triangles ({} in view), largest error {:.3} px; \
         quadtree: {} patches, {} triangles ({:.4} of those in view), largest error {:.3} px",
        writeup.patches.len(),
        writeup.visible,
        writeup.patches.len() as u64 * per_patch,
        visible,
        writeup.max_error_px,
        ours.patches.len(),
        ours.triangles,
        ours.triangles as f64 / visible as f64,
        ours.max_error_px
    );
    assert!(ours.max_error_px <= writeup.max_error_px);
    assert!(
        ours.triangles * 10 <= visible,
        "{} against {visible}",
        ours.triangles
    );
}

#[test]
fn height_error_follows_the_sampling() {
    let w = Waves::new(
        vec![Wave {
            direction: Vec2::X,
            amplitude: 2.0,
            wavelength: 10.0,
            speed: 0.0,
        }],
        0.0,
    )
    .unwrap();
    let none = Look {
        height_layers: vec![],
        ..Look::default()
    };
    // Half a wavelength apart: samples can sit on the zero crossings, missing all of A.
    assert!((height_error(&w, &none, 10.0) - 4.0).abs() < 1e-12);
    assert!((height_error(&w, &none, 5.0) - 2.0).abs() < 1e-12);
    // A quarter wavelength: A (1 − cos(π/4)).
    assert!(
        (height_error(&w, &none, 2.5) - 2.0 * (1.0 - (std::f64::consts::FRAC_PI_4).cos())).abs()
            < 1e-12
    );
    assert!(height_error(&w, &Look::default(), 2.5) > height_error(&w, &none, 2.5));
}

#[test]
fn bad_settings_are_refused() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    for s in [
        LodSettings {
            size: 0.0,
            ..LodSettings::default()
        },
        LodSettings {
            max_error_px: f64::NAN,
            ..LodSettings::default()
        },
        LodSettings {
            max_error_px: 0.0,
            ..LodSettings::default()
        },
        LodSettings {
            centre: DVec2::new(f64::INFINITY, 0.0),
            ..LodSettings::default()
        },
        LodSettings {
            max_depth: 40,
            ..LodSettings::default()
        },
    ] {
        assert!(select(&w, &look, &cam, 1080, &s).is_err(), "{s:?}");
    }
    assert!(select(&w, &look, &cam, 0, &LodSettings::default()).is_err());
}

/// An error bound no quadtree can meet (a millionth of a pixel, 24 levels) is refused once the
/// walk passes `MAX_LOD_NODES`, instead of walking 4²⁴ nodes (found by
/// `tests/api/properties.rs::ocean_lod_selects_or_refuses`: 5 GiB allocated before it was bounded).
#[test]
fn an_unreachable_error_is_refused_not_walked() {
    let (w, look, cam) = (waves(), Look::default(), camera());
    let s = LodSettings {
        max_error_px: 1e-6,
        max_depth: 24,
        ..LodSettings::default()
    };
    match select(&w, &look, &cam, 1080, &s) {
        Err(fieldkit::Error::Size { got, max, .. }) => {
            assert_eq!(max, fieldkit::ocean::MAX_LOD_NODES);
            assert!(got > max, "{got} ≤ {max}");
        }
        other => panic!("expected Error::Size, got {other:?}"),
    }
    // The default settings stay far below the budget.
    let sel = select(&w, &look, &cam, 1080, &LodSettings::default()).unwrap();
    assert!((sel.patches.len() as u64 + sel.culled as u64) < fieldkit::ocean::MAX_LOD_NODES / 16);
}
