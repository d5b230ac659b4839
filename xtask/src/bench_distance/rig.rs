//! What `bench distance` runs on: the device (with `--workgroup-storage` where asked), the
//! heater, and one `Distance3d` per way of running the exact transform, so that every way is
//! timed in the same command.

use fieldkit::distance::{
    ColumnPasses, Distance3d, Jfa2d, Method, Settings3d, Variant, tile_columns, tile_columns_3d,
};
use fieldkit::gpu::Context;

use super::{GLOBAL, ROWS_PASS, UNSWEPT, WORKGROUP, label3};
use crate::heater::Heater;
use crate::measure::{Args, Timing, time_runs};

pub(super) struct Rig<'a> {
    pub(super) args: &'a Args,
    pub(super) ctx: Context,
    /// The adapter as the tables name it.
    pub(super) adapter: String,
    /// Clocks held up as the volume and voxelize benches hold them: a 20 ms spin before every
    /// run (outside the timestamps), on hardware adapters.
    pub(super) heater: Option<Heater>,
    /// The transform as a user gets it (with the bench's knobs from `args`).
    pub(super) d3: Distance3d,
    /// With the column passes in global memory.
    pub(super) global: Distance3d,
    /// With the column passes in workgroup memory wherever a tile fits.
    pub(super) workgroup: Distance3d,
    /// With the 3D row pass as a pass of its own.
    pub(super) rows: Distance3d,
    /// Without the resolving global z pass's sweep.
    pub(super) unswept: Distance3d,
    pub(super) jfa2: Jfa2d,
    /// The device's workgroup memory, bytes.
    pub(super) storage: u32,
}

impl<'a> Rig<'a> {
    pub(super) fn open(args: &'a Args) -> Result<Self, String> {
        let ctx = context(args)?;
        let info = ctx
            .adapter
            .as_ref()
            .expect("Context::new opens an adapter")
            .get_info();
        let adapter = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
        println!("adapter: {adapter}");
        let new = || Distance3d::new(&ctx.device).map_err(|e| e.to_string());
        let mut d3 = new()?;
        d3.set_column_bands(args.column_bands)
            .map_err(|e| e.to_string())?;
        d3.set_split_columns(args.split_columns)
            .map_err(|e| e.to_string())?;
        d3.set_split_bytes(args.split_bytes);
        let mut global = new()?;
        global.set_column_passes(ColumnPasses::Global);
        global
            .set_column_bands(args.column_bands)
            .map_err(|e| e.to_string())?;
        let mut workgroup = new()?;
        workgroup.set_column_passes(ColumnPasses::Workgroup);
        let mut rows = new()?;
        rows.set_fold_rows(false);
        let mut unswept = new()?;
        unswept.set_sweep(false);
        unswept
            .set_column_bands(args.column_bands)
            .map_err(|e| e.to_string())?;
        let heater = if ctx.is_software() {
            None
        } else {
            Some(Heater::new(&ctx, 20.0)?)
        };
        Ok(Self {
            args,
            adapter,
            heater,
            d3,
            global,
            workgroup,
            rows,
            unswept,
            jfa2: Jfa2d::new(&ctx.device).map_err(|e| e.to_string())?,
            storage: ctx.device.limits().max_compute_workgroup_storage_size,
            ctx,
        })
    }

    /// `record`'s runs timed with the sweep's warm-up, repetitions and heater.
    pub(super) fn time(
        &self,
        record: impl FnMut(&mut wgpu::CommandEncoder, &mut fieldkit::gpu::Profiler),
    ) -> Result<Timing, String> {
        time_runs(
            &self.ctx,
            self.args.warmup,
            self.args.reps,
            self.heater.as_ref(),
            record,
        )
    }

    /// The transform a 3D method's row is timed with.
    pub(super) fn transform(&self, method: &str) -> &Distance3d {
        match method {
            GLOBAL => &self.global,
            WORKGROUP => &self.workgroup,
            ROWS_PASS => &self.rows,
            UNSWEPT => &self.unswept,
            _ => &self.d3,
        }
    }

    /// What Auto takes per pass: 3D y up to `AUTO_TILE_MAX_LENGTH_Y`, 3D z and 2D by
    /// `tile_columns`.
    pub(super) fn print_paths(&self, sizes3: &[[usize; 3]], sizes2: &[usize]) {
        let path = |c: Option<u32>| c.map_or("global".to_string(), |c| format!("{c} columns"));
        let storage = self.storage;
        println!(
            "workgroup memory: {storage} bytes; column passes by length: {}",
            sizes3
                .iter()
                .map(|&size| {
                    let edge = size.map(|s| s as u32);
                    let y_path = tile_columns_3d(storage, edge, 1);
                    let z_path = tile_columns_3d(storage, edge, 2);
                    format!("{} y {}, z {}", label3(size), path(y_path), path(z_path))
                })
                .chain(
                    sizes2
                        .iter()
                        .map(|&n| format!("{n}² {}", path(tile_columns(storage, n as u32, 2))))
                )
                .collect::<Vec<_>>()
                .join("; ")
        );
    }
}

/// The device: the default one, or one asking for `--workgroup-storage` bytes of workgroup
/// memory.
fn context(args: &Args) -> Result<Context, String> {
    let mut ctx = Context::new().map_err(|e| e.to_string())?;
    if let Some(bytes) = args.workgroup_storage {
        let adapter = ctx.adapter.take().expect("Context::new opens an adapter");
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("bench distance"),
            required_features: ctx.device.features(),
            required_limits: wgpu::Limits {
                max_compute_workgroup_storage_size: bytes,
                ..adapter.limits()
            },
            ..Default::default()
        }))
        .map_err(|e| format!("--workgroup-storage {bytes}: {e}"))?;
        ctx = Context::from_device(device, queue);
        ctx.adapter = Some(adapter);
    }
    Ok(ctx)
}

/// The 3D methods in the order the tables list them: the exact transform's ways and its
/// signed field (only these with `--exact-only`), then JFA's variants and the banded JFA+2.
pub(super) fn methods3(args: &Args) -> Vec<(String, Settings3d)> {
    let exact = [EXACT, GLOBAL, WORKGROUP, ROWS_PASS, UNSWEPT]
        .into_iter()
        .map(|name| (name.to_string(), Settings3d::default()))
        .chain(std::iter::once((
            EXACT_SIGNED.to_string(),
            Settings3d::signed(),
        )));
    let jfa = Variant::ALL.into_iter().map(|v| {
        (
            v.name().to_string(),
            Settings3d {
                method: Method::Jfa(v),
                ..Settings3d::default()
            },
        )
    });
    let banded = (
        format!("JFA+2 band {}", args.band),
        Settings3d {
            method: Method::Jfa(Variant::JfaPlus2),
            band: Some(args.band),
            ..Settings3d::default()
        },
    );
    exact
        .chain(jfa)
        .chain(std::iter::once(banded))
        .take(if args.exact_only { 6 } else { usize::MAX })
        .collect()
}

/// The exact transform as a user gets it.
pub(super) const EXACT: &str = "exact";
/// The same, signed: a transform of the inside seeds and one of the outside seeds, the second
/// resolving against the first.
pub(super) const EXACT_SIGNED: &str = "exact signed";
