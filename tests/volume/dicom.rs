//! DICOM series (issue 24, seed 002: the source's demo volume is one): slices written here with
//! dicom-rs, given out of order, stacked by position with the rescale applied, against the
//! values written.

use dicom_core::{DataElement, PrimitiveValue, VR, dicom_value};
use dicom_dictionary_std::tags;
use dicom_object::{InMemDicomObject, meta::FileMetaTableBuilder};
use fieldkit::volume::load;
use glam::Vec3;

const W: u16 = 4;
const H: u16 = 3;

/// One slice at height `z`: pixels `base + i` (i16), slope 2, intercept −1024.
fn slice(z: f64, base: i16, syntax: &str) -> Vec<u8> {
    let pixels: Vec<u8> = (0..(W * H) as i16)
        .flat_map(|i| (base + i).to_le_bytes())
        .collect();
    let obj = InMemDicomObject::from_element_iter([
        DataElement::new(tags::SOP_CLASS_UID, VR::UI, "1.2.840.10008.5.1.4.1.1.2"),
        DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
        DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(H)),
        DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(W)),
        DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16)),
        DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16)),
        DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16)),
        DataElement::new(
            tags::PIXEL_REPRESENTATION,
            VR::US,
            PrimitiveValue::from(1u16),
        ),
        DataElement::new(
            tags::PIXEL_SPACING,
            VR::DS,
            dicom_value!(Strs, ["0.6", "0.7"]),
        ),
        DataElement::new(
            tags::IMAGE_POSITION_PATIENT,
            VR::DS,
            dicom_value!(Strs, ["-5".to_string(), "3".to_string(), format!("{z}")]),
        ),
        DataElement::new(
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            dicom_value!(Strs, ["1", "0", "0", "0", "1", "0"]),
        ),
        DataElement::new(tags::RESCALE_SLOPE, VR::DS, "2"),
        DataElement::new(tags::RESCALE_INTERCEPT, VR::DS, "-1024"),
        DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::from(pixels)),
    ]);
    let file = obj
        .with_meta(
            FileMetaTableBuilder::new()
                .transfer_syntax(syntax)
                .media_storage_sop_class_uid("1.2.840.10008.5.1.4.1.1.2")
                .media_storage_sop_instance_uid(format!("1.2.3.{}", base + 1000)),
        )
        .unwrap();
    let mut out = Vec::new();
    file.write_all(&mut out).unwrap();
    out
}

#[test]
fn a_series_stacks_by_position_with_the_rescale() {
    let explicit = "1.2.840.10008.1.2.1";
    // Given out of order: z = 15, 10, 12.5.
    let files = [
        slice(15.0, 300, explicit),
        slice(10.0, -100, explicit),
        slice(12.5, 100, "1.2.840.10008.1.2"),
    ];
    let refs: Vec<&[u8]> = files.iter().map(|f| f.as_slice()).collect();
    let v = load::dicom(&refs).unwrap();
    assert_eq!(v.dims, [4, 3, 3]);
    // PixelSpacing is (between rows, between columns): x gets the second.
    assert!(
        v.spacing.abs_diff_eq(Vec3::new(0.7, 0.6, 2.5), 1e-6),
        "{}",
        v.spacing
    );
    assert_eq!(v.origin, Vec3::new(-5.0, 3.0, 10.0));
    for (z, base) in [-100i32, 100, 300].into_iter().enumerate() {
        for i in 0..12 {
            let want = (base + i) as f32 * 2.0 - 1024.0;
            assert_eq!(v.values[z * 12 + i as usize], want, "slice {z} pixel {i}");
        }
    }
}

#[test]
fn what_cannot_be_stacked_is_a_typed_error() {
    let ok = "1.2.840.10008.1.2.1";
    let uneven = [slice(0.0, 0, ok), slice(1.0, 0, ok), slice(5.0, 0, ok)];
    let refs: Vec<&[u8]> = uneven.iter().map(|f| f.as_slice()).collect();
    let e = load::dicom(&refs).unwrap_err();
    assert!(e.to_string().contains("evenly spaced"), "{e}");
    let jpeg = [slice(0.0, 0, "1.2.840.10008.1.2.4.50")];
    let refs: Vec<&[u8]> = jpeg.iter().map(|f| f.as_slice()).collect();
    let e = load::dicom(&refs).unwrap_err();
    assert!(e.to_string().contains("transfer syntax"), "{e}");
    assert!(load::dicom(&[]).is_err());
    assert!(load::dicom(&[b"not dicom at all".as_slice()]).is_err());
}
