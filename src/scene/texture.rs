//! Decoded textures: RGBA texels with their colour encoding and sampler, plus a CPU
//! lookup used to estimate the power of emissive-textured triangles.

use crate::vk::{SamplerDesc, Texels, TextureFormat, WrapMode};

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
    pub texels: Texels,
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

/// Convert decoded glTF image data to RGBA texels: 8-bit images stay 8 bits per channel,
/// 16-bit ones keep all 16 (until 2026-11-29 they were rounded to 8, which an independent
/// glTF reader saw: a 16-bit texture's image 0.2 % bright against Mitsuba, which reads all
/// 16 bits, when the high byte was taken, and one block off at t = 14 when rounded).
/// Grey spreads over R, G and B; a missing alpha is opaque.
pub fn to_texels(data: &gltf::image::Data) -> Option<Texels> {
    use gltf::image::Format as F;
    let px = (data.width as usize).checked_mul(data.height as usize)?;
    let p = &data.pixels;
    let u16_at = |i: usize| u16::from_le_bytes([p[2 * i], p[2 * i + 1]]);
    // Float images (not from PNG or JPEG) to the nearest 16-bit code.
    let f32_at = |i: usize| {
        let v = f32::from_le_bytes([p[4 * i], p[4 * i + 1], p[4 * i + 2], p[4 * i + 3]]);
        (v.clamp(0.0, 1.0) * 65535.0 + 0.5) as u16
    };
    let (channels, wide) = match data.format {
        F::R8 => (1, false),
        F::R8G8 => (2, false),
        F::R8G8B8 => (3, false),
        F::R8G8B8A8 => (4, false),
        F::R16 => (1, true),
        F::R16G16 => (2, true),
        F::R16G16B16 => (3, true),
        F::R16G16B16A16 => (4, true),
        F::R32G32B32FLOAT => (3, true),
        F::R32G32B32A32FLOAT => (4, true),
    };
    let bytes_per_value = match data.format {
        F::R32G32B32FLOAT | F::R32G32B32A32FLOAT => 4,
        _ if wide => 2,
        _ => 1,
    };
    if p.len() != px * channels * bytes_per_value {
        return None;
    }
    // RGBA from a pixel's channels: grey → (g, g, g), grey + alpha → (g, g, g, a).
    fn rgba<T: Copy>(c: &[T], opaque: T) -> [T; 4] {
        match c.len() {
            1 => [c[0], c[0], c[0], opaque],
            2 => [c[0], c[0], c[0], c[1]],
            3 => [c[0], c[1], c[2], opaque],
            _ => [c[0], c[1], c[2], c[3]],
        }
    }
    Some(if !wide {
        Texels::Rgba8(
            p.chunks_exact(channels)
                .flat_map(|c| rgba(c, 255))
                .collect(),
        )
    } else {
        let values: Vec<u16> = if bytes_per_value == 4 {
            (0..px * channels).map(f32_at).collect()
        } else {
            (0..px * channels).map(u16_at).collect()
        };
        Texels::Rgba16(
            values
                .chunks_exact(channels)
                .flat_map(|c| rgba(c, u16::MAX))
                .collect(),
        )
    })
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

/// Texel index `i` of `n` along an axis, wrapped as the sampler's mode says.
fn wrap_index(i: i64, n: u32, mode: WrapMode) -> u32 {
    let n = i64::from(n);
    let i = match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::ClampToEdge => i.clamp(0, n - 1),
        WrapMode::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    };
    i as u32
}

impl TextureData {
    /// Nearest texel at `uv`, decoded to linear RGBA.
    pub fn texel(&self, uv: [f32; 2]) -> [f32; 4] {
        let u = wrap(uv[0], self.sampler.wrap_u);
        let v = wrap(uv[1], self.sampler.wrap_v);
        let x = ((u * self.width as f32) as u32).min(self.width - 1);
        let y = ((v * self.height as f32) as u32).min(self.height - 1);
        let i = ((y * self.width + x) * 4) as usize;
        let c = |k: usize| self.texels.unorm(i + k);
        let s = |k: usize| self.texels.srgb(i + k);
        match self.format {
            TextureFormat::Srgb => [s(0), s(1), s(2), c(3)],
            TextureFormat::Linear => [c(0), c(1), c(2), c(3)],
        }
    }

