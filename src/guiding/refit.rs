//! The refit between training iterations (Müller et al. 2017, §3–4, and the rules of
//! the reference implementation): every leaf's training tree is built and becomes its
//! sampling tree; the next training trees start empty with the topology refined from
//! those (subdivide while a quadrant's share of the energy exceeds ρ, collapse below,
//! depth cap); and a spatial leaf splits in half, recursively, while its statistical
//! weight exceeds c·√(spp/4), each half assumed to have received half the weight. Splits
//! go to the heaviest leaves first and stop before the GPU arrays would exceed the
//! memory cap; the two halves share the parent's sampling tree.

use super::config::GuideDensity;
use super::flat::{LEAF_TOTAL_BYTES, QUAD_NODE_BYTES, SPATIAL_NODE_BYTES};
use super::sdtree::{SdTree, SpatialNode};
use std::collections::BinaryHeap;

/// What a refit did, and the size of the result.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefitStats {
    /// Statistical weight above which a leaf split.
    pub split_threshold: f32,
    pub splits: u32,
    /// Splits that were wanted but refused by the memory cap or the depth cap.
    pub refused_splits: u32,
    pub leaves: usize,
    pub spatial_nodes: usize,
    /// Nodes in the GPU sampling array (shared trees counted once).
    pub sampling_nodes: usize,
    /// Nodes in the GPU training array (headers included).
    pub training_nodes: usize,
    pub max_quad_depth: u32,
    /// Bytes of the four GPU buffers.
    pub gpu_bytes: u64,
    /// Non-finite or negative training sums that were dropped (overflowed atomics).
    pub dropped_sums: u32,
    /// Total statistical weight the finished iteration recorded.
    pub recorded_weight: f64,
}

