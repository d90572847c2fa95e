//! Export a loaded scene to Mitsuba 3 (XML + binary PLY meshes + images), so that an
//! independent renderer can check lanterna's images. The export starts from what
//! lanterna itself loaded — the same world-space triangles, materials, light table,
//! camera and resolution — and maps every convention explicitly: the camera's −Z view
//! axis and vertical field of view, one-sided front-face emission (double-sided emitters
//! become two one-sided sheets a hair apart, since Mitsuba's `area` emitter is one-sided),
//! two-sided BSDFs, the box pixel filter, segment-counted `max_depth`, sRGB textures and
//! the glTF spot falloff (baked into the spot's projection texture), normal maps (as
//! `normalmap`, the frame's handedness per triangle). Anything that has no exact
//! Mitsuba counterpart (glossy glTF materials → `principled`, alpha, a normal-mapped
//! texel seen from below, …) is approximated and listed in
//! [`MitsubaExport::approximations`]: the peer check is exact only when that list is
//! empty. The directory is written under a
//! temporary name and renamed into place, so a failed export leaves nothing behind.

mod camera_lights;
mod files;
mod geometry;
mod materials;
mod textures;
mod uv_cover;
mod writer;
mod xml;

use crate::lights::LightTable;
use crate::scene::{Camera, Scene};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use writer::Writer;
use xml::xml_escape;

/// Name of the XML scene inside the export directory.
pub const SCENE_XML: &str = "scene.xml";
/// Name of the export's manifest (settings, approximations, warnings) as JSON.
pub const MANIFEST: &str = "lanterna_export.json";

/// What to put in the Mitsuba scene besides the geometry.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    pub width: u32,
    pub height: u32,
    /// Path segments, lanterna's `--max-depth` = Mitsuba's `max_depth`.
    pub max_depth: u32,
    /// Default sample count of the XML's sampler (`$spp`, overridable at load time).
    pub spp: u32,
    /// Default seed of the XML's sampler (`$seed`).
    pub seed: u32,
    /// Leave out emission seen directly by the camera, as lanterna's `--hide-emitters`:
    /// recorded in the manifest (`hide_emitters`), for the renderer of the reference to
    /// take max_depth D minus max_depth 1 with the same seed. The XML does not set
    /// Mitsuba's own `hide_emitters`, which makes emitters invisible to camera rays
    /// (lanterna keeps the light their surfaces reflect).
    pub hide_emitters: bool,
}

/// What an export wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MitsubaExport {
    pub dir: PathBuf,
    pub xml: PathBuf,
    /// Mitsuba shapes written (meshes, after grouping per material).
    pub shapes: usize,
    /// Mitsuba emitters: emissive shapes plus punctual lights.
    pub emitters: usize,
    pub triangles: u64,
    /// Where the Mitsuba scene differs from lanterna's on purpose; empty = exact match
    /// expected (up to Monte Carlo noise).
    pub approximations: Vec<String>,
    /// Everything else worth knowing (files, ignored attributes that do not matter).
    pub warnings: Vec<String>,
}

/// Errors while exporting. Every variant names the file or directory at fault.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{path} exists and is not a lanterna Mitsuba export (no {MANIFEST}); refusing to replace it")]
    NotAnExport { path: PathBuf },
    #[error("{0}")]
    Invalid(String),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |error| ExportError::Io {
        path: path.to_path_buf(),
        error,
    }
}

