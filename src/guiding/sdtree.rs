//! The SD-tree on the CPU: a binary spatial tree over a cube made from the scene's
//! bounding box (split axes cycle x, y, z with depth), each leaf owning two directional
//! quadtrees: the sampling tree (the previous iteration's statistics, read-only on the
//! GPU) and the training tree (this iteration's records). Lookup and recording mirror
//! `guide_find_leaf` / `guide_record` in shaders_glsl/inc/guiding.glsl, so the CPU can
//! stand in for the GPU in tests and accumulate appended records (the records mode).

use super::light_mix::LightSums;
use super::quadtree::QuadTree;
use super::selection::SelectionState;
use super::sphere::dir_to_square;
use super::{DirectionalFilter, GuidingConfig, GuidingError, SpatialFilter};
use crate::gpu::GuideRecord;
use glam::Vec3;
use std::sync::Arc;

/// A spatial tree node. Interior nodes split their box in half along `axis`; their
/// children are `first` (low half) and `first + 1` (high half).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SpatialNode {
    Interior { axis: u32, first: u32 },
    Leaf { leaf: u32 },
}

/// A spatial leaf and its quadtrees.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    pub box_min: Vec3,
    pub box_size: Vec3,
    /// Depth in the spatial tree (the root is 0); the leaf splits along `depth % 3`.
    pub depth: u32,
    /// What the GPU samples from: the last iteration's training tree, built. Leaves
    /// made by a split share their parent's until the next refit.
    pub sampling: Arc<QuadTree>,
    /// Statistical weight (≈ number of records) the sampling tree was learned from.
    pub sampling_weight: f32,
    /// Where this iteration's records go.
    pub training: QuadTree,
    pub training_weight: f32,
    /// Learned light selection: (light model, probability), probabilities summing to 1,
    /// or empty; shared with the parent after a split until the next refit.
    pub lights: Arc<Vec<(u32, f32)>>,
    /// Probability of choosing the light model from `lights` rather than from the source
    /// distribution (per leaf: `light_mix::choose_mix`, or the configured one).
    pub light_mix: f32,
    /// The sum of the estimates `lights` was normalised from (its weight as a prior for
    /// `GuidingConfig::history`; not saved: a loaded tree renders frozen).
    pub lights_total: f32,
    /// Per light model, the NEE estimates recorded this iteration (sum and square sum).
    pub light_training: Vec<LightSums>,
    /// Σ v² over all of this iteration's NEE estimates in the leaf.
    pub light_second: f32,
    /// Learned BSDF selection probability (its optimiser; copied to both halves on a
    /// split, as the reference does).
    pub selection: SelectionState,
}

/// The SD-tree. See the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct SdTree {
    pub(crate) config: GuidingConfig,
    pub(crate) origin: Vec3,
    pub(crate) size: f32,
    pub(crate) nodes: Vec<SpatialNode>,
    pub(crate) leaves: Vec<Leaf>,
    pub(crate) iterations: u32,
}

impl SdTree {
    /// Each leaf's share of per-leaf work that grows with its training tree (for
    /// splitting it among threads: `parallel::map_mut_by_cost`).
    pub(crate) fn training_costs(&self) -> Vec<u64> {
        self.leaves
            .iter()
            .map(|l| l.training.node_count() as u64 + 1)
            .collect()
    }

    /// A fresh tree over the scene's bounding box: one leaf, sampling uniformly, with
    /// the uniform initial training topology.
    pub fn new(
        bbox_min: Vec3,
        bbox_max: Vec3,
        config: &GuidingConfig,
    ) -> Result<Self, GuidingError> {
        config.validate()?;
        let extent = bbox_max - bbox_min;
        let size = extent.max_element();
        if !(bbox_min.is_finite() && bbox_max.is_finite() && size > 0.0) {
            return Err(GuidingError::BadBounds {
                min: bbox_min.to_array(),
                max: bbox_max.to_array(),
            });
        }
        let leaf = Leaf {
            box_min: bbox_min,
            box_size: Vec3::splat(size),
            depth: 0,
            sampling: Arc::new(QuadTree::empty()),
            sampling_weight: 0.0,
            training: QuadTree::initial(config.rho, config.max_quad_depth),
            training_weight: 0.0,
            lights: Arc::new(Vec::new()),
            light_mix: config.light_mix,
            lights_total: 0.0,
            light_training: Vec::new(),
            light_second: 0.0,
            selection: SelectionState::new(config.bsdf_fraction),
        };
        Ok(Self {
            config: config.clone(),
            origin: bbox_min,
            size,
            nodes: vec![SpatialNode::Leaf { leaf: 0 }],
            leaves: vec![leaf],
            iterations: 0,
        })
    }

