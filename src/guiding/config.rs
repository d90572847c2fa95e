//! Options of the SD-tree: the refit rules of Müller et al. 2017 (spatial split threshold
//! c, directional subdivision threshold ρ, quadtree depth cap), the memory cap, the
//! training filters, and the two renderer-side switches the kernels read from the
//! guiding header (record NEE contributions, BSDF sampling fraction). Defaults are the
//! reference implementation's, except the spatial filter: nearest, measured better than
//! the reference's stochastic box at equal spp on every scene where they differ (README,
//! Path guiding); the directional filter is the reference's box, spread over the grid of
//! the record's cell depth instead of walked depth first (`guide_splat_box`).

use super::GuidingError;

/// How a training record is placed in space.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpatialFilter {
    /// Into the leaf holding the vertex.
    #[default]
    Nearest,
    /// Into the leaf holding the vertex jittered uniformly within a box of the size of
    /// its leaf (clamped to the tree's cube): a stochastic box filter.
    StochasticBox,
}

/// How a training record is placed on the directional square.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DirectionalFilter {
    /// Into the quadtree cell holding the direction.
    Nearest,
    /// Spread over a box of the size of the cell holding the direction, centred on it:
    /// by area over the (at most four) cells of that size it overlaps, each share in the
    /// leaf holding it, or evenly over a finer subtree (`guide_splat_box`).
    #[default]
    Box,
}

/// What radiance the training records measure (`--guide-target`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum GuideTarget {
    /// All incident radiance: direction samples' full incident light and NEE's light
    /// samples (Müller et al.; Sugita and Fujishiro's NEE records; the renderer's
    /// default, see `GuidingSettings`).
    #[default]
    All,
    /// Indirect light only: what the next vertex reflects; no NEE records, and emission
    /// reached by the sampled direction is not recorded (Müller's suggestion for NEE).
    Indirect,
    /// What the direction estimator carries: its MIS-weighted emission plus the
    /// reflected light; no NEE records (with RIS NEE the same as `indirect` for
    /// emitters NEE can sample).
    Contribution,
}

/// Which statistic of the target the directional quadtrees follow (`--guide-density`).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum GuideDensity {
    /// The mean: density ∝ E[L] (Müller et al. 2017; the paper's).
    #[default]
    Radiance,
    /// The square root of the second moment: density ∝ √E[L²] (Rath et al. 2020,
    /// "Variance-aware path guiding"), which accounts for the noise of the estimates
    /// that follow the sampled direction.
    VarianceAware,
}

/// How each leaf learns its BSDF selection probability (`--selection-learner`;
/// src/guiding/selection.rs).
#[derive(
    Clone,
    Copy,
    Debug,
    PartialEq,
    Eq,
    Default,
    serde::Serialize,
    serde::Deserialize,
    clap::ValueEnum,
)]
#[serde(rename_all = "kebab-case")]
pub enum SelectionLearner {
    /// After each pass, the α minimising the pass's estimate of the direction
    /// estimator's second moment, averaged with the leaf's α by the effective number of
    /// records behind each.
    #[default]
    Variance,
    /// Adam on the KL divergence between the mixture and f·cos·L, one step per two
    /// records (Müller et al. 2019; the reference implementation's).
    KlAdam,
}

/// SD-tree options.
#[derive(Clone, Debug, PartialEq)]
pub struct GuidingConfig {
    /// c: a spatial leaf splits while its statistical weight exceeds
    /// c·√(spp of the coming iteration / 4) (reference: `sTreeThreshold` = 12000).
    pub spatial_threshold: f32,
    /// ρ: a quadrant subdivides while its share of the tree's energy exceeds ρ.
    pub rho: f32,
    /// Deepest quadtree node level (the root is level 1; reference: 20).
    pub max_quad_depth: u32,
    /// Deepest spatial leaf (the root is depth 0).
    pub max_spatial_depth: u32,
    /// Spatial splits stop before the GPU arrays would exceed this many bytes.
    pub memory_cap_bytes: u64,
    pub spatial_filter: SpatialFilter,
    pub directional_filter: DirectionalFilter,
    /// Whether NEE contributions train the tree (read by the render kernel).
    pub record_nee: bool,
    /// Probability of sampling the BSDF rather than the quadtree (read by the kernel).
    pub bsdf_fraction: f32,
    /// Learn, per leaf, which light models deliver NEE contributions, and choose light
    /// models from (1 − light_mix)·source + light_mix·learned table.
    pub learn_lights: bool,
    pub light_mix: f32,
    /// Choose the mix per leaf between passes (`light_mix` is then each leaf's starting
    /// value; src/guiding/light_mix.rs).
    pub learn_light_mix: bool,
    /// Learn the BSDF selection probability per leaf (`bsdf_fraction` is then each
    /// leaf's starting value).
    pub learn_selection: bool,
    pub selection_learner: SelectionLearner,
    /// What the training records measure.
    pub target: GuideTarget,
    /// Which statistic of it the quadtrees follow.
    pub density: GuideDensity,
    /// Weight of the earlier iterations' statistics in each refit, relative to the
    /// finished iteration's (per record): 0 builds each sampling tree from the last
    /// iteration alone (Müller et al.), 1 from every training record so far, equally.
    pub history: f32,
}

