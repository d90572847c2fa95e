//! What to render and how: one [`RenderSettings`] value (method, resolution, the knobs of
//! NEE and RIS, the view and output overrides, and the guiding options nested in
//! [`GuidingSettings`]) that every entry point (the CLI's render, reference, compare and
//! guiding view, the bench, the tests) builds and that [`RenderSettings::validate`]
//! checks in one place, with the flag names in its errors. Its serde form is what the
//! EXR metadata records ([`RenderSettings::metadata_pairs`]), so no list of keys is kept
//! by hand.

use crate::guiding::{
    DirectionalFilter, GuideDensity, GuideTarget, SelectionLearner, SpatialFilter,
};
use std::fmt;
use std::str::FromStr;

/// Rendering method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Path tracing with NEE from the source distribution and power-heuristic MIS.
    Pt,
    /// NEE whose light is chosen by streaming RIS.
    Ris,
    /// SD-tree path guiding with `pt`'s NEE.
    Guided,
    /// SD-tree path guiding with RIS NEE, RIS contributions training the tree (the paper).
    GuidedRis,
}

impl Method {
    pub const ALL: [Method; 4] = [Method::Pt, Method::Ris, Method::Guided, Method::GuidedRis];

    pub fn name(self) -> &'static str {
        match self {
            Method::Pt => "pt",
            Method::Ris => "ris",
            Method::Guided => "guided",
            Method::GuidedRis => "guided-ris",
        }
    }

    pub fn uses_ris(self) -> bool {
        matches!(self, Method::Ris | Method::GuidedRis)
    }

    pub fn uses_guiding(self) -> bool {
        matches!(self, Method::Guided | Method::GuidedRis)
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown method `{s}` (expected pt, ris, guided or guided-ris)"))
    }
}

/// Source distribution of light samples (NEE in `pt`, candidates in RIS).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum LightSource {
    /// Uniform light model → uniform triangle in it → uniform point (the paper's).
    Uniform,
    /// Models and triangles proportionally to emitted power (alias tables).
    Power,
    /// Models by a bound of what they send toward the shading point (a light tree over
    /// the models, mixed with the uniform source), triangles by power.
    Tree,
}

/// How direct light is estimated: both techniques combined by MIS (the default), or one
/// alone (for debugging and for tests that check all three agree).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum Strategy {
    Mis,
    /// Next-event estimation only (emission reached by direction sampling is dropped
    /// unless NEE cannot sample that emitter).
    Nee,
    /// Direction sampling only (no NEE).
    Bsdf,
}

/// What a guided render outputs.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum GuidedOutput {
    /// Every pass, training and render phase, every sample weighted equally: the film
    /// is the whole budget's range of sample indices; unbiased, exact film sums (see
    /// `render/pass_output.rs`).
    AllPasses,
    /// The render phase alone (training images are discarded).
    RenderPhase,
    /// The render phase and the last four training passes, every sample weighted
    /// equally: unbiased, exact film sums (see `render/pass_output.rs`).
    LatePasses,
    /// Müller et al.'s option: the training iterations' images and the render phase's,
    /// weighted by the inverse of their estimated variance.
    InverseVariance,
}

/// Default `--guide-history` (README, Path guiding: "Training history").
pub const DEFAULT_GUIDE_HISTORY: f32 = 0.0;