impl SdTree {
    /// Refit after a training iteration; `next_spp` is the samples per pixel the coming
    /// iteration renders (it scales the spatial threshold; see
    /// `GuidingConfig::split_threshold`). The caller then uploads `gpu_arrays()`.
    pub fn refit(&mut self, next_spp: u32) -> RefitStats {
        let rho = self.config.rho;
        let max_depth = self.config.max_quad_depth;
        let mut stats = RefitStats::default();

        // Sampling trees := the finished iteration's statistics; training trees start
        // over with the refined topology.
        let density = self.config.density;
        let initial_mix = self.config.light_mix;
        let history = self.config.history;
        // The share of the earlier statistics that fell in each leaf's box: the leaves
        // split from one leaf since the last refit share its sampling tree and light
        // table, each holding 2^-k of them after k halvings, so 1 / (leaves sharing it).
        let mut sharing: std::collections::HashMap<*const super::QuadTree, u32> =
            std::collections::HashMap::new();
        for leaf in &self.leaves {
            *sharing
                .entry(std::sync::Arc::as_ptr(&leaf.sampling))
                .or_default() += 1;
        }
        let shares: Vec<f32> = self
            .leaves
            .iter()
            .map(|l| 1.0 / sharing[&std::sync::Arc::as_ptr(&l.sampling)] as f32)
            .collect();
        let cost = self.training_costs();
        let per_leaf = super::parallel::map_mut_by_cost(&mut self.leaves, &cost, |i, leaf| {
            let mut built = std::mem::take(&mut leaf.training);
            let share = shares[i];
            // The earlier iterations' statistics, as the sampling tree holds them, join
            // this iteration's with weight `history` (0: Müller et al.'s reset).
            if history > 0.0 && density == GuideDensity::Radiance {
                built.add_prior(&leaf.sampling, history * share);
            }
            let dropped = match density {
                GuideDensity::Radiance => built.build(),
                GuideDensity::VarianceAware => built.build_second_moment(),
            };
            let weight = leaf.training_weight;
            let depth = built.depth();
            let retired = std::mem::replace(&mut leaf.sampling, std::sync::Arc::new(built));
            // The retired sampling tree's nodes hold the next training tree, unless
            // another leaf (split from the same parent) still shares it.
            let storage = std::sync::Arc::try_unwrap(retired)
                .map(|t| t.into_nodes())
                .unwrap_or_default();
            leaf.training = leaf.sampling.refined_into(rho, max_depth, storage);
            leaf.sampling_weight = leaf.training_weight;
            leaf.training_weight = 0.0;
            // Light tables := this iteration's contributions (with the earlier ones'
            // under `history`), normalised.
            let mut recorded = std::mem::take(&mut leaf.light_training);
            let mut table: Vec<(u32, f32)> = recorded
                .drain(..)
                .filter(|s| s.value.is_finite() && s.value > 0.0)
                .map(|s| (s.model, s.value))
                .collect();
            let earlier = history * share * leaf.lights_total;
            if earlier > 0.0 {
                for &(model, p) in leaf.lights.iter() {
                    match table.iter_mut().find(|e| e.0 == model) {
                        Some(e) => e.1 += earlier * p,
                        None => table.push((model, earlier * p)),
                    }
                }
            }
            table.sort_by(|a, b| b.1.total_cmp(&a.1));
            // The GPU holds GUIDE_LIGHT_SLOTS models per leaf: keep the strongest.
            table.truncate(crate::gpu::GUIDE_LIGHT_SLOTS as usize);
            let total: f32 = table.iter().map(|&(_, v)| v).sum();
            table.iter_mut().for_each(|e| e.1 /= total);
            leaf.lights_total = if table.is_empty() { 0.0 } else { total };
            // A leaf without a table samples the source alone; its next table starts
            // at the configured mix.
            if table.is_empty() {
                leaf.light_mix = initial_mix;
            }
            leaf.lights = std::sync::Arc::new(table);
            leaf.light_second = 0.0;
            (dropped, weight, depth)
        });
        // Summed in leaf order, as one thread would.
        let mut max_depth_built = 1;
        for (dropped, weight, depth) in per_leaf {
            stats.dropped_sums += dropped;
            stats.recorded_weight += f64::from(weight);
            max_depth_built = max_depth_built.max(depth);
        }

        let threshold = self.config.split_threshold(next_spp);
        stats.split_threshold = threshold;
        self.split_leaves(threshold, &mut stats);

        self.iterations += 1;
        stats.leaves = self.leaves.len();
        stats.spatial_nodes = self.nodes.len();
        // The GPU buffers' sizes (`gpu_buffer_lens`: the sampling and the training
        // trees are the third and fourth).
        let lens = self.gpu_buffer_lens();
        stats.sampling_nodes = lens[2] / QUAD_NODE_BYTES as usize;
        stats.training_nodes = lens[3] / QUAD_NODE_BYTES as usize;
        // Splits share the trees just built: their depth is the deepest of those.
        stats.max_quad_depth = max_depth_built;
        stats.gpu_bytes = lens.iter().sum::<usize>() as u64;
        stats
    }

