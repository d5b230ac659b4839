//! The 2D distance scenes: the test picture (shapes and the word FIELDKIT) and the field drawn with the visualize stage.

use super::*;

/// 5×7 glyphs for the letters of "FIELDKIT", one row per byte, high bit left.
pub(crate) const GLYPHS: &[(char, [u8; 7])] = &[
    (
        'F',
        [
            0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000,
        ],
    ),
    (
        'I',
        [
            0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b11111,
        ],
    ),
    (
        'E',
        [
            0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b11111,
        ],
    ),
    (
        'L',
        [
            0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b10000, 0b11111,
        ],
    ),
    (
        'D',
        [
            0b11110, 0b10001, 0b10001, 0b10001, 0b10001, 0b10001, 0b11110,
        ],
    ),
    (
        'K',
        [
            0b10001, 0b10010, 0b10100, 0b11000, 0b10100, 0b10010, 0b10001,
        ],
    ),
    (
        'T',
        [
            0b11111, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100, 0b00100,
        ],
    ),
];

/// A recognisable mask: a circle, a ring, a rotated box, a triangle and the word FIELDKIT.
pub fn shapes_mask(width: u32, height: u32) -> Vec<u8> {
    let (w, h) = (width as f32, height as f32);
    let mut m = vec![0u8; (width * height) as usize];
    for y in 0..height {
        for x in 0..width {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let circle = ((px - 0.16 * w).powi(2) + (py - 0.3 * h).powi(2)).sqrt() < 0.11 * h;
            let r = ((px - 0.42 * w).powi(2) + (py - 0.3 * h).powi(2)).sqrt();
            let ring = r > 0.07 * h && r < 0.13 * h;
            let (bx, by) = (px - 0.66 * w, py - 0.3 * h);
            let (c, s) = (0.5f32.cos(), 0.5f32.sin());
            let (rx, ry) = (c * bx + s * by, -s * bx + c * by);
            let boxed = rx.abs() < 0.09 * h && ry.abs() < 0.06 * h;
            let (tx, ty) = (px - 0.87 * w, py - 0.3 * h);
            let tri = ty < 0.1 * h && ty > -0.12 * h + 1.8 * tx.abs();
            if circle || ring || boxed || tri {
                m[(y * width + x) as usize] = 255;
            }
        }
    }
    // The word, scaled to fill the lower half.
    let text = "FIELDKIT";
    let scale = ((0.9 * w) / (text.len() as f32 * 6.0))
        .min(0.4 * h / 7.0)
        .floor()
        .max(1.0) as u32;
    let x0 = (width - text.len() as u32 * 6 * scale) / 2;
    let y0 = (0.55 * h) as u32;
    for (i, ch) in text.chars().enumerate() {
        let glyph = GLYPHS
            .iter()
            .find(|g| g.0 == ch)
            .map(|g| g.1)
            .unwrap_or([0; 7]);
        for (row, bits) in glyph.iter().enumerate() {
            for col in 0..5 {
                if bits & (1 << (4 - col)) == 0 {
                    continue;
                }
                for sy in 0..scale {
                    for sx in 0..scale {
                        let x = x0 + (i as u32 * 6 + col) * scale + sx;
                        let y = y0 + row as u32 * scale + sy;
                        if x < width && y < height {
                            m[(y * width + x) as usize] = 255;
                        }
                    }
                }
            }
        }
    }
    m
}

/// Colour-map a distance texture (`R32Float`) with iso-lines into RGBA8 pixels.
pub fn visualize_distance(
    ctx: &Context,
    distance: &wgpu::Texture,
    spacing: f32,
    range: f32,
) -> Result<Vec<u8>, Error> {
    if !(spacing.is_finite() && spacing > 0.0 && range.is_finite() && range > 0.0) {
        return Err(Error::Invalid {
            stage: visualize::STAGE,
            what: format!("spacing {spacing} and range {range} must be finite and positive"),
        });
    }
    let device = &ctx.device;
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let pipeline: RenderPipeline<visualize::fs_main::Entry> = RenderPipeline::new(
        device,
        &RenderTargets {
            color: &[Some(format.into())],
            ..Default::default()
        },
    )?;
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("gallery target"),
        size: distance.size(),
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let params = fieldkit::gpu::uniform_buffer(
        device,
        "view params",
        &visualize::ViewParams { spacing, range },
    );
    let dv = distance.create_view(&Default::default());
    let bound = pipeline.bind(
        device,
        &visualize::fs_main::Resources {
            params: (&params).into(),
            distance: (&dv).into(),
        },
    )?;
    let tv = target.create_view(&Default::default());
    let mut enc = ctx.encoder("visualize");
    {
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visualize"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &tv,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&pipeline.pipeline);
        bound.set_render(&mut pass);
        pass.draw(0..3, 0..1);
    }
    ctx.submit_and_wait(visualize::STAGE, enc)?;
    let px: Vec<[u8; 4]> = read_texture(ctx, &target)?;
    Ok(px.concat())
}