/// The options of the guided methods.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GuidingSettings {
    /// Probability of sampling the BSDF in the one-sample mixture (`--bsdf-fraction`).
    pub bsdf_fraction: f32,
    /// Share of the budget spent training the SD-tree (`--train-fraction`).
    pub train_fraction: f32,
    /// Record NEE contributions into the SD-tree.
    pub record_nee: bool,
    /// How a training record is placed in space and on the directional square.
    pub spatial_filter: SpatialFilter,
    pub directional_filter: DirectionalFilter,
    /// c in the spatial split threshold c·√(spp of the coming iteration / 4), for a
    /// 1280×720 image (scaled by √(pixels / 921 600) for others).
    pub spatial_threshold: f32,
    /// Stop splitting before the SD-tree's buffers exceed this.
    pub memory_cap_bytes: u64,
    /// Learn per SD-tree leaf which lights deliver NEE contributions and choose light
    /// models from (1 − light_mix)·source + light_mix·learned table.
    pub learn_lights: bool,
    pub light_mix: f32,
    /// Choose the mix per SD-tree leaf between passes, starting from `light_mix`
    /// (`--light-mix learned`); false: `light_mix` everywhere (`--light-mix X`); None
    /// (`--light-mix auto`): learned for `guided`, fixed for `guided-ris`
    /// (`learns_light_mix`).
    #[serde(default)]
    pub learn_light_mix: Option<bool>,
    /// Which passes make the image: the render phase alone, with the last training
    /// passes, or all passes weighted by inverse variance.
    pub output: GuidedOutput,
    /// Learn the BSDF selection probability per SD-tree leaf (Müller et al. 2019),
    /// starting from `bsdf_fraction`; off: `bsdf_fraction` everywhere
    /// (`--bsdf-fraction X` turns learning off).
    #[serde(default)]
    pub learn_selection: bool,
    /// How the selection probability is learned (`--selection-learner`). Settings
    /// written before the option existed read as `KlAdam`, what they rendered with.
    #[serde(default = "kl_adam")]
    pub selection_learner: SelectionLearner,
    /// What radiance the SD-tree learns (`--guide-target`).
    #[serde(default)]
    pub target: GuideTarget,
    /// Which statistic of the target the quadtrees follow (`--guide-density`).
    #[serde(default)]
    pub density: GuideDensity,
    /// Weight of the earlier training iterations' statistics in each refit, per record,
    /// against the finished iteration's (`--guide-history`; 0: Müller et al.'s reset).
    /// Settings written before the option existed read as 0, what they rendered with.
    #[serde(default)]
    pub history: f32,
}

fn kl_adam() -> SelectionLearner {
    SelectionLearner::KlAdam
}

impl Default for GuidingSettings {
    fn default() -> Self {
        GuidingSettings {
            bsdf_fraction: 0.5,
            train_fraction: 0.3,
            record_nee: true,
            // Measured better than the stochastic box at equal spp on gap,
            // bistro-night and the street, equal on cornell-lights (README, Path
            // guiding): the box's jitter carries records through walls into leaves
            // that are still large.
            spatial_filter: SpatialFilter::Nearest,
            directional_filter: DirectionalFilter::Box,
            spatial_threshold: 12000.0,
            memory_cap_bytes: crate::guiding::DEFAULT_MEMORY_CAP_BYTES,
            // Measured better at equal spp on every shipped scene, on the GPU at
            // 1024×576 also at equal time (README, Path guiding); costs 35–60 % more
            // per guided-ris sample.
            learn_lights: true,
            light_mix: 0.5,
            learn_light_mix: None,
            // Measured better than the render phase alone and than the last training
            // passes with it (stratified sample indices gain most as one whole range;
            // README, Path guiding), and unbiased.
            output: GuidedOutput::AllPasses,
            learn_selection: true,
            // Measured better than the reference's Adam on the KL divergence for
            // `guided-ris` on nine scenes at 256 spp and level for `guided` (README,
            // Path guiding).
            selection_learner: SelectionLearner::Variance,
            // The paper's target: measured far better than `Indirect` for `guided` at
            // 1024×576 on bistro-night and the street, and better on both at 80×45;
            // `Indirect` wins only on gap (README, Path guiding).
            target: GuideTarget::All,
            density: GuideDensity::Radiance,
            history: DEFAULT_GUIDE_HISTORY,
        }
    }
}

