//! Decoded textures: RGBA8 pixels with their colour encoding and sampler, plus a CPU
//! lookup used to estimate the power of emissive-textured triangles.

use crate::vk::{srgb_decode, SamplerDesc, TextureFormat, WrapMode};

/// Identifies one GPU texture: the same glTF image used as colour and as data, or with
/// two samplers, becomes two textures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureKey {
    pub image: usize,
    pub format: TextureFormat,
    pub sampler: SamplerDesc,
}

/// A texture ready for upload.
#[derive(Clone)]
pub struct TextureData {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub format: TextureFormat,
    pub sampler: SamplerDesc,
}

impl std::fmt::Debug for TextureData {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "TextureData({} {}x{} {:?})",
            self.name, self.width, self.height, self.format
        )
    }
}

/// Convert decoded glTF image data to RGBA8.
pub fn to_rgba8(data: &gltf::image::Data) -> Option<Vec<u8>> {
    use gltf::image::Format as F;
    let px = (data.width * data.height) as usize;
    let p = &data.pixels;
    // The nearest 8-bit code, round(v · 255 / 65535): exact for samples widened from 8
    // bits (v = 257 k), where the high byte alone was up to one code off (a 16-bit
    // texture's image 0.2 % bright against Mitsuba, which reads all 16 bits).
    let u16_at = |i: usize| {
        let v = u32::from(u16::from_le_bytes([p[2 * i], p[2 * i + 1]]));
        ((v * 255 + 32767) / 65535) as u8
    };
    let f32_at = |i: usize| {
        let v = f32::from_le_bytes([p[4 * i], p[4 * i + 1], p[4 * i + 2], p[4 * i + 3]]);
        (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    };
    let mut out = Vec::with_capacity(px * 4);
    for i in 0..px {
        let rgba = match data.format {
            F::R8 => [p[i], p[i], p[i], 255],
            F::R8G8 => [p[2 * i], p[2 * i], p[2 * i], p[2 * i + 1]],
            F::R8G8B8 => [p[3 * i], p[3 * i + 1], p[3 * i + 2], 255],
            F::R8G8B8A8 => [p[4 * i], p[4 * i + 1], p[4 * i + 2], p[4 * i + 3]],
            F::R16 => {
                let v = u16_at(i);
                [v, v, v, 255]
            }
            F::R16G16 => [
                u16_at(2 * i),
                u16_at(2 * i),
                u16_at(2 * i),
                u16_at(2 * i + 1),
            ],
            F::R16G16B16 => [u16_at(3 * i), u16_at(3 * i + 1), u16_at(3 * i + 2), 255],
            F::R16G16B16A16 => [
                u16_at(4 * i),
                u16_at(4 * i + 1),
                u16_at(4 * i + 2),
                u16_at(4 * i + 3),
            ],
            F::R32G32B32FLOAT => [f32_at(3 * i), f32_at(3 * i + 1), f32_at(3 * i + 2), 255],
            F::R32G32B32A32FLOAT => [
                f32_at(4 * i),
                f32_at(4 * i + 1),
                f32_at(4 * i + 2),
                f32_at(4 * i + 3),
            ],
        };
        out.extend_from_slice(&rgba);
    }
    (out.len() == px * 4).then_some(out)
}

fn wrap(t: f32, mode: WrapMode) -> f32 {
    match mode {
        WrapMode::Repeat => t - t.floor(),
        WrapMode::ClampToEdge => t.clamp(0.0, 1.0),
        WrapMode::MirroredRepeat => {
            let m = t.rem_euclid(2.0);
            if m > 1.0 {
                2.0 - m
            } else {
                m
            }
        }
    }
}

impl TextureData {
    /// Nearest texel at `uv`, decoded to linear RGBA.
    pub fn texel(&self, uv: [f32; 2]) -> [f32; 4] {
        let u = wrap(uv[0], self.sampler.wrap_u);
        let v = wrap(uv[1], self.sampler.wrap_v);
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        let i = ((y * self.width + x) * 4) as usize;
        let c = |k: usize| self.rgba[i + k] as f32 / 255.0;
        let s = |k: usize| srgb_decode(self.rgba[i + k]);
        match self.format {
            TextureFormat::Srgb => [s(0), s(1), s(2), c(3)],
            TextureFormat::Linear => [c(0), c(1), c(2), c(3)],
        }
    }

    /// Largest linear luminance over all texels (0 means the texture is black).
    pub fn max_luminance(&self) -> f32 {
        let lut: Vec<f32> = (0..=255u8)
            .map(|v| match self.format {
                TextureFormat::Srgb => srgb_decode(v),
                TextureFormat::Linear => v as f32 / 255.0,
            })
            .collect();
        self.rgba
            .chunks_exact(4)
            .map(|p| {
                0.2126 * lut[p[0] as usize]
                    + 0.7152 * lut[p[1] as usize]
                    + 0.0722 * lut[p[2] as usize]
            })
            .fold(0.0, f32::max)
    }
}
