//! Real volumes from files: NRRD (the format of 3D Slicer, ITK and most research volumes) and
//! raw voxels with fieldkit's small text header, into [`VolumeData`] for
//! [`super::Volume::upload`]. Pure parsing on the CPU, from bytes the caller read.
//!
//! ```
//! use fieldkit::volume::load;
//! let header = "fieldkit-raw 1\ndims 2 1 1\ntype uint8\nspacing 0.5 0.5 2\n\n";
//! let mut bytes = header.as_bytes().to_vec();
//! bytes.extend_from_slice(&[0, 255]);
//! let v = load::raw(&bytes)?;
//! assert_eq!(v.dims, [2, 1, 1]);
//! assert_eq!(v.values, vec![0.0, 255.0]);
//! let unit = v.normalised(); // 0..1 for an R8Unorm upload
//! assert_eq!(unit.values, vec![0.0, 1.0]);
//! # Ok::<(), fieldkit::Error>(())
//! ```
//!
//! **fieldkit's raw header** (`raw`): UTF-8 lines, then an empty line, then the voxels, x
//! fastest, then y, then z:
//!
//! ```text
//! fieldkit-raw 1
//! dims 256 256 113                 # voxels per axis
//! type uint16                      # int8 uint8 int16 uint16 int32 uint32 float32 float64
//! endian little                    # little (default) or big
//! spacing 1 1 2                    # voxel edge per axis (default 1 1 1)
//! origin 0 0 0                     # corner of voxel (0, 0, 0) (default 0 0 0)
//!
//! <voxels>
//! ```
//!
//! `#` starts a comment. [`raw_with`] reads headerless bytes with the layout given in code.
//!
//! **NRRD** (`nrrd`): magic `NRRD0001` to `NRRD0005`; `dimension: 3`; `type` any scalar;
//! `sizes`; `encoding: raw` (or `gzip` with feature `gzip`); `endian`; `spacings` or
//! `space directions` (their lengths; axes must be aligned to the grid up to sign); `space
//! origin`. Detached data (`data file:`), `block` and other encodings are typed errors.

use glam::Vec3;

use crate::error::Error;

const STAGE: &str = "volume::load";

/// A scalar volume on the CPU: values as the file stores them (converted to f32), x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct VolumeData {
    /// Voxels per axis.
    pub dims: [u32; 3],
    /// Voxel edge per axis.
    pub spacing: Vec3,
    /// Corner of voxel (0, 0, 0).
    pub origin: Vec3,
    /// One value per voxel, x fastest, then y, then z.
    pub values: Vec<f32>,
}

impl VolumeData {
    /// The values mapped to 0..1 by their least and greatest (a constant volume becomes 0), as
    /// `R8Unorm` and the transfer functions take them.
    pub fn normalised(&self) -> Self {
        let (lo, hi) = self
            .values
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let span = hi - lo;
        let values = self
            .values
            .iter()
            .map(|&v| if span > 0.0 { (v - lo) / span } else { 0.0 })
            .collect();
        Self {
            values,
            ..self.clone()
        }
    }
}

/// A scalar type of a volume file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// Signed 8-bit.
    I8,
    /// Unsigned 8-bit.
    U8,
    /// Signed 16-bit.
    I16,
    /// Unsigned 16-bit.
    U16,
    /// Signed 32-bit.
    I32,
    /// Unsigned 32-bit.
    U32,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl Scalar {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn read(self, b: &[u8], big: bool) -> f32 {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let a: [u8; $n] = b.try_into().expect("sized by the caller");
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => b[0] as i8 as f32,
            Scalar::U8 => b[0] as f32,
            Scalar::I16 => get!(i16, 2) as f32,
            Scalar::U16 => get!(u16, 2) as f32,
            Scalar::I32 => get!(i32, 4) as f32,
            Scalar::U32 => get!(u32, 4) as f32,
            Scalar::F32 => get!(f32, 4),
            Scalar::F64 => get!(f64, 8) as f32,
        }
    }

    /// NRRD's and fieldkit's names for the type.
    fn parse(name: &str) -> Option<Self> {
        Some(match name.trim() {
            "signed char" | "int8" | "int8_t" | "char" => Scalar::I8,
            "uchar" | "unsigned char" | "uint8" | "uint8_t" => Scalar::U8,
            "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
                Scalar::I16
            }
            "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => {
                Scalar::U16
            }
            "int" | "signed int" | "int32" | "int32_t" => Scalar::I32,
            "uint" | "unsigned int" | "uint32" | "uint32_t" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
}