    /// The bilinear filter at `uv`, as the GPU's sampler takes it (texel centres at
    /// half-integers, the sampler's wrap mode per axis), of the texels decoded to linear
    /// RGBA.
    pub fn bilinear(&self, uv: [f32; 2]) -> [f32; 4] {
        let taps = |t: f32, n: u32, mode: WrapMode| {
            let x = t * n as f32 - 0.5;
            let x0 = x.floor();
            let f = x - x0;
            let i = x0 as i64;
            [
                (wrap_index(i, n, mode), 1.0 - f),
                (wrap_index(i + 1, n, mode), f),
            ]
        };
        let xs = taps(uv[0], self.width, self.sampler.wrap_u);
        let ys = taps(uv[1], self.height, self.sampler.wrap_v);
        let mut out = [0.0; 4];
        for (y, wy) in ys {
            for (x, wx) in xs {
                let c = self.texel([
                    (x as f32 + 0.5) / self.width as f32,
                    (y as f32 + 0.5) / self.height as f32,
                ]);
                for k in 0..4 {
                    out[k] += wx * wy * c[k];
                }
            }
        }
        out
    }

    /// Largest linear luminance over all texels (0 means the texture is black).
    pub fn max_luminance(&self) -> f32 {
        let decode = |i: usize| match self.format {
            TextureFormat::Srgb => self.texels.srgb(i),
            TextureFormat::Linear => self.texels.unorm(i),
        };
        (0..self.texels.len() / 4)
            .map(|p| {
                0.2126 * decode(4 * p) + 0.7152 * decode(4 * p + 1) + 0.0722 * decode(4 * p + 2)
            })
            .fold(0.0, f32::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CPU's bilinear filter (the export's cut of a bilinear MASK) samples as the GPU
    /// does: texel centres at half-integers, and each wrap mode's neighbour past the edge.
    #[test]
    fn bilinear_filter_matches_the_samplers_rules() {
        let texture = |wrap: WrapMode| TextureData {
            name: "ramp".into(),
            width: 4,
            height: 1,
            // Red 0, 1/3, 2/3, 1 (as 8-bit codes), linear.
            texels: Texels::Rgba8(
                [0u8, 85, 170, 255]
                    .iter()
                    .flat_map(|&r| [r, 0, 0, 255])
                    .collect(),
            ),
            format: TextureFormat::Linear,
            sampler: SamplerDesc {
                wrap_u: wrap,
                wrap_v: wrap,
                nearest: false,
            },
        };
        let red = |t: &TextureData, u: f32| t.bilinear([u, 0.5])[0];
        let close = |a: f32, b: f32| (a - b).abs() < 1e-6;
        for wrap in [
            WrapMode::Repeat,
            WrapMode::ClampToEdge,
            WrapMode::MirroredRepeat,
        ] {
            let t = texture(wrap);
            // At a texel centre, its own value; halfway between two, their mean.
            assert!(close(red(&t, 0.375), 1.0 / 3.0), "{wrap:?}");
            assert!(close(red(&t, 0.5), 0.5), "{wrap:?}");
            assert!(close(red(&t, 0.3125), 0.25), "{wrap:?}");
        }
        // Left of the first centre: the neighbour is the last texel (repeat), the first
        // itself (clamp and mirror).
        assert!(close(red(&texture(WrapMode::Repeat), 0.0), 0.5));
        assert!(close(red(&texture(WrapMode::ClampToEdge), 0.0), 0.0));
        assert!(close(red(&texture(WrapMode::MirroredRepeat), 0.0), 0.0));
        // Past the right edge: repeat starts over, clamp holds, mirror walks back.
        assert!(close(red(&texture(WrapMode::Repeat), 1.125), 0.0));
        assert!(close(red(&texture(WrapMode::ClampToEdge), 1.125), 1.0));
        assert!(close(
            red(&texture(WrapMode::MirroredRepeat), 1.375),
            2.0 / 3.0
        ));
    }
}
