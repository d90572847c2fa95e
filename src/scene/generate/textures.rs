//! Procedural textures for the generated scenes, encoded as PNG: the emissive shop-sign
//! atlas (block letters from a built-in 5×7 font), an alpha-masked wrought-iron railing,
//! alpha-masked foliage, cobblestones, paving slabs and an alpha checkerboard. Colours are
//! authored in sRGB as glTF requires for base-colour and emissive textures; the means the
//! writer needs for emitted power are computed in linear space.

use super::rng::Rng;
use super::GenerateError;

pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub fn linear_to_srgb(x: f32) -> u8 {
    let x = x.clamp(0.0, 1.0);
    let c = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round() as u8
}

pub struct Image {
    pub width: u32,
    pub height: u32,
    /// RGBA8, row-major, top row first.
    pub pixels: Vec<u8>,
    pub has_alpha: bool,
}

impl Image {
    fn new(width: u32, height: u32, has_alpha: bool, fill: [u8; 4]) -> Self {
        Image {
            width,
            height,
            pixels: fill.repeat((width * height) as usize),
            has_alpha,
        }
    }
    fn set(&mut self, x: u32, y: u32, c: [u8; 4]) {
        let i = ((y * self.width + x) * 4) as usize;
        self.pixels[i..i + 4].copy_from_slice(&c);
    }
    fn get(&self, x: u32, y: u32) -> [u8; 4] {
        let i = ((y * self.width + x) * 4) as usize;
        [
            self.pixels[i],
            self.pixels[i + 1],
            self.pixels[i + 2],
            self.pixels[i + 3],
        ]
    }

    /// Mean linear RGB value (averaged over channels) of the pixel rectangle.
    pub fn linear_mean(&self, x0: u32, y0: u32, x1: u32, y1: u32) -> f32 {
        let mut sum = 0.0f64;
        for y in y0..y1 {
            for x in x0..x1 {
                let p = self.get(x, y);
                sum += (0..3).map(|k| srgb_to_linear(p[k]) as f64).sum::<f64>() / 3.0;
            }
        }
        (sum / ((x1 - x0) * (y1 - y0)) as f64) as f32
    }

    pub fn png(&self) -> Result<Vec<u8>, GenerateError> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        let enc = image::codecs::png::PngEncoder::new_with_quality(
            &mut out,
            image::codecs::png::CompressionType::Best,
            image::codecs::png::FilterType::Adaptive,
        );
        let result = if self.has_alpha {
            enc.write_image(
                &self.pixels,
                self.width,
                self.height,
                image::ExtendedColorType::Rgba8,
            )
        } else {
            let rgb: Vec<u8> = self
                .pixels
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            enc.write_image(
                &rgb,
                self.width,
                self.height,
                image::ExtendedColorType::Rgb8,
            )
        };
        result.map_err(|e| GenerateError::Texture(e.to_string()))?;
        Ok(out)
    }
}

/// 5×7 glyphs, one string of 35 cells per letter ('#' lit).
fn glyph(c: char) -> &'static str {
    match c {
        'A' => ".###.#...##...#######...##...##...#",
        'B' => "####.#...##...#####.#...##...#####.",
        'C' => ".#####....#....#....#....#.....####",
        'E' => "######....#....####.#....#....#####",
        'F' => "######....#....####.#....#....#....",
        'H' => "#...##...##...#######...##...##...#",
        'I' => ".###...#....#....#....#....#...###.",
        'J' => "..###...#....#....#....#.#..#..##..",
        'L' => "#....#....#....#....#....#....#####",
        'N' => "#...###..##.#.##..###...##...##...#",
        'O' => ".###.#...##...##...##...##...#.###.",
        'P' => "####.#...##...#####.#....#....#....",
        'R' => "####.#...##...#####.#.#..#..#.#...#",
        'S' => ".#####....#.....###.....#....#####.",
        'T' => "#####..#....#....#....#....#....#..",
        'U' => "#...##...##...##...##...##...#.###.",
        'V' => "#...##...##...##...#.#.#..#.#...#..",
        'Z' => "#####....#...#...#...#...#....#####",
        _ => "...................................",
    }
}