/// How headerless voxels are laid out ([`raw_with`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RawLayout {
    /// Voxels per axis.
    pub dims: [u32; 3],
    /// The scalar type.
    pub scalar: Scalar,
    /// Big-endian values.
    pub big_endian: bool,
    /// Voxel edge per axis.
    pub spacing: Vec3,
    /// Corner of voxel (0, 0, 0).
    pub origin: Vec3,
    /// Bytes to skip before the voxels (a header of another format).
    pub skip: usize,
}

fn bad(what: String) -> Error {
    Error::Invalid { stage: STAGE, what }
}

/// Voxels laid out as `layout` says. Too few bytes, a zero side or a bad spacing are typed
/// errors; bytes past the voxels are ignored.
pub fn raw_with(bytes: &[u8], layout: &RawLayout) -> Result<VolumeData, Error> {
    let count = layout
        .dims
        .iter()
        .try_fold(1usize, |c, &d| c.checked_mul(d as usize))
        .filter(|&c| c > 0)
        .ok_or_else(|| bad(format!("dims {:?}: no voxels or too many", layout.dims)))?;
    if !(layout.spacing.is_finite() && layout.spacing.min_element() > 0.0) {
        return Err(bad(format!(
            "spacing must be finite and positive, got {}",
            layout.spacing
        )));
    }
    if !layout.origin.is_finite() {
        return Err(bad(format!("origin must be finite, got {}", layout.origin)));
    }
    let size = layout.scalar.size();
    let need = count
        .checked_mul(size)
        .and_then(|n| n.checked_add(layout.skip))
        .ok_or_else(|| bad("the volume's byte count overflows".into()))?;
    if bytes.len() < need {
        return Err(bad(format!(
            "{} bytes of data, {:?} of {:?} need {}",
            bytes.len(),
            layout.dims,
            layout.scalar,
            need
        )));
    }
    let values = bytes[layout.skip..need]
        .chunks_exact(size)
        .map(|b| layout.scalar.read(b, layout.big_endian))
        .collect();
    Ok(VolumeData {
        dims: layout.dims,
        spacing: layout.spacing,
        origin: layout.origin,
        values,
    })
}

/// Split a header ending at the first empty line (`\n\n`) from the data after it.
fn split_header(bytes: &[u8], what: &str) -> Result<(String, usize), Error> {
    let end = bytes
        .windows(2)
        .position(|w| w == b"\n\n")
        .ok_or_else(|| bad(format!("no empty line ends the {what} header")))?;
    let text = std::str::from_utf8(&bytes[..end])
        .map_err(|e| bad(format!("the {what} header is not UTF-8: {e}")))?
        .replace('\r', "");
    Ok((text, end + 2))
}

fn numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N], Error> {
    let v: Vec<f64> = s
        .split(|c: char| c.is_whitespace() || c == ',' || c == '(' || c == ')')
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| bad(format!("{what} {s:?}: {e}")))?;
    v.try_into()
        .map_err(|v: Vec<f64>| bad(format!("{what} needs {N} numbers, got {}", v.len())))
}

fn dims_of(v: [f64; 3]) -> Result<[u32; 3], Error> {
    let mut out = [0u32; 3];
    for (o, x) in out.iter_mut().zip(v) {
        if !(x >= 1.0 && x <= u32::MAX as f64 && x.fract() == 0.0) {
            return Err(bad(format!("sizes must be whole numbers ≥ 1, got {v:?}")));
        }
        *o = x as u32;
    }
    Ok(out)
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// A volume in fieldkit's raw format: the text header this module documents, an empty line,
/// the voxels.
pub fn raw(bytes: &[u8]) -> Result<VolumeData, Error> {
    let (header, start) = split_header(bytes, "fieldkit-raw")?;
    let mut lines = header
        .lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty());
    if lines.next() != Some("fieldkit-raw 1") {
        return Err(bad("the first line must be \"fieldkit-raw 1\"".into()));
    }
    let mut layout = RawLayout {
        dims: [0; 3],
        scalar: Scalar::U8,
        big_endian: false,
        spacing: Vec3::ONE,
        origin: Vec3::ZERO,
        skip: start,
    };
    let (mut dims, mut scalar) = (None, None);
    for line in lines {
        let (key, value) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        match key {
            "dims" => dims = Some(dims_of(numbers(value, "dims")?)?),
            "type" => {
                scalar = Some(
                    Scalar::parse(value)
                        .ok_or_else(|| bad(format!("unknown type {:?}", value.trim())))?,
                )
            }
            "endian" => {
                layout.big_endian = match value.trim() {
                    "little" => false,
                    "big" => true,
                    other => return Err(bad(format!("endian {other:?}: little or big"))),
                }
            }
            "spacing" => layout.spacing = vec3(numbers(value, "spacing")?),
            "origin" => layout.origin = vec3(numbers(value, "origin")?),
            other => return Err(bad(format!("unknown header field {other:?}"))),
        }
    }
    layout.dims = dims.ok_or_else(|| bad("the header has no dims line".into()))?;
    layout.scalar = scalar.ok_or_else(|| bad("the header has no type line".into()))?;
    raw_with(bytes, &layout)
}

