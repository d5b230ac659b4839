//! The time-against-error scatter the technique benchmarks draw: log-log, one colour per group,
//! each point labelled.

/// One measured configuration.
pub(crate) struct Point {
    /// Legend entry; points of one group share a colour.
    pub group: String,
    pub ms: f64,
    pub err: f64,
    pub label: String,
}

/// Axis descriptions and the error floor (errors below it are drawn at it, the log axis has no 0).
pub(crate) struct Axes<'a> {
    pub caption: String,
    pub x: &'a str,
    pub y: &'a str,
    pub floor: f64,
}

/// Creates the folder a chart goes into (`--replot --out DIR` may name one that does not exist
/// yet), naming it if that fails.
fn make_parent(path: &std::path::Path) -> Result<(), String> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display())),
        _ => Ok(()),
    }
}

pub(crate) fn time_vs_error(
    path: &std::path::Path,
    axes: &Axes,
    points: &[Point],
) -> Result<(), String> {
    use plotters::prelude::*;
    make_parent(path)?;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let y_of = |p: &Point| p.err.max(axes.floor);
    let (tmin, tmax) = points.iter().fold((f64::INFINITY, 0f64), |(a, b), p| {
        (a.min(p.ms), b.max(p.ms))
    });
    let emax = points.iter().map(y_of).fold(axes.floor * 100.0, f64::max);
    let mut c = ChartBuilder::on(&root)
        .caption(&axes.caption, ("sans-serif", 15))
        .margin(12)
        .x_label_area_size(38)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (tmin / 1.6..tmax * 2.5).log_scale(),
            (axes.floor / 1.5..emax * 3.0).log_scale(),
        )
        .map_err(|x| e(&x))?;
    c.configure_mesh()
        .x_desc(axes.x)
        .y_desc(axes.y)
        .x_labels(6)
        .y_labels(5)
        .x_label_formatter(&|v| format!("{v:.2}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|x| e(&x))?;
    let mut groups: Vec<&str> = Vec::new();
    for p in points {
        if !groups.contains(&p.group.as_str()) {
            groups.push(&p.group);
        }
    }
    for (k, group) in groups.into_iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let pts: Vec<&Point> = points.iter().filter(|p| p.group == group).collect();
        c.draw_series(
            pts.iter()
                .map(|p| Circle::new((p.ms, y_of(p)), 4, color.filled())),
        )
        .map_err(|x| e(&x))?
        .label(group)
        .legend(move |(x, y)| Circle::new((x, y), 4, color.filled()));
        c.draw_series(pts.iter().map(|p| {
            Text::new(
                format!(" {}", p.label),
                (p.ms, y_of(p)),
                ("sans-serif", 10).into_font().color(&color),
            )
        }))
        .map_err(|x| e(&x))?;
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// A named line of (x, y) points.
pub(crate) type Series = (String, Vec<(f64, f64)>);

/// Lines on log-log axes, one colour per series, each point marked.
pub(crate) fn log_log(
    path: &std::path::Path,
    caption: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), String> {
    use plotters::prelude::*;
    make_parent(path)?;
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let _ =
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    let all: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.1.iter().copied())
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    if all.is_empty() {
        return Err(format!("{}: nothing to draw", path.display()));
    }
    let (xmin, xmax, ymin, ymax) = all.iter().fold(
        (f64::INFINITY, 0f64, f64::INFINITY, 0f64),
        |(a, b, c, d), p| (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1)),
    );
    let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let mut c = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 15))
        .margin(12)
        .x_label_area_size(38)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xmin / 1.3..xmax * 1.3).log_scale(),
            (ymin / 2.0..ymax * 3.0).log_scale(),
        )
        .map_err(|x| e(&x))?;
    c.configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&|v| format!("{v:.0}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 11))
        .draw()
        .map_err(|x| e(&x))?;
    for (k, (name, pts)) in series.iter().enumerate() {
        let pts: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .collect();
        if pts.is_empty() {
            continue;
        }
        let color = Palette99::pick(k).to_rgba();
        c.draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(|x| e(&x))?
            .label(name.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
            });
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|x| e(&x))?;
    }
    c.configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(|x| e(&x))?;
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    /// A chart drawn into a folder that does not exist yet (as `--replot --out` may name) is
    /// written there, not refused.
    #[test]
    fn charts_go_into_new_folders() {
        let dir = std::env::temp_dir().join(format!("fieldkit-chart-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("a").join("b").join("chart.png");
        let series = vec![("s".to_string(), vec![(1.0, 1.0), (2.0, 4.0)])];
        super::log_log(&path, "caption", "x", "y", &series).unwrap();
        assert!(path.is_file(), "{} not written", path.display());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
