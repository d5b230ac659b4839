//! Mesh distance fields (`mesh_sdf/mesh_sdf`): every voxel against the f64 reference of the same
//! mesh (brute-force nearest triangle, sign by the generalized winding number) on closed meshes
//! (sphere, torus, box on a non-cubic grid away from the origin), unsigned fields, an open mesh
//! (a sphere with its cap cut off) where the sign rule is shown against the winding number, and
//! bad input.

use fieldkit::Error;
use fieldkit::gpu::{Context, read_texture};
use fieldkit::mesh_sdf::{Grid, Mesh, MeshSdf, Settings, cpu};
use glam::DVec3;

fn field(ctx: &Context, mesh: &Mesh, grid: &Grid, settings: Settings) -> Vec<f32> {
    let sdf = MeshSdf::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("mesh sdf");
    let f = sdf
        .encode(&ctx.device, &mut enc, mesh, grid, &settings)
        .unwrap();
    ctx.submit_and_wait("mesh sdf", enc).unwrap();
    read_texture(ctx, &f.texture).unwrap()
}

/// How a field compares with the reference: the largest distance error inside the band
/// (voxels), voxels signed against the winding number's sign, and the values beyond the band
/// that are not ±band.
#[derive(Debug, Default)]
struct Compared {
    in_band: usize,
    max_error: f64,
    wrong_sign: Vec<[u32; 3]>,
    beyond_not_clamped: usize,
}

fn compare(mesh: &Mesh, grid: &Grid, settings: Settings, got: &[f32]) -> Compared {
    let local = mesh.to_grid(grid).unwrap();
    let triangles = cpu::triangles(&local);
    let [nx, ny, nz] = grid.size;
    let band = settings.band as f64;
    let mut out = Compared::default();
    let mut i = 0;
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let p = cpu::centre([x, y, z]);
                let d = cpu::distance(p, &triangles);
                let value = got[i] as f64 / grid.voxel;
                i += 1;
                if settings.signed {
                    let inside = cpu::winding_number(p, &triangles) > 0.5;
                    // A centre on the surface has no side.
                    if d > 1e-3 && (value < 0.0) != inside {
                        out.wrong_sign.push([x, y, z]);
                    }
                }
                if d <= band - 1e-3 {
                    out.in_band += 1;
                    out.max_error = out.max_error.max((value.abs() - d).abs());
                } else if d > band + 1e-3 && (value.abs() - band).abs() > 1e-6 * band {
                    out.beyond_not_clamped += 1;
                }
            }
        }
    }
    out
}

// llvmpipe: f32 arithmetic on grid-local coordinates within 2e-5 voxels of the f64 reference at
// these sizes; 1e-3 leaves room for other GPUs' rounding and fused multiply-adds.
const MAX_ERROR: f64 = 1e-3;

fn check_closed(ctx: &Context, name: &str, mesh: &Mesh, grid: &Grid) {
    let settings = Settings::default();
    let got = field(ctx, mesh, grid, settings);
    let c = compare(mesh, grid, settings, &got);
    println!("{name}: {c:?}");
    assert!(c.in_band > 500, "{name}: only {} voxels in the band", c.in_band);
    assert!(c.max_error <= MAX_ERROR, "{name}: {c:?}");
    assert_eq!(c.wrong_sign, Vec::<[u32; 3]>::new(), "{name}: signs");
    assert_eq!(c.beyond_not_clamped, 0, "{name}");
}

#[test]
fn closed_meshes_match_the_reference() {
    let ctx = Context::shared();
    let sphere = Mesh::uv_sphere(DVec3::splat(8.1), 5.3, 24, 12);
    check_closed(&ctx, "sphere", &sphere, &Grid::new([16, 17, 18]));
    let torus = Mesh::torus(DVec3::new(9.0, 8.7, 6.2), 5.5, 2.1, 24, 12);
    check_closed(&ctx, "torus", &torus, &Grid::new([19, 18, 13]));
    // A box far from the origin on a grid of 0.25-unit voxels that cuts through it: the box's
    // faces leave the grid, so rows meet triangles outside it.
    let origin = DVec3::new(1000.0, -2000.0, 30.0);
    let cuboid = Mesh::cuboid(origin + DVec3::new(1.1, 0.9, 0.6), origin + DVec3::new(4.2, 3.1, 6.0));
    let grid = Grid {
        origin,
        voxel: 0.25,
        size: [20, 16, 14],
    };
    check_closed(&ctx, "box", &cuboid, &grid);
}

#[test]
fn unsigned_fields_are_the_distance() {
    let ctx = Context::shared();
    let torus = Mesh::torus(DVec3::new(8.0, 8.0, 5.0), 5.0, 2.0, 20, 10);
    let grid = Grid::new([16, 16, 10]);
    let settings = Settings {
        band: 2.5,
        signed: false,
    };
    let got = field(&ctx, &torus, &grid, settings);
    assert!(got.iter().all(|&v| v >= 0.0), "an unsigned field has no negative value");
    let c = compare(&torus, &grid, settings, &got);
    assert!(c.in_band > 300 && c.max_error <= MAX_ERROR, "{c:?}");
    assert_eq!(c.beyond_not_clamped, 0);
}