    pub fn config(&self) -> &GuidingConfig {
        &self.config
    }

    /// Replace the options (e.g. the filters or BSDF fraction of a loaded tree). The
    /// trees are kept; refit options apply from the next refit on.
    pub fn set_config(&mut self, config: &GuidingConfig) -> Result<(), GuidingError> {
        config.validate()?;
        self.config = config.clone();
        Ok(())
    }

    /// The cube the spatial tree subdivides: (corner, edge length).
    pub fn cube(&self) -> (Vec3, f32) {
        (self.origin, self.size)
    }

    /// Number of refits so far (0 while the first iteration trains).
    pub fn iterations(&self) -> u32 {
        self.iterations
    }

    pub fn leaves(&self) -> &[Leaf] {
        &self.leaves
    }

    pub fn leaf(&self, index: u32) -> &Leaf {
        &self.leaves[index as usize]
    }

    /// Mean light mix of the leaves with a learned light table, weighted by the records
    /// their sampling trees were learned from (0 when no leaf has a table).
    pub fn mean_light_mix(&self) -> f32 {
        let (mut sum, mut weight) = (0.0f64, 0.0f64);
        for l in self.leaves.iter().filter(|l| !l.lights.is_empty()) {
            let w = f64::from(l.sampling_weight.max(1.0));
            sum += w * f64::from(l.light_mix);
            weight += w;
        }
        if weight > 0.0 {
            (sum / weight) as f32
        } else {
            0.0
        }
    }

    pub fn spatial_node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The leaf holding `p` (`guide_find_leaf`); points outside the cube use the
    /// nearest leaf.
    pub fn find_leaf(&self, p: Vec3) -> u32 {
        let mut x = ((p - self.origin) / self.size).clamp(Vec3::ZERO, Vec3::ONE);
        let mut n = 0;
        loop {
            match self.nodes[n] {
                SpatialNode::Leaf { leaf } => return leaf,
                SpatialNode::Interior { axis, first } => {
                    let a = axis as usize;
                    let c = x[a];
                    if c < 0.5 {
                        x[a] = c * 2.0;
                        n = first as usize;
                    } else {
                        x[a] = (c - 0.5) * 2.0;
                        n = first as usize + 1;
                    }
                }
            }
        }
    }

    /// Sample leaf `leaf`'s sampling quadtree (`guide_sample`).
    pub fn sample(&self, leaf: u32, u: [f32; 2]) -> (Vec3, f32) {
        self.leaf(leaf).sampling.sample(u)
    }

    /// Solid-angle pdf of leaf `leaf`'s sampling quadtree (`guide_pdf`).
    pub fn pdf(&self, leaf: u32, dir: Vec3) -> f32 {
        self.leaf(leaf).sampling.pdf(dir)
    }

    /// Record a training sample (`guide_record`; see [`GuideRecord`] for what its value
    /// and statistical weight mean); `u` ∈ [0,1)³ jitters the position (stochastic
    /// spatial filter).
    pub fn record(&mut self, rec: &GuideRecord, u: [f32; 3]) {
        let leaf = self.find_leaf(Vec3::from_array(rec.pos));
        self.record_from_leaf(leaf, rec, u);
    }

