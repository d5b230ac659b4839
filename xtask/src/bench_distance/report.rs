//! `bench distance`'s output: `distance.csv` and `distance_passes.csv`, the printed tables,
//! the chart, and the column passes' load/store floors; `--replot` reads a table back.

use std::io::Write;
use std::path::Path;

use super::three::Floor;
use super::{PEAK_BYTES_PER_S, Row};
use crate::measure::Args;

/// `--replot`: the chart of a written `distance.csv` again, without a device.
pub(super) fn replot(args: &Args, csv: &Path) -> Result<(), String> {
    let (adapter, rows) = read_table(csv)?;
    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;
    let png = args.out.join("distance.png");
    chart(&png, &adapter, &rows, (1000, 640))?;
    println!("wrote {}", png.display());
    Ok(())
}

/// Two floors for the resolving z pass: its copy as the prototype's mode 1 makes it (the
/// answers' loads and stores), and with the distance store the pass makes too.
pub(super) fn print_floors(rows: &[Row], floors: &[Floor]) {
    println!(
        "| size | column pass | ms (median) | load/store only ms | ratio | with the distance store ms | ratio |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (size, tag, floor, stored) in floors {
        // "columns (z)" also names "columns (z) + resolve" and a sweep's two dispatches
        // ("columns (z) sweep + resolve", "columns (z) + resolve (rest)"), summed; not
        // "columns (z, workgroup)".
        let times: Vec<f64> = rows
            .iter()
            .filter(|r| &r.size == size && r.method == "exact")
            .flat_map(|r| &r.passes)
            .filter(|p| p.0.starts_with(tag))
            .map(|p| p.1)
            .collect();
        if !times.is_empty() {
            let ms: f64 = times.iter().sum();
            let with_store = stored.map_or("| — | — |".to_string(), |s| {
                format!("| {s:.3} | {:.2} |", ms / s)
            });
            println!(
                "| {size} | {tag} | {ms:.3} | {floor:.3} | {:.2} {with_store}",
                ms / floor
            );
        }
    }
}

/// The header of `distance.csv`.
pub(super) const TABLE_HEADER: &str = "adapter,dims,size,cells,method,median_ms,min_ms,max_ms,wrong,wrong_fraction,max_err_voxels,mean_err_voxels,peer_ms,ratio_to_peer";

pub(super) fn write_csv(dir: &Path, adapter: &str, rows: &[Row]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(dir.join("distance.csv"))?;
    writeln!(f, "{TABLE_HEADER}")?;
    for r in rows {
        let peer = r.peer_ms.map_or(String::new(), |p| format!("{p:.4}"));
        let ratio = r
            .peer_ms
            .map_or(String::new(), |p| format!("{:.3}", r.median_ms / p));
        writeln!(
            f,
            "\"{adapter}\",{},{},{},\"{}\",{:.4},{:.4},{:.4},{},{:.3e},{:.4},{:.3e},{peer},{ratio}",
            r.dims,
            r.size,
            r.voxels,
            r.method,
            r.median_ms,
            r.min_ms,
            r.max_ms,
            r.wrong,
            r.wrong as f64 / r.voxels as f64,
            r.max_err,
            r.mean_err
        )?;
    }
    let mut f = std::fs::File::create(dir.join("distance_passes.csv"))?;
    writeln!(
        f,
        "adapter,size,method,pass,median_ms,bytes,gb_per_s,fraction_of_3tb_s"
    )?;
    for r in rows {
        for (p, ms, bytes) in &r.passes {
            let bw = bytes / (ms / 1e3);
            writeln!(
                f,
                "\"{adapter}\",{},\"{}\",\"{p}\",{ms:.4},{bytes:.0},{:.1},{:.3}",
                r.size,
                r.method,
                bw / 1e9,
                bw / PEAK_BYTES_PER_S
            )?;
        }
    }
    Ok(())
}

pub(super) fn print_table(rows: &[Row]) {
    println!(
        "| size | method | ms (median) | min–max | spread (max/min) | peer ms | ratio | wrong | max err | bytes/voxel (floor) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let peer = r.peer_ms.map_or("".into(), |p| format!("{p:.3}"));
        let ratio = r
            .peer_ms
            .map_or("".into(), |p| format!("{:.2}", r.median_ms / p));
        let bytes: f64 = r.passes.iter().map(|p| p.2).sum::<f64>() / r.voxels as f64;
        println!(
            "| {} | {} | {:.3} | {:.3}–{:.3} | {:.2} | {peer} | {ratio} | {} | {:.3} | {bytes:.0} |",
            r.size,
            r.method,
            r.median_ms,
            r.min_ms,
            r.max_ms,
            r.max_ms / r.min_ms,
            r.wrong,
            r.max_err
        );
    }
    println!();
    println!("| size | method | pass | ms (median) | bytes/voxel (floor) | GB/s at the floor |");
    println!("|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.method.starts_with("exact")) {
        for (pass, ms, bytes) in &r.passes {
            println!(
                "| {} | {} | {pass} | {ms:.3} | {:.0} | {:.0} |",
                r.size,
                r.method,
                bytes / r.voxels as f64,
                bytes / (ms * 1e-3) / 1e9
            );
        }
    }
}

