//! The per-stage test harness: compact deterministic summaries of a stage's output for insta snapshots, and image comparison against a reference PNG with a
//! tolerance (writing the actual and a difference image when it fails).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A render pipeline from WGSL written in place, for a demo's or a test's own drawing (a blit,
/// a floor, debug lines) rather than a stage of the crate's: vertex entry `vs`, fragment entry
/// `fs`, one colour target of `colour`, the depth state `depth` where given, the vertex
/// `buffers` and `primitive` the drawing needs, the layout derived from the shader. wgpu
/// compiles the WGSL here, so a mistake in it shows as wgpu's validation error.
///
/// ```no_run
/// # fn f(device: &wgpu::Device) {
/// let pipeline = fieldkit::harness::wgsl_pipeline(
///     device,
///     "my overlay",
///     "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
///          return vec4<f32>(f32(i % 2u), f32(i / 2u), 0.0, 1.0);
///      }
///      @fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(1.0); }",
///     wgpu::TextureFormat::Rgba8Unorm,
///     None,
///     &[],
///     wgpu::PrimitiveState::default(),
/// );
/// # }
/// ```
pub fn wgsl_pipeline(
    device: &wgpu::Device,
    label: &str,
    wgsl: &str,
    colour: wgpu::TextureFormat,
    depth: Option<wgpu::DepthStencilState>,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    primitive: wgpu::PrimitiveState,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers,
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(colour.into())],
        }),
        primitive,
        depth_stencil: depth,
        multisample: Default::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// FNV-1a, 64-bit: a stable hash for summaries (std's hasher may change between releases).
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

/// A compact description of a stage output that is the same on every adapter.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary(pub String);

impl std::fmt::Display for Summary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl Summary {
    /// Integer output: shape, count of distinct values, min, max, and a hash of every value.
    pub fn ints(shape: &[usize], values: &[u32]) -> Self {
        let mut s = String::new();
        let mut sorted = values.to_vec();
        sorted.sort_unstable();
        sorted.dedup();
        writeln!(s, "shape: {shape:?}").unwrap();
        writeln!(s, "distinct: {}", sorted.len()).unwrap();
        writeln!(s, "min: {}", sorted.first().copied().unwrap_or(0)).unwrap();
        writeln!(s, "max: {}", sorted.last().copied().unwrap_or(0)).unwrap();
        writeln!(
            s,
            "hash: {:016x}",
            fnv1a(values.iter().flat_map(|v| v.to_le_bytes()))
        )
        .unwrap();
        Self(s)
    }

    /// Float output: shape, min, max, mean and RMS rounded to `decimals`, and how many values are
    /// not finite. Floats are summarised, not hashed: adapters round `sqrt` differently in the
    /// last bit, which a hash would turn into a different snapshot.
    pub fn floats(shape: &[usize], values: &[f32], decimals: usize) -> Self {
        let finite: Vec<f64> = values
            .iter()
            .filter(|v| v.is_finite())
            .map(|&v| v as f64)
            .collect();
        let n = finite.len().max(1) as f64;
        let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
        let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mean = finite.iter().sum::<f64>() / n;
        let rms = (finite.iter().map(|v| v * v).sum::<f64>() / n).sqrt();
        let mut s = String::new();
        writeln!(s, "shape: {shape:?}").unwrap();
        writeln!(s, "non_finite: {}", values.len() - finite.len()).unwrap();
        writeln!(s, "min: {min:.decimals$}").unwrap();
        writeln!(s, "max: {max:.decimals$}").unwrap();
        writeln!(s, "mean: {mean:.decimals$}").unwrap();
        writeln!(s, "rms: {rms:.decimals$}").unwrap();
        Self(s)
    }

    /// Append another section (e.g. an integer view of the same output).
    pub fn and(mut self, label: &str, other: Summary) -> Self {
        writeln!(self.0, "[{label}]").unwrap();
        self.0.push_str(&other.0);
        self
    }
}

/// How far an image may differ from its reference. Both limits are capped (see
/// [`Tolerance::MAX_MEAN`]) so a loose threshold cannot hide a broken stage.
#[derive(Debug, Clone, Copy)]
pub struct Tolerance {
    /// Mean absolute difference per channel, in 0..=255 units.
    pub mean: f32,
    /// Fraction of pixels allowed to differ by more than `pixel` in any channel.
    pub outlier_fraction: f32,
    /// Largest per-channel difference (0–255) a pixel may have without counting as an outlier.
    pub pixel: u8,
}

