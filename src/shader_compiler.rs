//! GLSL → SPIR-V compilation with shaderc, shared by `build.rs` (kernels built into the
//! binary) and the runtime `--shader-dir` path (kernels compiled from a directory while
//! debugging). It depends on nothing but `shaderc` and `std` so that the build script can
//! include it with `#[path]`.
//!
//! Conventions: every `*.comp` file under the shader root (and under `tests/`) is a kernel;
//! everything else is an include. `#include "x"` resolves relative to the including file,
//! then relative to the root; `#include <x>` resolves relative to the root only. Errors are
//! reported as `path:line: message`, one per line, with paths as the caller named the root.

use std::cell::RefCell;
use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};

/// A compiled kernel and every file that went into it (for `rerun-if-changed`).
pub struct CompiledKernel {
    pub spirv: Vec<u32>,
    pub sources: Vec<PathBuf>,
}

/// A compile failure: the messages are already in `file:line: message` form.
#[derive(Debug)]
pub struct CompileError {
    pub kernel: PathBuf,
    pub messages: Vec<String>,
}

impl fmt::Display for CompileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, m) in self.messages.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{m}")?;
        }
        Ok(())
    }
}

impl std::error::Error for CompileError {}

/// All kernels below `root`, sorted, as paths relative to `root`.
pub fn find_kernels(root: &Path) -> std::io::Result<Vec<PathBuf>> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
        for entry in std::fs::read_dir(dir)? {
            let path = entry?.path();
            if path.is_dir() {
                walk(root, &path, out)?;
            } else if path.extension().is_some_and(|e| e == "comp") {
                out.push(path.strip_prefix(root).unwrap_or(&path).to_path_buf());
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(root, root, &mut out)?;
    out.sort();
    Ok(out)
}

/// The name a kernel is known by at run time: its path below the root without the
/// extension, with `/` separators (`render`, `tests/reservoir`).
pub fn kernel_name(relative: &Path) -> String {
    let stem = relative.with_extension("");
    stem.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

/// Compile one kernel. `root` is the shader directory; `kernel` is relative to it.
/// `debug_info` keeps names and line info in the SPIR-V (for debuggers and debug printf).
pub fn compile_kernel(
    root: &Path,
    kernel: &Path,
    debug_info: bool,
) -> Result<CompiledKernel, CompileError> {
    let fail = |messages: Vec<String>| CompileError {
        kernel: kernel.to_path_buf(),
        messages,
    };
    let full = root.join(kernel);
    let source = std::fs::read_to_string(&full)
        .map_err(|e| fail(vec![format!("{}: cannot read: {e}", full.display())]))?;

    // Declared before `options`, which borrows them in the include callback.
    let sources = RefCell::new(BTreeSet::from([full.clone()]));
    let root_owned = root.to_path_buf();
    let compiler =
        shaderc::Compiler::new().map_err(|e| fail(vec![format!("shaderc unavailable: {e}")]))?;
    let mut options = shaderc::CompileOptions::new()
        .map_err(|e| fail(vec![format!("shaderc options unavailable: {e}")]))?;
    options.set_target_env(
        shaderc::TargetEnv::Vulkan,
        shaderc::EnvVersion::Vulkan1_2 as u32,
    );
    options.set_target_spirv(shaderc::SpirvVersion::V1_5);
    options.set_source_language(shaderc::SourceLanguage::GLSL);
    options.set_warnings_as_errors();
    // No spirv-opt: the drivers (Mesa's NIR/LLVM, vendor compilers) optimise anyway, and
    // unoptimised SPIR-V keeps the struct and member names that build.rs checks offsets by
    // and that debuggers show.
    options.set_optimization_level(shaderc::OptimizationLevel::Zero);
    if debug_info {
        options.set_generate_debug_info();
    }

    options.set_include_callback(|requested, kind, requester, _depth| {
        let mut candidates = Vec::new();
        if kind == shaderc::IncludeType::Relative {
            if let Some(parent) = Path::new(requester).parent() {
                candidates.push(parent.join(requested));
            }
        }
        candidates.push(root_owned.join(requested));
        for c in candidates {
            if let Ok(content) = std::fs::read_to_string(&c) {
                let name = normalize(&c);
                sources.borrow_mut().insert(name.clone());
                return Ok(shaderc::ResolvedInclude {
                    resolved_name: name.to_string_lossy().into_owned(),
                    content,
                });
            }
        }
        Err(format!("cannot find include \"{requested}\""))
    });

    let name = full.to_string_lossy().into_owned();
    let result = compiler.compile_into_spirv(
        &source,
        shaderc::ShaderKind::Compute,
        &name,
        "main",
        Some(&options),
    );
    drop(options);
    match result {
        Ok(artifact) => Ok(CompiledKernel {
            spirv: artifact.as_binary().to_vec(),
            sources: sources.into_inner().into_iter().collect(),
        }),
        Err(shaderc::Error::CompilationError(_, text)) => Err(fail(format_messages(&text))),
        Err(e) => Err(fail(vec![format!("{name}: {e}")])),
    }
}

/// shaderc reports `file:line: error: text`; keep those lines (dropping the summary line
/// "N errors generated.") so every message reads `file:line: message`.
fn format_messages(text: &str) -> Vec<String> {
    let lines: Vec<String> = text
        .lines()
        .map(str::trim_end)
        .filter(|l| !l.is_empty() && !l.ends_with("generated."))
        .map(str::to_string)
        .collect();
    if lines.is_empty() {
        vec![text.trim().to_string()]
    } else {
        lines
    }
}

/// Lexically remove `.` and `..` so that the same file always has the same name.
fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                out.pop();
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}