    fn split_leaves(&mut self, threshold: f32, stats: &mut RefitStats) {
        let mut node_of_leaf = vec![0u32; self.leaves.len()];
        for (n, node) in self.nodes.iter().enumerate() {
            if let SpatialNode::Leaf { leaf } = node {
                node_of_leaf[*leaf as usize] = n as u32;
            }
        }
        let mut bytes = self.gpu_bytes();
        let cap = self.config.memory_cap_bytes;
        // Heaviest first; ties by leaf index, for determinism. Positive floats order
        // like their bits.
        let mut heap: BinaryHeap<(u32, std::cmp::Reverse<u32>)> = self
            .leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| l.sampling_weight > threshold)
            .map(|(i, l)| (l.sampling_weight.to_bits(), std::cmp::Reverse(i as u32)))
            .collect();
        while let Some((weight_bits, std::cmp::Reverse(leaf))) = heap.pop() {
            let l = &self.leaves[leaf as usize];
            let cost = 2 * SPATIAL_NODE_BYTES
                + LEAF_TOTAL_BYTES
                + QUAD_NODE_BYTES * (l.training.node_count() as u64 + 1);
            if l.depth >= self.config.max_spatial_depth || bytes + cost > cap {
                stats.refused_splits += 1;
                continue;
            }
            bytes += cost;
            let new_leaf = self.split(leaf, node_of_leaf[leaf as usize]);
            stats.splits += 1;
            let first = self.nodes.len() as u32 - 2;
            node_of_leaf[leaf as usize] = first;
            node_of_leaf.push(first + 1);
            // Each half is assumed to have received half the weight.
            let half = f32::from_bits(weight_bits) * 0.5;
            if half > threshold {
                heap.push((half.to_bits(), std::cmp::Reverse(leaf)));
                heap.push((half.to_bits(), std::cmp::Reverse(new_leaf)));
            }
        }
    }

    /// Split leaf `leaf` (spatial node `node`) in half along `depth % 3`: the low half
    /// keeps the leaf index, the high half is a new leaf. Returns the new leaf's index.
    pub(crate) fn split(&mut self, leaf: u32, node: u32) -> u32 {
        let first = self.nodes.len() as u32;
        let new_leaf = self.leaves.len() as u32;
        let low = &mut self.leaves[leaf as usize];
        let axis = low.depth % 3;
        low.depth += 1;
        low.box_size[axis as usize] *= 0.5;
        let mut high = low.clone();
        high.box_min[axis as usize] += high.box_size[axis as usize];
        self.leaves.push(high);
        self.nodes[node as usize] = SpatialNode::Interior { axis, first };
        self.nodes.push(SpatialNode::Leaf { leaf });
        self.nodes.push(SpatialNode::Leaf { leaf: new_leaf });
        new_leaf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guiding::light_mix::LightSums;
    use crate::guiding::GuidingConfig;
    use glam::Vec3;

    fn tree(config: &GuidingConfig) -> SdTree {
        SdTree::new(
            Vec3::new(-1.0, -2.0, -1.0),
            Vec3::new(3.0, 1.0, 0.0),
            config,
        )
        .unwrap()
    }

    /// Record `n` weight-1 samples at `p` with a fixed direction.
    fn record_at(t: &mut SdTree, p: Vec3, n: u32) {
        for i in 0..n {
            let u = [
                (i % 7) as f32 / 7.0,
                (i % 11) as f32 / 11.0,
                (i % 13) as f32 / 13.0,
            ];
            t.record(
                &crate::gpu::GuideRecord::new(p, Vec3::new(0.3, 0.4, 0.866), 1.0, 1.0),
                u,
            );
        }
    }

    #[test]
    fn cube_and_threshold_scaling() {
        let config = GuidingConfig::default();
        let t = tree(&config);
        assert_eq!(t.cube(), (Vec3::new(-1.0, -2.0, -1.0), 4.0));
        // The reference at its default 4 spp per pass: c·√(2^k) before iteration k.
        for k in 0..8 {
            let spp = 4 << k;
            let expected = 12000.0 * 2f32.powi(k).sqrt();
            assert!((config.split_threshold(spp) - expected).abs() < 1e-3 * expected);
        }
        // One sample per pixel in iteration 0 of lanterna's schedule: half of c.
        assert_eq!(config.split_threshold(1), 6000.0);
    }

    #[test]
    fn split_threshold_is_strict_and_recursive() {
        let config = GuidingConfig {
            spatial_filter: crate::guiding::SpatialFilter::Nearest,
            ..GuidingConfig::default()
        };
        // Threshold at 4 spp is exactly c = 12000.
        let mut t = tree(&config);
        record_at(&mut t, Vec3::ZERO, 12000);
        let s = t.refit(4);
        assert_eq!((s.splits, t.leaves().len()), (0, 1));
        record_at(&mut t, Vec3::ZERO, 12001);
        let s = t.refit(4);
        assert_eq!((s.splits, t.leaves().len()), (1, 2));
        // 4c: the leaf and both halves (2c each) split; the quarters (exactly c) do not.
        let mut t = tree(&config);
        record_at(&mut t, Vec3::ZERO, 4 * 12000);
        let s = t.refit(4);
        assert_eq!((s.splits, t.leaves().len()), (3, 4));
        // Axes cycle x, y, z: the four leaves split the cube in x, then y.
        let mut boxes: Vec<_> = t
            .leaves()
            .iter()
            .map(|l| (l.box_min.to_array(), l.box_size.to_array()))
            .collect();
        boxes.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(
            boxes,
            vec![
                ([-1.0, -2.0, -1.0], [2.0, 2.0, 4.0]),
                ([-1.0, 0.0, -1.0], [2.0, 2.0, 4.0]),
                ([1.0, -2.0, -1.0], [2.0, 2.0, 4.0]),
                ([1.0, 0.0, -1.0], [2.0, 2.0, 4.0]),
            ]
        );
        // The halves share the parent's sampling tree until the next refit.
        assert!(std::sync::Arc::ptr_eq(
            &t.leaves()[0].sampling,
            &t.leaves()[1].sampling
        ));
        // Lookup agrees with the boxes.
        for (i, l) in t.leaves().iter().enumerate() {
            assert_eq!(t.find_leaf(l.box_min + 0.5 * l.box_size), i as u32);
        }
        // A larger spp raises the bar: the same weight at 64 spp (4c) splits nothing.
        let mut t = tree(&config);
        record_at(&mut t, Vec3::ZERO, 4 * 12000);
        assert_eq!(t.refit(64).splits, 0);
    }

    #[test]
    fn sampling_is_last_iteration_and_training_starts_empty() {
        let config = GuidingConfig::default();
        let mut t = tree(&config);
        assert!(t.leaves()[0].sampling.is_empty());
        record_at(&mut t, Vec3::ZERO, 100);
        let before = t.leaves()[0].training.clone();
        t.refit(2);
        let l = &t.leaves()[0];
        assert_eq!(l.sampling_weight, 100.0);
        assert!((l.sampling.total() - 100.0).abs() < 1e-3);
        assert_eq!(l.training_weight, 0.0);
        assert_eq!(l.training.total(), 0.0);
        let mut built = before;
        built.build();
        assert_eq!(*l.sampling, built);
        assert_eq!(l.training, built.refined(config.rho, config.max_quad_depth));
        // A second iteration without records: sampling becomes empty (uniform) again.
        t.refit(4);
        assert!(t.leaves()[0].sampling.is_empty());
    }

    #[test]
    fn history_carries_earlier_iterations_by_their_share_of_the_box() {
        let config = GuidingConfig {
            spatial_filter: crate::guiding::SpatialFilter::Nearest,
            history: 1.0,
            ..GuidingConfig::default()
        };
        let record_dir = |t: &mut SdTree, dir: Vec3, n: u32| {
            for _ in 0..n {
                let rec = crate::gpu::GuideRecord::new(Vec3::ZERO, dir, 1.0, 1.0);
                t.record(&rec, [0.5; 3]);
            }
        };
        let (up, down) = (Vec3::new(0.3, 0.4, 0.866), Vec3::new(-0.6, 0.0, -0.8));
        // Iteration 0: 2c records towards `up`, and light 7 the only one seen; the
        // leaf splits once (the halves hold c each, at the bar), so each half inherits
        // half of what the parent learned.
        let mut t = tree(&config);
        record_dir(&mut t, up, 24000);
        t.leaves[0].light_training = vec![LightSums {
            model: 7,
            value: 10.0,
            second: 10.0,
        }];
        assert_eq!(t.refit(4).splits, 1);
        // Iteration 1: 1,000 records towards `down` and light 3 with twice the light,
        // all in the half holding the origin.
        let here = t.find_leaf(Vec3::ZERO) as usize;
        record_dir(&mut t, down, 1000);
        t.leaves[here].light_training = vec![LightSums {
            model: 3,
            value: 10.0,
            second: 10.0,
        }];
        t.refit(8);
        for (i, l) in t.leaves().iter().enumerate() {
            let own = if i == here { 1000.0 } else { 0.0 };
            let total = l.sampling.total();
            assert!(
                (total / (12000.0 + own) - 1.0).abs() < 1e-4,
                "leaf {i}: {total}"
            );
            // Both iterations' directions: a cell holding a share s of the mass has
            // density at least s / 4π.
            let floor = |mass: f32| 0.999 * mass / total / (4.0 * std::f32::consts::PI);
            assert!(l.sampling.pdf(up) >= floor(12000.0), "leaf {i}");
            assert!(l.sampling.pdf(down) >= floor(own), "leaf {i}");
        }
        let lights = &t.leaves()[here].lights;
        assert_eq!(lights.len(), 2, "{lights:?}");
        // Light 7's 10 with share ½, light 3's 10: 1/3 and 2/3.
        assert_eq!(lights[0].0, 3);
        assert!((lights[0].1 - 2.0 / 3.0).abs() < 1e-5, "{lights:?}");
        assert!((lights[1].1 - 1.0 / 3.0).abs() < 1e-5, "{lights:?}");
        // Without history the refit forgets: Müller et al.'s reset.
        let mut t = tree(&GuidingConfig {
            history: 0.0,
            ..config
        });
        record_dir(&mut t, up, 100);
        t.refit(2);
        record_dir(&mut t, down, 100);
        t.refit(4);
        assert!((t.leaves()[0].sampling.total() - 100.0).abs() < 1e-3);
        assert!(t.leaves()[0].sampling.pdf(up) < t.leaves()[0].sampling.pdf(down));
    }

    #[test]
    fn memory_cap_stops_splits() {
        let uncapped = GuidingConfig {
            spatial_filter: crate::guiding::SpatialFilter::Nearest,
            ..GuidingConfig::default()
        };
        // Weight 64c spread over the cube: without a cap it splits into 64+ leaves.
        let fill = |t: &mut SdTree| {
            for i in 0..64u32 {
                let p = Vec3::new(
                    -1.0 + 4.0 * ((i % 4) as f32 + 0.5) / 4.0,
                    -2.0 + 4.0 * (((i / 4) % 4) as f32 + 0.5) / 4.0,
                    -1.0 + 4.0 * ((i / 16) as f32 + 0.5) / 4.0,
                );
                record_at(t, p, 12001);
            }
        };
        let mut t = tree(&uncapped);
        fill(&mut t);
        let free = t.refit(4);
        assert!(free.leaves >= 64, "{free:?}");
        let cap = free.gpu_bytes / 3;
        let capped = GuidingConfig {
            memory_cap_bytes: cap,
            ..uncapped
        };
        let mut t = tree(&capped);
        fill(&mut t);
        let s = t.refit(4);
        assert!(s.gpu_bytes <= cap, "{} > {cap}", s.gpu_bytes);
        assert!(s.refused_splits > 0 && s.splits > 0);
        assert_eq!(s.gpu_bytes, t.gpu_arrays().byte_size());
        // A cap below the current size refuses every split.
        let tiny = GuidingConfig {
            memory_cap_bytes: 1,
            ..capped
        };
        let mut t = tree(&tiny);
        fill(&mut t);
        assert_eq!(t.refit(4).splits, 0);
    }

    #[test]
    fn spatial_depth_cap() {
        let config = GuidingConfig {
            spatial_filter: crate::guiding::SpatialFilter::Nearest,
            max_spatial_depth: 3,
            ..GuidingConfig::default()
        };
        let mut t = tree(&config);
        record_at(&mut t, Vec3::ZERO, 1 << 20);
        let s = t.refit(4);
        assert_eq!(s.leaves, 8);
        assert!(t.leaves().iter().all(|l| l.depth == 3));
    }
}