impl Tolerance {
    /// Cap on [`Tolerance::mean`]: no test may loosen past it.
    pub const MAX_MEAN: f32 = 4.0;
    /// Cap on [`Tolerance::outlier_fraction`].
    pub const MAX_OUTLIERS: f32 = 0.02;
}

/// Result of an image comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImageDiff {
    /// Mean absolute difference per channel (0–255) measured.
    pub mean: f32,
    /// Fraction of pixels measured past [`Tolerance::pixel`].
    pub outlier_fraction: f32,
}

/// Compare RGBA8 pixels with `<dir>/<name>.png`. With `FIELDKIT_BLESS=1`, or when the reference
/// does not exist yet and `FIELDKIT_BLESS` is unset outside CI, the reference is (re)written.
/// On failure `<name>.actual.png` and `<name>.diff.png` are written beside it (git-ignored).
pub fn compare_image(
    dir: &Path,
    name: &str,
    rgba: &[u8],
    width: u32,
    height: u32,
    tol: Tolerance,
) -> Result<ImageDiff, String> {
    assert!(
        tol.mean <= Tolerance::MAX_MEAN && tol.outlier_fraction <= Tolerance::MAX_OUTLIERS,
        "tolerance {tol:?} is looser than the cap ({} mean, {} outliers)",
        Tolerance::MAX_MEAN,
        Tolerance::MAX_OUTLIERS
    );
    let reference = dir.join(format!("{name}.png"));
    let bless = std::env::var("FIELDKIT_BLESS").is_ok_and(|v| v == "1");
    let in_ci = std::env::var("CI").is_ok();
    if bless || (!reference.exists() && !in_ci) {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        image::save_buffer(
            &reference,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| e.to_string())?;
        return Ok(ImageDiff {
            mean: 0.0,
            outlier_fraction: 0.0,
        });
    }
    let expected = image::open(&reference)
        .map_err(|e| format!("cannot read reference {}: {e}", reference.display()))?
        .to_rgba8();
    let actual_path: PathBuf = dir.join(format!("{name}.actual.png"));
    let diff_path: PathBuf = dir.join(format!("{name}.diff.png"));
    // Beside the reference for a look, on failure; a write that fails leaves the error as it is.
    let save = |path: &Path, pixels: &[u8]| {
        let _ = image::save_buffer(path, pixels, width, height, image::ExtendedColorType::Rgba8);
    };
    if expected.dimensions() != (width, height) {
        save(&actual_path, rgba);
        return Err(format!(
            "{name}: size {width}x{height}, reference is {:?}",
            expected.dimensions()
        ));
    }
    let mut total = 0u64;
    let mut outliers = 0usize;
    let mut diff = vec![0u8; rgba.len()];
    for (i, (a, e)) in rgba.chunks(4).zip(expected.as_raw().chunks(4)).enumerate() {
        let mut worst = 0u8;
        for c in 0..4 {
            let d = a[c].abs_diff(e[c]);
            total += d as u64;
            worst = worst.max(d);
        }
        if worst > tol.pixel {
            outliers += 1;
        }
        diff[i * 4..i * 4 + 4].copy_from_slice(&[worst.saturating_mul(8), 0, 0, 255]);
    }
    let result = ImageDiff {
        mean: total as f32 / rgba.len().max(1) as f32,
        outlier_fraction: outliers as f32 / (width * height).max(1) as f32,
    };
    if result.mean > tol.mean || result.outlier_fraction > tol.outlier_fraction {
        save(&actual_path, rgba);
        save(&diff_path, &diff);
        return Err(format!(
            "{name}: mean difference {:.3} (allowed {}), outliers {:.4} (allowed {}); wrote {} and {}",
            result.mean,
            tol.mean,
            result.outlier_fraction,
            tol.outlier_fraction,
            actual_path.display(),
            diff_path.display()
        ));
    }
    Ok(result)
}

