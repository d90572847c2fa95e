//! Log–log plots of error against samples per pixel and against render time, one line
//! per method, drawn with plotters into an RGB buffer (embedded font, no system fonts)
//! and saved as PNG.

use std::path::Path;

use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;

use super::compare_types::CompareError;
use super::fonts;
use super::report::{Record, Report};
use super::text::TextBackend;
use crate::image_io::write_png_rgb8;

/// Plot size in pixels.
pub const PLOT_SIZE: (u32, u32) = (960, 640);
/// Right margin of the ratio plots, where their legend goes.
const LEGEND_WIDTH: u32 = 250;

/// What the horizontal axis shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Samples per pixel reached; drawn from the equal-spp records (or, with none, the
    /// equal-time ones).
    Spp,
    /// Render seconds; drawn from the equal-time records (or, with none, the equal-spp
    /// ones, whose measured times are just as valid).
    Seconds,
}

/// A stable colour per method, so every figure agrees.
pub fn method_color(method: &str, index: usize) -> RGBColor {
    match method {
        "pt" => RGBColor(90, 90, 90),
        "ris" => RGBColor(31, 119, 180),
        "guided" => RGBColor(255, 127, 14),
        "guided-ris" => RGBColor(214, 39, 40),
        _ => {
            let c = Palette99::pick(index + 4).to_rgba();
            RGBColor(c.0, c.1, c.2)
        }
    }
}

/// The (x, MAE) points of one method for `axis`, sorted by x, positive values only.
pub fn series(report: &Report, method: &str, axis: Axis) -> Vec<(f64, f64)> {
    let primary = match axis {
        Axis::Spp => "spp",
        Axis::Seconds => "time",
    };
    let has_primary = report.records.iter().any(|r| r.budget_kind == primary);
    let x_of = |r: &Record| match axis {
        Axis::Spp => r.spp as f64,
        Axis::Seconds => r.render_seconds,
    };
    let mut points: Vec<(f64, f64)> = report
        .records
        .iter()
        .filter(|r| r.method == method && (r.budget_kind == primary) == has_primary)
        .map(|r| (x_of(r), r.mae))
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    points
}

/// A log range around `[lo, hi]` with a little margin.
fn log_bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = values.fold((f64::INFINITY, 0f64), |(l, h), v| (l.min(v), h.max(v)));
    if !lo.is_finite() || hi <= 0.0 {
        return (1.0, 10.0);
    }
    if hi / lo < 2.0 {
        lo /= 1.5;
        hi *= 1.5;
    }
    (lo / 1.25, hi * 1.25)
}

/// Draws MAE against `axis` for every method of the report and writes the PNG.
pub fn write_error_plot(path: &Path, report: &Report, axis: Axis) -> Result<(), CompareError> {
    let (w, h) = PLOT_SIZE;
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    draw(&mut buffer, report, axis).map_err(|problem| CompareError::Figure {
        path: path.to_path_buf(),
        problem,
    })?;
    write_png_rgb8(path, w, h, &buffer)?;
    Ok(())
}

