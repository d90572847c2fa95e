//! Debug view of the SD-tree: the sampling quadtree of the spatial leaf holding a point
//! (the renderer passes a pixel's first hit) drawn as an image of the square
//! ((cosθ+1)/2 along x, φ/2π along y, y down), colour-mapped by log density, with the
//! leaf's bounds, statistical weight and tree size as text.

use super::quadtree::QuadTree;
use super::sdtree::SdTree;
use glam::Vec3;
use std::fmt;

/// An RGB f32 image of a leaf's sampling quadtree, and what it shows.
#[derive(Clone, Debug)]
pub struct LeafView {
    pub width: u32,
    pub height: u32,
    /// Row-major RGB, values in [0, 1].
    pub rgb: Vec<f32>,
    pub info: LeafInfo,
}

/// Facts about a spatial leaf, printable as a few lines of text.
#[derive(Clone, Debug, PartialEq)]
pub struct LeafInfo {
    pub leaf: u32,
    pub box_min: Vec3,
    pub box_size: Vec3,
    pub spatial_depth: u32,
    /// Statistical weight (≈ records) the sampling tree was learned from.
    pub sampling_weight: f32,
    pub training_weight: f32,
    pub nodes: usize,
    pub quad_depth: u32,
    /// Densities on the square (1 = uniform) at the colour map's ends.
    pub min_density: f32,
    pub max_density: f32,
    pub uniform: bool,
}

impl fmt::Display for LeafInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.box_min;
        let e = self.box_min + self.box_size;
        writeln!(
            f,
            "spatial leaf {} (depth {})",
            self.leaf, self.spatial_depth
        )?;
        writeln!(
            f,
            "  bounds [{}, {}, {}] .. [{}, {}, {}]",
            b.x, b.y, b.z, e.x, e.y, e.z
        )?;
        writeln!(
            f,
            "  sample weight {} (sampling tree), {} (training so far)",
            self.sampling_weight, self.training_weight
        )?;
        writeln!(
            f,
            "  quadtree: {} nodes, depth {}",
            self.nodes, self.quad_depth
        )?;
        if self.uniform {
            writeln!(f, "  nothing learned: samples uniformly")
        } else {
            writeln!(
                f,
                "  density (1 = uniform) from {:.4} (dark blue) to {:.4} (yellow), log scale; \
                 x = (cos θ + 1)/2, y = φ/2π; black: never sampled; grey lines: cells",
                self.min_density, self.max_density
            )
        }
    }
}

/// A blue → green → yellow colour map of t ∈ [0, 1] (viridis-like, 4 stops).
fn colour(t: f32) -> [f32; 3] {
    const STOPS: [[f32; 3]; 4] = [
        [0.267, 0.005, 0.329],
        [0.191, 0.407, 0.556],
        [0.208, 0.719, 0.473],
        [0.993, 0.906, 0.144],
    ];
    let x = t.clamp(0.0, 1.0) * 3.0;
    let i = (x as usize).min(2);
    let f = x - i as f32;
    std::array::from_fn(|k| STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f)
}

/// The density of `tree` (1 = uniform over the square) at the centres of a `size` ×
/// `size` grid over the (cosθ, φ) square, row-major: `x = (cosθ + 1)/2`, `y = φ/2π`.
pub fn density_grid(tree: &QuadTree, size: u32) -> Vec<f32> {
    let n = size as usize;
    let mut density = vec![0.0f32; n * n];
    for j in 0..n {
        for i in 0..n {
            let p = [
                (i as f32 + 0.5) / size as f32,
                (j as f32 + 0.5) / size as f32,
            ];
            density[j * n + i] = tree.density(p);
        }
    }
    density
}

/// Draw `tree` as a `size` × `size` image. Cell borders at least 4 pixels apart are
/// drawn in grey.
pub fn draw_quadtree(tree: &QuadTree, size: u32) -> (Vec<f32>, f32, f32) {
    let n = size as usize;
    let density = density_grid(tree, size);
    let max = density.iter().copied().fold(0.0f32, f32::max);
    let min = density
        .iter()
        .copied()
        .filter(|&d| d > 0.0)
        .fold(f32::INFINITY, f32::min);
    let (lmin, lmax) = (min.max(1e-30).ln(), max.max(1e-30).ln());
    let mut rgb = Vec::with_capacity(n * n * 3);
    for &d in &density {
        let c = if d > 0.0 {
            colour(if lmax > lmin {
                (d.ln() - lmin) / (lmax - lmin)
            } else {
                1.0
            })
        } else {
            [0.0; 3]
        };
        rgb.extend_from_slice(&c);
    }
    for cell in tree.cells() {
        let px = cell.size * size as f32;
        if px < 4.0 {
            continue;
        }
        let (x0, y0) = (
            (cell.origin[0] * size as f32) as usize,
            (cell.origin[1] * size as f32) as usize,
        );
        let len = px as usize;
        for k in 0..len {
            for (x, y) in [(x0 + k, y0), (x0, y0 + k)] {
                if x < n && y < n {
                    rgb[(y * n + x) * 3..(y * n + x) * 3 + 3].copy_from_slice(&[0.5; 3]);
                }
            }
        }
    }
    (rgb, if min.is_finite() { min } else { 0.0 }, max)
}

impl SdTree {
    /// The debug view of the leaf holding `pos`, `size` pixels square.
    pub fn leaf_view(&self, pos: Vec3, size: u32) -> LeafView {
        let leaf_index = self.find_leaf(pos);
        let leaf = self.leaf(leaf_index);
        let (rgb, min, max) = draw_quadtree(&leaf.sampling, size);
        LeafView {
            width: size,
            height: size,
            rgb,
            info: LeafInfo {
                leaf: leaf_index,
                box_min: leaf.box_min,
                box_size: leaf.box_size,
                spatial_depth: leaf.depth,
                sampling_weight: leaf.sampling_weight,
                training_weight: leaf.training_weight,
                nodes: leaf.sampling.node_count(),
                quad_depth: leaf.sampling.depth(),
                min_density: min,
                max_density: max,
                uniform: leaf.sampling.is_empty(),
            },
        }
    }
}