fn glyph_bit(c: char, x: u32, y: u32) -> bool {
    glyph(c).as_bytes().get((y * 5 + x) as usize) == Some(&b'#')
}

pub struct SignAtlas {
    pub image: Image,
    pub rows: u32,
    /// Mean linear value of each sign's region, for emitted power.
    pub means: Vec<f32>,
}

/// One sign per atlas row (256×64 texels each; rows padded to a power of two): a coloured word in a coloured frame on a
/// dark ground.
pub fn sign_atlas(signs: &[(&str, [f32; 3])]) -> SignAtlas {
    let rows = signs.len().next_power_of_two().max(1) as u32;
    let (w, row_h) = (256u32, 64u32);
    let mut img = Image::new(w, rows * row_h, false, [8, 6, 6, 255]);
    let mut means = Vec::new();
    for (r, (word, color)) in signs.iter().enumerate() {
        let y0 = r as u32 * row_h;
        let lit = [
            linear_to_srgb(color[0]),
            linear_to_srgb(color[1]),
            linear_to_srgb(color[2]),
            255,
        ];
        for x in 3..w - 3 {
            for t in [3, 4, row_h - 5, row_h - 4] {
                img.set(x, y0 + t, lit);
            }
        }
        for y in 3..row_h - 3 {
            for t in [3, 4, w - 5, w - 4] {
                img.set(t, y0 + y, lit);
            }
        }
        let scale = 6u32;
        let advance = 6 * scale;
        let text_w = word.len() as u32 * advance - scale;
        let x0 = (w - text_w) / 2;
        for (i, c) in word.chars().enumerate() {
            for gy in 0..7 * scale {
                for gx in 0..5 * scale {
                    if glyph_bit(c, gx / scale, gy / scale) {
                        img.set(x0 + i as u32 * advance + gx, y0 + 11 + gy, lit);
                    }
                }
            }
        }
        means.push(img.linear_mean(0, y0, w, y0 + row_h));
    }
    SignAtlas {
        image: img,
        rows,
        means,
    }
}

/// A wrought-iron railing: top and bottom rails, bars, and a ring between each pair of
/// bars; everything else fully transparent (alpha 0).
pub fn railing() -> Image {
    let n = 64u32;
    let iron = [28, 30, 32, 255];
    let mut img = Image::new(n, n, true, [0, 0, 0, 0]);
    for y in 0..n {
        for x in 0..n {
            let rail = y < 5 || (n - 6..n - 1).contains(&y);
            let bar = x % 16 < 3;
            let (dx, dy) = (((x + 8) % 16) as f32 - 9.5, y as f32 - 32.0);
            let ring = ((dx * dx + dy * dy).sqrt() - 5.0).abs() < 1.3;
            if rail || bar || ring {
                img.set(x, y, iron);
            }
        }
    }
    img
}

/// Leaves: overlapping ellipses in shades of green, transparent between them.
pub fn foliage(rng: &mut Rng) -> Image {
    let n = 128u32;
    let mut img = Image::new(n, n, true, [0, 0, 0, 0]);
    for _ in 0..260 {
        let (cx, cy) = (rng.range(0.0, n as f32), rng.range(0.0, n as f32));
        let (a, b) = (rng.range(4.0, 8.0), rng.range(1.8, 3.2));
        let ang = rng.range(0.0, std::f32::consts::PI);
        let shade = rng.range(0.5, 1.0);
        let c = [
            (40.0 * shade) as u8,
            (110.0 * shade) as u8,
            (35.0 * shade) as u8,
            255,
        ];
        for y in (cy - a) as i32..=(cy + a) as i32 {
            for x in (cx - a) as i32..=(cx + a) as i32 {
                let (dx, dy) = (x as f32 - cx, y as f32 - cy);
                let (u, v) = (
                    dx * ang.cos() + dy * ang.sin(),
                    -dx * ang.sin() + dy * ang.cos(),
                );
                if (u / a).powi(2) + (v / b).powi(2) <= 1.0 {
                    img.set(
                        x.rem_euclid(n as i32) as u32,
                        y.rem_euclid(n as i32) as u32,
                        c,
                    );
                }
            }
        }
    }
    img
}

