//! `lanterna scene export-mitsuba`: write a scene, as lanterna loads it, as a Mitsuba 3
//! scene directory (XML, PLY meshes, textures, a JSON manifest) for the peer check in
//! `scripts/mitsuba_compare.py`.

use anyhow::{Context, Result};
use lanterna::render::session;
use lanterna::scene::export_mitsuba::{self, ExportOptions};
use lanterna::scene::CameraOverride;
use std::path::PathBuf;

#[derive(clap::Args, Clone, Debug)]
pub struct ExportArgs {
    /// glTF 2.0 scene (.gltf or .glb).
    pub scene: PathBuf,
    /// Output directory (replaced if it holds an earlier export).
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,
    /// Camera of the file to use, by index or name (default: the first).
    #[arg(long)]
    pub camera: Option<String>,
    /// Image width (default 512, or derived from --height and the camera's aspect).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: from the width and the camera's aspect ratio).
    #[arg(long)]
    pub height: Option<u32>,
    /// Maximum path length in segments (lanterna's --max-depth = Mitsuba's max_depth).
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Default samples per pixel of the XML's sampler (`$spp`).
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Default seed of the XML's sampler (`$seed`).
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// The reference leaves out emission seen directly by the camera, as lanterna's
    /// --hide-emitters: recorded in the manifest for scripts/mitsuba_compare.py, which
    /// renders max_depth D minus max_depth 1 with the same seed (Mitsuba's own
    /// `hide_emitters`, which makes emitters invisible to camera rays, stays off).
    #[arg(long)]
    pub hide_emitters: bool,
    /// Follow buffer and image URIs that lead outside the scene's folder.
    #[arg(long)]
    pub allow_outside_uris: bool,
    #[command(flatten)]
    pub version: super::common::VersionArgs,
}

pub fn run(args: ExportArgs) -> Result<()> {
    anyhow::ensure!(args.max_depth >= 1, "--max-depth must be at least 1");
    anyhow::ensure!(args.spp >= 1, "--spp must be at least 1");
    let options = args.version.load_options(args.allow_outside_uris);
    let loaded = session::load_scene_with(&args.scene, &options)?;
    let camera = session::choose_camera(
        &loaded.scene,
        args.camera.as_deref(),
        &CameraOverride::default(),
    )?;
    let (width, height) = session::resolution(&camera, args.width, args.height);
    anyhow::ensure!(
        width > 0 && height > 0 && (width as u64 * height as u64) <= 1 << 28,
        "image size {width}×{height} is out of range"
    );
    let options = ExportOptions {
        width,
        height,
        max_depth: args.max_depth,
        spp: args.spp,
        seed: args.seed,
        hide_emitters: args.hide_emitters,
    };
    let summary = export_mitsuba::export(
        &loaded.scene,
        &loaded.lights,
        &camera,
        &options,
        &args.output,
    )
    .with_context(|| {
        format!(
            "cannot export {} to {}",
            args.scene.display(),
            args.output.display()
        )
    })?;
    for w in &summary.warnings {
        log::warn!("{w}");
    }
    for a in &summary.approximations {
        log::warn!("approximation: {a}");
    }
    log::info!(
        "wrote {} ({} shapes, {} emitters, {} triangles, {}×{}, max depth {}){}",
        summary.xml.display(),
        summary.shapes,
        summary.emitters,
        summary.triangles,
        width,
        height,
        args.max_depth,
        if summary.approximations.is_empty() {
            "; exact: the peer check applies"
        } else {
            "; approximate: the peer check is not exact for this scene"
        }
    );
    Ok(())
}
