//! Render images on disk. An [`Image`] is a linear-RGB mean plus, for lanterna's own
//! renders, the film's exact 64-bit fixed-point sums, the render's metadata and any AOV
//! layers; [`write_exr`]/[`read_exr`] store all of it in one single-part OpenEXR file so
//! that chunks of samples can be merged, and references resumed, bit for bit, and
//! [`write_png`] tonemaps for viewing. Layout of the EXR (one part, scan lines, ZIP16):
//!
//! * `R`, `G`, `B` — f32 mean radiance (what any EXR viewer shows);
//! * `film_sum_hi.R|G|B`, `film_sum_lo.R|G|B` — u32 high and low halves of the per-pixel
//!   `u64` sums (`sum = hi << 32 | lo`) in units of `1 / FILM_FIXED_SCALE`, over `spp`
//!   samples: `mean = sum / FILM_FIXED_SCALE / spp` (see [`film_mean`]);
//! * `<aov>.<channel>` — f32 AOV layers (`albedo.R`, `normal.X`, `depth.Z`, …);
//! * header attributes, all prefixed `lanterna.`: integers (`spp`, `sample_offset`,
//!   `seed`, `max_depth`) as decimal text so every `u64` survives exactly, strings as
//!   UTF-8 text, `render_seconds` and `film_scale` as doubles, `resolution` as `WxH`,
//!   `aovs` as `name:C1,C2;name2:…` (the channel order, which EXR's sorting loses),
//!   and each free-form key/value as `lanterna.kv.<key>`.
//!
//! Every write goes to a temporary file in the destination directory and is renamed into
//! place, so a crash never leaves a half-written image under the final name.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::ops::Range;
use std::path::{Path, PathBuf};

use exr::meta::attribute::TextBytes;
use exr::prelude as x;
use exr::prelude::traits::{ReadChannels, ReadLayers, WritableImage};

/// The film's fixed-point scale: one unit of a sum is `1 / FILM_SCALE` of radiance.
pub const FILM_SCALE: f64 = crate::gpu::FILM_FIXED_SCALE as f64;

/// The version of lanterna writing files (stored as `lanterna.version`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

const ATTR_PREFIX: &str = "lanterna.";
const KV_PREFIX: &str = "lanterna.kv.";
const SUM_HI: &str = "film_sum_hi";
const SUM_LO: &str = "film_sum_lo";
/// Extra key recording the sample ranges of a merge whose ranges are not contiguous.
pub const SAMPLE_RANGES_KEY: &str = "sample_ranges";

/// Something went wrong reading or writing an image; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: file not found", path.display())]
    NotFound { path: PathBuf },
    /// Reading or writing the file failed (it names the file and says why).
    #[error(transparent)]
    File(#[from] crate::files::FileError),
    #[error("{}: not an OpenEXR file ({reason})", path.display())]
    NotExr { path: PathBuf, reason: String },
    #[error("{}: missing channel(s) {missing} (channels present: {present})", path.display())]
    MissingChannels {
        path: PathBuf,
        missing: String,
        present: String,
    },
    #[error("{}: {problem}", path.display())]
    Invalid { path: PathBuf, problem: String },
    #[error("{}: PNG encoding failed: {reason}", path.display())]
    Png { path: PathBuf, reason: String },
    /// An in-memory image is inconsistent (wrong buffer length, bad AOV, …).
    #[error("invalid image: {0}")]
    Shape(String),
    /// A pixel value is NaN or infinite where finite values are required.
    #[error("{name}: non-finite value {value} at pixel ({x}, {y}) channel {channel}")]
    NonFinite {
        name: String,
        x: u32,
        y: u32,
        channel: String,
        value: f32,
    },
}

/// Where a non-finite value sits in an image.
#[derive(Clone, Debug, PartialEq)]
pub struct NonFiniteAt {
    pub x: u32,
    pub y: u32,
    /// `R`, `G`, `B`, or `<aov>.<channel>`.
    pub channel: String,
    pub value: f32,
}

