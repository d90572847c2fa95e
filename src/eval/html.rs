//! `index.html`: one self-contained page with the comparison's table and figures, the
//! PNGs inlined as base64 data URIs so it opens offline and can be mailed as one file.

use std::fmt::Write as _;
use std::path::Path;

use super::compare_types::CompareError;
use super::report::{budget_label, Report};
use crate::image_io::write_atomically;

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const TABLE: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let v = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(TABLE[(v >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&#39;")
}

fn opt(v: Option<f64>, fmt: impl Fn(f64) -> String) -> String {
    v.map(fmt).unwrap_or_else(|| "—".into())
}

/// Writes the page; the figures are read from `dir` (written before this).
pub fn write_index(path: &Path, report: &Report, dir: &Path) -> Result<(), CompareError> {
    let mut html = String::new();
    let title = format!("lanterna comparison — {}", report.scene);
    let _ = write!(
        html,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>{}</title>\n<style>\
         body{{font-family:sans-serif;margin:2em;color:#222}}\
         table{{border-collapse:collapse;font-size:14px}}\
         th,td{{border:1px solid #ccc;padding:3px 8px;text-align:right}}\
         th{{background:#f0f0f0}} td.m{{text-align:left;font-weight:bold}}\
         td.best{{background:#dff0d8}} img{{max-width:100%;border:1px solid #ddd}}\
         </style></head><body>\n<h1>{}</h1>\n",
        escape(&title),
        escape(&title)
    );
    let _ = writeln!(
        html,
        "<p>Reference: <code>{}</code> ({}x{}{}). lanterna {}. MAE is the mean of |x − ref| \
         over pixels and RGB channels; relMSE the mean of (x − ref)² / (ref² + 0.01). \
         Ratios are to <code>pt</code> at the same budget (below 1 is better).</p>",
        escape(&report.reference),
        report.width,
        report.height,
        report
            .reference_spp
            .map(|s| format!(", {s} spp"))
            .unwrap_or_default(),
        escape(&report.version)
    );

    html.push_str(
        "<h2>Results</h2>\n<table>\n<tr><th>budget</th><th>method</th><th>spp</th>\
         <th>render s</th><th>setup s</th><th>GPU s</th><th>training s</th><th>MAE</th>\
         <th>MAE / pt</th><th>relMSE</th><th>relMSE / pt</th></tr>\n",
    );
    for r in &report.records {
        let label = budget_label(r);
        let best = report
            .records
            .iter()
            .filter(|o| budget_label(o) == label && o.budget_kind == r.budget_kind)
            .all(|o| o.mae >= r.mae);
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"m\">{}</td><td>{}</td><td>{:.3}</td><td>{:.3}</td>\
             <td>{}</td><td>{}</td><td{}>{:.4e}</td><td>{}</td><td>{:.4e}</td><td>{}</td></tr>",
            escape(&label),
            escape(&r.method),
            r.spp,
            r.render_seconds,
            r.setup_seconds,
            opt(r.gpu_seconds, |v| format!("{v:.3}")),
            opt(r.training_seconds, |v| format!("{v:.3}")),
            if best { " class=\"best\"" } else { "" },
            r.mae,
            opt(r.mae_ratio_to_pt, |v| format!("{v:.3}")),
            r.relmse,
            opt(r.relmse_ratio_to_pt, |v| format!("{v:.3}")),
        );
    }
    html.push_str("</table>\n");

    for (file, heading) in [
        ("mae_vs_spp.png", "MAE vs samples per pixel"),
        ("mae_vs_time.png", "MAE vs render time"),
        ("grid.png", "Images at the grid budget"),
    ] {
        let png = dir.join(file);
        let bytes = std::fs::read(&png).map_err(|error| CompareError::Io {
            path: png.clone(),
            error,
        })?;
        let extra = if file == "grid.png" {
            format!(" ({})", escape(&report.grid_budget))
        } else {
            String::new()
        };
        let _ = writeln!(
            html,
            "<h2>{heading}{extra}</h2>\n<p><img alt=\"{file}\" src=\"data:image/png;base64,{}\"></p>",
            base64(&bytes)
        );
    }
    html.push_str(
        "<p>Data: <a href=\"report.json\">report.json</a>, <a href=\"report.csv\">report.csv</a>.</p>\n\
         </body></html>\n",
    );
    write_atomically(path, html.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_rfc4648_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected);
        }
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    #[test]
    fn escaping() {
        assert_eq!(
            escape("<a href=\"x\">&'"),
            "&lt;a href=&quot;x&quot;&gt;&amp;&#39;"
        );
    }
}
