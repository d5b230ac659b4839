//! The per-stage test harness: compact deterministic summaries of a stage's output for insta snapshots, and image comparison against a reference PNG with a
//! tolerance (writing the actual and a difference image when it fails).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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
    if expected.dimensions() != (width, height) {
        let _ = image::save_buffer(
            &actual_path,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        );
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
        let _ = image::save_buffer(
            &actual_path,
            rgba,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        );
        let _ = image::save_buffer(
            &diff_path,
            &diff,
            width,
            height,
            image::ExtendedColorType::Rgba8,
        );
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