/// What a write found worth telling the caller; writes succeed with non-finite values
/// (an EXR can hold them, a PNG shows them magenta) but report them here and warn.
#[derive(Clone, Debug, Default, PartialEq)]
#[must_use = "a write reports non-finite pixels here"]
pub struct WriteSummary {
    /// Number of NaN/±Inf values written (RGB and AOVs).
    pub nonfinite: u64,
    /// The first one in scan-line order.
    pub first_nonfinite: Option<NonFiniteAt>,
}

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

/// A named layer of per-pixel values (albedo, normal, depth, …), 1–4 f32 channels,
/// interleaved per pixel in scan-line order: `data[(y * width + x) * channels.len() + c]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Aov {
    pub name: String,
    pub channels: Vec<String>,
    pub data: Vec<f32>,
}

impl Aov {
    /// Checks the name and channel names (ASCII letters, digits, `_`, `-`; no dots).
    pub fn new(name: &str, channels: &[&str], data: Vec<f32>) -> Result<Aov, ImageError> {
        let aov = Aov {
            name: name.to_string(),
            channels: channels.iter().map(|c| c.to_string()).collect(),
            data,
        };
        aov.check_names()?;
        Ok(aov)
    }

    fn check_names(&self) -> Result<(), ImageError> {
        let ok = |s: &str| {
            !s.is_empty()
                && s.len() <= 64
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        };
        if !ok(&self.name) || self.name == SUM_HI || self.name == SUM_LO {
            return Err(ImageError::Shape(format!("bad AOV name {:?}", self.name)));
        }
        if self.channels.is_empty() || self.channels.len() > 4 {
            return Err(ImageError::Shape(format!(
                "AOV {:?} has {} channels, expected 1 to 4",
                self.name,
                self.channels.len()
            )));
        }
        for (i, c) in self.channels.iter().enumerate() {
            if !ok(c) || self.channels[..i].contains(c) {
                return Err(ImageError::Shape(format!(
                    "AOV {:?}: bad or repeated channel name {c:?}",
                    self.name
                )));
            }
        }
        Ok(())
    }
}

/// A rendered image: see the module comment for how it is stored.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Linear RGB mean, scan-line order from the top-left pixel: `rgb[y * width + x]`.
    pub rgb: Vec<[f32; 3]>,
    /// The film's exact per-pixel sums (units of `1 / FILM_SCALE`) over `meta.spp`
    /// samples, when the image comes from lanterna's film.
    pub sums: Option<Vec<[u64; 3]>>,
    pub meta: RenderMeta,
    pub aovs: Vec<Aov>,
}

/// The one conversion from a film sum to a mean: `sum / FILM_SCALE / spp`, in f64 and
/// rounded once to f32, so every path (render, merge, resume) yields the same bits.
pub fn film_mean(sum: u64, spp: u64) -> f32 {
    (sum as f64 / FILM_SCALE / spp as f64) as f32
}

impl Image {
    /// An image of the given mean values, with `RenderMeta::new()` metadata.
    pub fn new(width: u32, height: u32, rgb: Vec<[f32; 3]>) -> Result<Image, ImageError> {
        let image = Image {
            width,
            height,
            rgb,
            sums: None,
            meta: RenderMeta::new(),
            aovs: Vec::new(),
        };
        image.check_shape()?;
        Ok(image)
    }