/// A volume in NRRD (attached data; see the module's documentation for what is read).
pub fn nrrd(bytes: &[u8]) -> Result<VolumeData, Error> {
    if !(bytes.len() >= 8 && bytes.starts_with(b"NRRD000")) {
        return Err(bad("not an NRRD file (no NRRD000x magic)".into()));
    }
    let (header, start) = split_header(bytes, "NRRD")?;
    let mut lines = header.lines();
    let magic = lines.next().unwrap_or("");
    if !matches!(
        &magic[..magic.len().min(8)],
        "NRRD0001" | "NRRD0002" | "NRRD0003" | "NRRD0004" | "NRRD0005"
    ) {
        return Err(bad(format!("unsupported NRRD version {magic:?}")));
    }
    let (mut dims, mut scalar, mut big, mut encoding) = (None, None, false, String::from("raw"));
    let (mut spacing, mut origin) = (Vec3::ONE, Vec3::ZERO);
    for line in lines {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        // Key/value pairs (`key:=value`) are metadata.
        if line.contains(":=") {
            continue;
        }
        let Some((key, value)) = line.split_once(':') else {
            return Err(bad(format!("NRRD header line {line:?} has no field")));
        };
        let value = value.trim();
        match key.trim() {
            "type" => {
                scalar = Some(
                    Scalar::parse(value)
                        .ok_or_else(|| bad(format!("NRRD type {value:?} is not read")))?,
                )
            }
            "dimension" if value != "3" => {
                return Err(bad(format!(
                    "NRRD dimension {value}: only 3D volumes are read"
                )));
            }
            "dimension" => {}
            "sizes" => dims = Some(dims_of(numbers(value, "sizes")?)?),
            "endian" => big = value == "big",
            "encoding" => encoding = value.to_string(),
            "spacings" => spacing = vec3(numbers(value, "spacings")?),
            "space origin" => origin = vec3(numbers(value, "space origin")?),
            "space directions" => {
                let v: [f64; 9] = numbers(value, "space directions")?;
                let axes = [&v[0..3], &v[3..6], &v[6..9]];
                for (i, a) in axes.iter().enumerate() {
                    let off_axis = a
                        .iter()
                        .enumerate()
                        .any(|(k, &c)| k != i && c.abs() > 1e-6 * a[i].abs().max(1e-30));
                    if off_axis {
                        return Err(bad(format!(
                            "space directions {value:?}: axis {i} is not aligned to the grid \
                             (resample the volume first)"
                        )));
                    }
                }
                spacing = Vec3::new(v[0].abs() as f32, v[4].abs() as f32, v[8].abs() as f32);
            }
            "data file" | "datafile" => {
                return Err(bad(
                    "detached NRRD data (data file:) is not read: attach it (.nrrd) or read the \
                     raw file with raw_with"
                        .into(),
                ));
            }
            "byte skip" | "byteskip" | "line skip" | "lineskip" if value != "0" => {
                return Err(bad(format!("NRRD {key}: {value} is not read")));
            }
            // Fields that do not change the voxels.
            _ => {}
        }
    }
    let dims = dims.ok_or_else(|| bad("NRRD header has no sizes".into()))?;
    let scalar = scalar.ok_or_else(|| bad("NRRD header has no type".into()))?;
    let data: std::borrow::Cow<[u8]> = match encoding.as_str() {
        "raw" => std::borrow::Cow::Borrowed(&bytes[start..]),
        "gzip" | "gz" => std::borrow::Cow::Owned(gunzip(&bytes[start..])?),
        other => {
            return Err(bad(format!(
                "NRRD encoding {other:?} is not read (raw, gzip)"
            )));
        }
    };
    raw_with(
        &data,
        &RawLayout {
            dims,
            scalar,
            big_endian: big,
            spacing,
            origin,
            skip: 0,
        },
    )
}

