//! What to render and how: method, sample budget, resolution and the knobs of NEE, RIS
//! and guiding.

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

/// SD-tree options beyond the kernel's.
#[derive(Clone, Debug)]
pub struct GuidingSettings {
    /// c in the spatial split threshold c·√(spp of the coming iteration / 4), for a
    /// 1280×720 image (scaled by √(pixels / 921 600) for others).
    pub spatial_threshold: f32,
    /// Stop splitting before the SD-tree's buffers exceed this.
    pub memory_cap_bytes: u64,
    /// Learn per SD-tree leaf which lights deliver NEE contributions and choose light
    /// models from (1 − light_mix)·source + light_mix·learned table.
    pub learn_lights: bool,
    pub light_mix: f32,
}

impl Default for GuidingSettings {
    fn default() -> Self {
        GuidingSettings {
            spatial_threshold: 12000.0,
            memory_cap_bytes: crate::guiding::DEFAULT_MEMORY_CAP_BYTES,
            learn_lights: false,
            light_mix: 0.5,
        }
    }
}

/// What a guided render outputs.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum GuidedOutput {
    /// The render phase alone (training images are discarded).
    RenderPhase,
    /// Müller et al.'s option: the training iterations' images and the render phase's,
    /// weighted by the inverse of their estimated variance.
    InverseVariance,
}

/// Parameters of one render that the kernel sees.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub method: Method,
    pub width: u32,
    pub height: u32,
    /// Path segments (Mitsuba's max_depth): 1 = emitters seen directly, 2 = direct light.
    pub max_depth: u32,
    /// Russian roulette from this depth on; 0 = off.
    pub rr_depth: u32,
    pub seed: u32,
    pub source: LightSource,
    /// RIS candidates per NEE (M).
    pub ris_candidates: u32,
    /// Guiding: probability of sampling the BSDF in the one-sample mixture.
    pub bsdf_fraction: f32,
    /// Guiding: share of the budget spent training the SD-tree.
    pub train_fraction: f32,
    /// Guiding: record NEE contributions into the SD-tree.
    pub record_nee: bool,
    /// Guiding: stochastic spatial filter (else nearest).
    pub spatial_jitter: bool,
    /// Guiding: box directional filter (else nearest).
    pub directional_box: bool,
    pub strategy: Strategy,
    /// Emitters seen directly by the camera contribute nothing (Mitsuba's
    /// `hide_emitters`); light they send into the scene still counts.
    pub hide_emitters: bool,
    /// Accumulate first-hit AOVs and per-pixel outliers (costs memory and a little time).
    pub aovs: bool,
    pub guiding: GuidingSettings,
    pub guided_output: GuidedOutput,
}

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
            bsdf_fraction: 0.5,
            train_fraction: 0.3,
            record_nee: true,
            spatial_jitter: true,
            directional_box: true,
            strategy: Strategy::Mis,
            hide_emitters: false,
            aovs: false,
            guiding: GuidingSettings::default(),
            guided_output: GuidedOutput::RenderPhase,
        }
    }
}
