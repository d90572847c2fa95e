//! The comparison's results as data: one [`Record`] per method and budget, with each
//! metric's ratio to `pt` at the same budget, serialised as `report.json` and
//! `report.csv` (the comparison writes them, with the figures and the HTML page).

use std::fmt::Write as _;

use super::compare_types::Crop;

/// One render's measurements.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Record {
    pub method: String,
    /// `spp` (equal samples) or `time` (equal wall-clock seconds).
    pub budget_kind: String,
    /// The budget: samples per pixel, or seconds.
    pub budget: f64,
    /// Samples per pixel reached.
    pub spp: u64,
    /// Wall-clock seconds of rendering only (training included).
    pub render_seconds: f64,
    /// Scene load + acceleration-structure build seconds.
    pub setup_seconds: f64,
    pub gpu_seconds: Option<f64>,
    pub training_seconds: Option<f64>,
    pub mae: f64,
    pub relmse: f64,
    /// `mae / mae(pt)` at the same budget; `None` without a `pt` record there.
    pub mae_ratio_to_pt: Option<f64>,
    pub relmse_ratio_to_pt: Option<f64>,
    /// The render's EXR relative to the report directory, when saved.
    pub image: Option<String>,
}

/// The whole comparison (`report.json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Report {
    /// lanterna version.
    pub version: String,
    pub scene: String,
    pub reference: String,
    pub reference_spp: Option<u64>,
    pub width: u32,
    pub height: u32,
    pub methods: Vec<String>,
    /// The budget the grid's images were rendered at (e.g. `10 s`).
    pub grid_budget: String,
    pub crop: Option<Crop>,
    pub records: Vec<Record>,
}

/// Sets each record's ratios to the `pt` record of the same budget kind and value.
pub fn fill_ratios(records: &mut [Record]) {
    let pts: Vec<Record> = records
        .iter()
        .filter(|r| r.method == "pt")
        .cloned()
        .collect();
    for r in records.iter_mut() {
        let pt = pts
            .iter()
            .find(|p| p.budget_kind == r.budget_kind && p.budget == r.budget);
        let ratio = |a: f64, b: f64| if b > 0.0 { Some(a / b) } else { None };
        r.mae_ratio_to_pt = pt.and_then(|p| ratio(r.mae, p.mae));
        r.relmse_ratio_to_pt = pt.and_then(|p| ratio(r.relmse, p.relmse));
    }
}

/// CSV with a header row; numbers in Rust's shortest round-trip form, empty cells for
/// missing values, RFC 4180 quoting.
pub fn to_csv(report: &Report) -> String {
    fn cell(s: &str) -> String {
        if s.contains([',', '"', '\n']) {
            format!("\"{}\"", s.replace('"', "\"\""))
        } else {
            s.to_string()
        }
    }
    let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    let mut out = String::from(
        "method,budget_kind,budget,spp,render_seconds,setup_seconds,gpu_seconds,\
         training_seconds,mae,relmse,mae_ratio_to_pt,relmse_ratio_to_pt,image\n",
    );
    for r in &report.records {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            cell(&r.method),
            r.budget_kind,
            r.budget,
            r.spp,
            r.render_seconds,
            r.setup_seconds,
            opt(r.gpu_seconds),
            opt(r.training_seconds),
            r.mae,
            r.relmse,
            opt(r.mae_ratio_to_pt),
            opt(r.relmse_ratio_to_pt),
            cell(r.image.as_deref().unwrap_or(""))
        );
    }
    out
}

/// The budget of a record as [`super::compare_types::Budget`]'s `Display` writes it.
pub fn budget_label(r: &Record) -> String {
    match r.budget_kind.as_str() {
        "spp" => format!("{} spp", r.budget as u64),
        _ => format!("{} s", r.budget),
    }
}