#[cfg(feature = "gzip")]
fn gunzip(bytes: &[u8]) -> Result<Vec<u8>, Error> {
    use std::io::Read;
    let mut out = Vec::new();
    flate2::read::GzDecoder::new(bytes)
        .read_to_end(&mut out)
        .map_err(|e| bad(format!("NRRD gzip data: {e}")))?;
    Ok(out)
}

#[cfg(not(feature = "gzip"))]
fn gunzip(_: &[u8]) -> Result<Vec<u8>, Error> {
    Err(Error::Unsupported {
        stage: STAGE,
        what: "gzip-encoded NRRD needs fieldkit's feature `gzip`".into(),
    })
}

/// A DICOM series (feature `dicom`): one file per slice, single-frame, uncompressed (implicit
/// or explicit VR little endian), 8- or 16-bit, signed or unsigned, one sample per pixel.
/// Slices are stacked by their `ImagePositionPatient` along the slice normal
/// (`ImageOrientationPatient`'s row × column, +z where absent), in any order given; the
/// spacing is `PixelSpacing` (column spacing along x, row spacing along y) and the distance
/// between consecutive slices, which must be even to 1%. Values are the stored pixels ×
/// `RescaleSlope` + `RescaleIntercept` (Hounsfield units for CT). The origin is the first
/// slice's position. Compressed transfer syntaxes, colour images and uneven or missing slice
/// positions are typed errors.
#[cfg(feature = "dicom")]
pub fn dicom(files: &[&[u8]]) -> Result<VolumeData, Error> {
    if files.is_empty() {
        return Err(bad("a DICOM series needs at least one file".into()));
    }
    let mut slices = Vec::with_capacity(files.len());
    for (i, bytes) in files.iter().enumerate() {
        slices.push(dicom_slice(i, bytes)?);
    }
    let first = &slices[0];
    let (rows, columns, spacing, normal) = (first.rows, first.columns, first.spacing, first.normal);
    if let Some(i) = slices
        .iter()
        .position(|s| (s.rows, s.columns) != (rows, columns) || s.spacing != spacing)
    {
        return Err(bad(format!(
            "DICOM file {i}: its size or pixel spacing differs from the first file's"
        )));
    }
    slices.sort_by(|a, b| a.position.dot(normal).total_cmp(&b.position.dot(normal)));
    let gaps: Vec<f64> = slices
        .windows(2)
        .map(|w| (w[1].position - w[0].position).dot(normal))
        .collect();
    let dz = gaps.first().copied().unwrap_or(1.0);
    if dz.is_nan() || dz <= 0.0 || gaps.iter().any(|g| (g - dz).abs() > 0.01 * dz) {
        return Err(bad(format!(
            "DICOM slices are not evenly spaced (gaps {gaps:?}): resample the series"
        )));
    }
    let origin = slices[0].position.as_vec3();
    let depth = slices.len() as u32;
    Ok(VolumeData {
        dims: [columns, rows, depth],
        spacing: Vec3::new(spacing[1] as f32, spacing[0] as f32, dz as f32),
        origin,
        values: slices.into_iter().flat_map(|s| s.values).collect(),
    })
}

/// One slice of a DICOM series: where it lies, its pixels' size and spacing, and its values.
#[cfg(feature = "dicom")]
struct Slice {
    position: glam::DVec3,
    rows: u32,
    columns: u32,
    spacing: [f64; 2],
    normal: glam::DVec3,
    values: Vec<f32>,
}

