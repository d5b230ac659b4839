//! A 2D distance field to files, as the source's tool exports it: a 16-bit PNG with its scale
//! written into the file, a 32-bit float PFM, and a normalised 8-bit picture. Each takes the
//! field as read back (`R32Float`, row-major, x fastest, row 0 at the top) and returns the
//! file's bytes.
//!
//! ```
//! use fieldkit::distance::export;
//! let field = [-1.5f32, 0.0, 2.0, 4.0]; // 2 × 2, world units
//! let pfm = export::pfm(&field, 2, 2)?;
//! assert!(pfm.starts_with(b"Pf\n2 2\n-1.0\n"));
//! # #[cfg(feature = "png")] {
//! let png = export::png16(&field, 2, 2, 4.0)?; // ±4 world units span the 16 bits
//! # }
//! # Ok::<(), fieldkit::Error>(())
//! ```

use crate::error::Error;

const STAGE: &str = "distance::export";

/// The PNG text key holding the 16-bit encoding's range.
pub const RANGE_KEY: &str = "fieldkit:distance_range";
/// The PNG text key holding the decoding rule, in words.
pub const DECODE_KEY: &str = "fieldkit:decode";

fn check(field: &[f32], width: u32, height: u32) -> Result<(), Error> {
    let n = width as u64 * height as u64;
    if width == 0 || height == 0 || field.len() as u64 != n {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!(
                "a {width} × {height} field needs {n} values (and no zero side), got {}",
                field.len()
            ),
        });
    }
    Ok(())
}

/// The 16-bit code of distance `d` for `range`: d = (v / 65535 − ½) · 2 · range, so 0 sits at
/// mid-grey, ±range at the ends, and each step is range / 32767.5. Beyond ±range (and the no-seed
/// [`super::FAR`]) the code saturates; NaN is 0.
pub fn code16(d: f32, range: f32) -> u16 {
    let v = (d as f64 / range as f64 * 0.5 + 0.5).clamp(0.0, 1.0) * 65535.0;
    if v.is_nan() { 0 } else { v.round() as u16 }
}

/// The distance a 16-bit code stands for (the inverse of [`code16`]).
pub fn decode16(v: u16, range: f32) -> f32 {
    ((v as f64 / 65535.0 - 0.5) * 2.0 * range as f64) as f32
}

/// A 16-bit greyscale PNG of the field, [`code16`] per texel, with `range` and the decoding
/// rule in text chunks ([`RANGE_KEY`], [`DECODE_KEY`]). `range` must be finite and positive.
#[cfg(feature = "png")]
pub fn png16(field: &[f32], width: u32, height: u32, range: f32) -> Result<Vec<u8>, Error> {
    check(field, width, height)?;
    if !(range.is_finite() && range > 0.0) {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("range must be finite and positive, got {range}"),
        });
    }
    let data: Vec<u8> = field
        .iter()
        .flat_map(|&d| code16(d, range).to_be_bytes())
        .collect();
    let text = [
        (RANGE_KEY, format!("{range}")),
        (
            DECODE_KEY,
            format!("distance = (value / 65535 - 0.5) * 2 * {range}"),
        ),
    ];
    encode_png(&data, width, height, png::BitDepth::Sixteen, &text)
}

/// A normalised 8-bit greyscale PNG for looking at: the field's least distance black, its
/// greatest white (texels with no seed, [`super::FAR`], white too); a constant field is
/// mid-grey.
#[cfg(feature = "png")]
pub fn png8(field: &[f32], width: u32, height: u32) -> Result<Vec<u8>, Error> {
    check(field, width, height)?;
    let finite = field
        .iter()
        .filter(|d| d.is_finite() && d.abs() < super::FAR);
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &d| {
        (lo.min(d), hi.max(d))
    });
    let data: Vec<u8> = field
        .iter()
        .map(|&d| {
            if lo >= hi {
                128
            } else if !(d.is_finite() && d.abs() < super::FAR) {
                if d < 0.0 { 0 } else { 255 }
            } else {
                ((d - lo) / (hi - lo) * 255.0).round() as u8
            }
        })
        .collect();
    let text = [(
        DECODE_KEY,
        format!("normalised for viewing: black {lo}, white {hi}"),
    )];
    encode_png(&data, width, height, png::BitDepth::Eight, &text)
}

#[cfg(feature = "png")]
fn encode_png(
    data: &[u8],
    width: u32,
    height: u32,
    depth: png::BitDepth,
    text: &[(&str, String)],
) -> Result<Vec<u8>, Error> {
    let fail = |e: png::EncodingError| Error::Invalid {
        stage: STAGE,
        what: format!("PNG encoding: {e}"),
    };
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, width, height);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(depth);
        for (key, value) in text {
            enc.add_text_chunk(key.to_string(), value.clone())
                .map_err(fail)?;
        }
        let mut writer = enc.write_header().map_err(fail)?;
        writer.write_image_data(data).map_err(fail)?;
        writer.finish().map_err(fail)?;
    }
    Ok(out)
}

/// A greyscale Portable Float Map (`Pf`): the distances themselves as little-endian f32 (scale
/// −1.0 in the header: little-endian, no further scaling), rows from the bottom up as the
/// format has them. Read by ImageMagick, GIMP, OpenCV and most HDR tools.
pub fn pfm(field: &[f32], width: u32, height: u32) -> Result<Vec<u8>, Error> {
    check(field, width, height)?;
    let mut out = format!("Pf\n{width} {height}\n-1.0\n").into_bytes();
    out.reserve(field.len() * 4);
    for row in (0..height as usize).rev() {
        let w = width as usize;
        for &d in &field[row * w..(row + 1) * w] {
            out.extend_from_slice(&d.to_le_bytes());
        }
    }
    Ok(out)
}
