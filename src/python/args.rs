//! Arguments of the renderer's methods converted and refused the way the command line
//! refuses them (the same messages).

use super::errors;
use crate::render::run::Budget;
use crate::vk::DeviceSelector;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// A non-negative integer argument, refused like the command line refuses it.
pub fn unsigned<T: TryFrom<i64>>(flag: &str, v: i64) -> PyResult<T> {
    T::try_from(v).map_err(|_| {
        PyValueError::new_err(format!(
            "invalid value '{v}' for '--{flag}': expected a non-negative integer in range"
        ))
    })
}

pub fn device_selector(device: Option<&Bound<'_, PyAny>>) -> PyResult<DeviceSelector> {
    let Some(d) = device.filter(|d| !d.is_none()) else {
        return Ok(DeviceSelector::Auto);
    };
    if let Ok(i) = d.extract::<i64>() {
        return Ok(DeviceSelector::Index(unsigned("device", i)?));
    }
    let s: String = d.extract()?;
    Ok(s.parse().unwrap_or(DeviceSelector::Auto))
}

/// The budget of `spp=` or `seconds=` (16 spp when neither is given).
pub fn budget(spp: Option<i64>, seconds: Option<f64>) -> PyResult<Budget> {
    let spp = spp.map(|n| if n < 0 { 0 } else { n as u64 });
    Budget::from_request(spp, seconds).map_err(errors::render)
}
