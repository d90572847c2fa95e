//! Images across the boundary. An [`Image`] travels as a tuple
//! `(width, height, rgb, sums, meta, aovs)`: `rgb` little-endian f32 bytes (H×W×3),
//! `sums` little-endian u64 bytes (H×W×3) or None, `meta` a dict, `aovs` a list of
//! `(name, [channel, …], f32 bytes)`. The Python package wraps these in numpy arrays.
//!
//! Metadata is one flat dict: the [`RenderMeta`] fields by name, typed, and the free-form
//! entries beside them. Free-form values are stored as text; reading turns `true` and
//! `false` back into bools and decimal numbers back into ints and floats, so a dict of
//! such values survives `write_exr` and `read_exr`.

use crate::image_io::{Aov, Image, RenderMeta};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyByteArray, PyBytes, PyDict, PyList, PyTuple};

/// A serialisable value as the Python object `json.loads` makes of it.
pub fn json_value<'py, T: serde::Serialize>(
    py: Python<'py>,
    value: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(super::errors::value)?;
    py.import("json")?.call_method1("loads", (text,))
}

pub fn f32_bytes<'py>(py: Python<'py>, values: &[f32]) -> Bound<'py, PyByteArray> {
    PyByteArray::new(py, bytemuck::cast_slice(values))
}

fn u64_bytes<'py>(py: Python<'py>, values: &[u64]) -> Bound<'py, PyByteArray> {
    PyByteArray::new(py, bytemuck::cast_slice(values))
}

/// Little-endian f32 values from a bytes-like object holding `expected` of them.
pub fn read_f32(obj: &Bound<'_, PyAny>, expected: usize, what: &str) -> PyResult<Vec<f32>> {
    let bytes = raw_bytes(obj, what)?;
    if bytes.len() != expected * 4 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes, expected {} (f32 × {expected})",
            bytes.len(),
            expected * 4
        )));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

fn read_u64(obj: &Bound<'_, PyAny>, expected: usize, what: &str) -> PyResult<Vec<u64>> {
    let bytes = raw_bytes(obj, what)?;
    if bytes.len() != expected * 8 {
        return Err(PyValueError::new_err(format!(
            "{what}: {} bytes, expected {} (u64 × {expected})",
            bytes.len(),
            expected * 8
        )));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().unwrap()))
        .collect())
}

fn raw_bytes(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u8>> {
    if let Ok(b) = obj.cast::<PyBytes>() {
        Ok(b.as_bytes().to_vec())
    } else if let Ok(b) = obj.cast::<PyByteArray>() {
        Ok(b.to_vec())
    } else {
        Err(PyTypeError::new_err(format!(
            "{what}: expected bytes or bytearray"
        )))
    }
}

/// Metadata as a flat dict.
pub fn meta_to_dict<'py>(py: Python<'py>, m: &RenderMeta) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let Some(v) = m.spp {
        d.set_item("spp", v)?;
    }
    if let Some(v) = m.sample_offset {
        d.set_item("sample_offset", v)?;
    }
    if let Some(v) = &m.method {
        d.set_item("method", v)?;
    }
    if let Some(v) = m.seed {
        d.set_item("seed", v)?;
    }
    if let Some(v) = m.max_depth {
        d.set_item("max_depth", v)?;
    }
    if let Some(v) = m.render_seconds {
        d.set_item("render_seconds", v)?;
    }
    if let Some(v) = &m.device {
        d.set_item("device", v)?;
    }
    if let Some(v) = &m.scene_path {
        d.set_item("scene_path", v)?;
    }
    if let Some(v) = &m.scene_hash {
        d.set_item("scene_hash", v)?;
    }
    if let Some(v) = &m.version {
        d.set_item("version", v)?;
    }
    for (k, v) in &m.extra {
        if let Ok(b) = v.parse::<bool>() {
            d.set_item(k, b)?;
        } else if let Ok(i) = v.parse::<i64>() {
            d.set_item(k, i)?;
        } else if let Some(f) = v.parse::<f64>().ok().filter(|f| f.is_finite()) {
            d.set_item(k, f)?;
        } else {
            d.set_item(k, v)?;
        }
    }
    Ok(d)
}