fn draw(buffer: &mut [u8], report: &Report, axis: Axis) -> Result<(), String> {
    fonts::ensure_registered();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let root = TextBackend::with_buffer(buffer, PLOT_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let lines: Vec<(String, Vec<(f64, f64)>)> = report
        .methods
        .iter()
        .map(|m| (m.clone(), series(report, m, axis)))
        .collect();
    let (x_lo, x_hi) = log_bounds(lines.iter().flat_map(|(_, p)| p.iter().map(|q| q.0)));
    let (y_lo, y_hi) = log_bounds(lines.iter().flat_map(|(_, p)| p.iter().map(|q| q.1)));
    let (caption, x_desc) = match axis {
        Axis::Spp => ("MAE vs samples per pixel", "samples per pixel"),
        Axis::Seconds => (
            "MAE vs render time",
            "render time (s, excluding scene setup)",
        ),
    };
    let caption = format!("{caption} — {}", report.scene);
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, (fonts::FAMILY, 26))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(90)
        .build_cartesian_2d(
            (x_lo..x_hi)
                .log_scale()
                .with_key_points(log_ticks(x_lo, x_hi, axis == Axis::Spp))
                .with_light_points(log_ticks(x_lo, x_hi, false)),
            (y_lo..y_hi)
                .log_scale()
                .with_key_points(log_ticks(y_lo, y_hi, false))
                .with_light_points(light_ticks(y_lo, y_hi)),
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("MAE (mean |x − ref| over pixels and RGB)")
        .label_style((fonts::FAMILY, 16))
        .axis_desc_style((fonts::FAMILY, 18))
        .x_label_formatter(&|v| format_tick(*v))
        .y_label_formatter(&|v| format_tick(*v))
        .draw()
        .map_err(|x| e(&x))?;
    let mut any = false;
    for (i, (method, points)) in lines.iter().enumerate() {
        if points.is_empty() {
            continue;
        }
        any = true;
        let color = method_color(method, i);
        chart
            .draw_series(LineSeries::new(
                points.iter().copied(),
                color.stroke_width(3),
            ))
            .map_err(|x| e(&x))?
            .label(method.as_str())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(3))
            });
        chart
            .draw_series(points.iter().map(|&p| Circle::new(p, 5, color.filled())))
            .map_err(|x| e(&x))?;
    }
    if any {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((fonts::FAMILY, 18))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|x| e(&x))?;
    } else {
        root.draw_text(
            "no data",
            &(fonts::FAMILY, 28).into_text_style(&root),
            (PLOT_SIZE.0 as i32 / 2 - 50, PLOT_SIZE.1 as i32 / 2),
        )
        .map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}