/// Export `scene` (with its light table, the chosen camera and the image size) as a
/// Mitsuba 3 scene in directory `out_dir` (`scene.xml`, `meshes/`, `textures/`,
/// `lanterna_export.json`). An existing earlier export in `out_dir` is replaced.
pub fn export(
    scene: &Scene,
    lights: &LightTable,
    camera: &Camera,
    options: &ExportOptions,
    out_dir: &Path,
) -> Result<MitsubaExport, ExportError> {
    if options.width == 0 || options.height == 0 {
        return Err(ExportError::Invalid(format!(
            "image size {}×{} is empty",
            options.width, options.height
        )));
    }
    if options.max_depth == 0 {
        return Err(ExportError::Invalid("max depth must be at least 1".into()));
    }
    if lights.instance_lights.len() != scene.instances.len() {
        return Err(ExportError::Invalid(
            "the light table was built for another scene".into(),
        ));
    }
    if out_dir.exists() && !out_dir.join(MANIFEST).is_file() {
        let empty = std::fs::read_dir(out_dir)
            .map(|mut d| d.next().is_none())
            .unwrap_or(false);
        if !empty {
            return Err(ExportError::NotAnExport {
                path: out_dir.to_path_buf(),
            });
        }
    }
    let parent = match out_dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(io_err(&parent))?;
    let name = out_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "export".into());
    let tmp = TempDir(parent.join(format!(".{name}.tmp-{}", std::process::id())));
    if tmp.0.exists() {
        std::fs::remove_dir_all(&tmp.0).map_err(io_err(&tmp.0))?;
    }
    for sub in ["", "meshes", "textures"] {
        let d = tmp.0.join(sub);
        std::fs::create_dir_all(&d).map_err(io_err(&d))?;
    }

    let mut w = Writer {
        scene,
        dir: tmp.0.clone(),
        textures: HashMap::new(),
        derived_textures: HashMap::new(),
        masks: false,
        emitter_coverage: HashMap::new(),
        approximations: Vec::new(),
        warnings: Vec::new(),
        sampled_emitters: 0,
        thin_walls: false,
        smooth_thin_walls: false,
        // Far above float resolution at the scene's coordinates (so Mitsuba always
        // orders the sheets), far below a pixel (so silhouettes do not move).
        epsilon: 4e-6
            * scene
                .bounds_min
                .abs()
                .max(scene.bounds_max.abs())
                .max_element()
                .max(scene.extent()),
    };
    let mut xml = String::new();
    let body = w.scene_body(lights, camera, options)?;
    xml.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = writeln!(
        xml,
        "<!-- Exported by lanterna {} from {} (scene hash {}). -->",
        env!("CARGO_PKG_VERSION"),
        xml_escape(&scene.path.display().to_string()),
        scene.hash
    );
    xml.push_str("<scene version=\"3.0.0\">\n");
    let _ = writeln!(xml, "  <default name=\"spp\" value=\"{}\"/>", options.spp);
    let _ = writeln!(xml, "  <default name=\"seed\" value=\"{}\"/>", options.seed);
    let _ = writeln!(
        xml,
        "  <default name=\"max_depth\" value=\"{}\"/>",
        options.max_depth
    );
    xml.push_str(&body.xml);
    xml.push_str("</scene>\n");
    w.write(SCENE_XML, xml.as_bytes())?;

    w.approximations.sort();
    w.approximations.dedup();
    w.warnings.sort();
    w.warnings.dedup();
    let summary = MitsubaExport {
        dir: out_dir.to_path_buf(),
        xml: out_dir.join(SCENE_XML),
        shapes: body.shapes,
        emitters: body.emitters,
        triangles: body.triangles,
        approximations: w.approximations.clone(),
        warnings: w.warnings.clone(),
    };
    let manifest = serde_json::json!({
        "generator": format!("lanterna {}", env!("CARGO_PKG_VERSION")),
        "scene_path": scene.path.display().to_string(),
        "scene_hash": scene.hash,
        // The version of the file exported (--animation-time, --animation, --variant):
        // scripts/mitsuba_compare.py renders lanterna's side with the same.
        "animation_time": scene.pose.as_ref().map(|p| p.time),
        "animation": scene.pose.as_ref().and_then(|p| p.animation.clone()),
        "variant": scene.variant,
        "camera": camera.name,
        "camera_index": scene.cameras.iter().position(|c| {
            c.name == camera.name && c.to_world == camera.to_world && c.projection == camera.projection
        }),
        "width": options.width,
        "height": options.height,
        "max_depth": options.max_depth,
        "spp": options.spp,
        "seed": options.seed,
        "hide_emitters": options.hide_emitters,
        "shapes": body.shapes,
        "emitters": body.emitters,
        "triangles": body.triangles,
        "exact": summary.approximations.is_empty(),
        "approximations": summary.approximations,
        "warnings": summary.warnings,
    });
    let text = serde_json::to_string_pretty(&manifest).expect("JSON of plain values");
    w.write(MANIFEST, text.as_bytes())?;

    // Swap the finished directory into place; an earlier export is removed only after.
    let old = parent.join(format!(".{name}.old-{}", std::process::id()));
    if out_dir.exists() {
        std::fs::rename(out_dir, &old).map_err(io_err(out_dir))?;
    }
    std::fs::rename(&tmp.0, out_dir).map_err(io_err(out_dir))?;
    std::mem::forget(tmp);
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(io_err(&old))?;
    }
    Ok(summary)
}

/// Removes the temporary directory unless the export succeeded.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
