//! The comparison figure: the reference and each method's render side by side (tonemapped,
//! labelled with the MAE), under them false-colour maps of the absolute error on one
//! shared scale with a colour bar, and optionally a row of zoomed crops of one region.
//! Panels are composited into an RGB buffer, then plotters draws the text on top.

use std::path::Path;

use plotters::prelude::*;

use super::compare_types::{CompareError, Crop};
use super::fonts;
use super::metrics::abs_error_map;
use super::text::TextBackend;
use crate::image_io::{tonemap, write_png_rgb8, Image};

/// One method's column.
pub struct Column<'a> {
    pub label: String,
    pub image: &'a Image,
    pub mae: Option<f64>,
}

/// Panels are scaled to about this width (box-filtered down, or enlarged by whole
/// factors for tiny images so the labels fit).
pub const PANEL_WIDTH: u32 = 320;
const MIN_PANEL_WIDTH: u32 = 200;
const MARGIN: i32 = 12;
const GAP: i32 = 10;
const TITLE_H: i32 = 40;
const LABEL_H: i32 = 46;
const ROW_LABEL_H: i32 = 32;
const BAR_BAND_W: i32 = 120;
/// The error maps' scale saturates at this quantile of all methods' errors.
pub const ERROR_QUANTILE: f64 = 0.99;

/// Viridis' colours at ten evenly spaced points, interpolated linearly.
const VIRIDIS: [[u8; 3]; 10] = [
    [68, 1, 84],
    [72, 40, 120],
    [62, 74, 137],
    [49, 104, 142],
    [38, 130, 142],
    [31, 158, 137],
    [53, 183, 121],
    [109, 205, 89],
    [180, 222, 44],
    [253, 231, 37],
];

/// False colour of `t` in [0, 1] (clamped).
pub fn colormap(t: f32) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        1.0
    };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let (a, b) = (VIRIDIS[i], VIRIDIS[i + 1]);
    [0, 1, 2].map(|c| (f32::from(a[c]) * (1.0 - f) + f32::from(b[c]) * f + 0.5) as u8)
}

/// Resamples region `(x, y, w, h)` of a `width`-wide image to `out_w` × `out_h` by
/// averaging the source pixels each output pixel covers (nearest pixel when enlarging).
fn resample(
    src: &[[f32; 3]],
    width: u32,
    region: (u32, u32, u32, u32),
    out_w: u32,
    out_h: u32,
) -> Vec<[f32; 3]> {
    let (rx, ry, rw, rh) = region;
    let span = |o: u32, out: u32, len: u32, start: u32| {
        let a = start + (u64::from(o) * u64::from(len) / u64::from(out)) as u32;
        let b = start + (u64::from(o + 1) * u64::from(len) / u64::from(out)) as u32;
        (a, b.max(a + 1))
    };
    let mut out = Vec::with_capacity((out_w * out_h) as usize);
    for oy in 0..out_h {
        let (y0, y1) = span(oy, out_h, rh, ry);
        for ox in 0..out_w {
            let (x0, x1) = span(ox, out_w, rw, rx);
            let mut acc = [0f64; 3];
            for y in y0..y1 {
                for x in x0..x1 {
                    let p = src[(y * width + x) as usize];
                    for c in 0..3 {
                        acc[c] += f64::from(p[c]);
                    }
                }
            }
            let k = f64::from((y1 - y0) * (x1 - x0));
            out.push(acc.map(|v| (v / k) as f32));
        }
    }
    out
}

/// The panel size for a `w` × `h` image.
pub fn panel_size(w: u32, h: u32) -> (u32, u32) {
    let pw = if w > PANEL_WIDTH {
        PANEL_WIDTH
    } else if w < MIN_PANEL_WIDTH {
        w * MIN_PANEL_WIDTH.div_ceil(w)
    } else {
        w
    };
    let ph = ((u64::from(h) * u64::from(pw) + u64::from(w) / 2) / u64::from(w)).max(1) as u32;
    (pw, ph)
}

