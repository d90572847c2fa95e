//! The BVH of the software traversal (`shaders_glsl/inc/bvh.glsl`): a binned-SAH BVH2
//! over world-space triangles, built on the CPU and flattened into two storage buffers,
//! nodes that hold both children's boxes (one read tests two boxes) and triangles
//! prepared for Möller–Trumbore (v0 and two edges), in leaf order.
//!
//! Each triangle carries the instance index a ray query would report for it (the TLAS
//! instance's custom index + its geometry index, i.e. the instance's position in the GPU
//! instance buffer) and its index within its geometry, so the two traversals are
//! interchangeable behind `trace_closest` / `visible`.

use crate::gpu;
use glam::Vec3;

/// A triangle to build over.
#[derive(Clone, Copy, Debug)]
pub struct BuildTriangle {
    pub v: [Vec3; 3],
    pub instance: u32,
    pub primitive: u32,
    pub opaque: bool,
}

/// Build options.
#[derive(Clone, Copy, Debug)]
pub struct BvhOptions {
    /// Most triangles in one leaf (1..=16).
    pub max_leaf: usize,
}

impl Default for BvhOptions {
    fn default() -> Self {
        BvhOptions { max_leaf: 2 }
    }
}

impl BvhOptions {
    /// The defaults, with the leaf size from `LANTERNA_BVH_LEAF` when set (for
    /// measurements: `lanterna bench --suite traversal` with several values).
    pub fn from_env() -> BvhOptions {
        let mut o = BvhOptions::default();
        if let Some(n) = std::env::var("LANTERNA_BVH_LEAF")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
        {
            o.max_leaf = n.clamp(1, MAX_LEAF);
        }
        o
    }
}

const MAX_LEAF: usize = gpu::BVH_LEAF_COUNT_MASK as usize + 1;
const BINS: usize = 16;
/// Deeper than this, nodes split at the object median (which ends within log₂ n levels),
/// so the traversal stack of `BVH_STACK_SIZE` entries cannot overflow.
const SAH_MAX_DEPTH: usize = 32;

/// The flattened BVH.
pub struct Bvh {
    pub nodes: Vec<gpu::BvhNode>,
    pub triangles: Vec<gpu::BvhTriangle>,
    /// Depth of the deepest leaf (the root's children are at depth 1).
    pub depth: usize,
}

#[derive(Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    fn join(&mut self, b: &Aabb) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
    }
    fn area(&self) -> f32 {
        if self.min.x > self.max.x {
            return 0.0;
        }
        let e = self.max - self.min;
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// A child as the GPU node stores it: its box and reference.
#[derive(Clone, Copy)]
struct Child {
    bounds: Aabb,
    reference: u32,
}

const EMPTY_CHILD: Child = Child {
    // Finite and inverted: the slab test rejects it without infinities.
    bounds: Aabb {
        min: Vec3::splat(1e30),
        max: Vec3::splat(-1e30),
    },
    reference: gpu::BVH_EMPTY,
};

struct Builder {
    centroids: Vec<Vec3>,
    bounds: Vec<Aabb>,
    /// Triangle indices, permuted in place into leaf order.
    order: Vec<u32>,
    nodes: Vec<gpu::BvhNode>,
    options: BvhOptions,
    depth: usize,
}

impl Bvh {
    /// Build over `tris` (any number, including none).
    pub fn build(tris: &[BuildTriangle], options: BvhOptions) -> Bvh {
        assert!(
            tris.len() <= gpu::BVH_LEAF_FIRST_MASK as usize,
            "too many triangles for the software BVH"
        );
        let options = BvhOptions {
            max_leaf: options.max_leaf.clamp(1, MAX_LEAF),
        };
        let bounds: Vec<Aabb> = tris
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                for p in t.v {
                    b.grow(p);
                }
                b
            })
            .collect();
        let mut b = Builder {
            centroids: bounds.iter().map(|b| 0.5 * (b.min + b.max)).collect(),
            bounds,
            order: (0..tris.len() as u32).collect(),
            nodes: Vec::new(),
            options,
            depth: 0,
        };
        // Node 0 is always an inner node (the kernel starts there): a root that would be
        // a leaf becomes node 0's only child.
        b.nodes.push(zero_node());
        let n = tris.len();
        if n == 0 {
            b.nodes[0] = make_node(EMPTY_CHILD, EMPTY_CHILD);
        } else if n <= options.max_leaf {
            let c = b.build_range(0, n, 1);
            b.nodes[0] = make_node(c, EMPTY_CHILD);
        } else {
            let (_, mid) = b.split(0, n, 0);
            b.build_inner(0, (0, mid), (mid, n), 0);
        }
        let triangles = b
            .order
            .iter()
            .map(|&i| {
                let t = &tris[i as usize];
                let e1 = t.v[1] - t.v[0];
                let e2 = t.v[2] - t.v[0];
                gpu::BvhTriangle {
                    v0: t.v[0].to_array(),
                    instance: t.instance,
                    e1: e1.to_array(),
                    primitive: t.primitive,
                    e2: e2.to_array(),
                    flags: if t.opaque {
                        gpu::BVH_TRIANGLE_OPAQUE
                    } else {
                        0
                    },
                }
            })
            .collect();
        Bvh {
            nodes: b.nodes,
            triangles,
            depth: b.depth,
        }
    }
}

