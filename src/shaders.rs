//! Kernels: the SPIR-V built into the binary, or GLSL compiled at run time from a
//! directory (`--shader-dir`) so a kernel change can be tried without `cargo build`.

use std::path::{Path, PathBuf};

#[path = "shader_compiler.rs"]
#[allow(dead_code)]
mod shader_compiler;
pub use shader_compiler::CompileError;

mod builtin {
    include!(concat!(env!("OUT_DIR"), "/kernels.rs"));
}

/// Where kernels come from.
#[derive(Clone, Debug, Default)]
pub enum ShaderSource {
    /// SPIR-V compiled by build.rs.
    #[default]
    Builtin,
    /// GLSL compiled at run time from this directory (the layout of `shaders_glsl/`).
    Directory(PathBuf),
}

/// Error loading a kernel.
#[derive(Debug, thiserror::Error)]
pub enum ShaderError {
    #[error("no kernel named `{0}` is built into this binary")]
    Unknown(String),
    /// Already in `file:line: message` form (not a `source`, so it prints once).
    #[error("{0}")]
    Compile(CompileError),
    #[error("bad SPIR-V for kernel `{0}`: {1}")]
    BadSpirv(String, std::io::Error),
}

impl ShaderSource {
    /// SPIR-V words of kernel `name` (e.g. `render`, `tests/reservoir`).
    pub fn load(&self, name: &str) -> Result<Vec<u32>, ShaderError> {
        match self {
            ShaderSource::Builtin => {
                let (_, bytes) = builtin::KERNELS
                    .iter()
                    .find(|(n, _)| *n == name)
                    .ok_or_else(|| ShaderError::Unknown(name.to_string()))?;
                ash::util::read_spv(&mut std::io::Cursor::new(bytes))
                    .map_err(|e| ShaderError::BadSpirv(name.to_string(), e))
            }
            ShaderSource::Directory(dir) => {
                let rel = Path::new(name).with_extension("comp");
                let debug = std::env::var_os("LANTERNA_SHADER_DEBUG_INFO").is_some();
                Ok(shader_compiler::compile_kernel(dir, &rel, debug)?.spirv)
            }
        }
    }

    /// Names of the kernels built into the binary.
    pub fn builtin_names() -> impl Iterator<Item = &'static str> {
        builtin::KERNELS.iter().map(|(n, _)| *n)
    }
}

impl From<CompileError> for ShaderError {
    fn from(e: CompileError) -> Self {
        ShaderError::Compile(e)
    }
}