    /// `record` for a caller that already knows the leaf holding `rec.pos`.
    pub fn record_from_leaf(&mut self, leaf_at_pos: u32, rec: &GuideRecord, u: [f32; 3]) {
        // A weight that is not a finite number ≥ 0 marks a broken record: drop it whole.
        if !(rec.weight.is_finite() && rec.weight >= 0.0) {
            return;
        }
        let counts = rec.weight > 0.0;
        let splats = rec.value.is_finite() && rec.value > 0.0;
        if !counts && !splats {
            return;
        }
        let pos = Vec3::from_array(rec.pos);
        let mut leaf = leaf_at_pos;
        if self.config.spatial_filter == SpatialFilter::StochasticBox {
            let box_size = self.leaves[leaf_at_pos as usize].box_size;
            let q = pos + (Vec3::from_array(u) - 0.5) * box_size;
            let q = q.clamp(self.origin, self.origin + self.size);
            leaf = self.find_leaf(q);
        }
        let box_filter = self.config.directional_filter == DirectionalFilter::Box;
        let l = &mut self.leaves[leaf as usize];
        if counts {
            l.training_weight += rec.weight;
        }
        if !splats {
            return;
        }
        let p = dir_to_square(Vec3::from_array(rec.dir));
        if box_filter {
            l.training.splat_box(p, rec.value);
        } else {
            l.training.splat_nearest(p, rec.value);
        }
    }

    /// Accumulate records appended by the GPU (the records mode). The jitter's random
    /// numbers are a hash of (`seed`, record index), so the result is deterministic.
    pub fn record_batch(&mut self, records: &[GuideRecord], seed: u64) {
        for (i, r) in records.iter().enumerate() {
            let h = hash64(seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
            let unit = |bits: u64| (bits & 0xff_ffff) as f32 * (1.0 / 16_777_216.0);
            let u = [unit(h), unit(h >> 24), unit(h >> 40)];
            self.record(r, u);
        }
    }
}

impl GuideRecord {
    /// A record of `value` (radiance / pdf) arriving at `pos` from `dir`, standing for
    /// `weight` samples.
    pub fn new(pos: Vec3, dir: Vec3, value: f32, weight: f32) -> Self {
        GuideRecord {
            pos: pos.to_array(),
            value,
            dir: dir.to_array(),
            weight,
        }
    }
}

/// SplitMix64's finaliser: a cheap well-mixed hash.
pub(crate) fn hash64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(spatial: SpatialFilter, directional: DirectionalFilter) -> GuidingConfig {
        GuidingConfig {
            spatial_filter: spatial,
            directional_filter: directional,
            ..GuidingConfig::default()
        }
    }

    fn rec(pos: Vec3, dir: Vec3, value: f32, weight: f32) -> GuideRecord {
        GuideRecord::new(pos, dir, value, weight)
    }

