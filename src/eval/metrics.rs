//! Error metrics of an image against a reference: MAE (mean absolute error) and relMSE
//! (relative mean squared error), both averaged over pixels and the three RGB channels and
//! accumulated in f64. A NaN or infinity in either image is an error naming that image and
//! its first bad pixel: a metric that silently averaged one would be meaningless.

use crate::image_io::Image;

/// The ε in relMSE's denominator, `(x − r)² / (r² + ε)`, which keeps black pixels finite.
pub const RELMSE_EPSILON: f64 = 0.01;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricError {
    #[error("{image}: non-finite value {value} at pixel ({x}, {y}) channel {channel}")]
    NonFinite {
        image: String,
        x: u32,
        y: u32,
        channel: char,
        value: f32,
    },
    #[error("{image} is {got_w}x{got_h} but the reference {reference} is {ref_w}x{ref_h}")]
    SizeMismatch {
        image: String,
        reference: String,
        got_w: u32,
        got_h: u32,
        ref_w: u32,
        ref_h: u32,
    },
    #[error("{image}: buffer has {len} pixels, expected {width}x{height}")]
    BadBuffer {
        image: String,
        len: usize,
        width: u32,
        height: u32,
    },
}

/// A view of RGB pixels with the name errors should use (a file name, a method, …).
#[derive(Clone, Copy, Debug)]
pub struct Named<'a> {
    pub name: &'a str,
    pub width: u32,
    pub height: u32,
    /// Scan-line order, `rgb[y * width + x]`.
    pub rgb: &'a [[f32; 3]],
}

impl<'a> Named<'a> {
    pub fn new(name: &'a str, image: &'a Image) -> Self {
        Named {
            name,
            width: image.width,
            height: image.height,
            rgb: &image.rgb,
        }
    }

    /// The first non-finite value, as an error.
    pub fn check_finite(&self) -> Result<(), MetricError> {
        let expected = self.width as usize * self.height as usize;
        if self.rgb.len() != expected {
            return Err(MetricError::BadBuffer {
                image: self.name.to_string(),
                len: self.rgb.len(),
                width: self.width,
                height: self.height,
            });
        }
        for (i, p) in self.rgb.iter().enumerate() {
            if let Some(c) = p.iter().position(|v| !v.is_finite()) {
                return Err(MetricError::NonFinite {
                    image: self.name.to_string(),
                    x: (i % self.width as usize) as u32,
                    y: (i / self.width as usize) as u32,
                    channel: ['R', 'G', 'B'][c],
                    value: p[c],
                });
            }
        }
        Ok(())
    }
}

/// Both metrics of one image against a reference.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Errors {
    pub mae: f64,
    pub relmse: f64,
}

fn check_pair(image: &Named, reference: &Named) -> Result<(), MetricError> {
    reference.check_finite()?;
    image.check_finite()?;
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(MetricError::SizeMismatch {
            image: image.name.to_string(),
            reference: reference.name.to_string(),
            got_w: image.width,
            got_h: image.height,
            ref_w: reference.width,
            ref_h: reference.height,
        });
    }
    Ok(())
}

/// Mean over pixels and channels of `f(x, r)`, after checking both images.
fn mean_of(
    image: &Named,
    reference: &Named,
    f: impl Fn(f64, f64) -> f64,
) -> Result<f64, MetricError> {
    check_pair(image, reference)?;
    let mut sum = 0.0f64;
    for (p, q) in image.rgb.iter().zip(reference.rgb) {
        for c in 0..3 {
            sum += f(f64::from(p[c]), f64::from(q[c]));
        }
    }
    Ok(sum / (3 * image.rgb.len()) as f64)
}

/// Mean absolute error: mean over pixels and RGB channels of `|x − r|`.
pub fn mae(image: &Named, reference: &Named) -> Result<f64, MetricError> {
    mean_of(image, reference, |x, r| (x - r).abs())
}

/// Relative MSE: mean over pixels and RGB channels of `(x − r)² / (r² + 0.01)`.
pub fn relmse(image: &Named, reference: &Named) -> Result<f64, MetricError> {
    mean_of(image, reference, |x, r| {
        (x - r) * (x - r) / (r * r + RELMSE_EPSILON)
    })
}

/// MAE and relMSE together.
pub fn errors(image: &Named, reference: &Named) -> Result<Errors, MetricError> {
    Ok(Errors {
        mae: mae(image, reference)?,
        relmse: relmse(image, reference)?,
    })
}

/// Per-pixel absolute error averaged over the channels, `(|Δr| + |Δg| + |Δb|) / 3`, for
/// error maps; the caller has checked the pair (see [`errors`]).
pub fn abs_error_map(image: &[[f32; 3]], reference: &[[f32; 3]]) -> Vec<f32> {
    image
        .iter()
        .zip(reference)
        .map(|(p, q)| ((p[0] - q[0]).abs() + (p[1] - q[1]).abs() + (p[2] - q[2]).abs()) / 3.0)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named<'a>(name: &'a str, w: u32, h: u32, rgb: &'a [[f32; 3]]) -> Named<'a> {
        Named {
            name,
            width: w,
            height: h,
            rgb,
        }
    }

    #[test]
    fn hand_computed_values() {
        // 2x1 image. Differences: pixel 0: (0.5, -1, 0), pixel 1: (0, 0, 2).
        let r = [[0.5, 1.0, 0.0], [2.0, 0.0, 1.0]];
        let x = [[1.0, 0.0, 0.0], [2.0, 0.0, 3.0]];
        let (x, r) = (named("x", 2, 1, &x), named("r", 2, 1, &r));
        // MAE = (0.5 + 1 + 0 + 0 + 0 + 2) / 6 = 3.5 / 6
        assert!((mae(&x, &r).unwrap() - 3.5 / 6.0).abs() < 1e-12);
        // relMSE terms: 0.25/0.26, 1/1.01, 0, 0, 0, 4/1.01
        let expected = (0.25 / 0.26 + 1.0 / 1.01 + 4.0 / 1.01) / 6.0;
        assert!((relmse(&x, &r).unwrap() - expected).abs() < 1e-12);
        assert_eq!(mae(&r, &r).unwrap(), 0.0);
    }

    #[test]
    fn nonfinite_names_image_and_pixel() {
        let r = [[0.0; 3]; 4];
        let x = [[0.0; 3], [0.0; 3], [0.0, 0.0, f32::INFINITY], [f32::NAN; 3]];
        let e = mae(&named("guided.exr", 2, 2, &x), &named("ref.exr", 2, 2, &r)).unwrap_err();
        assert_eq!(
            e,
            MetricError::NonFinite {
                image: "guided.exr".into(),
                x: 0,
                y: 1,
                channel: 'B',
                value: f32::INFINITY
            }
        );
        assert!(e.to_string().contains("guided.exr") && e.to_string().contains("(0, 1)"));
        // NaN in the reference is reported against the reference.
        let e = relmse(&named("x", 2, 2, &r), &named("ref.exr", 2, 2, &x)).unwrap_err();
        assert!(matches!(e, MetricError::NonFinite { ref image, .. } if image == "ref.exr"));
    }

    #[test]
    fn size_mismatch() {
        let a = [[0.0; 3]; 4];
        let e = mae(&named("a", 4, 1, &a), &named("r", 2, 2, &a)).unwrap_err();
        assert!(matches!(e, MetricError::SizeMismatch { .. }), "{e}");
    }
}