/// Largest light mix: the source distribution keeps 5 % of the selection, so every
/// light stays samplable.
pub const MAX_LIGHT_MIX: f32 = 0.95;

/// Default `--guiding-memory`: 256 MiB of GPU arrays is thousands of well-resolved leaves.
pub const DEFAULT_MEMORY_CAP_BYTES: u64 = 256 << 20;

impl Default for GuidingConfig {
    fn default() -> Self {
        Self {
            spatial_threshold: 12000.0,
            rho: 0.01,
            max_quad_depth: 20,
            max_spatial_depth: crate::gpu::GUIDE_MAX_SPATIAL_DEPTH,
            memory_cap_bytes: DEFAULT_MEMORY_CAP_BYTES,
            spatial_filter: SpatialFilter::default(),
            directional_filter: DirectionalFilter::default(),
            record_nee: true,
            bsdf_fraction: 0.5,
            learn_lights: false,
            light_mix: 0.5,
            learn_light_mix: false,
            learn_selection: false,
            selection_learner: SelectionLearner::Variance,
            target: GuideTarget::All,
            density: GuideDensity::Radiance,
            history: 0.0,
        }
    }
}

impl GuidingConfig {
    /// Reject options the trees or the kernels cannot honour.
    pub fn validate(&self) -> Result<(), GuidingError> {
        let bad = |what: String| Err(GuidingError::Config(what));
        if !(self.spatial_threshold > 0.0 && self.spatial_threshold.is_finite()) {
            return bad(format!(
                "spatial threshold must be positive, got {}",
                self.spatial_threshold
            ));
        }
        if !(self.rho > 0.0 && self.rho < 1.0) {
            return bad(format!("rho must be in (0, 1), got {}", self.rho));
        }
        let max_quad = crate::gpu::GUIDE_MAX_QUAD_DEPTH;
        if self.max_quad_depth == 0 || self.max_quad_depth > max_quad {
            return bad(format!(
                "quadtree depth must be in 1..={max_quad}, got {}",
                self.max_quad_depth
            ));
        }
        let max_spatial = crate::gpu::GUIDE_MAX_SPATIAL_DEPTH;
        if self.max_spatial_depth > max_spatial {
            return bad(format!(
                "spatial depth must be at most {max_spatial}, got {}",
                self.max_spatial_depth
            ));
        }
        if !(0.0..=1.0).contains(&self.bsdf_fraction) {
            return bad(format!(
                "BSDF fraction must be in [0, 1], got {}",
                self.bsdf_fraction
            ));
        }
        if !(0.0..=MAX_LIGHT_MIX).contains(&self.light_mix) {
            return bad(format!(
                "light mix must be in [0, {MAX_LIGHT_MIX}], got {}",
                self.light_mix
            ));
        }
        Ok(())
    }

    /// The spatial split threshold for an iteration rendering `spp` samples per pixel.
    /// The reference refines with `√(2^k · sppPerPass / 4) · c` before iteration k, which
    /// renders 2^k passes of sppPerPass samples: c·√(spp/4) with its defaults giving
    /// c·√(2^k) at 4 spp per pass.
    pub fn split_threshold(&self, spp: u32) -> f32 {
        (f64::from(self.spatial_threshold) * (f64::from(spp) / 4.0).sqrt()) as f32
    }

    /// `GUIDE_FLAG_*` bits of the guiding header.
    pub fn flags(&self) -> u32 {
        use crate::gpu::{
            GUIDE_FLAG_DIRECTIONAL_BOX, GUIDE_FLAG_RECORD_NEE, GUIDE_FLAG_SPATIAL_JITTER,
        };
        let mut f = 0;
        if self.record_nee {
            f |= GUIDE_FLAG_RECORD_NEE;
        }
        if self.learn_lights {
            f |= crate::gpu::GUIDE_FLAG_LEARN_LIGHTS;
            if self.learn_light_mix {
                f |= crate::gpu::GUIDE_FLAG_LEARN_LIGHT_MIX;
            }
        }
        if self.learn_selection {
            f |= crate::gpu::GUIDE_FLAG_LEARN_SELECTION;
        }
        match self.target {
            GuideTarget::All => {}
            GuideTarget::Indirect => f |= crate::gpu::GUIDE_FLAG_TARGET_INDIRECT,
            GuideTarget::Contribution => f |= crate::gpu::GUIDE_FLAG_TARGET_CONTRIBUTION,
        }
        if self.density == GuideDensity::VarianceAware {
            f |= crate::gpu::GUIDE_FLAG_SECOND_MOMENT;
        }
        if self.spatial_filter == SpatialFilter::StochasticBox {
            f |= GUIDE_FLAG_SPATIAL_JITTER;
        }
        if self.directional_filter == DirectionalFilter::Box {
            f |= GUIDE_FLAG_DIRECTIONAL_BOX;
        }
        f
    }
}
