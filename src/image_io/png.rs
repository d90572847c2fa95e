//! Tonemapped 8-bit sRGB PNGs for viewing.

use std::path::Path;

use super::*;

/// Display mapping of one linear value scaled by `2^exposure`: clamp to [0, 1], sRGB
/// OETF, 8 bits with rounding. Non-finite values never reach here (see [`tonemap`]).
fn encode_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// The colour non-finite pixels are shown in, so that they stand out.
pub const NONFINITE_COLOR: [u8; 3] = [255, 0, 255];

/// Tonemaps linear RGB to 8-bit sRGB: multiply by `2^exposure`, clamp, sRGB OETF. A pixel
/// with any NaN/±Inf channel becomes magenta ([`NONFINITE_COLOR`]).
pub fn tonemap(rgb: &[[f32; 3]], exposure: f32) -> Vec<[u8; 3]> {
    let scale = exposure.exp2();
    rgb.iter()
        .map(|p| {
            if p.iter().all(|v| v.is_finite()) {
                p.map(|v| encode_srgb8(v * scale))
            } else {
                NONFINITE_COLOR
            }
        })
        .collect()
}

/// Encodes an 8-bit RGB buffer as PNG at `path` (temp file + rename).
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb8: &[u8]) -> Result<(), ImageError> {
    let bytes = encode_png_rgb8(width, height, rgb8).map_err(|e| match e {
        ImageError::Png { reason, .. } => ImageError::Png {
            path: path.to_path_buf(),
            reason,
        },
        e => e,
    })?;
    write_atomically(path, &bytes)
}

/// Encodes an 8-bit RGB buffer as PNG in memory (errors name no file).
pub fn encode_png_rgb8(width: u32, height: u32, rgb8: &[u8]) -> Result<Vec<u8>, ImageError> {
    use image::ImageEncoder;
    if rgb8.len() != width as usize * height as usize * 3 {
        return Err(ImageError::Shape(format!(
            "{width}x{height} RGB8 buffer has {} bytes",
            rgb8.len()
        )));
    }
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgb8, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| ImageError::Png {
            path: PathBuf::new(),
            reason: e.to_string(),
        })?;
    Ok(bytes)
}

/// Writes the tonemapped image (see [`tonemap`]) as an 8-bit sRGB PNG. Non-finite pixels
/// are drawn magenta and reported in the summary (and logged as a warning).
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<WriteSummary, ImageError> {
    image.check_shape()?;
    let summary = summarize(image, path);
    let bytes: Vec<u8> = tonemap(&image.rgb, exposure)
        .into_iter()
        .flatten()
        .collect();
    write_png_rgb8(path, image.width, image.height, &bytes)?;
    Ok(summary)
}
