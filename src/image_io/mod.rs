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

use std::path::{Path, PathBuf};

mod meta;
mod openexr;
mod png;

pub use meta::{format_ranges, parse_ranges, RenderMeta, SAMPLE_RANGES_KEY};
pub use openexr::{read_exr, write_exr};
pub use png::{encode_png_rgb8, tonemap, write_png, write_png_rgb8, NONFINITE_COLOR};

/// The film's fixed-point scale: one unit of a sum is `1 / FILM_SCALE` of radiance.
pub const FILM_SCALE: f64 = crate::gpu::FILM_FIXED_SCALE as f64;

/// The version of lanterna writing files (stored as `lanterna.version`).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// Names of the film-sum layers (reserved: no AOV may use them).
const SUM_HI: &str = "film_sum_hi";
const SUM_LO: &str = "film_sum_lo";

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