/// GPU time against max error, log-log, a point per method and size, 3D and 2D side by side.
/// Zero error cannot sit on a log axis: those points are drawn in a band at the bottom
/// (below 5e-3, staggered per method so their labels can be read). The peer is a hollow point.
pub(super) fn chart(
    path: &Path,
    adapter: &str,
    rows: &[Row],
    (w, h): (u32, u32),
) -> Result<(), String> {
    use plotters::prelude::*;
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let root = BitMapBackend::new(path, (w, h)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let root = root
        .titled(
            &format!("distance: GPU time vs max error, {adapter}"),
            ("sans-serif", 15),
        )
        .map_err(|e| e.to_string())?;
    let panels = root.split_evenly((1, 2));
    let floor = 1e-3;
    let mut methods: Vec<&str> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    let y_of = |r: &Row| {
        if r.max_err > 0.0 {
            // An infinite error (a voxel left without its seed) on a log axis has no place:
            // drawn at a million voxels, past any grid's diagonal (a log range to ∞ never ends).
            r.max_err.clamp(5e-3, 1e6)
        } else {
            floor * 1.18f64.powi(methods.iter().position(|m| *m == r.method).unwrap_or(0) as i32)
        }
    };
    for (panel, dims) in panels.iter().zip([3u32, 2]) {
        let sel: Vec<&Row> = rows.iter().filter(|r| r.dims == dims).collect();
        if sel.is_empty() {
            continue;
        }
        let times: Vec<f64> = sel
            .iter()
            .flat_map(|r| std::iter::once(r.median_ms).chain(r.peer_ms))
            .collect();
        let (tmin, tmax) = times
            .iter()
            .fold((f64::INFINITY, 0f64), |(a, b), &t| (a.min(t), b.max(t)));
        let emax = sel.iter().map(|r| y_of(r)).fold(1.0, f64::max);
        let mut c = ChartBuilder::on(panel)
            .caption(if dims == 3 { "3D" } else { "2D" }, ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(56)
            .build_cartesian_2d(
                (tmin / 1.6..tmax * 2.2).log_scale(),
                (floor / 1.5..emax * 2.0).log_scale(),
            )
            .map_err(|e| e.to_string())?;
        c.configure_mesh()
            .x_desc("GPU time, ms (median, log)")
            .y_desc("max error, voxels (log; bottom band = 0)")
            .x_labels(6)
            .y_labels(5)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(|e| e.to_string())?;
        c.draw_series(std::iter::once(PathElement::new(
            vec![(tmin / 1.6, 4.2e-3), (tmax * 2.2, 4.2e-3)],
            BLACK.mix(0.3),
        )))
        .map_err(|e| e.to_string())?;
        let mut sizes: Vec<&str> = sel.iter().map(|r| r.size.as_str()).collect();
        sizes.dedup();
        for (i, size) in sizes.iter().enumerate() {
            let color = Palette99::pick(i + if dims == 2 { 4 } else { 0 }).to_rgba();
            let pts: Vec<&Row> = sel.iter().copied().filter(|r| r.size == *size).collect();
            c.draw_series(
                pts.iter()
                    .map(|r| Circle::new((r.median_ms, y_of(r)), 4, color.filled())),
            )
            .map_err(|e| e.to_string())?
            .label(size.to_string())
            .legend(move |(x, y)| Circle::new((x, y), 4, color.filled()));
            c.draw_series(pts.iter().map(|r| {
                Text::new(
                    format!(" {}", r.method),
                    (r.median_ms, y_of(r)),
                    ("sans-serif", 10).into_font().color(&color),
                )
            }))
            .map_err(|e| e.to_string())?;
            let peer: Vec<f64> = pts.iter().filter_map(|r| r.peer_ms).collect();
            c.draw_series(
                peer.iter()
                    .map(|&p| Circle::new((p, floor), 6, color.stroke_width(2))),
            )
            .map_err(|e| e.to_string())?;
            c.draw_series(peer.iter().map(|&p| {
                Text::new(
                    " peer (PBA+)".to_string(),
                    (p, floor / 1.2),
                    ("sans-serif", 10).into_font().color(&color),
                )
            }))
            .map_err(|e| e.to_string())?;
        }
        c.configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 11))
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

/// `--replot`: the adapter and rows of a `distance.csv`, or of several joined into one file
/// (their header lines repeated), all from one adapter. Per-pass times are not in it.
pub(super) fn read_table(path: &Path) -> Result<(String, Vec<Row>), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut adapter: Option<String> = None;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line == TABLE_HEADER || line.is_empty() {
            continue;
        }
        let bad = |what: &str| format!("{} line {}: {what}: {line}", path.display(), i + 1);
        let fields = crate::measure::csv_fields(line);
        let [
            a,
            dims,
            size,
            cells,
            method,
            median,
            min,
            max,
            wrong,
            _,
            max_err,
            mean_err,
            peer,
            _,
        ] = &fields[..]
        else {
            return Err(bad("not the 14 fields of distance.csv"));
        };
        match &adapter {
            Some(first) if first != a => {
                return Err(bad(&format!("a second adapter ({first} before)")));
            }
            _ => adapter = Some(a.clone()),
        }
        let num = |v: &str, name: &str| v.parse::<f64>().map_err(|_| bad(name));
        let int = |v: &str, name: &str| v.parse::<u64>().map_err(|_| bad(name));
        rows.push(Row {
            dims: int(dims, "dims")? as u32,
            size: size.clone(),
            voxels: int(cells, "cells")?,
            method: method.clone(),
            median_ms: num(median, "median_ms")?,
            min_ms: num(min, "min_ms")?,
            max_ms: num(max, "max_ms")?,
            wrong: int(wrong, "wrong")?,
            max_err: num(max_err, "max_err_voxels")?,
            mean_err: num(mean_err, "mean_err_voxels")?,
            peer_ms: if peer.is_empty() {
                None
            } else {
                Some(num(peer, "peer_ms")?)
            },
            passes: Vec::new(),
        });
    }
    let adapter = adapter.ok_or_else(|| format!("{}: no rows", path.display()))?;
    Ok((adapter, rows))
}
