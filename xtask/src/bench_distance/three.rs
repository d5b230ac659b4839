//! The 3D rows of `bench distance`: every method at one grid, its errors against the exact
//! transform (itself against the peer or the CPU), the CPU cost of recording it, and the
//! column passes' load/store floors.

use fieldkit::distance::{Marks, Method, Settings3d, cpu, tile_columns_3d, upload_volume};

use super::rig::{EXACT, Rig};
use super::{Peer, ROWS_PASS, Row, UNSWEPT, WORKGROUP, d2_of, errors, label3, mask3, pass_bytes};

/// A column pass's floor: the size, the pass's name as the per-pass table has it, its copy's
/// median ms, and for the resolving z pass its copy's with the distance store.
pub(super) type Floor = (String, &'static str, f64, Option<f64>);

/// One 3D grid and what every method's row at it shares.
struct Case<'p> {
    size: [usize; 3],
    label: String,
    cells: u64,
    /// Larger than one storage binding (1024³ is 4 GiB): split across bindings, which only the
    /// exact transform's workgroup-memory passes do, always from the row words: the other exact
    /// rows would time the same passes or none, and JFA refuses the size.
    split: bool,
    mask: Vec<u8>,
    volume: wgpu::Texture,
    peer: Option<&'p Peer>,
}