    /// A tree split once along x (records at both ends, weight above c at 4 spp).
    fn split_tree(cfg: &GuidingConfig) -> SdTree {
        let mut t = SdTree::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0), cfg).unwrap();
        for i in 0..12001 {
            let x = if i % 2 == 0 { 0.1 } else { 1.9 };
            t.record(&rec(Vec3::new(x, 0.5, 0.5), Vec3::Z, 1.0, 1.0), [0.5; 3]);
        }
        t.refit(4);
        assert_eq!(t.leaves().len(), 2);
        t
    }

    #[test]
    fn rejects_bad_bounds_and_options() {
        let cfg = GuidingConfig::default();
        assert!(SdTree::new(Vec3::ONE, Vec3::ONE, &cfg).is_err());
        assert!(SdTree::new(Vec3::ZERO, Vec3::new(f32::NAN, 1.0, 1.0), &cfg).is_err());
        let bad = GuidingConfig {
            rho: 0.0,
            ..cfg.clone()
        };
        assert!(SdTree::new(Vec3::ZERO, Vec3::ONE, &bad).is_err());
        let bad = GuidingConfig {
            max_quad_depth: 21,
            ..cfg
        };
        assert!(matches!(
            SdTree::new(Vec3::ZERO, Vec3::ONE, &bad),
            Err(GuidingError::Config(_))
        ));
    }

    #[test]
    /// The record's value is splatted whatever its statistical weight (an NEE record has
    /// weight 0 and must still teach the tree: a splat of value × weight lost them all),
    /// the weight counts even without energy, and broken values or weights are dropped.
    fn weight_counts_even_without_energy_and_bad_values_are_ignored() {
        let cfg = config(SpatialFilter::Nearest, DirectionalFilter::Nearest);
        let mut t = SdTree::new(Vec3::ZERO, Vec3::ONE, &cfg).unwrap();
        let p = Vec3::splat(0.5);
        t.record(&rec(p, Vec3::Z, 0.0, 1.0), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, f32::NAN, 1.0), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, f32::INFINITY, 1.0), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, 2.0, 0.5), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, 2.0, f32::NAN), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, 2.0, -1.0), [0.5; 3]);
        t.record(&rec(p, Vec3::Z, 3.0, 0.0), [0.5; 3]);
        let l = &t.leaves()[0];
        assert_eq!(l.training_weight, 3.5);
        let mut built = l.training.clone();
        built.build();
        assert_eq!(built.total(), 5.0);
    }

    #[test]
    fn nearest_records_into_the_leaf_and_cell() {
        let cfg = config(SpatialFilter::Nearest, DirectionalFilter::Nearest);
        let mut t = split_tree(&cfg);
        let dir = Vec3::new(0.0, 0.6, -0.8);
        t.record(&rec(Vec3::new(1.5, 0.2, 0.9), dir, 3.0, 1.0), [0.0; 3]);
        assert_eq!(t.leaves()[0].training_weight, 0.0);
        assert_eq!(t.leaves()[1].training_weight, 1.0);
        let mut built = t.leaves()[1].training.clone();
        built.build();
        let p = dir_to_square(dir);
        let (o, s) = built.cell_at(p);
        let mass = built.mass_in_rect(
            [f64::from(o[0]), f64::from(o[1])],
            [f64::from(o[0] + s), f64::from(o[1] + s)],
        );
        assert!((mass - 1.0).abs() < 1e-12);
    }

    #[test]
    fn stochastic_spatial_filter_jitters_within_the_leaf_size() {
        let cfg = config(SpatialFilter::StochasticBox, DirectionalFilter::Nearest);
        let mut t = split_tree(&cfg);
        // Leaves are 1 wide in x. From x = 0.9 a jitter of (u - 0.5) · 1 reaches the
        // other leaf iff u > 0.6; it never leaves the cube (clamped).
        let p = Vec3::new(0.9, 0.5, 0.5);
        t.record(&rec(p, Vec3::Z, 1.0, 1.0), [0.55, 0.5, 0.5]);
        assert_eq!(
            (t.leaves()[0].training_weight, t.leaves()[1].training_weight),
            (1.0, 0.0)
        );
        t.record(&rec(p, Vec3::Z, 1.0, 1.0), [0.65, 0.5, 0.5]);
        assert_eq!(
            (t.leaves()[0].training_weight, t.leaves()[1].training_weight),
            (1.0, 1.0)
        );
        t.record(
            &rec(Vec3::new(0.0, 0.0, 0.0), Vec3::Z, 1.0, 1.0),
            [0.0, 0.0, 0.0],
        );
        assert_eq!(t.leaves()[0].training_weight, 2.0);
        // Uniform jitter from x = 0.9: a fraction 0.4 lands in the other leaf.
        let mut rng = 1u64;
        let n = 100_000;
        for _ in 0..n {
            rng = hash64(rng);
            let u = [(rng >> 40) as f32 / (1u64 << 24) as f32, 0.5, 0.5];
            t.record(&rec(p, Vec3::Z, 1.0, 1.0), u);
        }
        let frac = f64::from(t.leaves()[1].training_weight - 1.0) / f64::from(n);
        // Binomial: σ = √(0.24 / n) ≈ 0.0015; 5σ bound.
        assert!(
            (frac - 0.4).abs() < 5.0 * (0.24f64 / f64::from(n)).sqrt(),
            "{frac}"
        );
    }

    #[test]
    fn record_batch_is_deterministic() {
        let cfg = GuidingConfig::default();
        let recs: Vec<GuideRecord> = (0..1000)
            .map(|i| GuideRecord {
                pos: [(i % 10) as f32 / 10.0, 0.5, 0.5],
                value: 1.0,
                dir: [0.0, 0.6, 0.8],
                weight: 1.0,
            })
            .collect();
        let mut a = SdTree::new(Vec3::ZERO, Vec3::ONE, &cfg).unwrap();
        let mut b = a.clone();
        a.record_batch(&recs, 3);
        b.record_batch(&recs, 3);
        assert_eq!(a, b);
        assert_eq!(a.leaves()[0].training_weight, 1000.0);
    }
}
