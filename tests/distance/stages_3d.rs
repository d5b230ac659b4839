//! Per-stage snapshots of the 3D distance stages: each run alone through the harness, checked
//! against its CPU model and summarised for insta.

use crate::common;

use common::*;
use fieldkit::distance::cpu;
use fieldkit::distance::{
    ColumnPasses, Distance3d, Grid, Inside, Marks, Settings3d, key_index, upload_points,
    upload_volume,
};
use fieldkit::gpu::{Context, read_buffer, read_texture};
use fieldkit::harness::Summary;
use glam::Vec3;

const SIZE: [usize; 3] = [20, 13, 9];
const SHAPE: [usize; 3] = [9, 13, 20];

fn mask() -> Vec<bool> {
    random_mask_3d(SIZE, 0.02, 77)
}

fn words(ctx: &Context, b: &wgpu::Buffer) -> Vec<u32> {
    bytemuck::cast_slice(&read_buffer(ctx, b).unwrap()).to_vec()
}

fn d2s(nearest: &[u32]) -> Vec<u32> {
    (0..nearest.len())
        .map(|i| cpu::seed_d2_3(nearest[i], i, SIZE).map_or(u32::MAX, |d| d as u32))
        .collect()
}

/// The marks of a mask volume's marked voxels (the outside ones: `Inside::Mask`, unsigned).
fn marks(volume: &wgpu::Texture) -> Marks<'_> {
    Marks::new(volume, Inside::Mask, false)
}

/// Storage scratch of `like`'s size (a column pass's envelope stack).
fn scratch_like(ctx: &Context, like: &wgpu::Buffer) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: like.size(),
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    })
}

/// After a y pass every voxel of `m` (a grid of `size`) names its nearest seed within its own
/// z slice: the CPU's 2D transform of each slice, voxel for voxel.
fn assert_y_pass(m: &[bool], after_y: &[u32], size: [usize; 3], what: &str) {
    let [w, h, d] = size;
    for z in 0..d {
        let exact = cpu::edt_2d_squared(&m[z * w * h..(z + 1) * w * h], w, h);
        for (j, &want) in exact.iter().enumerate() {
            let i = z * w * h + j;
            let got = cpu::seed_d2_3(after_y[i], i, size).unwrap_or(cpu::NONE);
            assert_eq!(got, want, "{what}, slice {z}, texel {j}");
        }
    }
}

fn setup() -> (Context, Distance3d, Vec<bool>, wgpu::Texture) {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let m = mask();
    let volume = upload_volume(&ctx.device, &ctx.queue, &to_bytes(&m), size_u32(SIZE)).unwrap();
    (ctx, d3, m, volume)
}

