//! The three images: S0 in sRGB, degree of polarization (grey), angle of
//! polarization (hue = angle, brightness = degree).

use std::path::Path;

use crate::adapter::srgb8;

/// Per pixel: balanced XYZ, and the ȳ-weighted Stokes vector in the camera frame.
#[derive(Clone, Copy, Default)]
pub(crate) struct Pixel {
    pub(crate) xyz: [f32; 3],
    pub(crate) stokes: [f32; 4],
}

/// Writes `s0.png`, `dop.png` and `aop.png` of `pixels` (`width × height`, rows top down) into
/// `dir`; the S0 exposure maps the 99th percentile of luminance to 0.9.
pub(crate) fn write_images(
    dir: &Path,
    width: usize,
    height: usize,
    pixels: &[Pixel],
) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut lum: Vec<f32> = pixels.iter().map(|p| p.xyz[1].max(0.0)).collect();
    lum.sort_by(f32::total_cmp);
    let p99 = lum[(lum.len() * 99 / 100).min(lum.len() - 1)].max(1e-12);
    let exposure = 0.9 / p99;
    let mut s0 = Vec::with_capacity(pixels.len() * 3);
    let mut dop = Vec::with_capacity(pixels.len() * 3);
    let mut aop = Vec::with_capacity(pixels.len() * 3);
    for p in pixels {
        s0.extend(srgb8(p.xyz.map(|c| c * exposure)));
        let [i, q, u, v] = p.stokes;
        let d = if i > 0.0 {
            ((q * q + u * u + v * v).sqrt() / i).min(1.0)
        } else {
            0.0
        };
        let grey = (d * 255.0 + 0.5) as u8;
        dop.extend([grey; 3]);
        let angle = 0.5 * u.atan2(q); // −π/2 .. π/2 from the image's horizontal
        aop.extend(hsv(
            angle.rem_euclid(std::f32::consts::PI) / std::f32::consts::PI,
            d,
        ));
    }
    for (name, data) in [("s0.png", s0), ("dop.png", dop), ("aop.png", aop)] {
        let file = std::io::BufWriter::new(std::fs::File::create(dir.join(name))?);
        let mut enc = png::Encoder::new(file, width as u32, height as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header()?.write_image_data(&data)?;
    }
    Ok(())
}

/// Full-saturation colour of hue `h` ∈ [0, 1) and value `v`.
fn hsv(h: f32, v: f32) -> [u8; 3] {
    let h6 = h * 6.0;
    let f = h6 - h6.floor();
    let (r, g, b) = match h6 as u32 % 6 {
        0 => (1.0, f, 0.0),
        1 => (1.0 - f, 1.0, 0.0),
        2 => (0.0, 1.0, f),
        3 => (0.0, 1.0 - f, 1.0),
        4 => (f, 0.0, 1.0),
        _ => (1.0, 0.0, 1.0 - f),
    };
    let to = |c: f32| (c * v * 255.0 + 0.5) as u8;
    [to(r), to(g), to(b)]
}