/// Labelled ticks in `[lo, hi]`: powers of two (for spp, when there are few enough), else
/// 1, 2, 5 × 10^k, densified to every integer mantissa when that gives too few.
fn log_ticks(lo: f64, hi: f64, powers_of_two: bool) -> Vec<f64> {
    if powers_of_two {
        let ticks: Vec<f64> = (0..64)
            .map(|k| 2f64.powi(k))
            .filter(|v| *v >= lo && *v <= hi)
            .collect();
        if (2..=14).contains(&ticks.len()) {
            return ticks;
        }
    }
    for mantissas in [
        &[1.0, 2.0, 5.0][..],
        &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0][..],
    ] {
        let ticks = decade_ticks(lo, hi, mantissas);
        if ticks.len() >= 4 {
            return ticks;
        }
    }
    decade_ticks(lo, hi, &[1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

/// Unlabelled grid lines: every integer mantissa of every decade.
fn light_ticks(lo: f64, hi: f64) -> Vec<f64> {
    decade_ticks(lo, hi, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
}

fn decade_ticks(lo: f64, hi: f64, mantissas: &[f64]) -> Vec<f64> {
    let first = lo.log10().floor() as i32;
    let last = hi.log10().ceil() as i32;
    (first..=last)
        .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
        .filter(|v| *v >= lo && *v <= hi)
        .collect()
}

/// Tick labels that read naturally on a log axis: integers as integers, else 3 digits.
fn format_tick(v: f64) -> String {
    if v >= 1.0 && (v - v.round()).abs() < 1e-9 * v {
        format!("{}", v.round() as u64)
    } else if v >= 0.001 {
        format!("{}", (v * 1e4).round() / 1e4)
    } else {
        format!("{v:.1e}")
    }
}

/// One line of a ratio plot: `marker` picks the point shape (0 circles, 1 triangles,
/// 2 squares), so lines of the same colour from different scenes stay apart.
#[derive(Clone, Debug)]
pub struct RatioLine {
    pub label: String,
    pub color: RGBColor,
    pub marker: usize,
    pub points: Vec<(f64, f64)>,
}

/// Ratios (linear y) against a log x axis, with horizontal guide lines (value, label);
/// used by the bench's training-scale trend.
pub fn write_ratio_plot(
    path: &Path,
    title: &str,
    x_desc: &str,
    lines: &[RatioLine],
    guides: &[(f64, String)],
) -> Result<(), CompareError> {
    let (w, h) = PLOT_SIZE;
    let mut buffer = vec![0u8; (w * h * 3) as usize];
    draw_ratios(&mut buffer, title, x_desc, lines, guides).map_err(|problem| {
        CompareError::Figure {
            path: path.to_path_buf(),
            problem,
        }
    })?;
    write_png_rgb8(path, w, h, &buffer)?;
    Ok(())
}

/// A ratio line's marker at `at` (in any coordinates): 0 a disc, 1 a triangle, else a
/// cross; the same on the plot and in its legend.
fn marker<DB: DrawingBackend, C: Clone + 'static>(
    at: C,
    kind: usize,
    color: RGBColor,
) -> DynElement<'static, DB, C>
where
    Circle<C, i32>: Drawable<DB>,
    TriangleMarker<C, i32>: Drawable<DB>,
    Cross<C, i32>: Drawable<DB>,
    for<'b> &'b Circle<C, i32>: PointCollection<'b, C>,
    for<'b> &'b TriangleMarker<C, i32>: PointCollection<'b, C>,
    for<'b> &'b Cross<C, i32>: PointCollection<'b, C>,
{
    match kind {
        0 => Circle::new(at, 5, color.filled()).into_dyn(),
        1 => TriangleMarker::new(at, 7, color.filled()).into_dyn(),
        _ => Cross::new(at, 6, color.stroke_width(2)).into_dyn(),
    }
}

fn draw_ratios(
    buffer: &mut [u8],
    title: &str,
    x_desc: &str,
    lines: &[RatioLine],
    guides: &[(f64, String)],
) -> Result<(), String> {
    fonts::ensure_registered();
    let e = |e: &dyn std::fmt::Display| e.to_string();
    let root = TextBackend::with_buffer(buffer, PLOT_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(&x))?;
    let xs = || lines.iter().flat_map(|l| l.points.iter().map(|p| p.0));
    let (x_lo, x_hi) = log_bounds(xs());
    let ys = lines
        .iter()
        .flat_map(|l| l.points.iter().map(|p| p.1))
        .chain(guides.iter().map(|g| g.0));
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    let (y_lo, y_hi) = if lo.is_finite() && hi.is_finite() {
        ((lo - 0.1).max(0.0), hi + 0.1)
    } else {
        (0.0, 1.5)
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (fonts::FAMILY, 24))
        .margin(16)
        // Room for the legend right of the plot, where it hides no line or guide label.
        .margin_right(LEGEND_WIDTH)
        .x_label_area_size(56)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x_lo..x_hi)
                .log_scale()
                .with_key_points(log_ticks(x_lo, x_hi, false))
                .with_light_points(light_ticks(x_lo, x_hi)),
            y_lo..y_hi,
        )
        .map_err(|x| e(&x))?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("MAE ratio")
        .label_style((fonts::FAMILY, 16))
        .axis_desc_style((fonts::FAMILY, 18))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|x| e(&x))?;
    for (value, label) in guides {
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                [(x_lo, *value), (x_hi, *value)],
                8,
                6,
                grey.stroke_width(1),
            ))
            .map_err(|x| e(&x))?;
        chart
            .draw_series(std::iter::once(Text::new(
                label.clone(),
                (x_lo * 1.05, *value + 0.04 * (y_hi - y_lo)),
                (fonts::FAMILY, 14).into_font().color(&grey),
            )))
            .map_err(|x| e(&x))?;
    }
    for line in lines {
        if line.points.is_empty() {
            continue;
        }
        let color = line.color;
        chart
            .draw_series(LineSeries::new(
                line.points.iter().copied(),
                color.stroke_width(2),
            ))
            .map_err(|x| e(&x))?;
        chart
            .draw_series(line.points.iter().map(|&p| marker(p, line.marker, color)))
            .map_err(|x| e(&x))?;
    }
    // The legend, right of the plot where it hides no line or guide label, with each
    // line's marker (which tells the scenes apart).
    let x0 = (PLOT_SIZE.0 - LEGEND_WIDTH) as i32 + 8;
    let font = (fonts::FAMILY, 16).into_font();
    for (i, line) in lines.iter().filter(|l| !l.points.is_empty()).enumerate() {
        let (y, color) = (80 + 26 * i as i32, line.color);
        root.draw(&PathElement::new(
            vec![(x0, y), (x0 + 28, y)],
            color.stroke_width(2),
        ))
        .map_err(|x| e(&x))?;
        let at = (x0 + 14, y);
        root.draw(&marker(at, line.marker, color))
            .map_err(|x| e(&x))?;
        root.draw(&Text::new(
            line.label.clone(),
            (x0 + 36, y - 9),
            font.clone(),
        ))
        .map_err(|x| e(&x))?;
    }
    root.present().map_err(|x| e(&x))?;
    Ok(())
}