fn zero_node() -> gpu::BvhNode {
    make_node(EMPTY_CHILD, EMPTY_CHILD)
}

fn make_node(a: Child, b: Child) -> gpu::BvhNode {
    gpu::BvhNode {
        a_min: a.bounds.min.to_array(),
        a_ref: a.reference,
        a_max: a.bounds.max.to_array(),
        b_ref: b.reference,
        b_min: b.bounds.min.to_array(),
        pad0: 0,
        b_max: b.bounds.max.to_array(),
        pad1: 0,
    }
}

impl Builder {
    fn range_bounds(&self, begin: usize, end: usize) -> Aabb {
        let mut b = Aabb::EMPTY;
        for &i in &self.order[begin..end] {
            b.join(&self.bounds[i as usize]);
        }
        b
    }

    /// Fill inner node `index` with the two halves `a` and `b` of its range.
    fn build_inner(&mut self, index: usize, a: (usize, usize), b: (usize, usize), depth: usize) {
        let ca = self.build_range(a.0, a.1, depth + 1);
        let cb = self.build_range(b.0, b.1, depth + 1);
        self.nodes[index] = make_node(ca, cb);
    }

    /// The child for `order[begin..end]`: a leaf, or a new inner node.
    fn build_range(&mut self, begin: usize, end: usize, depth: usize) -> Child {
        let bounds = self.range_bounds(begin, end);
        let n = end - begin;
        if n <= self.options.max_leaf {
            self.depth = self.depth.max(depth);
            return Child {
                bounds,
                reference: gpu::BVH_LEAF_BIT
                    | ((n as u32 - 1) << gpu::BVH_LEAF_COUNT_SHIFT)
                    | begin as u32,
            };
        }
        let (_, mid) = self.split(begin, end, depth);
        let index = self.nodes.len();
        self.nodes.push(zero_node());
        self.build_inner(index, (begin, mid), (mid, end), depth);
        Child {
            bounds,
            reference: index as u32,
        }
    }