/// A flat dict back into metadata (see the module comment).
pub fn meta_from_dict(d: &Bound<'_, PyDict>) -> PyResult<RenderMeta> {
    let mut m = RenderMeta::default();
    for (k, v) in d.iter() {
        let key: String = k
            .extract()
            .map_err(|_| PyTypeError::new_err("metadata keys must be strings"))?;
        if v.is_none() {
            continue;
        }
        let bad = |_| PyTypeError::new_err(format!("metadata `{key}` has the wrong type"));
        match key.as_str() {
            "spp" => m.spp = Some(v.extract().map_err(bad)?),
            "sample_offset" => m.sample_offset = Some(v.extract().map_err(bad)?),
            "method" => m.method = Some(v.extract().map_err(bad)?),
            "seed" => m.seed = Some(v.extract().map_err(bad)?),
            "max_depth" => m.max_depth = Some(v.extract().map_err(bad)?),
            "render_seconds" => m.render_seconds = Some(v.extract().map_err(bad)?),
            "device" => m.device = Some(v.extract().map_err(bad)?),
            "scene_path" => m.scene_path = Some(v.extract().map_err(bad)?),
            "scene_hash" => m.scene_hash = Some(v.extract().map_err(bad)?),
            "version" => m.version = Some(v.extract().map_err(bad)?),
            _ => {
                // Python's str() of a float is its shortest round-trip form.
                let text = if v.is_instance_of::<PyBool>() {
                    if v.is_truthy()? { "true" } else { "false" }.to_string()
                } else {
                    v.str()?.to_string()
                };
                m.extra.insert(key, text);
            }
        }
    }
    Ok(m)
}

/// An image as the tuple described in the module comment.
pub fn image_to_py<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyTuple>> {
    let rgb: &[f32] = bytemuck::cast_slice(&image.rgb);
    let sums = match &image.sums {
        Some(s) => u64_bytes(py, bytemuck::cast_slice(s)).into_any(),
        None => py.None().into_bound(py),
    };
    let aovs = PyList::empty(py);
    for a in &image.aovs {
        aovs.append((a.name.as_str(), a.channels.clone(), f32_bytes(py, &a.data)))?;
    }
    PyTuple::new(
        py,
        [
            image.width.into_pyobject(py)?.into_any(),
            image.height.into_pyobject(py)?.into_any(),
            f32_bytes(py, rgb).into_any(),
            sums,
            meta_to_dict(py, &image.meta)?.into_any(),
            aovs.into_any(),
        ],
    )
}

/// An image from the tuple described in the module comment (`meta` may be None).
pub fn image_from_py(obj: &Bound<'_, PyAny>) -> PyResult<Image> {
    let t = obj
        .cast::<PyTuple>()
        .map_err(|_| PyTypeError::new_err("expected an image tuple"))?;
    if t.len() != 6 {
        return Err(PyTypeError::new_err("expected an image tuple of 6 items"));
    }
    let width: u32 = t.get_item(0)?.extract()?;
    let height: u32 = t.get_item(1)?.extract()?;
    let n = width as usize * height as usize;
    let rgb = read_f32(&t.get_item(2)?, n * 3, "rgb")?;
    let sums = t.get_item(3)?;
    let sums = if sums.is_none() {
        None
    } else {
        Some(read_u64(&sums, n * 3, "sums")?)
    };
    let meta = t.get_item(4)?;
    let meta = if meta.is_none() {
        RenderMeta::new()
    } else {
        meta_from_dict(meta.cast::<PyDict>()?)?
    };
    let mut aovs = Vec::new();
    for item in t.get_item(5)?.try_iter()? {
        let (name, channels, data): (String, Vec<String>, Bound<'_, PyAny>) = item?.extract()?;
        let data = read_f32(&data, n * channels.len(), &format!("AOV {name}"))?;
        let channels: Vec<&str> = channels.iter().map(String::as_str).collect();
        aovs.push(Aov::new(&name, &channels, data).map_err(super::errors::image)?);
    }
    let image = Image {
        width,
        height,
        rgb: rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        sums: sums.map(|s| s.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()),
        meta,
        aovs,
    };
    image.check_shape().map_err(super::errors::image)?;
    Ok(image)
}