struct Canvas {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Canvas {
    fn blit(&mut self, x: i32, y: i32, w: u32, pixels: &[[u8; 3]]) {
        for (i, p) in pixels.iter().enumerate() {
            let (px, py) = (x + (i as u32 % w) as i32, y + (i as u32 / w) as i32);
            if px >= 0 && py >= 0 && (px as u32) < self.width && (py as u32) < self.height {
                let o = ((py as u32 * self.width + px as u32) * 3) as usize;
                self.rgb[o..o + 3].copy_from_slice(p);
            }
        }
    }
}

fn quantile(mut values: Vec<f32>, q: f64) -> f32 {
    values.retain(|v| v.is_finite());
    if values.is_empty() {
        return 0.0;
    }
    let k = ((values.len() - 1) as f64 * q).round() as usize;
    let (_, v, _) = values.select_nth_unstable_by(k, f32::total_cmp);
    *v
}

/// Draws the grid and writes it as PNG. All images must have the reference's size.
pub fn write_grid(
    path: &Path,
    title: &str,
    reference: &Image,
    columns: &[Column],
    crop: Option<Crop>,
    exposure: f32,
) -> Result<(), CompareError> {
    let figure = |problem: String| CompareError::Figure {
        path: path.to_path_buf(),
        problem,
    };
    let (w, h) = (reference.width, reference.height);
    if let Some(c) = columns
        .iter()
        .find(|c| (c.image.width, c.image.height) != (w, h))
    {
        return Err(figure(format!("{} is not {w}x{h}", c.label)));
    }
    let (pw, ph) = panel_size(w, h);
    let crop_size = crop.map(|c| {
        let ch = ((u64::from(c.h) * u64::from(pw)) / u64::from(c.w)).clamp(1, u64::from(2 * ph));
        (pw, ch as u32)
    });

    // Error maps, on one scale for all methods.
    let errors: Vec<Vec<f32>> = columns
        .iter()
        .map(|c| abs_error_map(&c.image.rgb, &reference.rgb))
        .collect();
    let vmax = quantile(errors.iter().flatten().copied().collect(), ERROR_QUANTILE);
    let vmax = if vmax > 0.0 { vmax } else { 1e-6 };

    let ncols = columns.len() as i32 + 1;
    let row_top = MARGIN + TITLE_H + LABEL_H;
    let err_top = row_top + ph as i32 + ROW_LABEL_H;
    let crop_top = err_top + ph as i32 + ROW_LABEL_H;
    let height = match crop_size {
        Some((_, ch)) => crop_top + ch as i32 + MARGIN,
        None => err_top + ph as i32 + MARGIN,
    };
    let width = MARGIN + ncols * (pw as i32 + GAP) + BAR_BAND_W + MARGIN;
    let mut canvas = Canvas {
        width: width as u32,
        height: height as u32,
        rgb: vec![255; (width * height * 3) as usize],
    };
    let col_x = |i: i32| MARGIN + i * (pw as i32 + GAP);

    let full = (0, 0, w, h);
    let images: Vec<&Image> = std::iter::once(reference)
        .chain(columns.iter().map(|c| c.image))
        .collect();
    for (i, image) in images.iter().enumerate() {
        let x = col_x(i as i32);
        canvas.blit(
            x,
            row_top,
            pw,
            &tonemap(&resample(&image.rgb, w, full, pw, ph), exposure),
        );
        if let (Some(c), Some((cw, ch))) = (crop, crop_size) {
            let region = (c.x, c.y, c.w, c.h);
            canvas.blit(
                x,
                crop_top,
                cw,
                &tonemap(&resample(&image.rgb, w, region, cw, ch), exposure),
            );
        }
        if i == 0 {
            canvas.blit(x, err_top, pw, &vec![[235, 235, 235]; (pw * ph) as usize]);
        } else {
            let err: Vec<[f32; 3]> = errors[i - 1].iter().map(|&e| [e; 3]).collect();
            let small = resample(&err, w, full, pw, ph);
            let colored: Vec<[u8; 3]> = small.iter().map(|p| colormap(p[0] / vmax)).collect();
            canvas.blit(x, err_top, pw, &colored);
        }
    }
    // Colour bar: vmax at the top, 0 at the bottom.
    let bar_x = col_x(ncols) + 4;
    let bar_w = 22u32;
    let bar: Vec<[u8; 3]> = (0..ph)
        .flat_map(|y| {
            let t = 1.0 - y as f32 / (ph.max(2) - 1) as f32;
            std::iter::repeat_n(colormap(t), bar_w as usize)
        })
        .collect();
    canvas.blit(bar_x, err_top, bar_w, &bar);

    fonts::ensure_registered();
    let (cw, chh) = (canvas.width, canvas.height);
    {
        let root = TextBackend::with_buffer(&mut canvas.rgb, (cw, chh)).into_drawing_area();
        let e = |x: &dyn std::fmt::Display| figure(x.to_string());
        let text = |size: u32| (fonts::FAMILY, size).into_font().color(&BLACK);
        root.draw_text(title, &text(22), (MARGIN, MARGIN + 6))
            .map_err(|x| e(&x))?;
        for i in 0..ncols {
            let x = col_x(i);
            let (label, mae) = if i == 0 {
                ("reference".to_string(), None)
            } else {
                let c = &columns[i as usize - 1];
                (c.label.clone(), c.mae)
            };
            root.draw_text(&label, &text(18), (x, MARGIN + TITLE_H))
                .map_err(|x| e(&x))?;
            let sub = match (i, mae) {
                (0, _) => match reference.meta.spp {
                    Some(spp) => format!("{spp} spp"),
                    None => String::new(),
                },
                (_, Some(m)) => format!("MAE {m:.3e}"),
                (_, None) => String::new(),
            };
            root.draw_text(&sub, &text(15), (x, MARGIN + TITLE_H + 22))
                .map_err(|x| e(&x))?;
            if i == 0 {
                root.draw_text("(no error)", &text(14), (x + 8, err_top + 8))
                    .map_err(|x| e(&x))?;
            }
        }
        root.draw_text(
            &format!(
                "absolute error, mean over RGB (scale clamped at the {:.0}th percentile)",
                ERROR_QUANTILE * 100.0
            ),
            &text(15),
            (MARGIN, err_top - ROW_LABEL_H + 8),
        )
        .map_err(|x| e(&x))?;
        let tick_x = bar_x + bar_w as i32 + 6;
        for (t, label) in [(1.0f32, vmax), (0.5, vmax / 2.0), (0.0, 0.0)] {
            let y = err_top + ((1.0 - t) * (ph as f32 - 1.0)) as i32 - 7;
            let label = if label == 0.0 {
                "0".into()
            } else {
                format!("{label:.2e}")
            };
            root.draw_text(&label, &text(13), (tick_x, y.max(err_top - 7)))
                .map_err(|x| e(&x))?;
        }
        root.draw_text("|error|", &text(14), (bar_x, err_top - ROW_LABEL_H + 8))
            .map_err(|x| e(&x))?;
        if let Some(c) = crop {
            let zoom = f64::from(pw) / f64::from(c.w);
            root.draw_text(
                &format!(
                    "crop x={} y={} w={} h={} (zoom {zoom:.1}x)",
                    c.x, c.y, c.w, c.h
                ),
                &text(15),
                (MARGIN, crop_top - ROW_LABEL_H + 8),
            )
            .map_err(|x| e(&x))?;
            // Outline the crop on the reference panel.
            let s = f64::from(pw) / f64::from(w);
            let x0 = MARGIN + (f64::from(c.x) * s) as i32;
            let y0 = row_top + (f64::from(c.y) * s) as i32;
            let x1 = MARGIN + (f64::from(c.x + c.w) * s).ceil() as i32 - 1;
            let y1 = row_top + (f64::from(c.y + c.h) * s).ceil() as i32 - 1;
            root.draw(&Rectangle::new(
                [(x0, y0), (x1, y1)],
                RGBColor(255, 220, 0).stroke_width(2),
            ))
            .map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    write_png_rgb8(path, canvas.width, canvas.height, &canvas.rgb)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colormap_ends_and_clamp() {
        assert_eq!(colormap(0.0), VIRIDIS[0]);
        assert_eq!(colormap(1.0), VIRIDIS[9]);
        assert_eq!(colormap(7.0), VIRIDIS[9]);
        assert_eq!(colormap(-1.0), VIRIDIS[0]);
        assert_eq!(colormap(f32::NAN), VIRIDIS[9]);
    }

    #[test]
    fn resample_box_average_and_nearest() {
        // 4x2 image, values = x + 10 y; 2x1 output averages 2x2 blocks.
        let src: Vec<[f32; 3]> = (0..8)
            .map(|i| [(i % 4) as f32 + 10.0 * (i / 4) as f32; 3])
            .collect();
        let out = resample(&src, 4, (0, 0, 4, 2), 2, 1);
        assert_eq!(out, vec![[5.5; 3], [7.5; 3]]);
        // Enlarging a 1x1 region repeats it.
        let out = resample(&src, 4, (3, 1, 1, 1), 2, 2);
        assert_eq!(out, vec![[13.0; 3]; 4]);
    }

    #[test]
    fn panel_sizes() {
        assert_eq!(panel_size(640, 480), (320, 240));
        assert_eq!(panel_size(32, 24), (224, 168));
        assert_eq!(panel_size(256, 100), (256, 100));
    }

    #[test]
    fn large_image_with_tall_crop_downscales() {
        let (w, h) = (701u32, 301u32);
        let rgb: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [(i % w) as f32 / w as f32, 0.5, 0.25])
            .collect();
        let reference = Image::new(w, h, rgb.clone()).unwrap();
        let noisy =
            Image::new(w, h, rgb.iter().map(|p| [p[0] + 0.1, p[1], p[2]]).collect()).unwrap();
        let columns = [Column {
            label: "pt".into(),
            image: &noisy,
            mae: Some(0.1 / 3.0),
        }];
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("grid.png");
        let crop = Crop {
            x: 700,
            y: 0,
            w: 1,
            h: 301,
        };
        write_grid(&path, "big", &reference, &columns, Some(crop), 0.0).unwrap();
        let png = image::open(&path).unwrap();
        let (pw, ph) = panel_size(w, h);
        assert_eq!((pw, ph), (320, 137));
        assert_eq!(
            png.width() as i32,
            MARGIN + 2 * (pw as i32 + GAP) + BAR_BAND_W + MARGIN
        );
        // The tall crop is capped at twice the panel height.
        let crop_top = MARGIN + TITLE_H + LABEL_H + 2 * (ph as i32 + ROW_LABEL_H);
        assert_eq!(png.height() as i32, crop_top + 2 * ph as i32 + MARGIN);
    }
}