impl Rig<'_> {
    pub(super) fn bench_3d(
        &self,
        size: [usize; 3],
        methods: &[(String, Settings3d)],
        peer: Option<&Peer>,
        bar: &indicatif::ProgressBar,
        rows: &mut Vec<Row>,
        floors: &mut Vec<Floor>,
    ) -> Result<(), String> {
        let binding = self
            .ctx
            .device
            .limits()
            .max_storage_buffer_binding_size
            .min(self.args.split_bytes.unwrap_or(u64::MAX));
        let cells = size.iter().product::<usize>() as u64;
        let mask = mask3(self.args, size);
        let volume = upload_volume(
            &self.ctx.device,
            &self.ctx.queue,
            &mask,
            size.map(|s| s as u32),
        )
        .map_err(|e| e.to_string())?;
        let case = Case {
            size,
            label: label3(size),
            cells,
            split: cells * 4 > binding,
            mask,
            volume,
            peer,
        };
        let mut exact_d2: Vec<u64> = Vec::new();
        let mut reference: Option<Vec<u64>> = None;
        for (name, opts) in methods {
            bar.set_message(format!("{} {name}", case.label));
            if self.runs_3d(&case, name, opts) {
                let row = self.row_3d(&case, name, opts, &mut reference, &mut exact_d2)?;
                rows.push(row);
            }
            bar.inc(1);
        }
        if !case.split {
            floors.extend(self.floors(&case)?);
        }
        Ok(())
    }

    /// Whether `name` has a row at this grid: JFA takes fields of one binding only, a split
    /// field has no row pass of its own, and the workgroup-memory row is left out where no tile
    /// fits or where it is the path Auto takes anyway (both passes in workgroup memory).
    fn runs_3d(&self, case: &Case, name: &str, opts: &Settings3d) -> bool {
        if case.split && (name == ROWS_PASS || name == UNSWEPT || opts.method != Method::Exact) {
            return false;
        }
        if name == WORKGROUP {
            let probe = self.transform(name).encode(
                &self.ctx.device,
                &mut self.ctx.encoder("probe"),
                &case.volume,
                opts,
            );
            let auto_takes_it = [1, 2].iter().all(|&axis| {
                tile_columns_3d(self.storage, case.size.map(|s| s as u32), axis).is_some()
            });
            return probe.is_ok() && !auto_takes_it;
        }
        true
    }

    /// Time `name`, read its field back and count its errors: the exact rows against the
    /// reference (the peer's distances, or the CPU transform in quick mode), the others against
    /// the exact transform's.
    fn row_3d(
        &self,
        case: &Case,
        name: &str,
        opts: &Settings3d,
        reference: &mut Option<Vec<u64>>,
        exact_d2: &mut Vec<u64>,
    ) -> Result<Row, String> {
        let (ctx, d3) = (&self.ctx, self.transform(name));
        let (med, min, max, passes) = self.time(|enc, prof| {
            d3.encode(&ctx.device, &mut prof.record(enc), &case.volume, opts)
                .expect("encode");
        })?;
        if name == EXACT {
            self.host_times(case, opts)?;
        }
        let mut enc = ctx.encoder("bench readback");
        let field = d3
            .encode(&ctx.device, &mut enc, &case.volume, opts)
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let nearest = field
            .nearest
            .read(&ctx.device, &ctx.queue)
            .wait(ctx)
            .map_err(|e| e.to_string())?;
        let d2 = d2_of(&nearest, case.size, 3);
        let (wrong, max_err, mean_err, peer_ms) = if opts.method == Method::Exact {
            let reference = reference.get_or_insert_with(|| match case.peer {
                Some(p) => p.d2.clone(),
                None => {
                    let mask: Vec<bool> = case.mask.iter().map(|&m| m != 0).collect();
                    cpu::edt_3d_squared(&mask, case.size)
                }
            });
            let (w, mx, mean) = errors(&d2, reference, None);
            if name == EXACT {
                *exact_d2 = d2;
            }
            (w, mx, mean, case.peer.map(|p| p.ms))
        } else {
            let (w, mx, mean) = errors(&d2, exact_d2, opts.band.map(|b| b as f64));
            (w, mx, mean, None)
        };
        // A split field runs a pass once per part or slab: each moves its share.
        let count = |p: &str| passes.iter().filter(|(q, _)| q == p).count() as f64;
        let passes = passes
            .iter()
            .map(|(p, ms)| (p.clone(), *ms, pass_bytes(p, case.cells, 3) / count(p)))
            .collect();
        Ok(Row {
            dims: 3,
            size: case.label.clone(),
            voxels: case.cells,
            method: name.to_string(),
            median_ms: med,
            min_ms: min,
            max_ms: max,
            wrong,
            max_err,
            mean_err,
            peer_ms,
            passes,
        })
    }

    /// What a loop that runs the transform every frame spends on the CPU, with a new field each
    /// time and with each run's field recycled for the next (`Distance3d::recycle`).
    fn host_times(&self, case: &Case, opts: &Settings3d) -> Result<(), String> {
        let (ctx, d3, label) = (&self.ctx, &self.d3, &case.label);
        let (host, lo, hi) = crate::measure::host_times(ctx, self.args.reps, |enc| {
            d3.encode(&ctx.device, enc, &case.volume, opts)
                .map_err(|e| e.to_string())
        })?;
        println!("  host (record + submit) {EXACT} {label}: {host:.3} ms ({lo:.3}–{hi:.3})");
        let last = std::cell::RefCell::new(None);
        let (host, lo, hi) = crate::measure::host_times(ctx, self.args.reps, |enc| {
            if let Some(field) = last.borrow_mut().take() {
                d3.recycle(field);
            }
            let field = d3
                .encode(&ctx.device, enc, &case.volume, opts)
                .map_err(|e| e.to_string())?;
            *last.borrow_mut() = Some(field);
            Ok(())
        })?;
        println!(
            "  host (record + submit) {EXACT} {label}, recycled: {host:.3} ms ({lo:.3}–{hi:.3})"
        );
        Ok(())
    }

    /// The floor of each column pass: its loads and stores alone, without the envelopes (of a
    /// field in one binding): the tile copy where the pass runs in workgroup memory, else the
    /// global copy, which reads the row words as the y pass does. The z pass resolves: its copy
    /// is timed again with the distance store as well.
    fn floors(&self, case: &Case) -> Result<Vec<Floor>, String> {
        let (ctx, d3) = (&self.ctx, &self.d3);
        let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bench copy"),
            size: case.cells * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let mut enc = ctx.encoder("bench row words");
        let inside = Settings3d::default().inside;
        let words = d3
            .exact()
            .encode_row_words(
                &ctx.device,
                &mut enc,
                Marks::new(&case.volume, inside, false),
            )
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench row words", enc)
            .map_err(|e| e.to_string())?;
        let edge = case.size.map(|s| s as u32);
        let distance = fieldkit::gpu::texture(
            &ctx.device,
            "bench copy distance",
            edge,
            wgpu::TextureDimension::D3,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::STORAGE_BINDING,
        );
        let mut floors = Vec::new();
        for axis in [1u32, 2] {
            let mut tile = false;
            let mut copy = |store: Option<&wgpu::Texture>| {
                self.time(|enc, prof| {
                    let rec = &mut prof.record(enc);
                    tile = d3
                        .exact()
                        .encode_tile_copy(&ctx.device, rec, &buffer, edge, axis, store)
                        .expect("encode")
                        .is_some();
                    if !tile {
                        let words = (axis == 1).then_some(&words);
                        d3.exact()
                            .encode_global_copy(&ctx.device, rec, &buffer, words, edge, axis, store)
                            .expect("encode");
                    }
                })
            };
            let timing = copy(None)?;
            let stored = if axis == 2 {
                Some(copy(Some(&distance))?.0)
            } else {
                None
            };
            let tag = match (axis, tile) {
                (1, true) => "columns (y, workgroup)",
                (_, true) => "columns (z, workgroup)",
                (1, false) => "columns (y) from row words",
                (_, false) => "columns (z)",
            };
            floors.push((case.label.clone(), tag, timing.0, stored));
        }
        Ok(floors)
    }
}
