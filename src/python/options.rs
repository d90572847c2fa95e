//! `Renderer(..., **options)`: the command line's estimator and device flags as keyword
//! arguments, named like the flags with `_` for `-` (`--ris-candidates` is
//! `ris_candidates=`, `--no-record-nee` is `record_nee=False`). Values are checked where
//! the command line checks them (the renderer, the guiding configuration), so the same
//! values fail with the same messages.

use crate::render::{GuidedOutput, LightMix, LightSource, RenderSettings, Strategy, Traversal};
use crate::shaders::ShaderSource;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The keyword options `Renderer` accepts besides its named parameters.
pub const OPTIONS: [&str; 30] = [
    "rr_depth",
    "source",
    "ris_candidates",
    "bsdf_fraction",
    "selection_learner",
    "train_fraction",
    "record_nee",
    "guide_target",
    "guide_density",
    "guide_history",
    "strategy",
    "hide_emitters",
    "emission_rays",
    "pixel_emitters",
    "guiding_threshold",
    "guiding_memory",
    "spatial_filter",
    "directional_filter",
    "guided_output",
    "learn_lights",
    "light_mix",
    "light_reuse",
    "reuse_cell_pixels",
    "reuse_cap",
    "light_visibility",
    "visibility_cell_pixels",
    "visibility_floor",
    "traversal",
    "validation",
    "shader_dir",
];

/// Device-side options.
#[derive(Clone, Debug, Default)]
pub struct DeviceExtras {
    pub validation: bool,
    pub shaders: ShaderSource,
}

/// A value of one of the command line's value enums, with clap's message when unknown.
fn value_enum<T: clap::ValueEnum>(flag: &str, value: &str) -> PyResult<T> {
    T::from_str(value, false).map_err(|_| {
        let possible: Vec<String> = T::value_variants()
            .iter()
            .filter_map(|v| v.to_possible_value())
            .map(|p| p.get_name().to_string())
            .collect();
        PyValueError::new_err(format!(
            "invalid value '{value}' for '--{flag}' [possible values: {}]",
            possible.join(", ")
        ))
    })
}

fn choice(flag: &str, value: &str, choices: [&str; 2]) -> PyResult<bool> {
    match choices.iter().position(|c| *c == value) {
        Some(i) => Ok(i == 0),
        None => Err(PyValueError::new_err(format!(
            "invalid value '{value}' for '--{flag}' [possible values: {}]",
            choices.join(", ")
        ))),
    }
}

/// Apply `options` to `settings`; returns the device-side ones.
pub fn apply(
    settings: &mut RenderSettings,
    options: Option<&Bound<'_, PyDict>>,
) -> PyResult<DeviceExtras> {
    let mut extras = DeviceExtras::default();
    let Some(options) = options else {
        return Ok(extras);
    };
    for (k, v) in options.iter() {
        let key: String = k.extract()?;
        let flag = key.replace('_', "-");
        match key.as_str() {
            "rr_depth" => settings.rr_depth = v.extract()?,
            "source" => {
                settings.source = value_enum::<LightSource>(&flag, &v.extract::<String>()?)?
            }
            "ris_candidates" => settings.ris_candidates = v.extract()?,
            "bsdf_fraction" => {
                // A fixed fraction, as on the command line; None: learned per leaf.
                let f: Option<f32> = v.extract()?;
                settings.guiding.learn_selection = f.is_none();
                settings.guiding.bsdf_fraction = f.unwrap_or(0.5);
            }
            "selection_learner" => {
                settings.guiding.selection_learner =
                    value_enum::<crate::guiding::SelectionLearner>(&flag, &v.extract::<String>()?)?
            }
            "guide_target" => {
                settings.guiding.target =
                    value_enum::<crate::guiding::GuideTarget>(&flag, &v.extract::<String>()?)?
            }
            "guide_density" => {
                settings.guiding.density =
                    value_enum::<crate::guiding::GuideDensity>(&flag, &v.extract::<String>()?)?
            }
            "guide_history" => settings.guiding.history = v.extract()?,
            "train_fraction" => settings.guiding.train_fraction = v.extract()?,
            "record_nee" => settings.guiding.record_nee = v.extract()?,
            "strategy" => {
                settings.strategy = value_enum::<Strategy>(&flag, &v.extract::<String>()?)?
            }
            "hide_emitters" => settings.hide_emitters = v.extract()?,
            "emission_rays" => settings.emission_rays = v.extract()?,
            "pixel_emitters" => settings.pixel_emitters = v.extract()?,
            "guiding_threshold" => settings.guiding.spatial_threshold = v.extract()?,
            "guiding_memory" => {
                let mib: u64 = v.extract()?;
                settings.guiding.memory_cap_bytes = mib.saturating_mul(1 << 20);
            }
            "spatial_filter" => {
                settings.guiding.spatial_filter =
                    if choice(&flag, &v.extract::<String>()?, ["jitter", "nearest"])? {
                        crate::guiding::SpatialFilter::StochasticBox
                    } else {
                        crate::guiding::SpatialFilter::Nearest
                    }
            }
            "directional_filter" => {
                settings.guiding.directional_filter =
                    if choice(&flag, &v.extract::<String>()?, ["box", "nearest"])? {
                        crate::guiding::DirectionalFilter::Box
                    } else {
                        crate::guiding::DirectionalFilter::Nearest
                    }
            }
            "guided_output" => {
                settings.guiding.output =
                    value_enum::<GuidedOutput>(&flag, &v.extract::<String>()?)?
            }
            "learn_lights" => settings.guiding.learn_lights = v.extract()?,
            "light_mix" => {
                // As on the command line: a number (fixed), "learned", or "auto"/None.
                let mix = match v.extract::<Option<f32>>() {
                    Ok(m) => m.map_or(LightMix::Auto, LightMix::Fixed),
                    Err(_) => LightMix::parse(&v.extract::<String>()?)
                        .map_err(|e| PyValueError::new_err(format!("light_mix: {e}")))?,
                };
                settings.guiding.set_light_mix(mix);
            }
            "light_reuse" => {
                settings.light_reuse.world =
                    choice(&flag, &v.extract::<String>()?, ["world", "off"])?
            }
            "reuse_cell_pixels" => settings.light_reuse.cell_pixels = v.extract()?,
            "reuse_cap" => settings.light_reuse.confidence_cap = v.extract()?,
            "light_visibility" => {
                settings.light_visibility.learned =
                    choice(&flag, &v.extract::<String>()?, ["learned", "off"])?
            }
            "visibility_cell_pixels" => settings.light_visibility.cell_pixels = v.extract()?,
            "visibility_floor" => settings.light_visibility.floor = v.extract()?,
            "traversal" => {
                settings.traversal = value_enum::<Traversal>(&flag, &v.extract::<String>()?)?
            }
            "validation" => extras.validation = v.extract()?,
            "shader_dir" => {
                if !v.is_none() {
                    extras.shaders = ShaderSource::Directory(v.extract()?);
                }
            }
            _ => {
                return Err(PyTypeError::new_err(format!(
                    "Renderer() got an unexpected keyword argument '{key}' (options: {})",
                    OPTIONS.join(", ")
                )))
            }
        }
    }
    Ok(extras)
}