#[test]
fn seed_stage() {
    let (ctx, d3, m, volume) = setup();
    let mut enc = ctx.encoder("seed");
    let out = d3
        .jfa()
        .encode_seed(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    ctx.submit_and_wait("seed", enc).unwrap();
    let nearest = words(&ctx, &out);
    assert_eq!(
        nearest,
        cpu::jfa_3d(&m, SIZE, &[]),
        "seed stage = CPU model with no passes"
    );
    insta::assert_snapshot!(Summary::ints(&SHAPE, &nearest).to_string());
}

#[test]
fn one_jump_pass() {
    let (ctx, d3, m, volume) = setup();
    let mut enc = ctx.encoder("jump");
    let seeds = d3
        .jfa()
        .encode_seed(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    let out = d3
        .jfa()
        .encode_flood(&ctx.device, &mut enc, seeds, size_u32(SIZE), &[4], None)
        .unwrap();
    ctx.submit_and_wait("jump", enc).unwrap();
    let nearest = words(&ctx, &out);
    assert_eq!(nearest, cpu::jfa_3d(&m, SIZE, &[4]));
    insta::assert_snapshot!(Summary::ints(&SHAPE, &nearest).to_string());
}

#[test]
fn exact_rows_then_columns() {
    let (ctx, d3, m, volume) = setup();
    let [w, h, _] = SIZE;
    let mut enc = ctx.encoder("rows");
    let nearest = d3
        .exact()
        .encode_rows(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    ctx.submit_and_wait("rows", enc).unwrap();
    let rows = words(&ctx, &nearest);
    // CPU model of the row pass: nearest marked x in the row, the left one on a tie.
    for (i, &got) in rows.iter().enumerate() {
        let (x, row) = (i % w, i - i % w);
        let best = (0..w)
            .filter(|&s| m[row + s])
            .min_by_key(|&s| (s.abs_diff(x), s));
        let want = best.map_or(0, |s| cpu::pack_seed3(s, (i / w) % h, i / (w * h)));
        assert_eq!(got, want, "row pass, voxel {i}");
    }
    let stack = scratch_like(&ctx, &nearest);
    let mut enc = ctx.encoder("columns y");
    d3.exact()
        .encode_column_pass(&ctx.device, &mut enc, &nearest, &stack, size_u32(SIZE), 1)
        .unwrap();
    ctx.submit_and_wait("columns y", enc).unwrap();
    let after_y = words(&ctx, &nearest);
    assert_y_pass(&m, &after_y, SIZE, "y pass");
    let mut enc = ctx.encoder("columns z");
    d3.exact()
        .encode_column_pass(&ctx.device, &mut enc, &nearest, &stack, size_u32(SIZE), 2)
        .unwrap();
    ctx.submit_and_wait("columns z", enc).unwrap();
    let after_z = words(&ctx, &nearest);
    let exact: Vec<u32> = cpu::edt_3d_squared(&m, SIZE)
        .iter()
        .map(|&v| v as u32)
        .collect();
    assert_eq!(d2s(&after_z), exact);
    fieldkit::assert_summary!(
        "exact_rows_then_columns",
        Summary::ints(&SHAPE, &rows)
            .and("after y", Summary::ints(&SHAPE, &after_y))
            .and("after z", Summary::ints(&SHAPE, &after_z))
            .to_string()
    );
}

/// The row pass as words, then the y pass reading them: the words against a CPU model (bits,
/// nearest marks before and after), the y pass against the 2D transform of every slice and
/// against the row pass followed by the y pass (the same ties, so the same seeds); with the y
/// pass in workgroup memory (as `Auto` takes it at this length) and in global memory.
#[test]
fn exact_row_words_then_y() {
    for passes in [ColumnPasses::Auto, ColumnPasses::Global] {
        row_words_then_y(passes);
    }
}

fn row_words_then_y(passes: ColumnPasses) {
    // Rows of 70 voxels: three words, the last one partial.
    let size = [70usize, 13, 5];
    let [w, h, d] = size;
    let ctx = Context::shared();
    let mut d3 = Distance3d::new(&ctx.device).unwrap();
    d3.set_column_passes(passes);
    let m = random_mask_3d(size, 0.03, 5);
    let volume = upload_volume(&ctx.device, &ctx.queue, &to_bytes(&m), size_u32(size)).unwrap();
    let mut enc = ctx.encoder("row words");
    let row_words = d3
        .exact()
        .encode_row_words(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    let nearest = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: (w * h * d * 4) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    d3.exact()
        .encode_columns_from_words(&ctx.device, &mut enc, &row_words, &nearest, size_u32(size))
        .unwrap();
    ctx.submit_and_wait("row words", enc).unwrap();
    let got = words(&ctx, &row_words);
    let count = w.div_ceil(32);
    assert_eq!(got.len(), count * h * d * 2);
    for row in 0..h * d {
        let marks: Vec<usize> = (0..w).filter(|&x| m[row * w + x]).collect();
        for k in 0..count {
            let bits = marks
                .iter()
                .filter(|&&x| x / 32 == k)
                .fold(0u32, |b, &x| b | 1 << (x % 32));
            let before = marks
                .iter()
                .rev()
                .find(|&&x| x < 32 * k)
                .map_or(0, |&x| x + 1);
            let after = marks
                .iter()
                .find(|&&x| x >= 32 * (k + 1))
                .map_or(0, |&x| x + 1);
            let at = 2 * (row * count + k);
            assert_eq!(got[at], bits, "row {row}, word {k}: marks");
            assert_eq!(
                got[at + 1],
                (before | after << 16) as u32,
                "row {row}, word {k}: marks before and after"
            );
        }
    }
    let after_y = words(&ctx, &nearest);
    assert_y_pass(
        &m,
        &after_y,
        size,
        &format!("{passes:?}: y pass from words"),
    );
    let mut enc = ctx.encoder("rows, columns y");
    let by_rows = d3
        .exact()
        .encode_rows(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    let stack = scratch_like(&ctx, &by_rows);
    d3.exact()
        .encode_column_pass(&ctx.device, &mut enc, &by_rows, &stack, size_u32(size), 1)
        .unwrap();
    ctx.submit_and_wait("rows, columns y", enc).unwrap();
    assert_eq!(
        after_y,
        words(&ctx, &by_rows),
        "{passes:?}: the same seeds as rows, then y"
    );
}

#[test]
fn resolve_stage() {
    let (ctx, d3, m, volume) = setup();
    let mut enc = ctx.encoder("resolve");
    let inside = d3
        .exact()
        .encode(&ctx.device, &mut enc, marks(&volume))
        .unwrap();
    let outside = d3
        .exact()
        .encode(
            &ctx.device,
            &mut enc,
            Marks::new(&volume, Inside::Mask, true),
        )
        .unwrap();
    let (inside, outside) = (
        inside.whole().expect("one buffer"),
        outside.whole().expect("one buffer"),
    );
    let opts = Settings3d {
        voxel_size: 0.5,
        ..Settings3d::default()
    };
    let unsigned = d3
        .encode_resolve(&ctx.device, &mut enc, size_u32(SIZE), inside, None, &opts)
        .unwrap();
    let signed = d3
        .encode_resolve(
            &ctx.device,
            &mut enc,
            size_u32(SIZE),
            inside,
            Some(outside),
            &opts,
        )
        .unwrap();
    ctx.submit_and_wait("resolve", enc).unwrap();
    let u: Vec<f32> = read_texture(&ctx, &unsigned).unwrap();
    let s: Vec<f32> = read_texture(&ctx, &signed).unwrap();
    let reference = cpu::signed_3d(&m, SIZE);
    for i in 0..u.len() {
        assert!(
            (s[i] as f64 - 0.5 * reference[i]).abs() < 1e-5,
            "signed voxel {i}"
        );
    }
    // Squared distances are integers: rounding (2d)² recovers them exactly despite sqrt's last bit.
    let d2: Vec<u32> = u.iter().map(|v| (4.0 * v * v).round() as u32).collect();
    let exact: Vec<u32> = cpu::edt_3d_squared(&m, SIZE)
        .iter()
        .map(|&v| v as u32)
        .collect();
    assert_eq!(d2, exact);
    fieldkit::assert_summary!(
        "resolve_stage",
        Summary::floats(&SHAPE, &u, 3)
            .and("signed", Summary::floats(&SHAPE, &s, 3))
            .and("d² rounded", Summary::ints(&SHAPE, &d2))
            .to_string()
    );
}

#[test]
fn seed_points_stage() {
    let ctx = Context::shared();
    let d3 = Distance3d::new(&ctx.device).unwrap();
    let grid = Grid::new(size_u32(SIZE));
    // Two points share voxel (3, 4, 5): the one nearer its centre (index 1) must win.
    let pts = [
        Vec3::new(3.8, 4.9, 5.7),
        Vec3::new(3.6, 4.6, 5.6),
        Vec3::new(12.5, 0.6, 8.9),
        Vec3::new(19.9, 12.9, 0.1),
    ];
    let seeds = upload_points(&ctx.device, &ctx.queue, &grid, &pts).unwrap();
    let mut enc = ctx.encoder("points");
    let opts = Settings3d {
        method: fieldkit::distance::Method::Jfa(fieldkit::distance::Variant::JfaPlus2),
        ..Settings3d::default()
    };
    let field = d3
        .encode_points(&ctx.device, &mut enc, &seeds, size_u32(SIZE), None, &opts)
        .unwrap();
    ctx.submit_and_wait("points", enc).unwrap();
    let nearest = field
        .nearest
        .read(&ctx.device, &ctx.queue)
        .wait(&ctx)
        .unwrap();
    let dist: Vec<f32> = read_texture(&ctx, &field.distance).unwrap();
    let [w, h, _] = SIZE;
    let at = |v: [usize; 3]| (v[2] * h + v[1]) * w + v[0];
    assert_eq!(key_index(nearest[at([3, 4, 5])]), Some(1));
    assert_eq!(key_index(nearest[at([13, 1, 8])]), Some(2));
    assert_eq!(key_index(nearest[at([19, 12, 0])]), Some(3));
    // Seed 0 lost its voxel, so no voxel names it; every distance is to the named point.
    for i in 0..nearest.len() {
        let k = key_index(nearest[i]).unwrap() as usize;
        assert_ne!(k, 0);
        let p = Vec3::new((i % w) as f32, ((i / w) % h) as f32, (i / (w * h)) as f32);
        assert!(
            (dist[i] - grid.to_voxel(pts[k].as_dvec3()).as_vec3().distance(p)).abs() < 1e-4,
            "voxel {i}"
        );
    }
    fieldkit::assert_summary!(
        "seed_points_stage",
        Summary::ints(&SHAPE, &nearest)
            .and("distance", Summary::floats(&SHAPE, &dist, 3))
            .to_string()
    );
}