/// Parameters of one render.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderSettings {
    pub method: Method,
    /// Image size (recorded in the EXR as its resolution, not among the settings).
    #[serde(skip)]
    pub width: u32,
    #[serde(skip)]
    pub height: u32,
    /// Path segments (Mitsuba's max_depth): 1 = emitters seen directly, 2 = direct light.
    pub max_depth: u32,
    /// Russian roulette from this depth on; 0 = off.
    pub rr_depth: u32,
    pub seed: u32,
    pub source: LightSource,
    /// RIS candidates per NEE (M).
    pub ris_candidates: u32,
    pub strategy: Strategy,
    /// Emitters seen directly by the camera contribute nothing (Mitsuba's
    /// `hide_emitters`); light they send into the scene still counts.
    pub hide_emitters: bool,
    /// Camera rays per sample (`--emission-rays`): the path continues from the first;
    /// the others, each at its own stratified position in the pixel, add only the
    /// emission they see. 1: one camera ray, the plain estimator.
    #[serde(default = "one")]
    pub emission_rays: u32,
    /// Small emitters seen directly are sampled inside the pixels they cover
    /// (`--no-pixel-emitters` turns it off; `pixel_emitters.rs`).
    #[serde(default = "yes")]
    pub pixel_emitters: bool,
    /// Vertical field of view in degrees replacing the camera's (`--fov`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fov_degrees: Option<f32>,
    /// Exposure in stops of the tonemapped outputs (`--exposure`; the EXR is linear).
    pub exposure: f32,
    /// Accumulate first-hit AOVs and per-pixel outliers (costs memory and a little time;
    /// no influence on the image).
    #[serde(skip)]
    pub aovs: bool,
    /// Ray traversal asked for (`--traversal`); the renderer resolves it against the
    /// device (`Renderer::traversal` holds what is used and why).
    #[serde(default)]
    pub traversal: super::traversal::Traversal,
    /// Render with the kernel that counts SIMD lane utilisation (`--lane-stats`; slower,
    /// same image; see `RenderStats::lanes`).
    #[serde(skip)]
    pub lane_stats: bool,
    /// Read the scene's and the SD-tree's arrays through their device addresses (true)
    /// or the bound storage buffers (false); `None`: addresses on CPU devices, where
    /// they are faster (`Renderer::scene_addresses`; `--scene-arrays`). Same image
    /// either way.
    #[serde(skip)]
    pub scene_addresses: Option<bool>,
    /// Take the Lambertian lobe alone at Lambertian surfaces, and compile the kernels
    /// with that lobe alone where every material the scene uses is Lambertian
    /// (`Renderer::bsdf_kernel`; `--general-bsdf` turns it off, for measurements). Same
    /// image either way.
    #[serde(skip)]
    pub lambertian_shortcut: bool,
    /// World-space reuse of RIS light samples between paths (`--light-reuse`; RIS
    /// methods only; off by default).
    #[serde(default)]
    pub light_reuse: LightReuse,
    /// Learned light visibility in RIS's target (`--light-visibility`; RIS methods only;
    /// off by default).
    #[serde(default)]
    pub light_visibility: LightVisibility,
    pub guiding: GuidingSettings,
}

/// Learned light visibility (`shaders_glsl/inc/light_visibility.glsl`): RIS's target
/// p̂ = Le·f·G times each light model's unoccluded fraction, counted per cell of a
/// world-space hash grid from the shadow rays of earlier dispatches; unbiased.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LightVisibility {
    /// Learned visibility on (`--light-visibility learned`) or off.
    pub learned: bool,
    /// A cell's edge in pixel footprints at its distance from the camera
    /// (`--visibility-cell-pixels`; rounded to a power of two in world units).
    pub cell_pixels: f32,
    /// The least factor a learned visibility gives a light's target
    /// (`--visibility-floor`, in (0, 1]): bounds how much an occluded-looking light's
    /// samples can weigh when it is visible after all.
    pub floor: f32,
}

impl Default for LightVisibility {
    fn default() -> Self {
        LightVisibility {
            learned: false,
            cell_pixels: DEFAULT_VISIBILITY_CELL_PIXELS,
            floor: DEFAULT_VISIBILITY_FLOOR,
        }
    }
}

/// Default `--visibility-cell-pixels`.
pub const DEFAULT_VISIBILITY_CELL_PIXELS: f32 = 4.0;
/// Default `--visibility-floor`.
pub const DEFAULT_VISIBILITY_FLOOR: f32 = 0.1;

/// World-space light reuse (`shaders_glsl/inc/light_reuse.glsl`): each RIS vertex
/// combines its reservoir with the one a vertex of an earlier dispatch left in its cell
/// of a hash grid over the scene, by generalized RIS; unbiased.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LightReuse {
    /// Reuse on (`--light-reuse world`) or off.
    pub world: bool,
    /// A cell's edge in pixel footprints at its distance from the camera
    /// (`--reuse-cell-pixels`; rounded to a power of two in world units).
    pub cell_pixels: f32,
    /// The most canonical reservoirs one reused reservoir stands for (`--reuse-cap`).
    pub confidence_cap: f32,
}

impl Default for LightReuse {
    fn default() -> Self {
        LightReuse {
            world: false,
            cell_pixels: DEFAULT_REUSE_CELL_PIXELS,
            confidence_cap: DEFAULT_REUSE_CAP,
        }
    }
}

