//! The library's errors as Python exceptions, with the command line's messages: a file
//! that does not exist is `FileNotFoundError`, other I/O `OSError`, a bad argument or
//! input `ValueError`, a device or driver failure `RuntimeError`.

use crate::eval::compare::CompareError;
use crate::guiding::GuidingError;
use crate::image_io::ImageError;
use crate::render::session::ViewError;
use crate::render::RenderError;
use crate::scene::SceneError;
use crate::vk::VkError;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

/// The message the command line prints after `error: ` (the error and its causes).
pub fn message<E: std::error::Error + Send + Sync + 'static>(e: E) -> String {
    format!("{:#}", anyhow::Error::new(e))
}

fn io_kind(kind: std::io::ErrorKind, message: String) -> PyErr {
    match kind {
        std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
        _ => PyOSError::new_err(message),
    }
}

/// The exception class for a file error: `FileNotFoundError` for a missing file,
/// `OSError` for other I/O, `ValueError` for a file lanterna refuses.
fn file_kind(f: &crate::files::FileError) -> fn(String) -> PyErr {
    use crate::files::FileError;
    match f {
        FileError::NotFound { .. } => |m| PyFileNotFoundError::new_err(m),
        FileError::Io { error, .. } if error.kind() == std::io::ErrorKind::NotFound => {
            |m| PyFileNotFoundError::new_err(m)
        }
        FileError::Io { .. } => |m| PyOSError::new_err(m),
        _ => |m| PyValueError::new_err(m),
    }
}

pub fn scene(e: SceneError) -> PyErr {
    match &e {
        SceneError::File { error, .. } => {
            let make = file_kind(error);
            make(message(e))
        }
        _ => PyValueError::new_err(message(e)),
    }
}

pub fn view(e: ViewError) -> PyErr {
    match e {
        ViewError::Scene(e) => scene(e),
        e => PyValueError::new_err(message(e)),
    }
}

pub fn vulkan(e: VkError) -> PyErr {
    match &e {
        VkError::NoMatchingDevice(_) => PyValueError::new_err(message(e)),
        _ => PyRuntimeError::new_err(message(e)),
    }
}

/// Opening a device, with the command line's context.
pub fn device(e: VkError) -> PyErr {
    let selection = matches!(e, VkError::NoMatchingDevice(_));
    let text = format!("cannot open a Vulkan device: {}", message(e));
    if selection {
        PyValueError::new_err(text)
    } else {
        PyRuntimeError::new_err(text)
    }
}

pub fn render(e: RenderError) -> PyErr {
    match e {
        RenderError::Invalid(m) => PyValueError::new_err(m),
        e @ RenderError::Settings(_) => PyValueError::new_err(message(e)),
        RenderError::Vulkan(v) => vulkan(v),
        e => PyRuntimeError::new_err(message(e)),
    }
}

pub fn image(e: ImageError) -> PyErr {
    match &e {
        ImageError::NotFound { .. } => PyFileNotFoundError::new_err(message(e)),
        ImageError::File(f) => {
            let make = file_kind(f);
            make(message(e))
        }
        _ => PyValueError::new_err(message(e)),
    }
}

pub fn guiding(e: GuidingError) -> PyErr {
    match &e {
        GuidingError::File(f) => {
            let make = file_kind(f);
            make(message(e))
        }
        _ => PyValueError::new_err(message(e)),
    }
}

pub fn compare(e: CompareError) -> PyErr {
    match e {
        CompareError::Image(e) => image(e),
        CompareError::Io { error, path } => {
            let text = format!("{}: {error}", path.display());
            io_kind(error.kind(), text)
        }
        e @ CompareError::Runner { .. } => PyRuntimeError::new_err(message(e)),
        e => PyValueError::new_err(message(e)),
    }
}

/// Any other error: `ValueError` with its message.
pub fn value<E: std::error::Error + Send + Sync + 'static>(e: E) -> PyErr {
    PyValueError::new_err(message(e))
}
