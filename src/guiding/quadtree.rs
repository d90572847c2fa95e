//! The directional quadtree ("D-tree") of one spatial leaf: a hierarchy over the square
//! ((cosθ+1)/2, φ/2π) whose nodes hold the energy of their four quadrants. Sampling,
//! pdf and recording mirror shaders_glsl/inc/guiding.glsl operation for operation (the
//! GPU results are checked against these), and `build` / `refined` implement the
//! reference's refit of one tree: sums are completed bottom-up after a training pass,
//! and the next training tree's topology subdivides every quadrant holding more than ρ
//! of the energy (recursively, up to the depth cap) and collapses the others.

use super::sphere::{dir_to_square, square_to_dir, INV_4PI, ONE_MINUS_EPS};
use crate::gpu::{GUIDE_MAX_QUAD_DEPTH, GUIDE_SAMPLE_ATTEMPTS};
use glam::Vec3;

/// One node: the energy of its quadrants and their children (indices into the same
/// tree; 0 = the quadrant is a leaf cell, since the root is nobody's child). Quadrant
/// q covers u ∈ [q&1, (q&1)+1)/2, v ∈ [q>>1, (q>>1)+1)/2 of the node.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct QuadNode {
    pub sum: [f32; 4],
    pub child: [u32; 4],
}

/// A leaf cell of a tree: where it is, and the probability mass the tree gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    pub origin: [f32; 2],
    pub size: f32,
    /// Level of the node owning the cell (the root is level 1).
    pub level: u32,
    pub prob: f64,
}

/// Room for a depth-first walk's stack: a walk that pushes a node's children when it
/// pops the node holds at most 3 entries per level plus one, so the trees the kernel
/// takes (`GUIDE_MAX_QUAD_DEPTH` levels) never grow it.
const WALK_STACK: usize = 3 * crate::gpu::GUIDE_MAX_QUAD_DEPTH as usize + 1;

/// A depth-first walk's stack, sized for the deepest tree, holding `root`.
fn walk_stack<T>(root: T) -> Vec<T> {
    let mut stack = Vec::with_capacity(WALK_STACK);
    stack.push(root);
    stack
}

/// A directional quadtree. Node 0 is the root.
#[derive(Clone, Debug, PartialEq)]
pub struct QuadTree {
    nodes: Vec<QuadNode>,
}

/// Quadrant of `p` in its node's [0,1]² frame; `p` moves into the quadrant's frame.
/// Exact in float (doubling, and subtracting 0.5 from [0.5, 1]).
pub(crate) fn quadrant(p: &mut [f32; 2]) -> usize {
    let mut q = 0;
    if p[0] < 0.5 {
        p[0] *= 2.0;
    } else {
        p[0] = (p[0] - 0.5) * 2.0;
        q |= 1;
    }
    if p[1] < 0.5 {
        p[1] *= 2.0;
    } else {
        p[1] = (p[1] - 0.5) * 2.0;
        q |= 2;
    }
    q
}

/// The float total of a node's sums, in the kernel's order.
pub(crate) fn node_total(s: &[f32; 4]) -> f32 {
    (s[0] + s[1]) + (s[2] + s[3])
}

/// 4·sum[q]/total, or 1 in a node without energy (treated as uniform).
fn quadrant_factor(s: &[f32; 4], q: usize) -> f32 {
    let total = node_total(s);
    if total > 0.0 {
        (4.0 * s[q]) / total
    } else {
        1.0
    }
}

fn rescale(u: f32, lo: f32, width: f32) -> f32 {
    ((u - lo) / width).min(ONE_MINUS_EPS)
}

fn quadrant_origin(q: usize, h: f32) -> [f32; 2] {
    [(q & 1) as f32 * h, (q >> 1) as f32 * h]
}

impl Default for QuadTree {
    fn default() -> Self {
        Self::empty()
    }
}

impl QuadTree {
    /// A root without energy: sampling is uniform over the sphere.
    pub fn empty() -> Self {
        Self {
            nodes: vec![QuadNode::default()],
        }
    }

    /// The topology a training tree starts with before anything was learned: the
    /// refinement of an empty tree (uniform cells of ¼^level energy share each).
    pub fn initial(rho: f32, max_depth: u32) -> Self {
        Self::empty().refined(rho, max_depth)
    }