    /// An image from the film's exact sums over `meta.spp` samples (which must be set and
    /// positive); the mean is computed with [`film_mean`].
    pub fn from_sums(
        width: u32,
        height: u32,
        sums: Vec<[u64; 3]>,
        meta: RenderMeta,
    ) -> Result<Image, ImageError> {
        let spp = match meta.spp {
            Some(spp) if spp > 0 => spp,
            _ => return Err(ImageError::Shape("film sums need metadata spp > 0".into())),
        };
        let rgb = sums.iter().map(|s| s.map(|v| film_mean(v, spp))).collect();
        let image = Image {
            width,
            height,
            rgb,
            sums: Some(sums),
            meta,
            aovs: Vec::new(),
        };
        image.check_shape()?;
        Ok(image)
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Checks buffer lengths, AOV shapes and names, and that sums come with `spp`.
    pub fn check_shape(&self) -> Result<(), ImageError> {
        let n = self.pixel_count();
        if n == 0 {
            return Err(ImageError::Shape(format!(
                "empty image {}x{}",
                self.width, self.height
            )));
        }
        if self.rgb.len() != n {
            return Err(ImageError::Shape(format!(
                "{}x{} image has {} RGB pixels",
                self.width,
                self.height,
                self.rgb.len()
            )));
        }
        if let Some(sums) = &self.sums {
            if sums.len() != n {
                return Err(ImageError::Shape(format!(
                    "{}x{} image has {} film sums",
                    self.width,
                    self.height,
                    sums.len()
                )));
            }
            if !matches!(self.meta.spp, Some(s) if s > 0) {
                return Err(ImageError::Shape("film sums need metadata spp > 0".into()));
            }
        }
        for (i, aov) in self.aovs.iter().enumerate() {
            aov.check_names()?;
            if self.aovs[..i].iter().any(|a| a.name == aov.name) {
                return Err(ImageError::Shape(format!(
                    "AOV {:?} appears twice",
                    aov.name
                )));
            }
            if aov.data.len() != n * aov.channels.len() {
                return Err(ImageError::Shape(format!(
                    "AOV {:?} has {} values, expected {} ({} pixels x {} channels)",
                    aov.name,
                    aov.data.len(),
                    n * aov.channels.len(),
                    n,
                    aov.channels.len()
                )));
            }
        }
        for key in self.meta.extra.keys() {
            if key.is_empty() || key.len() > 200 || !key.chars().all(|c| c.is_ascii_graphic()) {
                return Err(ImageError::Shape(format!("bad metadata key {key:?}")));
            }
        }
        Ok(())
    }

    /// The first NaN/±Inf in RGB (then AOVs), and how many there are.
    pub fn nonfinite(&self) -> (u64, Option<NonFiniteAt>) {
        let w = self.width as usize;
        let mut count = 0u64;
        let mut first = None;
        let mut note = |index: usize, channel: String, value: f32| {
            count += 1;
            if first.is_none() {
                first = Some(NonFiniteAt {
                    x: (index % w) as u32,
                    y: (index / w) as u32,
                    channel,
                    value,
                });
            }
        };
        for (i, p) in self.rgb.iter().enumerate() {
            for (c, v) in p.iter().enumerate() {
                if !v.is_finite() {
                    note(i, ["R", "G", "B"][c].to_string(), *v);
                }
            }
        }
        for aov in &self.aovs {
            let k = aov.channels.len();
            for (j, v) in aov.data.iter().enumerate() {
                if !v.is_finite() {
                    note(j / k, format!("{}.{}", aov.name, aov.channels[j % k]), *v);
                }
            }
        }
        (count, first)
    }

    /// An error naming `name` and the first non-finite RGB or AOV value, if any.
    pub fn check_finite(&self, name: &str) -> Result<(), ImageError> {
        match self.nonfinite().1 {
            None => Ok(()),
            Some(at) => Err(ImageError::NonFinite {
                name: name.to_string(),
                x: at.x,
                y: at.y,
                channel: at.channel,
                value: at.value,
            }),
        }
    }
}

fn summarize(image: &Image, path: &Path) -> WriteSummary {
    let (nonfinite, first_nonfinite) = image.nonfinite();
    if let Some(at) = &first_nonfinite {
        log::warn!(
            "{}: {nonfinite} non-finite value(s), first {} at pixel ({}, {}) channel {}",
            path.display(),
            at.value,
            at.x,
            at.y,
            at.channel
        );
    }
    WriteSummary {
        nonfinite,
        first_nonfinite,
    }
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename
/// (the rules are [`crate::files::write_atomically`]'s).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    Ok(crate::files::write_atomically(path, bytes)?)
}

fn text(s: &str) -> x::Text {
    // EXR text is a byte string; OpenEXR treats it as UTF-8, and so do we.
    x::Text::from_bytes_unchecked(s.as_bytes().iter().copied().collect::<TextBytes>())
}

fn untext(t: &x::Text) -> String {
    String::from_utf8_lossy(t.bytes()).into_owned()
}

/// Writes an image as described in the module comment. Non-finite values are written as
/// they are and reported in the summary (and logged as a warning).
pub fn write_exr(path: &Path, image: &Image) -> Result<WriteSummary, ImageError> {
    image.check_shape()?;
    let summary = summarize(image, path);
    let n = image.pixel_count();
    let mut channels: Vec<x::AnyChannel<x::FlatSamples>> = Vec::new();
    for c in 0..3 {
        let values = image.rgb.iter().map(|p| p[c]).collect();
        channels.push(x::AnyChannel::new(
            ["R", "G", "B"][c],
            x::FlatSamples::F32(values),
        ));
    }
    if let Some(sums) = &image.sums {
        for c in 0..3 {
            let hi = sums.iter().map(|s| (s[c] >> 32) as u32).collect();
            let lo = sums.iter().map(|s| s[c] as u32).collect();
            let cname = ["R", "G", "B"][c];
            channels.push(x::AnyChannel::new(
                format!("{SUM_HI}.{cname}").as_str(),
                x::FlatSamples::U32(hi),
            ));
            channels.push(x::AnyChannel::new(
                format!("{SUM_LO}.{cname}").as_str(),
                x::FlatSamples::U32(lo),
            ));
        }
    }
    for aov in &image.aovs {
        let k = aov.channels.len();
        for (c, cname) in aov.channels.iter().enumerate() {
            let values = (0..n).map(|i| aov.data[i * k + c]).collect();
            channels.push(x::AnyChannel::new(
                format!("{}.{cname}", aov.name).as_str(),
                x::FlatSamples::F32(values),
            ));
        }
    }

    let mut attrs = x::LayerAttributes::default();
    let mut put = |key: &str, value: x::AttributeValue| {
        attrs
            .other
            .insert(text(&format!("{ATTR_PREFIX}{key}")), value);
    };
    let m = &image.meta;
    let t = |s: &str| x::AttributeValue::Text(text(s));
    if let Some(v) = m.spp {
        put("spp", t(&v.to_string()));
    }
    if let Some(v) = m.sample_offset {
        put("sample_offset", t(&v.to_string()));
    }
    if let Some(v) = &m.method {
        put("method", t(v));
    }
    if let Some(v) = m.seed {
        put("seed", t(&v.to_string()));
    }
    if let Some(v) = m.max_depth {
        put("max_depth", t(&v.to_string()));
    }
    if let Some(v) = m.render_seconds {
        put("render_seconds", x::AttributeValue::F64(v));
    }
    if let Some(v) = &m.device {
        put("device", t(v));
    }
    if let Some(v) = &m.scene_path {
        put("scene_path", t(v));
    }
    if let Some(v) = &m.scene_hash {
        put("scene_hash", t(v));
    }
    if let Some(v) = &m.version {
        put("version", t(v));
    }
    put(
        "resolution",
        t(&format!("{}x{}", image.width, image.height)),
    );
    if image.sums.is_some() {
        put("film_scale", x::AttributeValue::F64(FILM_SCALE));
    }
    if !image.aovs.is_empty() {
        let layout: Vec<String> = image
            .aovs
            .iter()
            .map(|a| format!("{}:{}", a.name, a.channels.join(",")))
            .collect();
        put("aovs", t(&layout.join(";")));
    }
    for (k, v) in &m.extra {
        attrs.other.insert(text(&format!("{KV_PREFIX}{k}")), t(v));
    }

    let encoding = x::Encoding {
        compression: x::Compression::ZIP16,
        blocks: x::Blocks::ScanLines,
        line_order: x::LineOrder::Increasing,
    };
    let size = (image.width as usize, image.height as usize);
    let channels = x::AnyChannels::sort(channels.into_iter().collect());
    let exr_image = x::Image::from_layer(x::Layer::new(size, attrs, encoding, channels));
    let mut bytes = Cursor::new(Vec::new());
    exr_image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| ImageError::Invalid {
            path: path.to_path_buf(),
            problem: format!("EXR encoding: {e}"),
        })?;
    write_atomically(path, bytes.get_ref())?;
    Ok(summary)
}