/// Default `--reuse-cell-pixels` (4 against 16: 0.89–0.95× the MAE on the streets at
/// 64 spp, against 0.94–0.95×; README, "World-space light reuse").
pub const DEFAULT_REUSE_CELL_PIXELS: f32 = 4.0;
/// Default `--reuse-cap` (1 against 2 and 4: the least correlation between a pixel's
/// samples; README, "World-space light reuse").
pub const DEFAULT_REUSE_CAP: f32 = 1.0;

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            method: Method::Pt,
            width: 512,
            height: 512,
            max_depth: 4,
            rr_depth: 0,
            seed: 0,
            source: LightSource::Uniform,
            ris_candidates: 32,
            strategy: Strategy::Mis,
            hide_emitters: false,
            emission_rays: 1,
            pixel_emitters: true,
            scene_addresses: None,
            lambertian_shortcut: true,
            light_reuse: LightReuse::default(),
            light_visibility: LightVisibility::default(),
            fov_degrees: None,
            exposure: 0.0,
            aovs: false,
            traversal: super::traversal::Traversal::Auto,
            lane_stats: false,
            guiding: GuidingSettings::default(),
        }
    }
}

/// Pixels of the largest image (the film, AOVs and outliers are per-pixel buffers).
pub const MAX_PIXELS: u64 = 1 << 28;
/// The most RIS candidates per NEE (each costs a light sample per path vertex).
pub const MAX_RIS_CANDIDATES: u32 = 1024;
/// Most camera rays per sample (`--emission-rays`).
pub const MAX_EMISSION_RAYS: u32 = 64;

fn one() -> u32 {
    1
}
fn yes() -> bool {
    true
}
/// The largest |--exposure| in stops (2^±64 spans every f32 radiance).
pub const MAX_EXPOSURE: f32 = 64.0;

/// A setting out of range: which one (by its command-line flag), its value, and what
/// it must be.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{setting} {value}: {expected}")]
pub struct SettingsError {
    pub setting: &'static str,
    pub value: String,
    pub expected: String,
}

impl RenderSettings {
    /// Checks every setting (see the module comment); the first problem is returned.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let bad = |setting: &'static str, value: String, expected: String| {
            Err(SettingsError {
                setting,
                value,
                expected,
            })
        };
        let pixels = u64::from(self.width) * u64::from(self.height);
        if pixels == 0 || pixels > MAX_PIXELS {
            return bad(
                "--width/--height",
                format!("{}×{}", self.width, self.height),
                format!("the image must have 1 to {MAX_PIXELS} pixels"),
            );
        }
        if self.max_depth == 0 {
            return bad("--max-depth", "0".into(), "must be at least 1".into());
        }
        // A training path keeps a record per vertex in registers until it ends; guided
        // methods refuse longer paths rather than silently dropping their far vertices.
        let max_guided_depth = crate::gpu::GUIDE_MAX_RECORDED_VERTICES + 1;
        if self.method.uses_guiding() && self.max_depth > max_guided_depth {
            return bad(
                "--max-depth",
                self.max_depth.to_string(),
                format!(
                    "at most {max_guided_depth} for the guided methods: their training records \
                     follow at most {max_guided_depth} path segments (use pt or ris for longer paths)"
                ),
            );
        }
        if !(1..=MAX_RIS_CANDIDATES).contains(&self.ris_candidates) {
            return bad(
                "--ris-candidates",
                self.ris_candidates.to_string(),
                format!("must be in 1..={MAX_RIS_CANDIDATES}"),
            );
        }
        if !(1..=MAX_EMISSION_RAYS).contains(&self.emission_rays) {
            return bad(
                "--emission-rays",
                self.emission_rays.to_string(),
                format!("must be in 1..={MAX_EMISSION_RAYS}"),
            );
        }
        if let Some(fov) = self.fov_degrees {
            if !(fov > 0.0 && fov < 180.0) {
                return bad(
                    "--fov",
                    fov.to_string(),
                    "must be a vertical field of view in degrees, above 0 and below 180".into(),
                );
            }
        }
        if !(self.exposure.is_finite() && self.exposure.abs() <= MAX_EXPOSURE) {
            return bad(
                "--exposure",
                self.exposure.to_string(),
                format!("must be a number of stops in [-{MAX_EXPOSURE}, {MAX_EXPOSURE}]"),
            );
        }
        let r = &self.light_reuse;
        if r.world && !self.method.uses_ris() {
            return bad(
                "--light-reuse",
                "world".into(),
                format!(
                    "reuses RIS reservoirs: it needs --method ris or guided-ris, not {}",
                    self.method.name()
                ),
            );
        }
        if !(r.cell_pixels.is_finite() && (0.25..=65536.0).contains(&r.cell_pixels)) {
            return bad(
                "--reuse-cell-pixels",
                r.cell_pixels.to_string(),
                "must be a cell size in pixels, in [0.25, 65536]".into(),
            );
        }
        if !(r.confidence_cap.is_finite() && (1.0..=1e6).contains(&r.confidence_cap)) {
            return bad(
                "--reuse-cap",
                r.confidence_cap.to_string(),
                "must be a number of reservoirs in [1, 1e6]".into(),
            );
        }
        let v = &self.light_visibility;
        if v.learned && !self.method.uses_ris() {
            return bad(
                "--light-visibility",
                "learned".into(),
                format!(
                    "weights RIS's target: it needs --method ris or guided-ris, not {}",
                    self.method.name()
                ),
            );
        }
        if !(v.cell_pixels.is_finite() && (0.25..=65536.0).contains(&v.cell_pixels)) {
            return bad(
                "--visibility-cell-pixels",
                v.cell_pixels.to_string(),
                "must be a cell size in pixels, in [0.25, 65536]".into(),
            );
        }
        if !(v.floor.is_finite() && v.floor > 0.0 && v.floor <= 1.0) {
            return bad(
                "--visibility-floor",
                v.floor.to_string(),
                "must be a factor in (0, 1]: a learned visibility may not rule a light out".into(),
            );
        }
        self.guiding.validate()
    }

    /// The settings as flat `(key, text)` pairs from their serde form, nested values
    /// as `outer.inner`: what an EXR's metadata records. The guiding options appear only
    /// for guided methods, where they mean something.
    pub fn metadata_pairs(&self) -> Vec<(String, String)> {
        // Through JSON text: f32s print as their shortest form (0.3, not 0.30000001…).
        let text = serde_json::to_string(self).expect("settings are plain data");
        let value: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
        let mut out = Vec::new();
        flatten("", &value, &mut out);
        if !self.method.uses_guiding() {
            out.retain(|(k, _)| !k.starts_with("guiding."));
        }
        out
    }
}

