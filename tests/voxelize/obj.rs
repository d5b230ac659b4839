//! OBJ input (`Mesh::from_obj`, through tobj): quads triangulated, groups welded back into one
//! closed mesh, vertex colours and per-corner normals read, bad files refused with typed errors;
//! and midpoint subdivision.

use fieldkit::Error;
use fieldkit::voxelize::Mesh;
use glam::DVec3;

/// A unit cube in two groups (so tobj gives two models with their own copies of the shared
/// vertices), quads, vertex colours, and one normal per face given per corner.
const CUBE: &str = "\
v 0 0 0 1 0 0
v 1 0 0 0 1 0
v 0 1 0 0 0 1
v 1 1 0 1 1 0
v 0 0 1 0 1 1
v 1 0 1 1 0 1
v 0 1 1 0.5 0.5 0.5
v 1 1 1 1 1 1
vn -1 0 0
vn 1 0 0
vn 0 -1 0
vn 0 1 0
vn 0 0 -1
vn 0 0 1
g sides
f 1//1 5//1 7//1 3//1
f 2//2 4//2 8//2 6//2
f 1//3 2//3 6//3 5//3
f 3//4 7//4 8//4 4//4
g caps
f 1//5 3//5 4//5 2//5
f 5//6 6//6 8//6 7//6
";

#[test]
fn a_grouped_quad_cube_comes_back_closed_with_its_attributes() {
    let mesh = Mesh::from_obj(&mut CUBE.as_bytes()).unwrap();
    assert_eq!(
        mesh.positions.len(),
        8,
        "groups' shared vertices are welded"
    );
    assert_eq!(mesh.triangles.len(), 12);
    assert_eq!(mesh.open_edge(), None);
    assert!(
        (mesh.volume() - 1.0).abs() < 1e-12,
        "volume {}",
        mesh.volume()
    );
    // Every vertex keeps its colour, converted to 8 bits.
    for (p, c) in mesh.positions.iter().zip(&mesh.colors) {
        let want = if *p == DVec3::new(0.0, 1.0, 1.0) {
            [128, 128, 128, 255]
        } else {
            let i = (p.x + 2.0 * p.y + 4.0 * p.z) as usize;
            let rgb = [
                [255, 0, 0],
                [0, 255, 0],
                [0, 0, 255],
                [255, 255, 0],
                [0, 255, 255],
                [255, 0, 255],
                [0; 3],
                [255; 3],
            ][i];
            [rgb[0], rgb[1], rgb[2], 255]
        };
        assert_eq!(*c, want, "colour of {p}");
    }
    // Each corner touches three faces: the normals given per corner sum to the diagonal.
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        let want = (*p * 2.0 - 1.0).normalize();
        assert!(n.normalize().distance(want) < 1e-12, "normal {n} at {p}");
    }
}

#[test]
fn bad_obj_input_gets_typed_errors() {
    let err = Mesh::from_obj(&mut "v 0 0 0\nv 1 0 0\nf 1 2 9\n".as_bytes()).unwrap_err();
    assert!(
        matches!(&err, Error::Invalid { what, .. } if what.starts_with("OBJ")),
        "{err}"
    );
    let err = Mesh::load_obj("/nonexistent/bunny.obj").unwrap_err();
    assert!(
        matches!(&err, Error::Invalid { what, .. } if what.contains("/nonexistent/bunny.obj")),
        "{err}"
    );
    // An OBJ with no faces is an empty mesh, which voxelization refuses by name.
    let empty = Mesh::from_obj(&mut "v 0 0 0\n".as_bytes()).unwrap();
    assert!(empty.triangles.is_empty());
}

/// Midpoint subdivision (how the bench turns the npm bunny's 3.7 k triangles into 59 k): the
/// same surface, four times the triangles per step, still closed, the same volume.
#[test]
fn subdivision_keeps_the_surface_closed_and_its_volume() {
    let mut sphere = Mesh::uv_sphere(DVec3::new(0.3, -0.2, 0.1), 1.5, 16, 9);
    sphere.colors = vec![[10, 200, 31, 255]; sphere.positions.len()];
    let twice = sphere.subdivided().subdivided();
    assert_eq!(twice.triangles.len(), sphere.triangles.len() * 16);
    assert_eq!(twice.open_edge(), None);
    assert_eq!(twice.colors.len(), twice.positions.len());
    assert!(twice.colors.iter().all(|&c| c == [10, 200, 31, 255]));
    let (a, b) = (sphere.volume(), twice.volume());
    assert!((a - b).abs() < 1e-12 * a, "volume {a} became {b}");
    // Euler: a closed genus-0 mesh keeps V − E + F = 2.
    let edges = twice.triangles.len() * 3 / 2;
    assert_eq!(
        twice.positions.len() as i64 - edges as i64 + twice.triangles.len() as i64,
        2
    );
}

/// The npm `bunny` layout (`exports.positions=[[x,y,z],…]; exports.cells=[[a,b,c],…]`), which
/// the gallery and the bench read.
#[test]
fn positions_and_cells_text_is_read_and_checked() {
    let js = "exports.positions=[[0,0,0],[1,0,0],[0,1,0],[0,0,1.5e0]];\nexports.cells=[[0,2,1],[0,1,3],[0,3,2],[1,2,3]];\n";
    let mesh = Mesh::from_positions_cells(js).unwrap();
    assert_eq!(mesh.positions[3], DVec3::new(0.0, 0.0, 1.5));
    assert_eq!(mesh.triangles[3], [1, 2, 3]);
    assert_eq!(mesh.open_edge(), None);
    assert!((mesh.volume() - 0.25).abs() < 1e-12, "{}", mesh.volume());
    for (bad, says) in [
        (
            "exports.positions=[[0,0],[1,0,0]];exports.cells=[[0,1,1]];",
            "threes",
        ),
        (
            "exports.positions=[[0,0,0]];exports.cells=[[0,-1,0]];",
            "not a vertex index",
        ),
        ("exports.positions=[[0,0,0]];", "cells"),
        (
            "exports.positions=[[0,0,x]];exports.cells=[[0,0,0]];",
            "\"x\"",
        ),
    ] {
        let err = Mesh::from_positions_cells(bad).unwrap_err();
        assert!(
            matches!(&err, fieldkit::Error::Invalid { what, .. } if what.contains(says)),
            "{bad}: {err}"
        );
    }
}