/// Check a [`Summary`] against its stored snapshot, `<manifest_dir>/tests/snapshots/<file
/// stem>__<name>.snap` (insta's layout, so the files stay readable and reviewable as before).
///
/// Lines must match, with one allowance: a number printed with `d` decimals may differ from
/// the stored one by one unit in its last decimal (10⁻ᵈ). A statistic whose true value sits
/// near a rounding boundary lands on either side of it on different adapters (llvmpipe and
/// NVIDIA round the last bit of `sqrt`, `exp` and filtering differently); a real change moves it
/// further. Integers, hashes and every other token compare exactly.
///
/// `FIELDKIT_BLESS=1` (or `INSTA_UPDATE=always`) rewrites the snapshot; a missing snapshot is
/// written outside CI and an error in CI.
pub fn check_summary(
    manifest_dir: &str,
    file: &str,
    name: &str,
    summary: &str,
) -> Result<(), String> {
    let stem = Path::new(file)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("test");
    let path = Path::new(manifest_dir)
        .join("tests/snapshots")
        .join(format!("{stem}__{name}.snap"));
    let bless = std::env::var("FIELDKIT_BLESS").is_ok_and(|v| v == "1")
        || std::env::var("INSTA_UPDATE").is_ok_and(|v| v == "always");
    let in_ci = std::env::var("CI").is_ok();
    if bless || (!path.exists() && !in_ci) {
        std::fs::create_dir_all(path.parent().expect("a parent")).map_err(|e| e.to_string())?;
        let text = format!(
            "---\nsource: {file}\nexpression: summary\n---\n{}\n",
            summary.trim_end()
        );
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        return Ok(());
    }
    let stored = std::fs::read_to_string(&path)
        .map_err(|e| format!("{}: {e} (FIELDKIT_BLESS=1 writes it)", path.display()))?;
    // The content follows the second `---` line of the header.
    let content = stored
        .splitn(3, "---\n")
        .nth(2)
        .ok_or_else(|| format!("{}: no snapshot header", path.display()))?;
    let want: Vec<&str> = content.trim_end().lines().map(str::trim_end).collect();
    let got: Vec<&str> = summary.trim_end().lines().map(str::trim_end).collect();
    let mut problems = Vec::new();
    if want.len() != got.len() {
        problems.push(format!("{} lines stored, {} now", want.len(), got.len()));
    }
    for (i, (w, g)) in want.iter().zip(&got).enumerate() {
        if !lines_agree(w, g) {
            problems.push(format!("line {}: stored `{w}`, now `{g}`", i + 1));
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{} differs beyond one unit in the last decimal:\n  {}\n(FIELDKIT_BLESS=1 rewrites it)",
            path.display(),
            problems.join("\n  ")
        ))
    }
}

/// Equal token by token, a decimal number allowed one unit in its last place.
fn lines_agree(want: &str, got: &str) -> bool {
    let (w, g): (Vec<&str>, Vec<&str>) = (
        want.split_whitespace().collect(),
        got.split_whitespace().collect(),
    );
    w.len() == g.len()
        && w.iter().zip(&g).all(|(a, b)| {
            if a == b {
                return true;
            }
            let decimals = |t: &str| t.split_once('.').map(|(_, f)| f.len());
            match (decimals(a), decimals(b), a.parse::<f64>(), b.parse::<f64>()) {
                (Some(da), Some(db), Ok(x), Ok(y)) if da == db && da > 0 => {
                    (x - y).abs() <= 10f64.powi(-(da as i32)) * 1.0001
                }
                _ => false,
            }
        })
}

/// Assert that a [`Summary`] (or any `Display`) matches its stored snapshot within one unit of
/// its last printed decimal: [`check_summary`] for the calling test file.
///
/// ```ignore
/// fieldkit::assert_summary!("resolve_stage", Summary::floats(&[h, w], &d, 3));
/// ```
#[macro_export]
macro_rules! assert_summary {
    ($name:expr, $summary:expr) => {
        if let Err(e) = $crate::harness::check_summary(
            env!("CARGO_MANIFEST_DIR"),
            file!(),
            $name,
            &$summary.to_string(),
        ) {
            panic!("{e}");
        }
    };
}

#[cfg(test)]
mod tests {
    use super::lines_agree;

    #[test]
    fn a_last_decimal_may_move_by_one_unit_and_no_more() {
        assert!(lines_agree("mean: 0.719", "mean: 0.720"));
        assert!(lines_agree("max: 1.017", "max: 1.016"));
        assert!(!lines_agree("mean: 0.719", "mean: 0.721"));
        assert!(!lines_agree("mean: 0.719", "mean: 0.72"));
        assert!(!lines_agree("distinct: 12", "distinct: 13"));
        assert!(!lines_agree("hash: 00ab", "hash: 00ac"));
        assert!(lines_agree(
            "mean rgb: 12.3 45.6 7.8",
            "mean rgb: 12.4 45.6 7.7"
        ));
        assert!(!lines_agree("shape: [32, 32]", "shape: [32, 33]"));
    }
}
