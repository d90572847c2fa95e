//! Texel data for Mitsuba: textures decoded to linear RGB exactly as lanterna's sampler
//! sees them, their average, and the glTF spot falloff baked into a spot texture.

use super::files;
use crate::gpu;
use crate::scene::TextureData;

/// Texels decoded to linear RGB (top row first), exactly as lanterna's sampler sees them.
pub(super) fn linear_texels(tex: &TextureData) -> Vec<[f32; 3]> {
    let (w, h) = (tex.width, tex.height);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let t = tex.texel([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]);
            out.push([t[0], t[1], t[2]]);
        }
    }
    out
}

pub(super) fn average_colour(tex: &TextureData) -> [f32; 3] {
    let texels = linear_texels(tex);
    let n = texels.len().max(1) as f64;
    let mut sum = [0.0f64; 3];
    for t in &texels {
        for c in 0..3 {
            sum[c] += t[c] as f64;
        }
    }
    sum.map(|s| (s / n) as f32)
}

/// The glTF spot falloff, (clamp((cosθ − cos_outer)/(cos_inner − cos_outer)))², on
/// Mitsuba's spot texture parameterisation.
pub(super) fn spot_falloff_pfm(l: &gpu::PunctualLight, outer: f32, res: u32) -> Vec<u8> {
    let tan_c = outer.tan();
    let mut rgb = Vec::with_capacity((res * res) as usize);
    for y in 0..res {
        for x in 0..res {
            let a = (2.0 * (x as f32 + 0.5) / res as f32 - 1.0) * tan_c;
            let b = (2.0 * (y as f32 + 0.5) / res as f32 - 1.0) * tan_c;
            let cos = 1.0 / (1.0 + a * a + b * b).sqrt();
            rgb.push([crate::lights::spot_falloff(l, cos); 3]);
        }
    }
    files::pfm_bytes(res, res, &rgb)
}
