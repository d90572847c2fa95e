//! Minimal stand-in for the image I/O module (replaced by the full one): PNG output and
//! a plain RGB EXR, with the same signatures.

use std::collections::BTreeMap;
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: {message}")]
    Io { path: String, message: String },
    #[error("{0}")]
    Shape(String),
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderMeta {
    pub spp: Option<u64>,
    pub sample_offset: Option<u64>,
    pub method: Option<String>,
    pub seed: Option<u64>,
    pub max_depth: Option<u32>,
    pub render_seconds: Option<f64>,
    pub device: Option<String>,
    pub scene_path: Option<String>,
    pub scene_hash: Option<String>,
    pub version: Option<String>,
    pub extra: BTreeMap<String, String>,
}

impl RenderMeta {
    pub fn new() -> Self {
        RenderMeta::default()
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<[f32; 3]>,
    pub sums: Option<Vec<[u64; 3]>>,
    pub meta: RenderMeta,
}

impl Image {
    pub fn from_sums(
        width: u32,
        height: u32,
        sums: Vec<[u64; 3]>,
        meta: RenderMeta,
    ) -> Result<Image, ImageError> {
        let spp = meta.spp.unwrap_or(1).max(1);
        let rgb = sums
            .iter()
            .map(|s| {
                s.map(|v| (v as f64 / crate::gpu::FILM_FIXED_SCALE as f64 / spp as f64) as f32)
            })
            .collect();
        Ok(Image {
            width,
            height,
            rgb,
            sums: Some(sums),
            meta,
        })
    }
}

pub fn write_exr(path: &Path, image: &Image) -> Result<(), ImageError> {
    let w = image.width as usize;
    exr::prelude::write_rgb_file(path, w, image.height as usize, |x, y| {
        let p = image.rgb[y * w + x];
        (p[0], p[1], p[2])
    })
    .map_err(|e| ImageError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}

pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    let scale = 2f32.powf(exposure);
    let enc = |c: f32| {
        let c = (c * scale).clamp(0.0, 1.0);
        let s = if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5) as u8
    };
    let bytes: Vec<u8> = image.rgb.iter().flat_map(|p| p.map(enc)).collect();
    image::save_buffer(
        path,
        &bytes,
        image.width,
        image.height,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| ImageError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    })
}
