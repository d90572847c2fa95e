//! Brute-force estimates of the incident radiance over the sphere, to check what an
//! SD-tree learned (tests/guiding_convergence.rs). A probe is an SD-tree whose spatial
//! tree is split uniformly to a fixed depth and whose training quadtrees are a fixed
//! uniform grid; its sampling trees stay empty, so a training pass with it uploaded
//! samples directions from the BSDF and the uniform sphere (a plain path tracer's
//! estimates) and accumulates every record into the grid cell of its direction. The
//! normalised grid of a leaf is then the brute-force directional distribution of the
//! radiance arriving in that leaf, to compare with a learned leaf's sampling quadtree
//! over the same grid.

use super::quadtree::QuadTree;
use super::sdtree::{SdTree, SpatialNode};
use super::{GuidingConfig, GuidingError};
use glam::Vec3;

impl SdTree {
    /// A probe over the box [bbox_min, bbox_max]: 2^`spatial_depth` leaves of equal size,
    /// each with a training grid of 2^`grid_level` × 2^`grid_level` cells.
    pub fn probe(
        bbox_min: Vec3,
        bbox_max: Vec3,
        config: &GuidingConfig,
        spatial_depth: u32,
        grid_level: u32,
    ) -> Result<SdTree, GuidingError> {
        let mut t = SdTree::new(bbox_min, bbox_max, config)?;
        let grid = QuadTree::uniform_grid(grid_level);
        for leaf in &mut t.leaves {
            leaf.training = grid.clone();
        }
        while let Some(i) = t.leaves.iter().position(|l| l.depth < spatial_depth) {
            let node = t
                .nodes
                .iter()
                .position(|n| *n == SpatialNode::Leaf { leaf: i as u32 })
                .expect("every leaf has a node");
            t.split(i as u32, node as u32);
        }
        Ok(t)
    }

    /// The normalised training energy of leaf `leaf` over an n × n grid of the square
    /// (row-major in v, then u), and its total; all zero when it recorded nothing.
    pub fn training_histogram(&self, leaf: u32, n: usize) -> (Vec<f64>, f64) {
        let mut t = self.leaf(leaf).training.clone();
        t.build();
        let total = f64::from(t.total());
        if total.is_nan() || total <= 0.0 {
            return (vec![0.0; n * n], 0.0);
        }
        (grid_masses(&t, n), total)
    }

    /// Leaf `leaf`'s sampling distribution over the same n × n grid.
    pub fn sampling_histogram(&self, leaf: u32, n: usize) -> Vec<f64> {
        grid_masses(&self.leaf(leaf).sampling, n)
    }
}

fn grid_masses(t: &QuadTree, n: usize) -> Vec<f64> {
    let step = 1.0 / n as f64;
    let mut out = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let lo = [i as f64 * step, j as f64 * step];
            out.push(t.mass_in_rect(lo, [lo[0] + step, lo[1] + step]));
        }
    }
    out
}

impl QuadTree {
    /// A tree subdivided uniformly to `level` (4^level leaf cells), without energy.
    pub fn uniform_grid(level: u32) -> QuadTree {
        use super::quadtree::QuadNode;
        let mut nodes = vec![QuadNode::default()];
        let mut frontier = vec![0usize];
        for _ in 1..level {
            let mut next = Vec::new();
            for &n in &frontier {
                for q in 0..4 {
                    let c = nodes.len();
                    nodes.push(QuadNode::default());
                    nodes[n].child[q] = c as u32;
                    next.push(c);
                }
            }
            frontier = next;
        }
        QuadTree::from_nodes(nodes).expect("a well-formed grid")
    }
}