/// Reads an EXR written by [`write_exr`] or any flat RGB(A) OpenEXR file (f16/f32/u32
/// samples; of a multi-part file, the first part with `R`, `G`, `B`). Foreign files come
/// back with empty metadata and no sums.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let pathbuf = path.to_path_buf();
    let invalid = |problem: String| ImageError::Invalid {
        path: pathbuf.clone(),
        problem,
    };
    use crate::files::{max_input_bytes, read_input, FileError, Start};
    let bytes = read_input(path, max_input_bytes(), &|start| {
        if start.len() < 4 || start[..4] != [0x76, 0x2f, 0x31, 0x01] {
            Err("no OpenEXR magic number".into())
        } else {
            Ok(Start::Continue)
        }
    })
    .map_err(|e| match e {
        FileError::NotFound { path } => ImageError::NotFound { path },
        FileError::Format { path, reason } => ImageError::NotExr { path, reason },
        e => ImageError::File(e),
    })?;
    let file = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(&bytes))
        .map_err(|e| ImageError::NotExr {
            path: pathbuf.clone(),
            reason: e.to_string(),
        })?;

    let has = |layer: &x::Layer<x::AnyChannels<x::FlatSamples>>, name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .any(|c| untext(&c.name) == name)
    };
    let Some(layer) = file
        .layer_data
        .iter()
        .find(|l| ["R", "G", "B"].iter().all(|c| has(l, c)))
    else {
        let first = file.layer_data.first();
        let present: Vec<String> = first
            .map(|l| {
                l.channel_data
                    .list
                    .iter()
                    .map(|c| untext(&c.name))
                    .collect()
            })
            .unwrap_or_default();
        let missing: Vec<&str> = ["R", "G", "B"]
            .into_iter()
            .filter(|c| first.is_none_or(|l| !has(l, c)))
            .collect();
        return Err(ImageError::MissingChannels {
            path: pathbuf.clone(),
            missing: missing.join(", "),
            present: if present.is_empty() {
                "none".into()
            } else {
                present.join(", ")
            },
        });
    };
    let (width, height) = (layer.size.width(), layer.size.height());
    let n = width * height;

    // Attributes: lanterna writes them on the layer; accept image-level ones too.
    let mut attrs: BTreeMap<String, x::AttributeValue> = BTreeMap::new();
    for (k, v) in file
        .attributes
        .other
        .iter()
        .chain(layer.attributes.other.iter())
    {
        let k = untext(k);
        if k.starts_with(ATTR_PREFIX) {
            attrs.insert(k, v.clone());
        }
    }
    let get_text = |key: &str| -> Result<Option<String>, ImageError> {
        match attrs.get(&format!("{ATTR_PREFIX}{key}")) {
            None => Ok(None),
            Some(x::AttributeValue::Text(t)) => Ok(Some(untext(t))),
            Some(other) => Err(invalid(format!(
                "attribute {ATTR_PREFIX}{key} should be text, found {other:?}"
            ))),
        }
    };
    let get_int = |key: &str| -> Result<Option<u64>, ImageError> {
        get_text(key)?
            .map(|s| {
                s.parse::<u64>().map_err(|_| {
                    invalid(format!(
                        "attribute {ATTR_PREFIX}{key} = {s:?} is not an integer"
                    ))
                })
            })
            .transpose()
    };
    let get_f64 = |key: &str| -> Result<Option<f64>, ImageError> {
        match attrs.get(&format!("{ATTR_PREFIX}{key}")) {
            None => Ok(None),
            Some(x::AttributeValue::F64(v)) => Ok(Some(*v)),
            Some(x::AttributeValue::F32(v)) => Ok(Some(f64::from(*v))),
            Some(other) => Err(invalid(format!(
                "attribute {ATTR_PREFIX}{key} should be a double, found {other:?}"
            ))),
        }
    };
    let mut meta = RenderMeta {
        spp: get_int("spp")?,
        sample_offset: get_int("sample_offset")?,
        method: get_text("method")?,
        seed: get_int("seed")?,
        max_depth: get_int("max_depth")?
            .map(|d| u32::try_from(d).map_err(|_| invalid(format!("max_depth {d} too large"))))
            .transpose()?,
        render_seconds: get_f64("render_seconds")?,
        device: get_text("device")?,
        scene_path: get_text("scene_path")?,
        scene_hash: get_text("scene_hash")?,
        version: get_text("version")?,
        extra: BTreeMap::new(),
    };
    for (k, v) in &attrs {
        if let Some(key) = k.strip_prefix(KV_PREFIX) {
            match v {
                x::AttributeValue::Text(t) => {
                    meta.extra.insert(key.to_string(), untext(t));
                }
                other => return Err(invalid(format!("attribute {k} should be text: {other:?}"))),
            }
        }
    }
    if let Some(res) = get_text("resolution")? {
        if res != format!("{width}x{height}") {
            return Err(invalid(format!(
                "size mismatch: header says {res} but the pixels are {width}x{height}"
            )));
        }
    }

    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| untext(&c.name) == name)
            .map(|c| &c.sample_data)
    };
    let floats = |name: &str| -> Result<Vec<f32>, ImageError> {
        let data = channel(name).expect("channel presence checked");
        if data.len() != n {
            return Err(invalid(format!(
                "channel {name} has {} samples, expected {n}",
                data.len()
            )));
        }
        Ok(data.values_as_f32().collect())
    };
    let (r, g, b) = (floats("R")?, floats("G")?, floats("B")?);
    let rgb: Vec<[f32; 3]> = (0..n).map(|i| [r[i], g[i], b[i]]).collect();

    // Film sums: all six channels, as u32, or none.
    let sum_names: Vec<String> = [SUM_HI, SUM_LO]
        .iter()
        .flat_map(|p| ["R", "G", "B"].map(|c| format!("{p}.{c}")))
        .collect();
    let present: Vec<&String> = sum_names.iter().filter(|s| channel(s).is_some()).collect();
    let mut sums = None;
    if !present.is_empty() {
        if present.len() != sum_names.len() {
            let missing: Vec<&str> = sum_names
                .iter()
                .filter(|s| channel(s).is_none())
                .map(String::as_str)
                .collect();
            return Err(ImageError::MissingChannels {
                path: pathbuf.clone(),
                missing: missing.join(", "),
                present: present
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let u32s = |name: &str| -> Result<&Vec<u32>, ImageError> {
            match channel(name) {
                Some(x::FlatSamples::U32(ref v)) if v.len() == n => Ok(v),
                _ => Err(invalid(format!("channel {name} must hold {n} u32 samples"))),
            }
        };
        let scale = get_f64("film_scale")?;
        if scale != Some(FILM_SCALE) {
            return Err(invalid(format!(
                "film sums have scale {scale:?}, this lanterna uses {FILM_SCALE}"
            )));
        }
        if !matches!(meta.spp, Some(s) if s > 0) {
            return Err(invalid(
                "film sums present but lanterna.spp is missing or 0".into(),
            ));
        }
        let mut s = vec![[0u64; 3]; n];
        for c in 0..3 {
            let cname = ["R", "G", "B"][c];
            let hi = u32s(&format!("{SUM_HI}.{cname}"))?;
            let lo = u32s(&format!("{SUM_LO}.{cname}"))?;
            for i in 0..n {
                s[i][c] = (u64::from(hi[i]) << 32) | u64::from(lo[i]);
            }
        }
        sums = Some(s);
    }

    // AOVs: from the recorded layout, else by grouping `layer.channel` names.
    let mut aov_layout: Vec<(String, Vec<String>)> = Vec::new();
    if let Some(layout) = get_text("aovs")? {
        for entry in layout.split(';').filter(|e| !e.is_empty()) {
            let (name, chans) = entry
                .split_once(':')
                .ok_or_else(|| invalid(format!("malformed lanterna.aovs entry {entry:?}")))?;
            aov_layout.push((
                name.to_string(),
                chans.split(',').map(str::to_string).collect(),
            ));
        }
    } else {
        let order = ["R", "G", "B", "A", "X", "Y", "Z", "W", "U", "V"];
        let mut groups: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for c in &layer.channel_data.list {
            let full = untext(&c.name);
            if let Some((prefix, chan)) = full.rsplit_once('.') {
                if prefix != SUM_HI && prefix != SUM_LO && !prefix.contains('.') {
                    groups
                        .entry(prefix.to_string())
                        .or_default()
                        .push(chan.to_string());
                }
            }
        }
        for (name, mut chans) in groups {
            if chans.len() > 4 {
                log::debug!(
                    "{}: skipping layer {name} with {} channels",
                    path.display(),
                    chans.len()
                );
                continue;
            }
            chans.sort_by_key(|c| (order.iter().position(|o| o == c).unwrap_or(99), c.clone()));
            aov_layout.push((name, chans));
        }
    }
    let mut aovs = Vec::new();
    for (name, chans) in aov_layout {
        let k = chans.len();
        let mut data = vec![0f32; n * k];
        for (c, cname) in chans.iter().enumerate() {
            let full = format!("{name}.{cname}");
            if channel(&full).is_none() {
                return Err(ImageError::MissingChannels {
                    path: pathbuf.clone(),
                    missing: full,
                    present: "see lanterna.aovs".into(),
                });
            }
            for (i, v) in floats(&full)?.into_iter().enumerate() {
                data[i * k + c] = v;
            }
        }
        let refs: Vec<&str> = chans.iter().map(String::as_str).collect();
        let aov = Aov::new(&name, &refs, data).map_err(|e| invalid(e.to_string()))?;
        aovs.push(aov);
    }

    let image = Image {
        width: width as u32,
        height: height as u32,
        rgb,
        sums,
        meta,
        aovs,
    };
    image.check_shape().map_err(|e| invalid(e.to_string()))?;
    Ok(image)
}

/// Display mapping of one linear value scaled by `2^exposure`: clamp to [0, 1], sRGB
/// OETF, 8 bits with rounding. Non-finite values never reach here (see [`tonemap`]).
fn encode_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// The colour non-finite pixels are shown in, so that they stand out.
pub const NONFINITE_COLOR: [u8; 3] = [255, 0, 255];

/// Tonemaps linear RGB to 8-bit sRGB: multiply by `2^exposure`, clamp, sRGB OETF. A pixel
/// with any NaN/±Inf channel becomes magenta ([`NONFINITE_COLOR`]).
pub fn tonemap(rgb: &[[f32; 3]], exposure: f32) -> Vec<[u8; 3]> {
    let scale = exposure.exp2();
    rgb.iter()
        .map(|p| {
            if p.iter().all(|v| v.is_finite()) {
                p.map(|v| encode_srgb8(v * scale))
            } else {
                NONFINITE_COLOR
            }
        })
        .collect()
}

/// Encodes an 8-bit RGB buffer as PNG at `path` (temp file + rename).
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb8: &[u8]) -> Result<(), ImageError> {
    let bytes = encode_png_rgb8(width, height, rgb8).map_err(|e| match e {
        ImageError::Png { reason, .. } => ImageError::Png {
            path: path.to_path_buf(),
            reason,
        },
        e => e,
    })?;
    write_atomically(path, &bytes)
}

/// Encodes an 8-bit RGB buffer as PNG in memory (errors name no file).
pub fn encode_png_rgb8(width: u32, height: u32, rgb8: &[u8]) -> Result<Vec<u8>, ImageError> {
    use image::ImageEncoder;
    if rgb8.len() != width as usize * height as usize * 3 {
        return Err(ImageError::Shape(format!(
            "{width}x{height} RGB8 buffer has {} bytes",
            rgb8.len()
        )));
    }
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgb8, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| ImageError::Png {
            path: PathBuf::new(),
            reason: e.to_string(),
        })?;
    Ok(bytes)
}

/// Writes the tonemapped image (see [`tonemap`]) as an 8-bit sRGB PNG. Non-finite pixels
/// are drawn magenta and reported in the summary (and logged as a warning).
pub fn write_png(path: &Path, image: &Image, exposure: f32) -> Result<WriteSummary, ImageError> {
    image.check_shape()?;
    let summary = summarize(image, path);
    let bytes: Vec<u8> = tonemap(&image.rgb, exposure)
        .into_iter()
        .flatten()
        .collect();
    write_png_rgb8(path, image.width, image.height, &bytes)?;
    Ok(summary)
}