    /// A tree from raw nodes, checked to be a tree (every node but the root reachable
    /// exactly once, in range, no deeper than the kernels walk) with finite,
    /// non-negative sums whose totals are finite.
    pub fn from_nodes(nodes: Vec<QuadNode>) -> Result<Self, String> {
        if nodes.is_empty() {
            return Err("quadtree without a root".into());
        }
        let mut seen = vec![false; nodes.len()];
        seen[0] = true;
        let mut stack = vec![(0usize, 1u32)];
        while let Some((n, level)) = stack.pop() {
            if level > GUIDE_MAX_QUAD_DEPTH {
                return Err(format!(
                    "quadtree deeper than {GUIDE_MAX_QUAD_DEPTH} levels"
                ));
            }
            for (i, &c) in nodes[n].child.iter().enumerate() {
                let s = nodes[n].sum[i];
                if !(s.is_finite() && s >= 0.0) {
                    return Err(format!("quadtree node {n} has energy {s}"));
                }
                if c == 0 {
                    continue;
                }
                let c = c as usize;
                if c >= nodes.len() || seen[c] {
                    return Err(format!("quadtree node {n} has a bad child index {c}"));
                }
                seen[c] = true;
                stack.push((c, level + 1));
            }
        }
        if let Some(orphan) = seen.iter().position(|s| !s) {
            return Err(format!("quadtree node {orphan} is unreachable"));
        }
        // Bounded sums: four finite sums near f32::MAX overflow a node's total, and
        // sampling would then lose every direction below it.
        for (n, node) in nodes.iter().enumerate() {
            if !node_total(&node.sum).is_finite() {
                return Err(format!("quadtree node {n}: its sums overflow"));
            }
        }
        Ok(Self { nodes })
    }

    /// Checks that every interior quadrant holds its subtree's total, as `build` leaves
    /// a sampling tree: sampling walks the ratios and the pdf multiplies them, so
    /// inconsistent sums would bias the estimator silently. (Training trees are not
    /// built: records sit where they landed.)
    pub fn check_sums_consistent(&self) -> Result<(), String> {
        for (n, node) in self.nodes.iter().enumerate() {
            for (q, &c) in node.child.iter().enumerate() {
                if c == 0 {
                    continue;
                }
                let (parent, child) = (node.sum[q], node_total(&self.nodes[c as usize].sum));
                if (parent - child).abs() > 1e-3 * parent.max(child) {
                    return Err(format!(
                        "quadtree node {n}: quadrant {q} holds {parent} but its child {c} sums to {child}"
                    ));
                }
            }
        }
        Ok(())
    }

    pub fn nodes(&self) -> &[QuadNode] {
        &self.nodes
    }