/// A UV sphere without the triangles of its top cap: an open mesh. The rows along z through the
/// hole cross the mesh once and abstain; the rows along x and y decide. Against the winding
/// number (½ at the plane of the hole's rim, seen as the hole's solid angle), the two rules
/// part only on the centres just below the rim that see the hole at close to half the sphere
/// and on those the winding number puts outside above it.
#[test]
fn open_meshes_take_the_rows_that_close() {
    let ctx = Context::shared();
    let mut sphere = Mesh::uv_sphere(DVec3::splat(8.0), 6.0, 24, 12);
    let top = |t: &[u32; 3]| t.iter().all(|&i| sphere.positions[i as usize].z > 8.0 + 6.0 * 0.8);
    let before = sphere.triangles.len();
    let kept: Vec<[u32; 3]> = sphere.triangles.iter().filter(|t| !top(t)).copied().collect();
    sphere.triangles = kept;
    assert!(sphere.triangles.len() < before && sphere.open_edge().is_some());
    let grid = Grid::new([16, 16, 16]);
    let settings = Settings::default();
    let got = field(&ctx, &sphere, &grid, settings);
    let c = compare(&sphere, &grid, settings, &got);
    println!("open sphere: {} wrong signs at {:?}", c.wrong_sign.len(), c.wrong_sign);
    assert!(c.max_error <= MAX_ERROR, "{c:?}");
    // Every centre the rule signs otherwise than the winding number lies within a voxel and a
    // half of the hole's rim plane (z = 8 + 4.8 = 12.8, centres at 11.5 to 13.5).
    for v in &c.wrong_sign {
        assert!((v[2] as f64 + 0.5 - 12.8).abs() <= 1.5, "{v:?} is far from the hole");
    }
    // Measured on llvmpipe: 2 of 4 096 centres, both at the rim's height.
    assert!(c.wrong_sign.len() <= 8, "{} wrong signs", c.wrong_sign.len());
    // Deep inside and far outside the sign holds.
    let at = |v: [u32; 3]| got[((v[2] * 16 + v[1]) * 16 + v[0]) as usize];
    assert!(at([8, 8, 8]) < 0.0 && at([8, 8, 5]) < 0.0);
    assert!(at([0, 0, 0]) > 0.0 && at([8, 8, 15]) > 0.0);
}

#[test]
fn bad_input_is_a_typed_error() {
    let ctx = Context::shared();
    let sdf = MeshSdf::new(&ctx.device).unwrap();
    let sphere = Mesh::uv_sphere(DVec3::splat(4.0), 2.0, 8, 4);
    let grid = Grid::new([8, 8, 8]);
    let run = |mesh: &Mesh, grid: &Grid, settings: Settings| {
        let mut enc = ctx.encoder("bad");
        sdf.encode(&ctx.device, &mut enc, mesh, grid, &settings)
            .map(|_| ())
    };
    let invalid = |r: Result<(), Error>, says: &str| match r {
        Err(Error::Invalid { what, .. }) => assert!(what.contains(says), "{what}"),
        other => panic!("expected Invalid saying {says:?}, got {other:?}"),
    };
    let empty = Mesh::default();
    assert!(matches!(
        run(&empty, &grid, Settings::default()),
        Err(Error::Size { what: "number of triangles", .. })
    ));
    let mut nan = sphere.clone();
    nan.positions[3].y = f64::NAN;
    invalid(run(&nan, &grid, Settings::default()), "vertex 3 is not finite");
    let mut flat = sphere.clone();
    // Every vertex on one line: no triangle has area.
    flat.positions.iter_mut().for_each(|p| *p = DVec3::splat(p.x));
    invalid(run(&flat, &grid, Settings::default()), "has no area");
    let mut out_of_range = sphere.clone();
    out_of_range.triangles[0][1] = 9999;
    invalid(run(&out_of_range, &grid, Settings::default()), "names vertex 9999");
    for band in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        invalid(run(&sphere, &grid, Settings { band, signed: true }), "band");
    }
    assert!(matches!(
        run(&sphere, &Grid::new([5000, 4, 4]), Settings::default()),
        Err(Error::Size { .. })
    ));
    let nan_grid = Grid {
        voxel: f64::NAN,
        ..grid
    };
    invalid(run(&sphere, &nan_grid, Settings::default()), "voxel edge");
    // Degenerate triangles among good ones are left out and counted.
    let mut some_flat = sphere.clone();
    some_flat.triangles.push([0, 0, 1]);
    let mut enc = ctx.encoder("degenerate");
    let f = sdf
        .encode(&ctx.device, &mut enc, &some_flat, &grid, &Settings::default())
        .unwrap();
    assert_eq!(f.degenerate, 1);
}