/// Cobblestones on a jittered grid (a tileable Voronoi pattern) with dark joints.
pub fn cobbles(rng: &mut Rng) -> Image {
    let (n, cells) = (256u32, 8i32);
    let cell = n as f32 / cells as f32;
    let mut centres = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            let c = [
                (i as f32 + rng.range(0.2, 0.8)) * cell,
                (j as f32 + rng.range(0.2, 0.8)) * cell,
            ];
            centres.push((c, rng.range(0.75, 1.25)));
        }
    }
    let mut img = Image::new(n, n, false, [0, 0, 0, 255]);
    for y in 0..n {
        for x in 0..n {
            let (mut d1, mut d2, mut shade) = (f32::MAX, f32::MAX, 1.0);
            for (c, s) in &centres {
                for (ox, oy) in [
                    (0.0, 0.0),
                    (n as f32, 0.0),
                    (-(n as f32), 0.0),
                    (0.0, n as f32),
                    (0.0, -(n as f32)),
                ] {
                    let d =
                        ((x as f32 - c[0] - ox).powi(2) + (y as f32 - c[1] - oy).powi(2)).sqrt();
                    if d < d1 {
                        (d2, d1, shade) = (d1, d, *s);
                    } else if d < d2 {
                        d2 = d;
                    }
                }
            }
            let col = if d2 - d1 < 2.5 {
                [0.05, 0.045, 0.04]
            } else {
                [0.2 * shade, 0.18 * shade, 0.16 * shade]
            };
            img.set(
                x,
                y,
                [
                    linear_to_srgb(col[0]),
                    linear_to_srgb(col[1]),
                    linear_to_srgb(col[2]),
                    255,
                ],
            );
        }
    }
    img
}

/// Square paving slabs with slightly different shades and thin joints.
pub fn paving(rng: &mut Rng) -> Image {
    let (n, slabs) = (128u32, 4u32);
    let shades: Vec<f32> = (0..slabs * slabs).map(|_| rng.range(0.85, 1.15)).collect();
    let mut img = Image::new(n, n, false, [0, 0, 0, 255]);
    let s = n / slabs;
    for y in 0..n {
        for x in 0..n {
            let joint = x % s < 2 || y % s < 2;
            let k = shades[((y / s) * slabs + x / s) as usize];
            let v = if joint { 0.12 } else { 0.4 * k };
            img.set(
                x,
                y,
                [
                    linear_to_srgb(v),
                    linear_to_srgb(v * 0.97),
                    linear_to_srgb(v * 0.92),
                    255,
                ],
            );
        }
    }
    img
}

/// An n×n checkerboard of opaque (black) and fully transparent cells.
pub fn alpha_checker(n: u32, cell: u32) -> Image {
    let mut img = Image::new(n * cell, n * cell, true, [0, 0, 0, 0]);
    for y in 0..n * cell {
        for x in 0..n * cell {
            if (x / cell + y / cell) % 2 == 0 {
                img.set(x, y, [0, 0, 0, 255]);
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_have_35_cells() {
        for c in "ABCEFHIJLNOPRSTUVZ".chars() {
            assert_eq!(glyph(c).len(), 35, "glyph {c}");
            assert!(glyph(c).contains('#'));
        }
    }

    #[test]
    fn srgb_round_trips() {
        for v in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(v)), v);
        }
    }
}
