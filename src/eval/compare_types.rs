//! Types the comparison shares with its report writers (`report`, `plot`, `grid`,
//! `html`): the budget of one render, the crop rectangle and the error type. A leaf
//! module, so that the writers need not import the comparison that calls them.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

use super::metrics;
use super::BoxError;
use crate::image_io::ImageError;

/// How much work one render may do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// Exactly this many samples per pixel.
    Spp(u64),
    /// Render (after setup) until this many wall-clock seconds have passed; the runner
    /// reports the spp it reached.
    Seconds(f64),
}

impl Budget {
    /// `spp` or `time`, as in the report's `budget_kind`.
    pub fn kind(&self) -> &'static str {
        match self {
            Budget::Spp(_) => "spp",
            Budget::Seconds(_) => "time",
        }
    }

    pub fn value(&self) -> f64 {
        match *self {
            Budget::Spp(n) => n as f64,
            Budget::Seconds(s) => s,
        }
    }

    /// A file-name-safe tag: `spp16`, `t2.5s`.
    pub fn tag(&self) -> String {
        match *self {
            Budget::Spp(n) => format!("spp{n}"),
            Budget::Seconds(s) => format!("t{s}s"),
        }
    }
}

impl fmt::Display for Budget {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Budget::Spp(n) => write!(f, "{n} spp"),
            Budget::Seconds(s) => write!(f, "{s} s"),
        }
    }
}

/// A rectangle of the reference, in pixels: `x,y,w,h` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl FromStr for Crop {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        let values: Vec<u32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
        if parts.len() != 4 || values.len() != 4 {
            return Err(format!(
                "crop {s:?} should be four non-negative integers x,y,w,h"
            ));
        }
        if values[2] == 0 || values[3] == 0 {
            return Err(format!("crop {s:?} has zero width or height"));
        }
        Ok(Crop {
            x: values[0],
            y: values[1],
            w: values[2],
            h: values[3],
        })
    }
}

impl Crop {
    /// An error unless the crop lies inside a `width` × `height` image.
    pub fn check_inside(&self, width: u32, height: u32) -> Result<(), String> {
        let fits = u64::from(self.x) + u64::from(self.w) <= u64::from(width)
            && u64::from(self.y) + u64::from(self.h) <= u64::from(height);
        if fits {
            Ok(())
        } else {
            Err(format!(
                "crop {},{},{},{} does not fit in the {width}x{height} reference",
                self.x, self.y, self.w, self.h
            ))
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error("invalid comparison settings: {0}")]
    Config(String),
    #[error("rendering {method} at {budget} failed")]
    Runner {
        method: String,
        budget: Budget,
        source: BoxError,
    },
    #[error("{method} at {budget}: {problem}")]
    BadResult {
        method: String,
        budget: Budget,
        problem: String,
    },
    #[error(transparent)]
    Metric(#[from] metrics::MetricError),
    #[error(transparent)]
    Image(#[from] ImageError),
    // `error` is not a `source`: the message already includes it, once.
    #[error("{}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{}: {problem}", path.display())]
    Figure { path: PathBuf, problem: String },
    #[error("{0}")]
    Reference(String),
}