fn flatten(prefix: &str, value: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match value {
        serde_json::Value::Object(map) => {
            for (k, v) in map {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        serde_json::Value::String(s) => out.push((prefix.to_string(), s.clone())),
        other => out.push((prefix.to_string(), other.to_string())),
    }
}

/// What `--light-mix` (and Python's `light_mix`) asks for: `auto`, `learned` or a fixed
/// probability (see `GuidingSettings::learn_light_mix`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightMix {
    Auto,
    Learned,
    Fixed(f32),
}

impl LightMix {
    /// `auto`, `learned` or a number (range-checked later, by `validate`).
    pub fn parse(s: &str) -> Result<LightMix, String> {
        match s {
            "auto" => Ok(LightMix::Auto),
            "learned" => Ok(LightMix::Learned),
            _ => s
                .parse::<f32>()
                .map(LightMix::Fixed)
                .map_err(|_| format!("`{s}`: expected auto, learned or a probability")),
        }
    }
}

impl GuidingSettings {
    /// Set the light mix options as `mix` asks (a learned mix starts from 0.5).
    pub fn set_light_mix(&mut self, mix: LightMix) {
        (self.light_mix, self.learn_light_mix) = match mix {
            LightMix::Auto => (0.5, None),
            LightMix::Learned => (0.5, Some(true)),
            LightMix::Fixed(m) => (m, Some(false)),
        };
    }

    /// Whether `method` chooses the light mix per leaf. By default (None) `guided` does
    /// and `guided-ris` keeps the fixed mix: the leaf's choice minimises the variance of
    /// one-sample NEE, exact for `guided`'s NEE and measured worse than the fixed 0.5 for
    /// RIS NEE (src/guiding/light_mix.rs, README).
    pub fn learns_light_mix(&self, method: Method) -> bool {
        self.learn_light_mix.unwrap_or(method == Method::Guided)
    }

    /// Checks the guiding options (part of [`RenderSettings::validate`]).
    pub fn validate(&self) -> Result<(), SettingsError> {
        let fraction = |setting: &'static str, v: f32, hi: f32| {
            if (0.0..=hi).contains(&v) {
                Ok(())
            } else {
                Err(SettingsError {
                    setting,
                    value: v.to_string(),
                    expected: format!("must be in [0, {hi}]"),
                })
            }
        };
        fraction("--bsdf-fraction", self.bsdf_fraction, 1.0)?;
        fraction("--train-fraction", self.train_fraction, 1.0)?;
        fraction("--guide-history", self.history, 1.0)?;
        fraction("--light-mix", self.light_mix, crate::guiding::MAX_LIGHT_MIX)?;
        if !(self.spatial_threshold.is_finite() && self.spatial_threshold > 0.0) {
            return Err(SettingsError {
                setting: "--guiding-threshold",
                value: self.spatial_threshold.to_string(),
                expected: "must be a positive number of records".into(),
            });
        }
        if self.memory_cap_bytes == 0 {
            return Err(SettingsError {
                setting: "--guiding-memory",
                value: "0".into(),
                expected: "must be at least 1 MiB".into(),
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        RenderSettings::default().validate().unwrap();
    }

    #[test]
    fn each_bad_value_names_its_flag() {
        type Change = Box<dyn Fn(&mut RenderSettings)>;
        let cases: Vec<(&str, Change)> = vec![
            ("--fov", Box::new(|s| s.fov_degrees = Some(180.0))),
            ("--fov", Box::new(|s| s.fov_degrees = Some(f32::NAN))),
            ("--fov", Box::new(|s| s.fov_degrees = Some(0.0))),
            ("--exposure", Box::new(|s| s.exposure = f32::INFINITY)),
            ("--exposure", Box::new(|s| s.exposure = 1e6)),
            (
                "--train-fraction",
                Box::new(|s| s.guiding.train_fraction = 1.5),
            ),
            (
                "--train-fraction",
                Box::new(|s| s.guiding.train_fraction = f32::NAN),
            ),
            ("--guide-history", Box::new(|s| s.guiding.history = -0.5)),
            (
                "--guide-history",
                Box::new(|s| s.guiding.history = f32::NAN),
            ),
            (
                "--guiding-threshold",
                Box::new(|s| s.guiding.spatial_threshold = 0.0),
            ),
            (
                "--guiding-threshold",
                Box::new(|s| s.guiding.spatial_threshold = f32::NAN),
            ),
            (
                "--bsdf-fraction",
                Box::new(|s| s.guiding.bsdf_fraction = -0.1),
            ),
            ("--light-mix", Box::new(|s| s.guiding.light_mix = 1.0)),
            (
                "--guiding-memory",
                Box::new(|s| s.guiding.memory_cap_bytes = 0),
            ),
            ("--max-depth", Box::new(|s| s.max_depth = 0)),
            ("--ris-candidates", Box::new(|s| s.ris_candidates = 0)),
            ("--light-reuse", Box::new(|s| s.light_reuse.world = true)),
            (
                "--reuse-cell-pixels",
                Box::new(|s| s.light_reuse.cell_pixels = f32::NAN),
            ),
            (
                "--reuse-cap",
                Box::new(|s| s.light_reuse.confidence_cap = 0.5),
            ),
            (
                "--light-visibility",
                Box::new(|s| s.light_visibility.learned = true),
            ),
            (
                "--visibility-cell-pixels",
                Box::new(|s| s.light_visibility.cell_pixels = 0.0),
            ),
            (
                "--visibility-floor",
                Box::new(|s| s.light_visibility.floor = 0.0),
            ),
            (
                "--visibility-floor",
                Box::new(|s| s.light_visibility.floor = 1.5),
            ),
            ("--emission-rays", Box::new(|s| s.emission_rays = 0)),
            ("--emission-rays", Box::new(|s| s.emission_rays = 65)),
            ("--width/--height", Box::new(|s| s.width = 0)),
            (
                "--width/--height",
                Box::new(|s| (s.width, s.height) = (1 << 15, 1 << 15)),
            ),
        ];
        for (flag, change) in cases {
            let mut s = RenderSettings::default();
            change(&mut s);
            let e = s.validate().unwrap_err();
            assert_eq!(e.setting, flag, "{e}");
        }
    }

    #[test]
    fn metadata_comes_from_the_serde_form() {
        let mut s = RenderSettings {
            method: Method::GuidedRis,
            ..RenderSettings::default()
        };
        let pairs: std::collections::BTreeMap<String, String> =
            s.metadata_pairs().into_iter().collect();
        assert_eq!(pairs["source"], "uniform");
        assert_eq!(pairs["ris_candidates"], "32");
        assert_eq!(pairs["guiding.train_fraction"], "0.3");
        assert_eq!(pairs["guiding.output"], "all-passes");
        assert!(!pairs.contains_key("width") && !pairs.contains_key("fov_degrees"));
        s.method = Method::Pt;
        s.fov_degrees = Some(40.0);
        let pairs: std::collections::BTreeMap<String, String> =
            s.metadata_pairs().into_iter().collect();
        assert!(pairs.keys().all(|k| !k.starts_with("guiding.")));
        assert_eq!(pairs["fov_degrees"], "40.0");
    }
}