/// DICOM file `i` of a series read as one slice: uncompressed little endian, one greyscale
/// frame, 8 or 16 bits, rescaled to its values.
#[cfg(feature = "dicom")]
fn dicom_slice(i: usize, bytes: &[u8]) -> Result<Slice, Error> {
    use dicom_dictionary_std::tags;
    use dicom_object::DefaultDicomObject;
    let fail = |what: String| bad(format!("DICOM file {i}: {what}"));
    let obj = DefaultDicomObject::from_reader(bytes).map_err(|e| fail(e.to_string()))?;
    let syntax = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches('\0')
        .to_string();
    if !matches!(syntax.as_str(), "1.2.840.10008.1.2" | "1.2.840.10008.1.2.1") {
        return Err(fail(format!(
            "transfer syntax {syntax} is not read (uncompressed little endian only: convert \
             the series with dcmdjpeg or gdcmconv --raw)"
        )));
    }
    let int = |tag, name: &str| -> Result<i64, Error> {
        obj.element(tag)
            .map_err(|e| fail(format!("{name}: {e}")))?
            .to_int::<i64>()
            .map_err(|e| fail(format!("{name}: {e}")))
    };
    let floats = |tag, name: &str| -> Result<Option<Vec<f64>>, Error> {
        match obj
            .element_opt(tag)
            .map_err(|e| fail(format!("{name}: {e}")))?
        {
            None => Ok(None),
            Some(e) => e
                .to_multi_float64()
                .map(Some)
                .map_err(|e| fail(format!("{name}: {e}"))),
        }
    };
    let (rows, columns) = (int(tags::ROWS, "Rows")?, int(tags::COLUMNS, "Columns")?);
    let bits = int(tags::BITS_ALLOCATED, "BitsAllocated")?;
    let signed = int(tags::PIXEL_REPRESENTATION, "PixelRepresentation")? == 1;
    let samples = obj
        .element_opt(tags::SAMPLES_PER_PIXEL)
        .ok()
        .flatten()
        .and_then(|e| e.to_int::<i64>().ok())
        .unwrap_or(1);
    let frames = obj
        .element_opt(tags::NUMBER_OF_FRAMES)
        .ok()
        .flatten()
        .and_then(|e| e.to_int::<i64>().ok())
        .unwrap_or(1);
    if samples != 1 || frames != 1 {
        return Err(fail(format!(
            "{samples} samples per pixel and {frames} frames: one greyscale frame per file \
             is read"
        )));
    }
    if !(1..=65536).contains(&rows) || !(1..=65536).contains(&columns) {
        return Err(fail(format!("{columns} × {rows} pixels")));
    }
    let scalar = match (bits, signed) {
        (8, false) => Scalar::U8,
        (8, true) => Scalar::I8,
        (16, false) => Scalar::U16,
        (16, true) => Scalar::I16,
        _ => return Err(fail(format!("{bits}-bit pixels are not read (8 or 16)"))),
    };
    let spacing = floats(tags::PIXEL_SPACING, "PixelSpacing")?.unwrap_or(vec![1.0, 1.0]);
    let position = floats(tags::IMAGE_POSITION_PATIENT, "ImagePositionPatient")?
        .ok_or_else(|| fail("no ImagePositionPatient: the slices cannot be stacked".into()))?;
    let orientation = floats(tags::IMAGE_ORIENTATION_PATIENT, "ImageOrientationPatient")?
        .unwrap_or(vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    if spacing.len() != 2 || position.len() != 3 || orientation.len() != 6 {
        return Err(fail(
            "PixelSpacing needs 2 values, ImagePositionPatient 3, ImageOrientationPatient 6".into(),
        ));
    }
    let slope = floats(tags::RESCALE_SLOPE, "RescaleSlope")?
        .and_then(|v| v.first().copied())
        .unwrap_or(1.0);
    let intercept = floats(tags::RESCALE_INTERCEPT, "RescaleIntercept")?
        .and_then(|v| v.first().copied())
        .unwrap_or(0.0);
    let pixels = obj
        .element(tags::PIXEL_DATA)
        .map_err(|e| fail(format!("PixelData: {e}")))?
        .to_bytes()
        .map_err(|e| fail(format!("PixelData: {e}")))?;
    let raw = raw_with(
        &pixels,
        &RawLayout {
            dims: [columns as u32, rows as u32, 1],
            scalar,
            big_endian: false,
            spacing: Vec3::ONE,
            origin: Vec3::ZERO,
            skip: 0,
        },
    )
    .map_err(|e| fail(e.to_string()))?;
    let row = glam::DVec3::new(orientation[0], orientation[1], orientation[2]);
    let column = glam::DVec3::new(orientation[3], orientation[4], orientation[5]);
    Ok(Slice {
        position: glam::DVec3::new(position[0], position[1], position[2]),
        rows: rows as u32,
        columns: columns as u32,
        spacing: [spacing[0], spacing[1]],
        normal: row.cross(column).normalize_or(glam::DVec3::Z),
        values: raw
            .values
            .iter()
            .map(|&v| (v as f64 * slope + intercept) as f32)
            .collect(),
    })
}