    /// Partition `order[begin..end]` (more than one leaf's worth) in two; returns
    /// (begin, mid).
    fn split(&mut self, begin: usize, end: usize, depth: usize) -> (usize, usize) {
        let mut cb = Aabb::EMPTY;
        for &i in &self.order[begin..end] {
            cb.grow(self.centroids[i as usize]);
        }
        let extent = cb.max - cb.min;
        let n = end - begin;
        let median = |b: &mut Self, axis: usize| {
            let mid = begin + n / 2;
            let c = &b.centroids;
            b.order[begin..end].select_nth_unstable_by(mid - begin, |&x, &y| {
                c[x as usize][axis].total_cmp(&c[y as usize][axis])
            });
            (begin, mid)
        };
        let axis_max = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        if depth >= SAH_MAX_DEPTH || extent[axis_max] <= 0.0 {
            return median(self, axis_max);
        }
        // Binned SAH over the three axes (Wald 2007).
        let mut best = (f32::INFINITY, 0usize, 0usize); // cost, axis, split bin
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            let scale = BINS as f32 / extent[axis];
            let mut bin_bounds = [Aabb::EMPTY; BINS];
            let mut bin_count = [0u32; BINS];
            for &i in &self.order[begin..end] {
                let k = (((self.centroids[i as usize][axis] - cb.min[axis]) * scale) as usize)
                    .min(BINS - 1);
                bin_count[k] += 1;
                bin_bounds[k].join(&self.bounds[i as usize]);
            }
            let mut right_area = [0f32; BINS];
            let mut right_count = [0u32; BINS];
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in (1..BINS).rev() {
                acc.join(&bin_bounds[k]);
                cnt += bin_count[k];
                right_area[k] = acc.area();
                right_count[k] = cnt;
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in 1..BINS {
                acc.join(&bin_bounds[k - 1]);
                cnt += bin_count[k - 1];
                if cnt == 0 || right_count[k] == 0 {
                    continue;
                }
                let cost = acc.area() * cnt as f32 + right_area[k] * right_count[k] as f32;
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        if !best.0.is_finite() {
            return median(self, axis_max);
        }
        let (_, axis, k) = best;
        let scale = BINS as f32 / extent[axis];
        let c = &self.centroids;
        let slice = &mut self.order[begin..end];
        let mut left = 0;
        for j in 0..slice.len() {
            let bin =
                (((c[slice[j] as usize][axis] - cb.min[axis]) * scale) as usize).min(BINS - 1);
            if bin < k {
                slice.swap(left, j);
                left += 1;
            }
        }
        (begin, begin + left)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(tris: &[BuildTriangle], o: Vec3, d: Vec3) -> Option<(u32, f32)> {
        let mut best: Option<(u32, f32)> = None;
        for t in tris {
            let e1 = t.v[1] - t.v[0];
            let e2 = t.v[2] - t.v[0];
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det == 0.0 {
                continue;
            }
            let tv = o - t.v[0];
            let u = tv.dot(p) / det;
            let q = tv.cross(e1);
            let v = d.dot(q) / det;
            let tt = e2.dot(q) / det;
            if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt >= 0.0 && best.is_none_or(|b| tt < b.1) {
                best = Some((t.primitive, tt));
            }
        }
        best
    }

    /// Every triangle lies in exactly one leaf, every leaf box contains its triangles and
    /// every inner box contains its children's.
    #[test]
    fn structure_is_sound() {
        let mut rng = 12345u32;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 17;
            rng ^= rng << 5;
            rng as f32 / u32::MAX as f32
        };
        let tris: Vec<BuildTriangle> = (0..1000)
            .map(|i| {
                let c = Vec3::new(next(), next(), next()) * 10.0;
                BuildTriangle {
                    v: [
                        c,
                        c + Vec3::new(next(), next(), next()),
                        c + Vec3::new(next(), next(), next()),
                    ],
                    instance: 0,
                    primitive: i,
                    opaque: true,
                }
            })
            .collect();
        for leaf in [1, 4, 8] {
            let bvh = Bvh::build(&tris, BvhOptions { max_leaf: leaf });
            assert!(bvh.depth < gpu::BVH_STACK_SIZE as usize);
            let mut seen = vec![0u32; tris.len()];
            fn walk(bvh: &Bvh, r: u32, lo: Vec3, hi: Vec3, seen: &mut [u32]) {
                if r == gpu::BVH_EMPTY {
                    return;
                }
                if r & gpu::BVH_LEAF_BIT != 0 {
                    let first = (r & gpu::BVH_LEAF_FIRST_MASK) as usize;
                    let n = ((r >> gpu::BVH_LEAF_COUNT_SHIFT) & gpu::BVH_LEAF_COUNT_MASK) + 1;
                    for t in &bvh.triangles[first..first + n as usize] {
                        seen[t.primitive as usize] += 1;
                        let v0 = Vec3::from(t.v0);
                        for p in [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)] {
                            assert!(p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all());
                        }
                    }
                    return;
                }
                let n = &bvh.nodes[r as usize];
                for (cmin, cmax, cr) in [(n.a_min, n.a_max, n.a_ref), (n.b_min, n.b_max, n.b_ref)] {
                    let (cmin, cmax) = (Vec3::from(cmin), Vec3::from(cmax));
                    if cr != gpu::BVH_EMPTY {
                        assert!(cmin.cmpge(lo).all() && cmax.cmple(hi).all());
                    }
                    walk(bvh, cr, cmin, cmax, seen);
                }
            }
            walk(
                &bvh,
                0,
                Vec3::splat(f32::NEG_INFINITY),
                Vec3::splat(f32::INFINITY),
                &mut seen,
            );
            assert!(seen.iter().all(|&s| s == 1), "leaf {leaf}");
        }
        // The brute-force closest hit is reachable: a crude CPU traversal agrees.
        let bvh = Bvh::build(&tris, BvhOptions::default());
        for k in 0..200 {
            let o = Vec3::new(-5.0, 5.0 + (k as f32 * 0.037) % 5.0, 5.0);
            let d = Vec3::new(1.0, 0.01 * k as f32 - 1.0, 0.3);
            let want = brute(&tris, o, d);
            let leaf_tris: Vec<BuildTriangle> = bvh
                .triangles
                .iter()
                .map(|t| {
                    let v0 = Vec3::from(t.v0);
                    BuildTriangle {
                        v: [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)],
                        instance: 0,
                        primitive: t.primitive,
                        opaque: true,
                    }
                })
                .collect();
            let got = brute(&leaf_tris, o, d);
            assert_eq!(want.map(|w| w.0), got.map(|g| g.0));
        }
    }

    #[test]
    fn empty_and_tiny_scenes() {
        let bvh = Bvh::build(&[], BvhOptions::default());
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!(bvh.nodes[0].a_ref, gpu::BVH_EMPTY);
        let t = BuildTriangle {
            v: [Vec3::ZERO, Vec3::X, Vec3::Y],
            instance: 3,
            primitive: 7,
            opaque: false,
        };
        let bvh = Bvh::build(&[t], BvhOptions::default());
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!(bvh.nodes[0].a_ref, gpu::BVH_LEAF_BIT);
        assert_eq!(bvh.triangles[0].instance, 3);
        assert_eq!(bvh.triangles[0].flags, 0);
    }
}
