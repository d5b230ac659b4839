//! The 2D tool's exports (issue 24, seed 003): a 16-bit PNG whose text chunks hold the scale, a
//! float PFM, and a normalised 8-bit picture, of a field computed on the GPU. Decoded here with
//! the `png` crate and by hand, against the formulas the docs state.

use crate::common;

use common::upload_2d;
use fieldkit::distance::{Distance2d, FAR, Settings2d, export};
use fieldkit::gpu::{Context, read_texture};

const W: u32 = 29;
const H: u32 = 17;

fn field(ctx: &Context) -> Vec<f32> {
    let mut mask = vec![0u8; (W * H) as usize];
    for y in 5..11 {
        for x in 8..19 {
            mask[(y * W + x) as usize] = 255;
        }
    }
    let tex = upload_2d(ctx, [W, H], wgpu::TextureFormat::R8Unorm, &mask);
    let d2 = Distance2d::new(&ctx.device).unwrap();
    let mut enc = ctx.encoder("export");
    let f = d2
        .encode(
            &ctx.device,
            &mut enc,
            &tex,
            &Settings2d {
                signed: true,
                texel_size: 0.25,
                ..Settings2d::default()
            },
        )
        .unwrap();
    ctx.submit_and_wait("export", enc).unwrap();
    read_texture(ctx, &f.distance).unwrap()
}

fn decode(bytes: &[u8]) -> (png::OutputInfo, Vec<u8>, Vec<(String, String)>) {
    let mut reader = png::Decoder::new(std::io::Cursor::new(bytes.to_vec()))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let text = reader
        .info()
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.clone(), t.text.clone()))
        .collect();
    buf.truncate(info.buffer_size());
    (info, buf, text)
}

#[test]
fn png16_holds_the_field_and_its_scale() {
    let ctx = Context::shared();
    let d = field(&ctx);
    let range = 4.0;
    let bytes = export::png16(&d, W, H, range).unwrap();
    let (info, buf, text) = decode(&bytes);
    assert_eq!((info.width, info.height), (W, H));
    assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
    assert_eq!(info.color_type, png::ColorType::Grayscale);
    let written: f32 = text
        .iter()
        .find(|(k, _)| k == export::RANGE_KEY)
        .map(|(_, v)| v.parse().unwrap())
        .expect("the range is written down");
    assert_eq!(written, range);
    assert!(
        text.iter()
            .any(|(k, v)| k == export::DECODE_KEY && v.contains("65535"))
    );
    let step = range / 32767.5;
    for (i, &want) in d.iter().enumerate() {
        let v = u16::from_be_bytes([buf[2 * i], buf[2 * i + 1]]);
        // d = (v / 65535 − ½) · 2 · range, within half a step.
        let got = (v as f64 / 65535.0 - 0.5) * 2.0 * written as f64;
        assert!(
            (got - want as f64).abs() <= 0.5 * step as f64 + 1e-6,
            "texel {i}: {got} vs {want}"
        );
        assert_eq!(export::decode16(v, range), got as f32);
    }
    // Zero at mid-grey; the ends saturate.
    assert_eq!(export::code16(0.0, range), 32768);
    assert_eq!(export::code16(-10.0, range), 0);
    assert_eq!(export::code16(FAR, range), 65535);
    assert!(export::png16(&d, W, H, 0.0).is_err());
    assert!(export::png16(&d[1..], W, H, 1.0).is_err());
}

#[test]
fn pfm_holds_the_floats_bottom_row_first() {
    let ctx = Context::shared();
    let d = field(&ctx);
    let bytes = export::pfm(&d, W, H).unwrap();
    let header = format!("Pf\n{W} {H}\n-1.0\n");
    assert!(bytes.starts_with(header.as_bytes()));
    let body = &bytes[header.len()..];
    assert_eq!(body.len(), d.len() * 4);
    for y in 0..H as usize {
        for x in 0..W as usize {
            // PFM rows run bottom-up.
            let at = ((H as usize - 1 - y) * W as usize + x) * 4;
            let v = f32::from_le_bytes(body[at..at + 4].try_into().unwrap());
            assert_eq!(v.to_bits(), d[y * W as usize + x].to_bits());
        }
    }
    // Signed: negative inside the rectangle (0.25 world units a texel).
    assert!(d.iter().any(|&v| v < 0.0) && d.iter().any(|&v| v > 1.0));
}

#[test]
fn png8_is_normalised_from_black_to_white() {
    let ctx = Context::shared();
    let d = field(&ctx);
    let (info, buf, _) = decode(&export::png8(&d, W, H).unwrap());
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let (lo, hi) = d
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    for (i, &v) in d.iter().enumerate() {
        let want = ((v - lo) / (hi - lo) * 255.0).round() as u8;
        assert_eq!(buf[i], want, "texel {i}");
    }
    assert!(buf.contains(&0) && buf.contains(&255));
}
