//! Images and metrics: `read_exr`, `write_exr`, `merge`, `mae`, `relmse`, and the
//! tonemapped PNG behind `Image._repr_png_`, all through `image_io` and `eval`.

use super::convert::{image_from_py, image_to_py};
use super::errors;
use crate::eval::merge::merge;
use crate::eval::metrics::{self, Named};
use crate::image_io;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyTuple};
use std::path::PathBuf;

#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyTuple>> {
    let image = py
        .detach(|| image_io::read_exr(&path))
        .map_err(errors::image)?;
    image_to_py(py, &image)
}

/// Returns the number of non-finite values written.
#[pyfunction]
fn write_exr(py: Python<'_>, path: PathBuf, image: &Bound<'_, PyAny>) -> PyResult<u64> {
    let image = image_from_py(image)?;
    let summary = py
        .detach(|| image_io::write_exr(&path, &image))
        .map_err(errors::image)?;
    Ok(summary.nonfinite)
}

/// Merge images of disjoint sample ranges: (image, exact, warnings).
#[pyfunction]
fn merge_images<'py>(
    py: Python<'py>,
    images: Vec<Bound<'py, PyAny>>,
    names: Vec<String>,
) -> PyResult<(Bound<'py, PyTuple>, bool, Vec<String>)> {
    let images: Vec<image_io::Image> = images.iter().map(image_from_py).collect::<PyResult<_>>()?;
    let inputs: Vec<(&str, &image_io::Image)> = names
        .iter()
        .map(String::as_str)
        .zip(images.iter())
        .collect();
    let merged = merge(&inputs).map_err(errors::value)?;
    Ok((
        image_to_py(py, &merged.image)?,
        merged.exact,
        merged.warnings,
    ))
}

fn metric(
    image: &Bound<'_, PyAny>,
    reference: &Bound<'_, PyAny>,
    f: fn(&Named, &Named) -> Result<f64, metrics::MetricError>,
) -> PyResult<f64> {
    let image = image_from_py(image)?;
    let reference = image_from_py(reference)?;
    f(
        &Named::new("image", &image),
        &Named::new("reference", &reference),
    )
    .map_err(errors::value)
}

#[pyfunction]
fn mae(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<f64> {
    metric(image, reference, metrics::mae)
}

#[pyfunction]
fn relmse(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<f64> {
    metric(image, reference, metrics::relmse)
}

/// The image tonemapped (exposure in stops, clamp, sRGB) and encoded as PNG.
#[pyfunction]
#[pyo3(signature = (image, exposure=0.0))]
fn png<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    exposure: f32,
) -> PyResult<Bound<'py, PyBytes>> {
    let image = image_from_py(image)?;
    let rgb8: Vec<u8> = image_io::tonemap(&image.rgb, exposure)
        .into_iter()
        .flatten()
        .collect();
    let bytes =
        image_io::encode_png_rgb8(image.width, image.height, &rgb8).map_err(errors::image)?;
    Ok(PyBytes::new(py, &bytes))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(merge_images, m)?)?;
    m.add_function(wrap_pyfunction!(mae, m)?)?;
    m.add_function(wrap_pyfunction!(relmse, m)?)?;
    m.add_function(wrap_pyfunction!(png, m)?)?;
    Ok(())
}
