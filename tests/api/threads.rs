//! Threads: every technique's pipeline object is `Send + Sync` (wgpu's objects are on native),
//! so one instance can be shared by an application's recording threads; the same technique
//! encoded from several threads into separate encoders gives the same results, bit for bit.

use std::sync::Arc;

use fieldkit::distance::{
    Distance2d, Distance3d, Jfa2d, Settings2d, Settings3d, upload_mask, upload_volume,
};
use fieldkit::gpu::{Context, read_texture};
use fieldkit::metaball::{Cubes, Raymarcher};
use fieldkit::metaball::{Metaballs, Settings, packed_grid};
use fieldkit::ocean::OceanRenderer;
use fieldkit::ocean::{SharedWaves, WaveGrid};
use fieldkit::volume::VolumeRenderer;
use fieldkit::voxelize::VoxelView;
use fieldkit::voxelize::{Grid, Mesh, Voxelizer};
use glam::DVec3;

fn assert_send_sync<T: Send + Sync>() {}
fn assert_send<T: Send>() {}

#[test]
fn pipeline_objects_are_send_and_sync() {
    assert_send_sync::<Distance2d>();
    assert_send_sync::<Jfa2d>();
    assert_send_sync::<Distance3d>();
    assert_send_sync::<Metaballs>();
    assert_send_sync::<Raymarcher>();
    assert_send_sync::<Cubes>();
    assert_send_sync::<VolumeRenderer>();
    assert_send_sync::<OceanRenderer>();
    assert_send_sync::<WaveGrid>();
    assert_send_sync::<SharedWaves>();
    assert_send_sync::<Voxelizer>();
    assert_send_sync::<fieldkit::mesh_sdf::MeshSdf>();
    assert_send_sync::<VoxelView>();
    assert_send_sync::<Context>();
    // What a bake recorded on a worker thread hands back to the frame's thread.
    assert_send::<fieldkit::mesh_sdf::MeshField>();
    assert_send::<fieldkit::voxelize::PendingAttributes>();
    assert_send::<fieldkit::voxelize::Surface>();
    assert_send::<fieldkit::gpu::Readback<Vec<f32>>>();
}

const THREADS: usize = 4;

/// Run `work` on [`THREADS`] threads at once, each with its own encoder, and return what each
/// read back.
fn on_threads<T: Send + 'static>(
    ctx: &Context,
    work: impl Fn(&Context) -> T + Send + Sync + 'static,
) -> Vec<T> {
    let work = Arc::new(work);
    let barrier = Arc::new(std::sync::Barrier::new(THREADS));
    let handles: Vec<_> = (0..THREADS)
        .map(|_| {
            let (ctx, work, barrier) = (ctx.clone(), work.clone(), barrier.clone());
            std::thread::spawn(move || {
                barrier.wait();
                work(&ctx)
            })
        })
        .collect();
    handles
        .into_iter()
        .map(|h| h.join().expect("a recording thread panicked"))
        .collect()
}

#[test]
fn the_same_technique_from_several_threads_gives_the_same_results() {
    let ctx = Context::shared();

    // Exact 3D distance: one shared Distance3d, one encoder per thread.
    let d3 = Arc::new(Distance3d::new(&ctx.device).unwrap());
    let n = 20u32;
    let mask: Vec<u8> = (0..n * n * n)
        .map(|i| u8::from(i % 97 == 0 || i % 131 == 5))
        .collect();
    let volume = Arc::new(upload_volume(&ctx.device, &ctx.queue, &mask, [n; 3]).unwrap());
    let fields = on_threads(&ctx, {
        let (d3, volume) = (d3.clone(), volume.clone());
        move |ctx| {
            let mut enc = ctx.encoder("thread distance");
            let f = d3
                .encode(&ctx.device, &mut enc, &volume, &Settings3d::default())
                .unwrap();
            ctx.submit_and_wait("thread distance", enc).unwrap();
            f.nearest.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()
        }
    });
    assert!(
        fields.iter().all(|f| f == &fields[0]),
        "3D nearest seeds differ"
    );

    // 2D distance, exact and JFA.
    let d2 = Arc::new(Distance2d::new(&ctx.device).unwrap());
    let m2: Vec<u8> = (0..64 * 48).map(|i| u8::from(i % 53 == 0) * 255).collect();
    let mask2 = Arc::new(upload_mask(&ctx.device, &ctx.queue, &m2, 64, 48).unwrap());
    for options in [
        Settings2d::default(),
        Settings2d {
            method: fieldkit::distance::Method2d::Jfa(fieldkit::distance::Variant::JfaPlus2),
            ..Settings2d::default()
        },
    ] {
        let out = on_threads(&ctx, {
            let (d2, mask2) = (d2.clone(), mask2.clone());
            move |ctx| {
                let mut enc = ctx.encoder("thread 2d");
                let f = d2.encode(&ctx.device, &mut enc, &mask2, &options).unwrap();
                ctx.submit_and_wait("thread 2d", enc).unwrap();
                read_texture::<f32>(ctx, &f.distance).unwrap()
            }
        });
        let bits = |v: &Vec<f32>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(
            out.iter().all(|f| bits(f) == bits(&out[0])),
            "2D distances differ between threads"
        );
    }

    // Metaballs: one shared Metaballs, its own instances per thread.
    let balls = Arc::new(Metaballs::new(&ctx.device).unwrap());
    let voxels = packed_grid([3, 2, 2], 1.0).unwrap();
    let out = on_threads(&ctx, {
        let balls = balls.clone();
        move |ctx| {
            let s = Settings::default();
            let inst = balls.upload(&ctx.device, &ctx.queue, &voxels).unwrap();
            let grid = s.fit_grid(&voxels, 1.0).unwrap().unwrap();
            let mut enc = ctx.encoder("thread metaballs");
            let f = balls
                .encode(&ctx.device, &mut enc, &inst, &grid, 1.0, &s)
                .unwrap();
            ctx.submit_and_wait("thread metaballs", enc).unwrap();
            read_texture::<f32>(ctx, &f.sdf)
                .unwrap()
                .iter()
                .map(|x| x.to_bits())
                .collect::<Vec<_>>()
        }
    });
    assert!(out.iter().all(|f| f == &out[0]), "metaball SDFs differ");

    // Voxelizer: one shared Voxelizer.
    let vox = Arc::new(Voxelizer::new(&ctx.device).unwrap());
    let out = on_threads(&ctx, {
        let vox = vox.clone();
        move |ctx| {
            let mesh = Mesh::torus(DVec3::ZERO, 1.0, 0.35, 24, 12);
            let grid = Grid::fit(&mesh, 20).unwrap();
            let mut enc = ctx.encoder("thread voxelize");
            let s = vox
                .encode_surface(&ctx.device, &mut enc, &mesh, &grid)
                .unwrap();
            ctx.submit_and_wait("thread voxelize", enc).unwrap();
            s.read(&ctx.device, &ctx.queue).wait(ctx).unwrap()
        }
    });
    assert!(out.iter().all(|f| f == &out[0]), "surface voxels differ");
    assert!(out[0].iter().any(|&b| b), "the torus has surface voxels");
}
