//! The 2D rows of `bench distance`: the exact transform (as a user gets it and with its column
//! passes in global memory) against the peer or the CPU, and JFA's variants against it.

use fieldkit::distance::{Distance3d, JfaSettings2d, Settings3d, Variant, cpu, upload_mask};
use fieldkit::gpu::read_texture;

use super::rig::{EXACT, Rig};
use super::{GLOBAL, Peer, Row, d2_of, errors, mask2, pass_bytes, words};

impl Rig<'_> {
    pub(super) fn bench_2d(
        &self,
        n: usize,
        variants: &[Variant],
        peer: Option<&Peer>,
        bar: &indicatif::ProgressBar,
        rows: &mut Vec<Row>,
    ) -> Result<(), String> {
        let ctx = &self.ctx;
        let mask = mask2(self.args, n);
        let tex = upload_mask(&ctx.device, &ctx.queue, &mask, n as u32, n as u32)
            .map_err(|e| e.to_string())?;
        bar.set_message(format!("{n}² exact"));
        let reference = match peer {
            Some(p) => p.d2.clone(),
            None => cpu::edt_2d_squared(&mask.iter().map(|&m| m != 0).collect::<Vec<_>>(), n, n),
        };
        let (exact, exact_d2) = self.exact_2d(n, &tex, &self.d3, EXACT, &reference, peer)?;
        rows.push(exact);
        rows.push(
            self.exact_2d(n, &tex, &self.global, GLOBAL, &reference, peer)?
                .0,
        );
        bar.inc(1);
        for &v in variants {
            bar.set_message(format!("{n}² {}", v.name()));
            rows.push(self.jfa_2d(n, &tex, v, &exact_d2)?);
            bar.inc(1);
        }
        Ok(())
    }

    /// The exact transform of the `n`² mask by `d3`, timed, against `reference`; its row and its
    /// squared distances.
    fn exact_2d(
        &self,
        n: usize,
        tex: &wgpu::Texture,
        d3: &Distance3d,
        method: &str,
        reference: &[u64],
        peer: Option<&Peer>,
    ) -> Result<(Row, Vec<u64>), String> {
        let ctx = &self.ctx;
        let opts = Settings3d::default();
        let timing = self.time(|enc, prof| {
            d3.exact()
                .encode_exact_2d(&ctx.device, &mut prof.record(enc), tex, &opts)
                .expect("encode");
        })?;
        let mut enc = ctx.encoder("bench readback");
        let field = d3
            .exact()
            .encode_exact_2d(&ctx.device, &mut enc, tex, &opts)
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let d2 = d2_of(&words(ctx, &field.nearest)?, [n, n, 1], 2);
        let (wrong, max_err, mean_err) = errors(&d2, reference, None);
        let row = row_2d(
            n,
            method,
            timing,
            (wrong, max_err, mean_err),
            peer.map(|p| p.ms),
        );
        Ok((row, d2))
    }

    /// JFA variant `v` of the `n`² mask, timed, against the exact transform's `exact_d2`.
    fn jfa_2d(
        &self,
        n: usize,
        tex: &wgpu::Texture,
        v: Variant,
        exact_d2: &[u64],
    ) -> Result<Row, String> {
        let (ctx, jfa2) = (&self.ctx, &self.jfa2);
        let opts = JfaSettings2d {
            variant: v,
            ..JfaSettings2d::default()
        };
        let timing = self.time(|enc, prof| {
            jfa2.encode(&ctx.device, &mut prof.record(enc), tex, &opts)
                .expect("encode");
        })?;
        let mut enc = ctx.encoder("bench readback");
        let field = jfa2
            .encode(&ctx.device, &mut enc, tex, &opts)
            .map_err(|e| e.to_string())?;
        ctx.submit_and_wait("bench", enc)
            .map_err(|e| e.to_string())?;
        let nearest: Vec<u32> = read_texture(ctx, &field.nearest).map_err(|e| e.to_string())?;
        let errs = errors(&d2_of(&nearest, [n, n, 1], 2), exact_d2, None);
        Ok(row_2d(n, v.name(), timing, errs, None))
    }
}

/// A 2D row from its timing and its errors.
fn row_2d(
    n: usize,
    method: &str,
    (median_ms, min_ms, max_ms, passes): crate::measure::Timing,
    (wrong, max_err, mean_err): (u64, f64, f64),
    peer_ms: Option<f64>,
) -> Row {
    let cells = (n * n) as u64;
    Row {
        dims: 2,
        size: format!("{n}²"),
        voxels: cells,
        method: method.into(),
        median_ms,
        min_ms,
        max_ms,
        wrong,
        max_err,
        mean_err,
        peer_ms,
        passes: passes
            .into_iter()
            .map(|(p, ms)| {
                let b = pass_bytes(&p, cells, 2);
                (p, ms, b)
            })
            .collect(),
    }
}
