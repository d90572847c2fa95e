//! The render metadata an image carries (method, seed, spp, sample ranges, settings, …)
//! and the text form of sample ranges.

use std::collections::BTreeMap;
use std::ops::Range;

use super::VERSION;

/// Extra key recording the sample ranges of a merge whose ranges are not contiguous.
pub const SAMPLE_RANGES_KEY: &str = "sample_ranges";

/// A render's metadata. Every field is optional because foreign EXRs carry none of it;
/// lanterna's renders fill all but `extra`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderMeta {
    /// Samples per pixel in this image.
    pub spp: Option<u64>,
    /// Index of the first sample: the image holds samples `[sample_offset, sample_offset + spp)`.
    pub sample_offset: Option<u64>,
    /// `pt`, `ris`, `guided`, `guided-ris`.
    pub method: Option<String>,
    pub seed: Option<u64>,
    /// Path segments, as in Mitsuba 3.
    pub max_depth: Option<u32>,
    /// Wall-clock seconds spent rendering (for merges, the sum).
    pub render_seconds: Option<f64>,
    pub device: Option<String>,
    pub scene_path: Option<String>,
    /// An identifier of the scene content given by the renderer; merges refuse mismatches.
    pub scene_hash: Option<String>,
    /// lanterna version that wrote the image.
    pub version: Option<String>,
    /// Free-form key/values (keys: 1–200 printable ASCII characters).
    pub extra: BTreeMap<String, String>,
}

impl RenderMeta {
    /// Empty metadata stamped with this lanterna version.
    pub fn new() -> Self {
        RenderMeta {
            version: Some(VERSION.to_string()),
            ..Default::default()
        }
    }

    /// The sample indices this image holds: `extra["sample_ranges"]` when a merge of
    /// non-contiguous ranges wrote it, else `[sample_offset, sample_offset + spp)` with a
    /// missing offset read as 0. `None` when `spp` is unknown or the ranges are malformed.
    pub fn sample_ranges(&self) -> Option<Vec<Range<u64>>> {
        if let Some(text) = self.extra.get(SAMPLE_RANGES_KEY) {
            return parse_ranges(text);
        }
        let spp = self.spp?;
        let start = self.sample_offset.unwrap_or(0);
        let end = start.checked_add(spp)?;
        Some(vec![Range { start, end }])
    }
}

/// Formats sample ranges as `a..b,c..d` (the `sample_ranges` extra key).
pub fn format_ranges(ranges: &[Range<u64>]) -> String {
    ranges
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect::<Vec<_>>()
        .join(",")
}

/// Parses `a..b,c..d`; `None` if malformed or a range is empty.
pub fn parse_ranges(text: &str) -> Option<Vec<Range<u64>>> {
    text.split(',')
        .map(|part| {
            let (a, b) = part.trim().split_once("..")?;
            let (a, b) = (a.parse::<u64>().ok()?, b.parse::<u64>().ok()?);
            (a < b).then_some(a..b)
        })
        .collect()
}
