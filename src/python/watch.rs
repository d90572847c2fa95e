//! What runs between chunks of samples while a render has released the GIL.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Between chunks: let Python handle signals and call the progress callback; the first
/// exception (KeyboardInterrupt from Ctrl-C, or the callback's) cancels the run and is
/// kept for the caller to raise.
pub struct Watch<'a> {
    callback: Option<&'a Py<PyAny>>,
    cancel: &'a AtomicBool,
    pub error: Option<PyErr>,
    started: Instant,
}

impl<'a> Watch<'a> {
    pub fn new(callback: Option<&'a Py<PyAny>>, cancel: &'a AtomicBool) -> Self {
        Watch {
            callback,
            cancel,
            error: None,
            started: Instant::now(),
        }
    }

    pub fn tick(&mut self, done: u64) {
        if self.error.is_some() {
            return;
        }
        let seconds = self.started.elapsed().as_secs_f64();
        let result = Python::attach(|py| -> PyResult<()> {
            py.check_signals()?;
            if let Some(cb) = self.callback {
                cb.call1(py, (done, seconds))?;
            }
            Ok(())
        });
        if let Err(e) = result {
            self.error = Some(e);
            self.cancel.store(true, Ordering::SeqCst);
        }
    }
}
