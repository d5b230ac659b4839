//! Unit tests of the voxelizer's host-side planning (listing, chunks, giants).

use super::*;

/// Three vertices of a right triangle at height `z` with legs `leg` from (x0, y0).
fn right(x0: f32, y0: f32, leg: f32, z: f32) -> [Vec4; 3] {
    [
        Vec4::new(x0, y0, z, 0.0),
        Vec4::new(x0 + leg, y0, z, 0.0),
        Vec4::new(x0, y0 + leg, z, 0.0),
    ]
}

fn grid_mesh(triangles: &[[Vec4; 3]]) -> GridMesh {
    GridMesh {
        vertices: triangles.concat(),
        degenerate: 0,
        source: (0..triangles.len() as u32).collect(),
    }
}

/// Triangles of more than `MAX_CHUNKS` chunks share `LIST_BUDGET`: while they fit it
/// every heavy triangle keeps chunks of `CHUNK`; past it the heaviest get longer chunks,
/// just enough to fit, that start at every multiple of their length up to their columns;
/// the chunks' columns ride in each heavy triangle's first vertex's w. Smaller triangles
/// neither get longer chunks nor count against the budget.
#[test]
fn the_heaviest_triangles_get_longer_chunks_past_the_budget() {
    let size = [4096, 4096, 2];
    let light = right(0.2, 0.2, 0.5, 0.5); // 1 column
    let heavy = right(0.5, 0.5, 5.0, 0.5); // its box: 6 × 6 = 36 columns
    let list = |triangles: &[[Vec4; 3]]| {
        listed(&grid_mesh(triangles), size, u64::MAX, Listing::default()).unwrap()
    };
    // 512² columns, 65 536 chunks: within the budget.
    let sorted = list(&[light, heavy, right(0.0, 0.0, 511.5, 1.5)]);
    assert_eq!(sorted.runs, [(9, CHUNK), (512 * 512 / 4, CHUNK)]);

    // 4096² and 2048² columns, 2^22 + 2^20 chunks of 4: the largest cap c with
    // min(2^22, c) + min(2^20, c) ≤ 2^20 is 2^19, so chunks of 32 and 8 columns.
    let giant = right(0.0, 0.0, 4096.0, 1.5);
    let sorted = list(&[light, heavy, giant, right(0.0, 0.0, 2047.5, 1.5)]);
    assert_eq!((sorted.light, &sorted.order[..]), (1, &[0, 1, 2, 3][..]));
    assert_eq!(sorted.runs, [(9, CHUNK), (1 << 19, 32), (1 << 19, 8)]);
    assert_eq!(sorted.chunks.len() as u64, 9 + LIST_BUDGET);
    let ws: Vec<f32> = sorted.vertices.iter().map(|p| p.w).collect();
    let mut want_ws = [0.0; 12];
    (want_ws[3], want_ws[6], want_ws[9]) = (4.0, 32.0, 8.0);
    assert_eq!(ws, want_ws);
    for (c, &[t, first]) in sorted.chunks.iter().enumerate() {
        let want = match c {
            0..9 => (1, 4 * c as u32),
            _ if c < 9 + (1 << 19) => (2, 32 * (c - 9) as u32),
            _ => (3, 8 * (c - 9 - (1 << 19)) as u32),
        };
        assert_eq!((t, first), want, "chunk {c}");
    }

    // 70 triangles of 256² columns (16 384 chunks each, 1.15 M in all) and one of 1024²
    // (262 144 chunks, within the budget on its own): every chunk keeps 4 columns.
    let mut many = vec![right(0.0, 0.0, 255.5, 0.5); 70];
    many.push(right(0.0, 0.0, 1023.5, 1.5));
    let sorted = list(&many);
    assert_eq!(sorted.runs.len(), 71);
    assert!(sorted.runs.iter().all(|&(_, columns)| columns == CHUNK));
    assert_eq!(sorted.chunks.len(), 70 * 16_384 + 262_144);
}

/// A triangle whose box misses the grid along one axis has no columns, however large its
/// box is along the other two (a roof above the grid's top layer), so it is listed as light
/// (one thread, which finds nothing) instead of in chunks; one that touches the grid's
/// last layer keeps them.
#[test]
fn triangles_outside_the_grid_list_no_chunks() {
    let size = [4096, 4096, 2];
    let above = right(0.0, 0.0, 4096.0, 2.5);
    let touching = right(0.0, 0.0, 4096.0, 2.0);
    let below = right(0.0, 0.0, 4096.0, -0.001);
    assert_eq!(box_columns(&above, size), 0);
    assert_eq!(box_columns(&below, size), 0);
    assert_eq!(box_columns(&touching, size), 4096 * 4096);
    let sorted = listed(
        &grid_mesh(&[above, touching, below]),
        size,
        u64::MAX,
        Listing::default(),
    )
    .unwrap();
    assert_eq!((sorted.light, &sorted.order[..]), (2, &[0, 2, 1][..]));
    assert_eq!(sorted.runs, [(1 << 20, 16)]);
}

/// More giant triangles than the budget holds at `MAX_CHUNKS` each: each lists exactly
/// that many (chunks of 1024 columns, no longer), and the list's bytes, counted before
/// anything is made, are refused past the limit.
#[test]
fn giant_triangles_list_at_least_max_chunks_each() {
    let size = [4096, 4096, 2];
    let giants: Vec<[Vec4; 3]> = (0..100)
        .map(|k| right(0.0, 0.0, 4096.0, 0.25 + k as f32 * 0.01))
        .collect();
    let mesh = grid_mesh(&giants);
    let sorted = listed(&mesh, size, u64::MAX, Listing::default()).unwrap();
    assert!(sorted.runs.iter().all(|&run| run == (MAX_CHUNKS, 1024)));
    assert_eq!(sorted.chunks.len(), 100 * MAX_CHUNKS as usize);
    let bytes = 100 * MAX_CHUNKS as u64 * 8;
    assert!(listed(&mesh, size, bytes, Listing::default()).is_ok());
    assert!(matches!(
        listed(&mesh, size, bytes - 1, Listing::default()),
        Err(Error::Size { got, .. }) if got == bytes
    ));
}

/// The host's copies of the shader's constants agree with `fieldkit::triangle_box`.
#[test]
fn constants_match_the_shader() {
    let src = include_str!("../../fieldkit-wesl/shaders/triangle_box.wesl");
    for (name, value) in [
        ("LIGHT", super::LIGHT),
        ("CHUNK", super::CHUNK),
        ("MAX_CHUNKS", super::MAX_CHUNKS),
        ("MAX_GIANTS", super::MAX_GIANTS),
        // `GIANT_BYTES`' header.
        ("GIANT_HEADER", 8),
    ] {
        let line = format!("const {name}: u32 = {value}u;");
        assert!(src.contains(&line), "triangle_box.wesl lacks `{line}`");
    }
}