    /// The nodes, for reuse as another tree's storage.
    pub(crate) fn into_nodes(self) -> Vec<QuadNode> {
        self.nodes
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The energy of the whole tree (after `build`), in the kernel's float order.
    pub fn total(&self) -> f32 {
        node_total(&self.nodes[0].sum)
    }

    /// Whether sampling falls back to uniform (nothing learned).
    pub fn is_empty(&self) -> bool {
        let total = self.total();
        total.is_nan() || total <= 0.0
    }

    /// Number of node levels (a lone root is 1).
    pub fn depth(&self) -> u32 {
        let mut deepest = 1;
        let mut stack = walk_stack((0usize, 1u32));
        while let Some((n, level)) = stack.pop() {
            deepest = deepest.max(level);
            for &c in &self.nodes[n].child {
                if c != 0 {
                    stack.push((c as usize, level + 1));
                }
            }
        }
        deepest
    }

    /// Density on the square at `p` (integrates to 1 over the square).
    pub fn density(&self, mut p: [f32; 2]) -> f32 {
        if self.is_empty() {
            return 1.0;
        }
        let mut n = 0;
        let mut density = 1.0f32;
        for _ in 0..GUIDE_MAX_QUAD_DEPTH {
            let node = &self.nodes[n];
            let q = quadrant(&mut p);
            density *= quadrant_factor(&node.sum, q);
            n = node.child[q] as usize;
            if n == 0 {
                break;
            }
        }
        density
    }

    /// Solid-angle pdf of `dir` (`guide_pdf`).
    pub fn pdf(&self, dir: Vec3) -> f32 {
        if self.is_empty() {
            return INV_4PI;
        }
        self.density(dir_to_square(dir)) * INV_4PI
    }

    /// Sample a direction with the uniform pair `u` (`guide_sample`): the direction and
    /// its solid-angle pdf, bitwise equal to `self.pdf(dir)`.
    pub fn sample(&self, u: [f32; 2]) -> (Vec3, f32) {
        let mut u = [u[0].min(ONE_MINUS_EPS), u[1].min(ONE_MINUS_EPS)];
        if self.is_empty() {
            return (square_to_dir(u), INV_4PI);
        }
        let mut origin = [0.0f32; 2];
        let mut size = 1.0f32;
        let mut density = 1.0f32;
        let mut n = 0;
        for _ in 0..GUIDE_MAX_QUAD_DEPTH {
            let node = &self.nodes[n];
            let s = &node.sum;
            let total = node_total(s);
            let mut q;
            if total > 0.0 {
                let lo = s[0] + s[2];
                let split = if lo == total { 1.0 } else { lo / total };
                if u[0] < split {
                    u[0] = rescale(u[0], 0.0, split);
                    q = 0;
                } else {
                    u[0] = rescale(u[0], split, 1.0 - split);
                    q = 1;
                }
                let (a, b) = (s[q], s[q + 2]);
                let split_y = if b == 0.0 { 1.0 } else { a / (a + b) };
                if u[1] < split_y {
                    u[1] = rescale(u[1], 0.0, split_y);
                } else {
                    u[1] = rescale(u[1], split_y, 1.0 - split_y);
                    q |= 2;
                }
            } else {
                q = quadrant(&mut u);
            }
            density *= quadrant_factor(s, q);
            size *= 0.5;
            let o = quadrant_origin(q, size);
            origin = [origin[0] + o[0], origin[1] + o[1]];
            n = node.child[q] as usize;
            if n == 0 {
                break;
            }
        }
        // Keep the direction in the sampled cell (see `guide_sample`).
        let mut p = [origin[0] + u[0] * size, origin[1] + u[1] * size];
        let centre = [origin[0] + 0.5 * size, origin[1] + 0.5 * size];
        let end = [origin[0] + size, origin[1] + size];
        let mut dir = Vec3::ZERO;
        let mut inside = false;
        for _ in 0..GUIDE_SAMPLE_ATTEMPTS {
            dir = square_to_dir(p);
            let back = dir_to_square(dir);
            inside = (0..2).all(|k| back[k] >= origin[k] && (back[k] < end[k] || end[k] == 1.0));
            if inside {
                break;
            }
            p = [0.5 * (p[0] + centre[0]), 0.5 * (p[1] + centre[1])];
        }
        let pdf = if inside {
            density * INV_4PI
        } else {
            self.pdf(dir)
        };
        (dir, pdf)
    }

    /// Every leaf cell with the probability the tree's sampling gives it (in f64).
    pub fn cells(&self) -> Vec<Cell> {
        let mut out = Vec::new();
        let mut stack = vec![(0usize, [0.0f32; 2], 1.0f32, 1u32, 1.0f64)];
        while let Some((n, origin, size, level, prob)) = stack.pop() {
            let node = &self.nodes[n];
            let total: f64 = node.sum.iter().map(|&s| f64::from(s)).sum();
            let h = size * 0.5;
            for q in 0..4 {
                let p = if total > 0.0 {
                    prob * f64::from(node.sum[q]) / total
                } else {
                    prob * 0.25
                };
                let o = quadrant_origin(q, h);
                let o = [origin[0] + o[0], origin[1] + o[1]];
                match node.child[q] {
                    0 => out.push(Cell {
                        origin: o,
                        size: h,
                        level,
                        prob: p,
                    }),
                    c => stack.push((c as usize, o, h, level + 1, p)),
                }
            }
        }
        out
    }

    /// Probability the tree's sampling gives the rectangle [lo, hi] of the square.
    pub fn mass_in_rect(&self, lo: [f64; 2], hi: [f64; 2]) -> f64 {
        self.cells()
            .iter()
            .map(|c| {
                let (o, s) = (
                    [f64::from(c.origin[0]), f64::from(c.origin[1])],
                    f64::from(c.size),
                );
                let lx = (hi[0].min(o[0] + s) - lo[0].max(o[0])).max(0.0);
                let ly = (hi[1].min(o[1] + s) - lo[1].max(o[1])).max(0.0);
                c.prob * lx * ly / (s * s)
            })
            .sum()
    }

    /// The leaf cell holding `p`: (origin, edge length).
    pub fn cell_at(&self, mut p: [f32; 2]) -> ([f32; 2], f32) {
        let mut n = 0;
        let mut origin = [0.0f32; 2];
        let mut size = 1.0f32;
        for _ in 0..GUIDE_MAX_QUAD_DEPTH {
            let q = quadrant(&mut p);
            size *= 0.5;
            let o = quadrant_origin(q, size);
            origin = [origin[0] + o[0], origin[1] + o[1]];
            n = self.nodes[n].child[q] as usize;
            if n == 0 {
                break;
            }
        }
        (origin, size)
    }

    /// Depth of the leaf cell holding `p` (as `guide_training_leaf` walks it; the
    /// root's quadrants are depth 1, a cell of depth k has edge 2^-k).
    pub fn cell_depth_at(&self, mut p: [f32; 2]) -> u32 {
        let mut n = 0;
        let mut depth = 1;
        for _ in 0..GUIDE_MAX_QUAD_DEPTH {
            let q = quadrant(&mut p);
            n = self.nodes[n].child[q] as usize;
            if n == 0 {
                break;
            }
            depth += 1;
        }
        depth
    }

    /// `v` into the cell holding `p`, `levels` levels deep at most
    /// (`guide_splat_to_depth`): a finer subtree takes it in its root quadrant's own sum,
    /// which `build` spreads evenly over the subtree.
    fn splat_to_depth(&mut self, mut p: [f32; 2], v: f32, levels: u32) {
        let mut n = 0;
        for level in 0..GUIDE_MAX_QUAD_DEPTH {
            let q = quadrant(&mut p);
            let c = self.nodes[n].child[q] as usize;
            if c == 0 || level + 1 >= levels {
                self.nodes[n].sum[q] += v;
                return;
            }
            n = c;
        }
    }

    /// Nearest directional filter (`guide_splat_nearest`).
    pub(crate) fn splat_nearest(&mut self, p: [f32; 2], v: f32) {
        self.splat_to_depth(p, v, GUIDE_MAX_QUAD_DEPTH);
    }

    /// Box directional filter (`guide_splat_box`, which explains it): a box the size of
    /// the leaf cell holding `p`, shifted inside the square along u and wrapped around
    /// along v (φ), spread over the cells of that depth's grid it overlaps. The same
    /// float operations as the kernel, so the two trees agree exactly.
    pub(crate) fn splat_box(&mut self, p: [f32; 2], v: f32) {
        let depth = self.cell_depth_at(p);
        let cells = (1u32 << depth) as f32;
        let mut lo = [p[0] * cells - 0.5, p[1] * cells - 0.5];
        lo[0] = lo[0].clamp(0.0, cells - 1.0);
        let base = [lo[0].floor(), lo[1].floor()];
        let f = [lo[0] - base[0], lo[1] - base[1]];
        for i in 0..4u32 {
            let corner = [i & 1, i >> 1];
            let wx = if corner[0] == 0 { 1.0 - f[0] } else { f[0] };
            let wy = if corner[1] == 0 { 1.0 - f[1] } else { f[1] };
            let w = wx * wy;
            if w.is_nan() || w <= 0.0 {
                continue;
            }
            let x = base[0] + corner[0] as f32;
            let mut y = base[1] + corner[1] as f32;
            if y < 0.0 {
                y += cells;
            } else if y >= cells {
                y -= cells;
            }
            self.splat_to_depth([(x + 0.5) / cells, (y + 0.5) / cells], v * w, depth);
        }
    }

    /// Replace the sums node by node (a GPU readback of the same topology).
    pub(crate) fn set_sums(&mut self, sums: impl Iterator<Item = [f32; 4]>) {
        for (node, s) in self.nodes.iter_mut().zip(sums) {
            node.sum = s;
        }
    }

    /// Complete the sums after training: energy deposited on an interior quadrant is
    /// spread uniformly over its subtree, then every interior quadrant gets the total of
    /// its subtree. Non-finite or negative sums (overflowed atomics) are dropped; returns
    /// how many were.
    pub(crate) fn build(&mut self) -> u32 {
        let mut dropped = 0;
        for node in &mut self.nodes {
            for s in &mut node.sum {
                if !(s.is_finite() && *s >= 0.0) {
                    *s = 0.0;
                    dropped += 1;
                }
            }
        }
        self.settle(0, 0.0);
        dropped
    }

    /// `build` for sums of second moments (records of L²/pdf): each leaf cell's S
    /// estimates ∫ L² over the cell, and becomes √(S·area), the integral of √E[L²] if
    /// it is constant over the cell; interior quadrants get their subtree's total. The
    /// density then follows √E[L²] (Rath et al. 2020) down to the tree's resolution.
    pub(crate) fn build_second_moment(&mut self) -> u32 {
        let dropped = self.build();
        self.root_of_areas(0, 1);
        dropped
    }

    /// Replace each leaf cell's sum under node `n` (at `level`; the root is 1) by
    /// √(sum·area) and each interior quadrant's by its subtree's total; returns the total.
    fn root_of_areas(&mut self, n: usize, level: u32) -> f64 {
        let area = 0.25f64.powi(level as i32);
        let mut total = 0.0;
        for q in 0..4 {
            let value = match self.nodes[n].child[q] {
                0 => (f64::from(self.nodes[n].sum[q]) * area).sqrt(),
                c => self.root_of_areas(c as usize, level + 1),
            };
            self.nodes[n].sum[q] = value as f32;
            total += value;
        }
        total
    }

    /// Settle node `n`, which also receives `inherited` spread uniformly over it; returns
    /// its total.
    fn settle(&mut self, n: usize, inherited: f64) -> f64 {
        let mut total = 0.0;
        for q in 0..4 {
            let own = f64::from(self.nodes[n].sum[q]) + inherited * 0.25;
            let value = match self.nodes[n].child[q] {
                0 => own,
                c => self.settle(c as usize, own),
            };
            self.nodes[n].sum[q] = value as f32;
            total += value;
        }
        total
    }

    /// Add `scale` × the energy `prior` (a built tree: every quadrant holds its subtree's
    /// total) has in each of this tree's leaf cells to that cell's sum, before `build`.
    /// Where this tree is finer than `prior`, a prior cell's energy is shared evenly by
    /// area; where it is coarser, a cell takes the whole subtree's total. The total
    /// added is `scale × prior.total()`.
    pub(crate) fn add_prior(&mut self, prior: &QuadTree, scale: f32) {
        #[derive(Clone, Copy)]
        enum Source {
            Node(usize),
            Uniform(f64),
        }
        if scale.is_nan() || scale <= 0.0 || prior.is_empty() {
            return;
        }
        let scale = f64::from(scale);
        let mut stack = walk_stack((0usize, Source::Node(0)));
        while let Some((n, source)) = stack.pop() {
            for q in 0..4 {
                let (energy, below) = match source {
                    Source::Node(o) => {
                        let e = f64::from(prior.nodes[o].sum[q]);
                        match prior.nodes[o].child[q] {
                            0 => (e, Source::Uniform(e * 0.25)),
                            c => (e, Source::Node(c as usize)),
                        }
                    }
                    Source::Uniform(e) => (e, Source::Uniform(e * 0.25)),
                };
                match self.nodes[n].child[q] {
                    0 => self.nodes[n].sum[q] += (scale * energy) as f32,
                    c => stack.push((c as usize, below)),
                }
            }
        }
    }

    /// The topology of the next training tree (all sums zero): a quadrant is
    /// subdivided while its share of this tree's energy exceeds `rho` and its node is
    /// above level `max_depth`. Quadrants that were leaves here subdivide as if their
    /// energy were uniform; subtrees below the threshold collapse. An empty tree gives
    /// uniform shares (¼ per level), as the reference does.
    pub fn refined(&self, rho: f32, max_depth: u32) -> QuadTree {
        self.refined_into(rho, max_depth, Vec::new())
    }

    /// [`QuadTree::refined`], built in `storage` (cleared first): the refit passes the
    /// nodes of the sampling tree it retires, so that each pass reuses memory already
    /// in use rather than asking the allocator (and the kernel: fresh pages are faulted
    /// in and zeroed) for the next training trees.
    pub fn refined_into(&self, rho: f32, max_depth: u32, mut storage: Vec<QuadNode>) -> QuadTree {
        #[derive(Clone, Copy)]
        enum Source {
            Node(usize),
            Uniform(f32),
        }
        let total = f64::from(self.total());
        storage.clear();
        // The next tree is about this one's size (it refines its energy).
        storage.reserve(self.nodes.len());
        storage.push(QuadNode::default());
        let mut out = QuadTree { nodes: storage };
        let mut stack = walk_stack((0usize, Source::Node(0), 1u32));
        while let Some((new, source, level)) = stack.pop() {
            let (sums, children) = match source {
                Source::Node(o) => (self.nodes[o].sum, self.nodes[o].child),
                Source::Uniform(s) => ([s * 0.25; 4], [0; 4]),
            };
            for q in 0..4 {
                let fraction = if total > 0.0 {
                    f64::from(sums[q]) / total
                } else {
                    0.25f64.powi(level as i32)
                };
                if level < max_depth && fraction > f64::from(rho) {
                    let next = match children[q] {
                        0 => Source::Uniform(sums[q]),
                        c => Source::Node(c as usize),
                    };
                    let index = out.nodes.len();
                    out.nodes.push(QuadNode::default());
                    out.nodes[new].child[q] = index as u32;
                    stack.push((index, next, level + 1));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator for the tests (SplitMix64 → floats in [0,1)).
    pub(crate) struct TestRng(u64);
    impl TestRng {
        pub fn new(seed: u64) -> Self {
            Self(seed)
        }
        pub fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        }
        pub fn f32(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// A tree trained on a lobe around +z plus a weaker lobe elsewhere.
    fn trained_tree(seed: u64) -> QuadTree {
        let mut rng = TestRng::new(seed);
        let mut tree = QuadTree::initial(0.01, 20);
        for round in 0..3 {
            for _ in 0..20000 {
                let (u, v) = (rng.f32(), rng.f32());
                let p = if rng.f32() < 0.7 {
                    [0.9 + 0.1 * u, 0.3 + 0.05 * v]
                } else {
                    [u, v]
                };
                tree.splat_box(p, 1.0 + rng.f32());
            }
            tree.build();
            if round < 2 {
                let sampling = tree.clone();
                tree = sampling.refined(0.01, 20);
            }
        }
        tree
    }

    #[test]
    fn initial_tree_is_uniform_depth_four() {
        let t = QuadTree::initial(0.01, 20);
        // ¼, 1/16, 1/64 exceed ρ = 0.01, 1/256 does not: 1 + 4 + 16 + 64 nodes.
        assert_eq!(t.node_count(), 85);
        assert_eq!(t.depth(), 4);
        assert!(t.cells().iter().all(|c| c.size == 1.0 / 16.0));
    }

    #[test]
    fn sample_pdf_is_bitwise_pdf() {
        let tree = trained_tree(1);
        assert!(tree.depth() > 5);
        let mut rng = TestRng::new(2);
        for _ in 0..100000 {
            let (d, pdf) = tree.sample([rng.f32(), rng.f32()]);
            assert_eq!(pdf.to_bits(), tree.pdf(d).to_bits());
            assert!(pdf > 0.0);
        }
    }

    #[test]
    fn build_conserves_box_splat_energy() {
        let mut tree = QuadTree::initial(0.01, 20).refined(0.01, 20);
        let mut rng = TestRng::new(3);
        let mut expected = 0.0f64;
        for _ in 0..1000 {
            let v = rng.f32();
            expected += f64::from(v);
            tree.splat_box([rng.f32(), rng.f32()], v);
        }
        assert_eq!(tree.build(), 0);
        assert!((f64::from(tree.total()) - expected).abs() < 1e-4 * expected);
    }

    /// The prior keeps its energy and where it lies: every cell of the new tree, finer
    /// or coarser than the prior's, gets the prior's mass over that cell's area.
    #[test]
    fn prior_is_added_by_area_into_finer_and_coarser_cells() {
        let prior = trained_tree(4);
        // A topology unlike the prior's: uniform depth 3 with one corner refined to depth
        // 7 (finer than the prior there) and no cell finer than 1/8 elsewhere (coarser).
        let mut tree = QuadTree::initial(0.02, 3);
        let mut n = 0;
        while tree.nodes[n].child[0] != 0 {
            n = tree.nodes[n].child[0] as usize;
        }
        for _ in 0..4 {
            let index = tree.nodes.len();
            tree.nodes.push(QuadNode::default());
            tree.nodes[n].child[0] = index as u32;
            n = index;
        }
        assert_eq!(tree.depth(), 7);
        tree.add_prior(&prior, 0.5);
        let added: f64 = tree
            .nodes
            .iter()
            .flat_map(|node| node.sum)
            .map(f64::from)
            .sum();
        let expected = 0.5 * f64::from(prior.total());
        assert!(
            (added - expected).abs() < 1e-5 * expected,
            "{added} vs {expected}"
        );
        tree.build();
        for cell in tree.cells() {
            let lo = [f64::from(cell.origin[0]), f64::from(cell.origin[1])];
            let s = f64::from(cell.size);
            let want = prior.mass_in_rect(lo, [lo[0] + s, lo[1] + s]);
            assert!(
                (cell.prob - want).abs() < 1e-4 * want + 1e-7,
                "cell {:?} size {s}: {} vs {want}",
                cell.origin,
                cell.prob
            );
        }
        // Nothing is added from an empty prior.
        let mut fresh = QuadTree::initial(0.01, 20);
        fresh.add_prior(&QuadTree::empty(), 1.0);
        assert!(fresh.is_empty());
    }

    #[test]
    fn second_moment_build_takes_the_root_per_cell_area() {
        // Root split once more in quadrant 0: cells of area 1/16 there, 1/4 elsewhere.
        let mut tree = QuadTree::from_nodes(vec![
            QuadNode {
                sum: [0.0; 4],
                child: [1, 0, 0, 0],
            },
            QuadNode::default(),
        ])
        .unwrap();
        // Constant second moment m over the square: S = m·area in every cell, so each
        // cell becomes √m·area and the density is uniform, as √m is.
        let m = 9.0f32;
        tree.set_sums([[0.0, m / 4.0, m / 4.0, m / 4.0], [m / 16.0; 4]].into_iter());
        assert_eq!(tree.build_second_moment(), 0);
        tree.check_sums_consistent().unwrap();
        assert!((tree.total() - 3.0).abs() < 1e-6);
        for p in [[0.1, 0.1], [0.3, 0.2], [0.7, 0.3], [0.6, 0.9]] {
            assert!((tree.density(p) - 1.0).abs() < 1e-5, "{p:?}");
        }
        // A cell with 4× the second moment gets 2× the density, not 4×.
        let mut tree = QuadTree::from_nodes(vec![QuadNode::default()]).unwrap();
        tree.set_sums([[4.0, 1.0, 1.0, 1.0]].into_iter());
        tree.build_second_moment();
        let d = |p| tree.density(p);
        assert!((d([0.2, 0.2]) / d([0.7, 0.7]) - 2.0).abs() < 1e-5);
    }

    #[test]
    fn box_splat_wraps_phi_and_stays_inside_u() {
        let mut tree = QuadTree::initial(0.01, 20);
        // Cells are 1/16: a box centred at v = 0 puts half its energy near v = 1.
        tree.splat_box([0.5, 0.0], 1.0);
        tree.build();
        let top = tree.mass_in_rect([0.0, 0.5], [1.0, 1.0]);
        assert!((top - 0.5).abs() < 1e-6, "{top}");
        // At the u = 0 border the box is shifted inside: all energy in the first column.
        let mut tree = QuadTree::initial(0.01, 20);
        tree.splat_box([0.0, 0.5], 1.0);
        tree.build();
        assert!((tree.total() - 1.0).abs() < 1e-6);
        assert!((tree.mass_in_rect([0.0, 0.0], [1.0 / 16.0, 1.0]) - 1.0).abs() < 1e-6);
    }

    /// The box's share of a neighbour: by the area it covers where the neighbour is as
    /// coarse as the record's cell or coarser, over the neighbour's whole cell where the
    /// tree is finer there.
    #[test]
    fn box_splat_shares_by_area_and_spreads_over_finer_neighbours() {
        // Root quadrant 0 (u, v < 1/2) split into cells of 1/4; the others are leaves.
        let tree = || {
            QuadTree::from_nodes(vec![
                QuadNode {
                    sum: [0.0; 4],
                    child: [1, 0, 0, 0],
                },
                QuadNode::default(),
            ])
            .unwrap()
        };
        // A record in the leaf [1/2, 1) × [0, 1/2) (edge 1/2) at u = 0.6: its box
        // reaches 0.15 into [0, 1/2) in u and is split evenly in v across v = 0 (wrap).
        // Quadrant 2 is a coarse leaf: exact share 0.3·0.5.
        let mut t = tree();
        t.splat_box([0.6, 0.0], 1.0);
        t.build();
        assert!((t.total() - 1.0).abs() < 1e-6);
        let upper_left = t.mass_in_rect([0.0, 0.5], [0.5, 1.0]);
        assert!((upper_left - 0.15).abs() < 1e-6, "{upper_left}");
        // Quadrant 0 is finer than the box: its share (also 0.15) is spread over the
        // whole quadrant, so half of it lies in u < 1/4, which an exact box (u from
        // 0.35) would not reach.
        let far = t.mass_in_rect([0.0, 0.0], [0.25, 0.5]);
        assert!((far - 0.075).abs() < 1e-6, "{far}");
        // A record in the fine quadrant keeps its box at that depth: edge 1/4, centred
        // at (0.2, 0.2), it covers [0.075, 0.325]², 0.7 of it in the cell [0, 1/4)
        // along each axis.
        let mut t = tree();
        t.splat_box([0.2, 0.2], 1.0);
        t.build();
        let inside = t.mass_in_rect([0.0, 0.0], [0.25, 0.25]);
        assert!((inside - 0.49).abs() < 1e-6, "{inside}");
        let corner = t.mass_in_rect([0.25, 0.25], [0.5, 0.5]);
        assert!((corner - 0.09).abs() < 1e-6, "{corner}");
    }

    #[test]
    fn refine_subdivides_by_rho() {
        // All energy in one 1/16 cell of the initial tree. The path to it is kept (share
        // 1 > ρ); below it the energy counts as uniform: quarters of 1/4, 1/16, 1/64 of
        // the total exceed ρ = 0.01, 1/256 does not, so 4 more levels appear; every
        // other quadrant (no energy) collapses.
        let mut tree = QuadTree::initial(0.01, 20);
        tree.splat_nearest([0.03, 0.03], 1.0);
        tree.build();
        let next = tree.refined(0.01, 20);
        assert_eq!(next.depth(), 8);
        assert_eq!(next.node_count(), 4 + 1 + 4 + 16 + 64);
        assert_eq!(next.cells().len(), 3 * 4 + 64 * 4);
        // A depth cap stops there.
        assert_eq!(tree.refined(0.01, 7).depth(), 7);
    }

    #[test]
    fn refine_into_used_storage_is_refine() {
        // The refit builds each next training tree in the nodes of the sampling tree it
        // retires: whatever they held must not show through.
        let tree = trained_tree(3);
        let used = trained_tree(4).into_nodes();
        assert!(used.len() > 1);
        assert_eq!(tree.refined_into(0.01, 20, used), tree.refined(0.01, 20));
        assert_eq!(
            tree.refined_into(0.01, 20, Vec::new()),
            tree.refined(0.01, 20)
        );
    }

    #[test]
    fn refine_respects_depth_cap_and_collapses() {
        // Energy concentrated at one point refines 4 levels per refit, up to level 20.
        let p1 = [0.123, 0.456];
        let mut tree = QuadTree::initial(0.01, 20);
        let mut depths = Vec::new();
        for _ in 0..6 {
            tree.splat_nearest(p1, 1.0);
            tree.build();
            tree = tree.refined(0.01, 20);
            depths.push(tree.depth());
        }
        assert_eq!(depths, [8, 12, 16, 20, 20, 20]);
        assert_eq!(tree.cell_depth_at(p1), 20);
        // When the energy moves to another root quadrant, the fine region collapses.
        let p2 = [0.9, 0.9];
        tree.splat_nearest(p2, 1.0);
        tree.build();
        let next = tree.refined(0.01, 20);
        assert_eq!(next.cell_depth_at(p1), 1);
        assert_eq!(next.cell_depth_at(p2), 5);
    }

    #[test]
    fn refine_threshold_is_strict_share_of_total() {
        // Root quadrant 0 holds 2% and quadrant 3 holds 98%: with ρ = 0.02 quadrant 0
        // (exactly ρ) stays a leaf; with ρ = 0.019 it subdivides once more (its quarters
        // hold 0.5% < ρ).
        let mut tree = QuadTree::empty();
        tree.nodes[0].sum = [0.02, 0.0, 0.0, 0.98];
        let a = tree.refined(0.02, 20);
        assert_eq!(a.nodes()[0].child[0], 0);
        assert_eq!(a.nodes()[0].child[1], 0);
        assert_ne!(a.nodes()[0].child[3], 0);
        let b = tree.refined(0.019, 20);
        let c = b.nodes()[0].child[0] as usize;
        assert_ne!(c, 0);
        assert_eq!(b.nodes()[c].child, [0; 4]);
    }

    #[test]
    fn pdf_integrates_to_one() {
        let tree = trained_tree(5);
        let n = 2048;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let p = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                sum += f64::from(tree.density(p));
            }
        }
        let integral = sum / (n * n) as f64;
        // Cells deeper than the grid's 2^-11 make the midpoint rule approximate.
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
        let cells: f64 = tree.cells().iter().map(|c| c.prob).sum();
        assert!((cells - 1.0).abs() < 1e-12);
    }

    #[test]
    fn from_nodes_rejects_non_trees() {
        let t = QuadTree::initial(0.01, 20);
        assert!(QuadTree::from_nodes(t.nodes().to_vec()).is_ok());
        let mut bad = t.nodes().to_vec();
        bad[1].child[0] = 1; // cycle
        assert!(QuadTree::from_nodes(bad).is_err());
        let mut bad = t.nodes().to_vec();
        bad[0].child[0] = 999;
        assert!(QuadTree::from_nodes(bad).is_err());
        let mut bad = t.nodes().to_vec();
        bad[3].sum[2] = f32::NAN;
        assert!(QuadTree::from_nodes(bad).is_err());
    }
}
