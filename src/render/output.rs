//! What a render hands back as an image: its metadata, the exact film (or the guided
//! inverse-variance combination) and the AOV layers. The command line writes these to an
//! EXR and the Python module returns them as arrays; both build them here, so the two
//! agree bit for bit.

use super::budget::RunOutcome;
use super::{RenderSettings, Renderer, Result};
use crate::gpu;
use crate::image_io::{self, Image, ImageError, RenderMeta};
use std::fmt;
use std::str::FromStr;

/// Metadata every render's EXR carries, from what was rendered and how: every setting
/// from the settings' serde form.
///
/// The version of the scene loaded (`--animation-time`, `--animation`, `--variant`) is
/// recorded as the extra keys `animation_time`, `animation` and `variant` where given.
pub fn render_meta(
    settings: &RenderSettings,
    scene_path: &str,
    scene: &crate::scene::Scene,
    device_name: &str,
) -> RenderMeta {
    let mut meta = RenderMeta::new();
    meta.device = Some(device_name.to_string());
    meta.scene_path = Some(scene_path.to_string());
    meta.scene_hash = Some(scene.hash.clone());
    if let Some(pose) = &scene.pose {
        meta.extra
            .insert("animation_time".into(), pose.time.to_string());
        if let Some(a) = &pose.animation {
            meta.extra.insert("animation".into(), a.clone());
        }
    }
    if let Some(v) = &scene.variant {
        meta.extra.insert("variant".into(), v.clone());
    }
    set_settings_meta(&mut meta, settings, None);
    meta
}

/// Records `settings` in `meta`: method, seed and depth in their fields, everything else
/// from the settings' serde form among the extra keys, replacing the keys `previous`
/// wrote (a comparison renders several methods with one metadata template, and a
/// method's image must not carry another method's settings).
pub fn set_settings_meta(
    meta: &mut RenderMeta,
    settings: &RenderSettings,
    previous: Option<&RenderSettings>,
) {
    if let Some(p) = previous {
        for (k, _) in p.metadata_pairs() {
            meta.extra.remove(&k);
        }
    }
    meta.method = Some(settings.method.name().to_string());
    meta.seed = Some(settings.seed as u64);
    meta.max_depth = Some(settings.max_depth);
    // Everything else the settings hold; these three have fields of their own.
    for (k, v) in settings.metadata_pairs() {
        if !matches!(k.as_str(), "method" | "seed" | "max_depth") {
            meta.extra.insert(k, v);
        }
    }
}

/// The image a run outputs: the film's exact sums, or the inverse-variance combination
/// of a guided run (float means only; its spp counts every pass).
pub fn outcome_image(
    out: &RunOutcome,
    width: u32,
    height: u32,
    mut meta: RenderMeta,
) -> std::result::Result<Image, ImageError> {
    meta.sample_offset = Some(out.film.sample_offset);
    let interrupted_in_training = out
        .guiding
        .as_ref()
        .is_some_and(|g| g.interrupted_in_training);
    if interrupted_in_training {
        meta.extra.insert(
            "guiding.interrupted".into(),
            "in training: the image is the training passes so far (with --guided-output late-passes the last four, with render-phase the last one)".into(),
        );
    }
    match &out.combined {
        Some(rgb) => {
            let trained: u64 = out
                .guiding
                .as_ref()
                .map_or(0, |g| g.iterations.iter().map(|i| i.spp).sum());
            // The passes are contiguous and end where the film's samples end; the film
            // is one of them when training was interrupted.
            let total = if interrupted_in_training {
                trained
            } else {
                out.film.spp + trained
            };
            meta.spp = Some(total);
            meta.sample_offset = Some(out.film.sample_offset + out.film.spp - total);
            meta.extra
                .insert("guided_output".into(), "inverse-variance".into());
            let pixels = rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let mut image = Image::new(width, height, pixels)?;
            image.meta = meta;
            Ok(image)
        }
        None => {
            meta.spp = Some(out.film.spp);
            let sums = out
                .film
                .sums
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect();
            Image::from_sums(width, height, sums, meta)
        }
    }
}

/// AOV layers: first-hit data the kernel accumulates when `settings.aovs` is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Aov {
    Albedo,
    Normal,
    Depth,
    Position,
    LightCount,
    RisWeight,
    SelectedLight,
    GuideFraction,
    SampleCount,
}

impl Aov {
    pub const ALL: [Aov; 9] = [
        Aov::Albedo,
        Aov::Normal,
        Aov::Depth,
        Aov::Position,
        Aov::LightCount,
        Aov::RisWeight,
        Aov::SelectedLight,
        Aov::GuideFraction,
        Aov::SampleCount,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Position => "position",
            Aov::LightCount => "light-count",
            Aov::RisWeight => "ris-weight",
            Aov::SelectedLight => "selected-light",
            Aov::GuideFraction => "guide-fraction",
            Aov::SampleCount => "sample-count",
        }
    }

    /// (first channel in the kernel's AOV buffer, channel names); None: computed on the host.
    pub fn layout(self) -> Option<(u32, &'static [&'static str])> {
        use gpu::*;
        Some(match self {
            Aov::Albedo => (AOV_ALBEDO, &["R", "G", "B"]),
            Aov::Normal => (AOV_NORMAL, &["X", "Y", "Z"]),
            Aov::Depth => (AOV_DEPTH, &["Z"]),
            Aov::Position => (AOV_POSITION, &["X", "Y", "Z"]),
            Aov::LightCount => (AOV_LIGHT_COUNT, &["Y"]),
            Aov::RisWeight => (AOV_RIS_WEIGHT, &["Y"]),
            Aov::SelectedLight => (AOV_SELECTED_LIGHT, &["Y"]),
            Aov::GuideFraction => (AOV_GUIDE_FRACTION, &["Y"]),
            Aov::SampleCount => return None,
        })
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Aov {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        Aov::ALL.into_iter().find(|a| a.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
            format!("unknown AOV `{s}` (expected {})", names.join(", "))
        })
    }
}

/// The layers `aovs` of the renderer's film (rendered with `settings.aovs` on), each as
/// named channels per pixel.
pub fn aov_layers(renderer: &Renderer, aovs: &[Aov]) -> Result<Vec<image_io::Aov>> {
    let data = renderer.aovs()?;
    let n = gpu::AOV_CHANNELS as usize;
    let pixels = renderer.settings.width as usize * renderer.settings.height as usize;
    let mut layers = Vec::with_capacity(aovs.len());
    for aov in aovs {
        let (channels, values): (&[&str], Vec<f32>) = match aov.layout() {
            Some((first, channels)) => (
                channels,
                data.chunks_exact(n)
                    .flat_map(|px| {
                        px[first as usize..first as usize + channels.len()]
                            .iter()
                            .copied()
                    })
                    .collect(),
            ),
            None => (&["Y"], vec![renderer.film_spp() as f32; pixels]),
        };
        let layer = image_io::Aov::new(aov.name(), channels, values)
            .map_err(|e| super::RenderError::Invalid(e.to_string()))?;
        layers.push(layer);
    }
    Ok(layers)
}
