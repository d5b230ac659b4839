//! Real volumes (issue 24, seed 002): NRRD (raw and gzip, both endians, spacing from `spacings`
//! or `space directions`) and fieldkit's raw header, parsed into values written here, then
//! uploaded and read back from the GPU.

use fieldkit::gpu::{Context, read_texture};
use fieldkit::volume::Volume;
use fieldkit::volume::load::{self, RawLayout, Scalar};
use glam::Vec3;

/// A 5 × 3 × 2 volume of distinct values.
fn values() -> Vec<u16> {
    (0..30u16).map(|i| i * 1000 + 7).collect()
}

fn nrrd(header_extra: &str, encoding: &str, big: bool) -> Vec<u8> {
    let mut out = format!(
        "NRRD0004\n# a test volume\ntype: unsigned short\ndimension: 3\nsizes: 5 3 2\n\
         endian: {}\nencoding: {encoding}\n{header_extra}\n\n",
        if big { "big" } else { "little" }
    )
    .into_bytes();
    let data: Vec<u8> = values()
        .iter()
        .flat_map(|v| {
            if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            }
        })
        .collect();
    if encoding == "gzip" {
        use std::io::Write;
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&data).unwrap();
        out.extend(gz.finish().unwrap());
    } else {
        out.extend(data);
    }
    out
}

#[test]
fn nrrd_raw_and_gzip_in_both_endians() {
    let want: Vec<f32> = values().iter().map(|&v| v as f32).collect();
    for (extra, spacing) in [
        ("spacings: 0.5 0.5 2", Vec3::new(0.5, 0.5, 2.0)),
        (
            "space: left-posterior-superior\nspace directions: (-0.7,0,0) (0,0.7,0) (0,0,1.25)\n\
             space origin: (10,-4,3.5)",
            Vec3::new(0.7, 0.7, 1.25),
        ),
    ] {
        for encoding in ["raw", "gzip"] {
            for big in [false, true] {
                let v = load::nrrd(&nrrd(extra, encoding, big)).unwrap();
                assert_eq!(v.dims, [5, 3, 2]);
                assert_eq!(v.values, want, "{encoding} big={big}");
                assert!(v.spacing.abs_diff_eq(spacing, 1e-6), "{}", v.spacing);
                if extra.contains("origin") {
                    assert_eq!(v.origin, Vec3::new(10.0, -4.0, 3.5));
                }
            }
        }
    }
}

#[test]
fn raw_header_and_layout() {
    let data: Vec<u8> = [-1.5f32, 0.0, 2.5, 1e3]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    let mut file = b"fieldkit-raw 1\n# a comment\ndims 2 2 1\ntype float32\nendian big\n\
                     spacing 1 2 3\norigin -1 0 1\n\n"
        .to_vec();
    file.extend(&data);
    let v = load::raw(&file).unwrap();
    assert_eq!(v.values, vec![-1.5, 0.0, 2.5, 1e3]);
    assert_eq!(v.spacing, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(v.origin, Vec3::new(-1.0, 0.0, 1.0));
    let same = load::raw_with(
        &data,
        &RawLayout {
            dims: [2, 2, 1],
            scalar: Scalar::F32,
            big_endian: true,
            spacing: Vec3::new(1.0, 2.0, 3.0),
            origin: Vec3::new(-1.0, 0.0, 1.0),
            skip: 0,
        },
    )
    .unwrap();
    assert_eq!(same, v);
    let n = v.normalised();
    assert_eq!(n.values, vec![0.0, 1.5 / 1001.5, 4.0 / 1001.5, 1.0]);
}

#[test]
fn bad_files_are_typed_errors() {
    let ok = nrrd("spacings: 1 1 1", "raw", false);
    let truncated = &ok[..ok.len() - 1];
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (truncated.to_vec(), "bytes of data"),
        (b"PNG\n\n".to_vec(), "not an NRRD"),
        (
            b"NRRD0004\ntype: float\ndimension: 2\nsizes: 2 2\n\n".to_vec(),
            "only 3D",
        ),
        (
            b"NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 5 3 2\ndata file: x.raw\n\n"
                .to_vec(),
            "detached",
        ),
        (
            b"NRRD0004\ntype: unsigned short\ndimension: 3\nsizes: 5 3 2\nencoding: bzip2\n\n"
                .to_vec(),
            "bzip2",
        ),
        (
            b"NRRD0004\ntype: quaternion\ndimension: 3\nsizes: 5 3 2\n\n".to_vec(),
            "quaternion",
        ),
        (
            b"NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 1\nspace directions: (1,1,0) (0,1,0) (0,0,1)\n\n"
                .to_vec(),
            "not aligned",
        ),
        (b"fieldkit-raw 1\ndims 2 2\ntype uint8\n\n".to_vec(), "3 numbers"),
        (b"fieldkit-raw 1\ndims 2 2 1\n\n\0\0\0\0".to_vec(), "no type"),
        (b"fieldkit-raw 1\ndims 0 2 1\ntype uint8\n\n".to_vec(), "whole numbers"),
    ];
    for (bytes, what) in cases {
        let e = if bytes.starts_with(b"fieldkit") {
            load::raw(&bytes)
        } else {
            load::nrrd(&bytes)
        }
        .expect_err(what);
        assert!(e.to_string().contains(what), "{what}: {e}");
    }
}

/// Loaded, normalised and uploaded as R8Unorm, the texture holds the file's voxels.
#[test]
fn a_loaded_volume_uploads() {
    let ctx = Context::shared();
    let v = load::nrrd(&nrrd("spacings: 0.5 0.5 2", "gzip", true))
        .unwrap()
        .normalised();
    let vol = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &v.values,
        v.dims,
        wgpu::TextureFormat::R8Unorm,
        v.spacing,
        v.origin,
    )
    .unwrap();
    let back: Vec<u8> = read_texture(&ctx, &vol.texture).unwrap();
    let lo = 7.0f32;
    let hi = 29.0 * 1000.0 + 7.0;
    for (i, &b) in back.iter().enumerate() {
        let want = ((values()[i] as f32 - lo) / (hi - lo) * 255.0).round() as u8;
        assert_eq!(b, want, "voxel {i}");
    }
    assert_eq!(vol.bounds().1, Vec3::new(2.5, 1.5, 4.0));
}

/// A volume larger than one upload slab (256 KiB) arrives whole: 72×72×61 R8 voxels go up in
/// slabs of 50 and 11 z slices, and every voxel reads back as written, the slabs' seam too.
#[test]
fn a_volume_of_several_upload_slabs_arrives_whole() {
    let ctx = Context::shared();
    let dims = [72u32, 72, 61];
    let code = |i: usize| ((i * 7 + i / 72 * 3 + i / (72 * 72) * 5) % 256) as u8;
    let n = dims.iter().product::<u32>() as usize;
    let values: Vec<f32> = (0..n).map(|i| code(i) as f32 / 255.0).collect();
    let vol = Volume::upload(
        &ctx.device,
        &ctx.queue,
        &values,
        dims,
        wgpu::TextureFormat::R8Unorm,
        Vec3::ONE,
        Vec3::ZERO,
    )
    .unwrap();
    let back: Vec<u8> = read_texture(&ctx, &vol.texture).unwrap();
    assert_eq!(back.len(), n);
    for (i, &b) in back.iter().enumerate() {
        assert_eq!(b, code(i), "voxel {i} (z {})", i / (72 * 72));
    }
}
