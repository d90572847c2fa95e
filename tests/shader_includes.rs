//! Every GLSL include compiles on its own: a kernel made of `#version 460`, the include
//! and an empty `main` must compile with the same options as the real kernels, with
//! ray-query traversal and with software traversal (`LANTERNA_SOFTWARE_TRAVERSAL`). An include
//! that uses a function, struct, buffer or extension without including the file that
//! declares it fails here, instead of working only because `render_main.glsl` happens to
//! include that file earlier.
//!
//! Seen failing: with `#include "scene_data.glsl"` removed from `inc/geometry.glsl`
//! (it indexes the vertex and index buffers), and with `#include "bsdf.glsl"` removed from
//! `inc/material.glsl` (its `Surface` holds a `BsdfParams`).

use lanterna::shaders::ShaderSource;
use std::path::{Path, PathBuf};

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// The includes of the path-tracing kernel: `inc/*.glsl` and its raygen and closest-hit
/// parts (relative to the shader root).
fn includes(root: &Path) -> Vec<PathBuf> {
    let mut list: Vec<PathBuf> = std::fs::read_dir(root.join("inc"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "glsl"))
        .map(|p| p.strip_prefix(root).unwrap().to_path_buf())
        .collect();
    list.extend(
        ["closesthit.glsl", "raygen.glsl", "render_main.glsl"]
            .iter()
            .map(PathBuf::from),
    );
    list.sort();
    list
}

/// Includes written against an interface their includer provides (RTXDI's "bridge"):
/// `ris.glsl` resamples whatever `RisContext` / `RisCandidate` / `ris_draw` /
/// `ris_target` the including kernel defines (closesthit.glsl for lights, the test kernel
/// `tests/ris.comp` for a stub distribution, which compiles it in every build).
///
/// `light_reuse.glsl` combines reservoirs of that same interface (closesthit.glsl's
/// `RisContext`, whose `s` and `d.bsdf` its `ris_target` reads, and `RisCandidate`), and
/// is compiled through closesthit.glsl.
///
/// `bvh.glsl` is the software half of `trace.glsl` (its `trace_closest` and `visible`
/// under `LANTERNA_SOFTWARE_TRAVERSAL`), included by it at that point and compiled
/// through it here.
const BRIDGED: [&str; 3] = ["ris.glsl", "light_reuse.glsl", "bvh.glsl"];

/// The parts that hold the kernel's `main`.
const HAS_MAIN: [&str; 2] = ["raygen.glsl", "render_main.glsl"];

#[test]
fn every_include_compiles_on_its_own() {
    let source = std::env::var_os("LANTERNA_TEST_SHADER_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders_glsl"));
    let dir = std::env::temp_dir().join(format!("lanterna-includes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    copy_tree(&source, &dir);
    std::fs::create_dir_all(dir.join("alone")).unwrap();
    let shaders = ShaderSource::Directory(dir.clone());
    let mut failures = Vec::new();
    let list = includes(&dir);
    assert!(list.len() >= 15, "found only {list:?}");
    for include in &list {
        let file = include.file_name().unwrap().to_string_lossy().to_string();
        if BRIDGED.contains(&file.as_str()) {
            continue;
        }
        // Both traversal variants (render.comp and render_sw.comp).
        for (variant, define) in [
            ("rq", ""),
            ("sw", "#define LANTERNA_SOFTWARE_TRAVERSAL 1\n"),
        ] {
            let name = format!(
                "{}_{variant}",
                include.to_string_lossy().replace(['/', '.'], "_")
            );
            // raygen.glsl and render_main.glsl hold the kernel's main.
            let main = if HAS_MAIN.contains(&file.as_str()) {
                ""
            } else {
                "void main() {}\n"
            };
            let kernel = format!(
                "#version 460\n{define}#include \"../{}\"\n{main}",
                include.display()
            );
            std::fs::write(dir.join("alone").join(format!("{name}.comp")), kernel).unwrap();
            if let Err(e) = shaders.load(&format!("alone/{name}")) {
                failures.push(format!("{} ({variant}):\n{e}", include.display()));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        failures.is_empty(),
        "includes that do not compile on their own:\n\n{}",
        failures.join("\n\n")
    );
}
