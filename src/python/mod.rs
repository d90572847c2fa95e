//! `lanterna._lanterna`, the extension module behind `import lanterna` (feature
//! `python`, built by maturin). It is a thin layer over the library the command line
//! uses: scenes load through `render::session`, renders run through `render::run`, images
//! are built by `render::output` and read and written by `image_io`, errors carry the
//! command line's messages. Pixel data crosses the boundary as little-endian bytes with
//! their shape; the pure-Python package (`python/lanterna/`) turns them into numpy
//! arrays, so this crate needs no numpy bindings.

mod args;
mod convert;
mod errors;
mod eval;
mod options;
mod renderer;
mod scene;
mod watch;

use crate::vk::{Device, DeviceSelector};
use pyo3::prelude::*;
use std::sync::{Arc, Mutex, Weak};

/// Devices open in this process, by selector and validation, so that renderers share
/// one instance and device as long as any of them lives.
static DEVICES: Mutex<Vec<(String, Weak<Device>)>> = Mutex::new(Vec::new());

fn shared_device(selector: &DeviceSelector, validation: bool) -> crate::vk::Result<Arc<Device>> {
    let key = format!("{selector:?}/{validation}");
    let mut devices = DEVICES.lock().unwrap_or_else(|e| e.into_inner());
    devices.retain(|(_, d)| d.strong_count() > 0);
    if let Some(d) = devices
        .iter()
        .find(|(k, _)| *k == key)
        .and_then(|(_, d)| d.upgrade())
    {
        return Ok(d);
    }
    let options = crate::render::session::DeviceOptions {
        selector: selector.clone(),
        validation,
        debug_printf: false,
    };
    let device = crate::render::session::open_device(&options)?;
    devices.push((key, Arc::downgrade(&device)));
    Ok(device)
}

/// Vulkan validation errors reported in this process so far (the tests run with
/// LANTERNA_VALIDATION=1 and check that none was).
#[pyfunction]
fn validation_error_count() -> u64 {
    crate::vk::validation_error_count()
}

#[pymodule]
fn _lanterna(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The library logs through `log`: show warnings (LANTERNA_LOG=info for more).
    let level = std::env::var("LANTERNA_LOG").unwrap_or_else(|_| "warn".into());
    let _ = env_logger::Builder::new()
        .parse_filters(&level)
        .format_timestamp(None)
        .format_target(false)
        .try_init();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(validation_error_count, m)?)?;
    scene::register(m)?;
    renderer::register(m)?;
    eval::register(m)?;
    Ok(())
}
