//! The light tree of `--source tree`: a binary tree over the light models whose nodes
//! bound where their lights are, how much they emit and toward which directions, so that
//! a shading point can choose a model in proportion to an estimate of what it receives
//! from it (the light-bounds importance of Conty Estevez & Kulla 2018, "Importance
//! sampling of many lights with adaptive tree splitting", as pbrt-v4 states it).
//!
//! Sampling descends from the root, choosing each child in proportion to its importance
//! at the shading point; the probability of a given model is the product of the choices
//! along its path, which each model stores (`LightModel::tree_path`, `tree_depth`) so
//! that MIS and RIS find it by walking that path alone. The kernels mix the tree with
//! the uniform source (`LIGHT_TREE_UNIFORM_SHARE`), so a model the bounds undervalue is
//! still sampled. Directional lights sit under a fixed split at the root: the tree's
//! bounds need a distance. This module builds the tree and mirrors the kernels'
//! importance and probabilities (`inc/light_tree.glsl`) for the tests.

use crate::gpu;
use crate::scene::ies;
use glam::Vec3;
use std::collections::HashMap;

/// The largest depth a model's path can describe (the bits of `tree_path`).
pub const MAX_DEPTH: u32 = 32;

/// Bounds of a set of emitters: a box, flux, and a cone of normals with the spread of the
/// emission around each normal.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3,
    max: Vec3,
    power: f64,
    axis: Vec3,
    /// θo in radians (π: any direction).
    theta_o: f32,
    /// θe in radians.
    theta_e: f32,
}

impl Bounds {
    fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    fn union(&self, o: &Bounds) -> Bounds {
        let (axis, theta_o) = cone_union(self.axis, self.theta_o, o.axis, o.theta_o);
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            power: self.power + o.power,
            axis,
            theta_o,
            theta_e: self.theta_e.max(o.theta_e),
        }
    }

    fn node(&self, child: u32, model: u32) -> gpu::LightTreeNode {
        gpu::LightTreeNode {
            bounds_min: self.min.into(),
            power: self.power as f32,
            bounds_max: self.max.into(),
            cos_normals: if self.theta_o >= std::f32::consts::PI {
                -1.0
            } else {
                self.theta_o.cos()
            },
            axis: self.axis.into(),
            cos_emission: self.theta_e.cos(),
            child,
            model,
            flags: 0,
        }
    }
}

/// The smallest cone (axis, half-angle) holding the cones (a, θa) and (b, θb).
fn cone_union(a: Vec3, theta_a: f32, b: Vec3, theta_b: f32) -> (Vec3, f32) {
    use std::f32::consts::PI;
    if theta_a >= PI || theta_b >= PI {
        return (Vec3::Z, PI);
    }
    let theta_d = a.dot(b).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (a, theta_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (b, theta_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return (Vec3::Z, PI);
    }
    // Turn a toward b by θo − θa about their common perpendicular.
    let turn = theta_o - theta_a;
    let w = a.cross(b);
    if w.length_squared() < 1e-12 {
        return (Vec3::Z, PI);
    }
    let w = w.normalize();
    let axis = (a * turn.cos() + w.cross(a) * turn.sin()).normalize();
    // Widen by float slack so that both cones stay inside.
    (axis, (theta_o * 1.0001 + 1e-5).min(PI))
}

/// An emission cone about an axis for the light tree, (θo, θe) in radians: the
/// importance weighs cos θ′ with θ′ the angle beyond θo, and nothing beyond θo + θe.
#[derive(Clone, Copy, Debug, PartialEq)]
struct EmissionCone {
    theta_o: f32,
    theta_e: f32,
    /// The emission's largest value toward any direction (per unit of the light's
    /// intensity: 1 but for IES profiles, whose candela it is).
    peak: f32,
}

impl EmissionCone {
    /// Every direction: an omnidirectional light's cone.
    const OMNI: EmissionCone = EmissionCone {
        theta_o: std::f32::consts::PI,
        theta_e: std::f32::consts::FRAC_PI_2,
        peak: 1.0,
    };
}

/// Bands across a cone in which [`dominating_cone`] takes the emission's maximum.
const CONE_BANDS: usize = 64;

/// The least θe the tree's cones keep: within θe of θo, cos θ′ is so close to 1 that
/// the kernels' f32 arithmetic cannot tell θ′ from cos θe any closer.
const MIN_THETA_E: f32 = 0.01;

/// The cone over [0, `cone`] (radians from the axis; the emission is 0 beyond it) whose
/// importance shape cos(max(θ − θo, 0)) is nowhere below the emission relative to its
/// peak: `band_max(a0, a1)` bounds the emission between a0 and a1 from the axis. The
/// least such θo keeps the importance low where the lamp is dim; with the lamp's power
/// at least π × its peak (`model_bounds`), its importance is at least π × what it sends,
/// as an emitting triangle's is toward its normal, with no heavy tail toward the cone's
/// edge (where a cosine from the axis alone would fall to 0 under a lamp still lit
/// there). θo is at least cone − 90°, so that cos θ′ stays
/// positive over the cone; the cone is widened a little, as the bound must hold it.
fn dominating_cone(cone: f32, band_max: impl Fn(f32, f32) -> f32) -> EmissionCone {
    use std::f32::consts::{FRAC_PI_2, PI};
    let maxima: Vec<(f32, f32)> = (0..CONE_BANDS)
        .map(|k| {
            let a0 = cone * k as f32 / CONE_BANDS as f32;
            let a1 = cone * (k + 1) as f32 / CONE_BANDS as f32;
            (a1, band_max(a0, a1))
        })
        .collect();
    let peak = maxima.iter().fold(0.0f32, |m, &(_, b)| m.max(b));
    let widened = (cone * 1.0001 + 1e-5).min(PI);
    let mut theta_o = (widened - FRAC_PI_2).max(0.0);
    if peak > 0.0 {
        for &(a1, b) in &maxima {
            theta_o = theta_o.max(a1 - (b / peak).clamp(0.0, 1.0).acos());
        }
    }
    if widened >= PI {
        return EmissionCone {
            peak,
            ..EmissionCone::OMNI
        };
    }
    let theta_o = theta_o.min(widened - MIN_THETA_E).max(0.0);
    EmissionCone {
        theta_o,
        theta_e: widened - theta_o,
        peak,
    }
}

/// The axis and cone of an IES light's profile, the axis being its aim (a downlight)
/// or the opposite (an uplight), whichever cone of lit vertical angles is narrower, or
/// None when the profile is dark everywhere.
fn profile_cone(profile: &ies::IesProfile) -> Option<(bool, EmissionCone)> {
    use std::f32::consts::PI;
    let (lo, hi) = profile.lit_vertical_range()?;
    let up = hi > PI - lo;
    let cone = if up { PI - lo } else { hi };
    Some((
        up,
        dominating_cone(cone, |a0, a1| {
            if up {
                profile.band_max(PI - a1, PI - a0)
            } else {
                profile.band_max(a0, a1)
            }
        }),
    ))
}

/// The cone of a glTF spot light, whose falloff (clamp((cos θ − cos θouter) / (cos
/// θinner − cos θouter)))² falls with θ.
fn spot_cone(l: &gpu::PunctualLight) -> EmissionCone {
    let outer = l.cos_outer.clamp(-1.0, 1.0).acos();
    dominating_cone(outer, |a0, _| super::spot_falloff(l, a0.cos()))
}

/// The bounds of one light model, or None for a directional light. `cones` gives the
/// cone of each IES profile by its offset ([`profile_cone`]).
fn model_bounds(
    m: &gpu::LightModel,
    triangles: &[gpu::LightTriangle],
    punctual: &[gpu::PunctualLight],
    cones: &HashMap<usize, Option<(bool, EmissionCone)>>,
) -> Option<Bounds> {
    use std::f32::consts::{FRAC_PI_2, PI};
    if m.punctual != gpu::INVALID_INDEX {
        let l = &punctual[m.punctual as usize];
        let p = Vec3::from(l.position);
        // The larger of the lamp's flux and π × its peak intensity. An emitting triangle's
        // importance (its flux, π·L·A, × cos θ′ / d²) promises about π × its intensity
        // toward its normal; a narrow lamp's flux is far below π × its peak, so without
        // the floor the tree would undervalue it where it shines (heavy tails).
        let lum = super::luminance(l.intensity) as f64;
        let aimed = |axis: Vec3, c: EmissionCone| Bounds {
            min: p,
            max: p,
            power: (m.power as f64).max(PI as f64 * lum * c.peak as f64),
            axis,
            theta_o: c.theta_o,
            theta_e: c.theta_e,
        };
        return match l.kind {
            gpu::PUNCTUAL_DIRECTIONAL => None,
            gpu::PUNCTUAL_SPOT => Some(aimed(
                Vec3::from(l.direction).normalize_or(Vec3::Z),
                spot_cone(l),
            )),
            gpu::PUNCTUAL_POINT if ies::profile_offset(l).is_some() => {
                let d = Vec3::from(l.direction).normalize_or(Vec3::NEG_Z);
                let cone = ies::profile_offset(l).and_then(|o| cones.get(&o).copied().flatten());
                // A profile dark everywhere (LightTable drops such a light, whose flux is
                // 0): any cone, with no peak to raise its power.
                let dark = EmissionCone {
                    peak: 0.0,
                    ..EmissionCone::OMNI
                };
                let (up, c) = cone.unwrap_or((false, dark));
                Some(aimed(if up { -d } else { d }, c))
            }
            _ => Some(aimed(Vec3::Z, EmissionCone::OMNI)),
        };
    }
    let range = m.first_triangle as usize..(m.first_triangle + m.triangle_count) as usize;
    let mut b: Option<Bounds> = None;
    for t in &triangles[range] {
        let (p0, p1, p2) = (Vec3::from(t.p0), Vec3::from(t.p1), Vec3::from(t.p2));
        let tb = Bounds {
            min: p0.min(p1).min(p2),
            max: p0.max(p1).max(p2),
            power: t.power as f64,
            axis: Vec3::from(t.normal).normalize_or(Vec3::Z),
            theta_o: if t.two_sided != 0 { PI } else { 0.0 },
            theta_e: FRAC_PI_2,
        };
        b = Some(match b {
            None => tb,
            Some(b) => b.union(&tb),
        });
    }
    // A model keeps at least one triangle (LightTable::build drops empty ones).
    b
}

/// The tree: its nodes (the root at 0) and, per light model, (path, depth).
pub struct LightTree {
    pub nodes: Vec<gpu::LightTreeNode>,
    pub paths: Vec<(u32, u32)>,
}

/// Build the tree over `models` (their `tree_path` and `tree_depth` are the caller's to
/// set from `paths`).
pub fn build(
    models: &[gpu::LightModel],
    triangles: &[gpu::LightTriangle],
    punctual: &[gpu::PunctualLight],
    profiles: &[f32],
) -> LightTree {
    // Each IES profile's cone, once per profile.
    let mut cones = HashMap::new();
    for offset in punctual.iter().filter_map(ies::profile_offset) {
        cones
            .entry(offset)
            .or_insert_with(|| profile_cone(&ies::unpack(profiles, offset)));
    }
    let mut finite = Vec::new();
    let mut directional = Vec::new();
    for (i, m) in models.iter().enumerate() {
        match model_bounds(m, triangles, punctual, &cones) {
            Some(b) => finite.push((i as u32, b)),
            None => directional.push(i as u32),
        }
    }
    let mut tree = LightTree {
        nodes: Vec::with_capacity(2 * models.len()),
        paths: vec![(0, 0); models.len()],
    };
    tree.nodes.push(placeholder());
    match (finite.is_empty(), directional.is_empty()) {
        (false, true) => build_finite(&mut tree, 0, &mut finite, 0, 0),
        (true, false) => build_fixed(&mut tree, 0, &directional, 0, 0),
        _ => {
            // The directional lights against the rest, in proportion to their power (as
            // the power source weighs them).
            let p_dir: f64 = directional
                .iter()
                .map(|&m| models[m as usize].power as f64)
                .sum();
            let p_fin: f64 = finite
                .iter()
                .map(|&(m, _)| models[m as usize].power as f64)
                .sum();
            let children = push_pair(&mut tree);
            tree.nodes[0] = fixed_split(children, (p_dir / (p_dir + p_fin)) as f32);
            build_fixed(&mut tree, children, &directional, 0, 1);
            build_finite(&mut tree, children + 1, &mut finite, 1, 1);
        }
    }
    tree
}

fn placeholder() -> gpu::LightTreeNode {
    gpu::LightTreeNode {
        bounds_min: [0.0; 3],
        power: 0.0,
        bounds_max: [0.0; 3],
        cos_normals: -1.0,
        axis: [0.0, 0.0, 1.0],
        cos_emission: 0.0,
        child: gpu::INVALID_INDEX,
        model: gpu::INVALID_INDEX,
        flags: 0,
    }
}

fn push_pair(tree: &mut LightTree) -> u32 {
    let first = tree.nodes.len() as u32;
    tree.nodes.push(placeholder());
    tree.nodes.push(placeholder());
    first
}

fn fixed_split(child: u32, left: f32) -> gpu::LightTreeNode {
    gpu::LightTreeNode {
        power: left,
        child,
        flags: gpu::LIGHT_TREE_FIXED_SPLIT,
        ..placeholder()
    }
}

fn set_path(tree: &mut LightTree, model: u32, path: u32, depth: u32) {
    assert!(depth <= MAX_DEPTH, "light tree deeper than {MAX_DEPTH}");
    tree.paths[model as usize] = (path, depth);
}

/// Directional lights: a balanced tree of fixed splits by count (uniform among them).
fn build_fixed(tree: &mut LightTree, at: u32, models: &[u32], path: u32, depth: u32) {
    if models.len() == 1 {
        tree.nodes[at as usize] = gpu::LightTreeNode {
            model: models[0],
            ..placeholder()
        };
        set_path(tree, models[0], path, depth);
        return;
    }
    let half = models.len() / 2;
    let children = push_pair(tree);
    tree.nodes[at as usize] = fixed_split(children, half as f32 / models.len() as f32);
    build_fixed(tree, children, &models[..half], path, depth + 1);
    build_fixed(
        tree,
        children + 1,
        &models[half..],
        path | (1 << depth),
        depth + 1,
    );
}

/// Buckets per axis that the surface-area-orientation heuristic tries splits between.
const SAOH_BUCKETS: usize = 12;

/// Depth left for median splits: a split by the heuristic may peel off one model per
/// level, so below this margin the build falls back to the median (depth ⌈log₂ n⌉ from
/// there), which keeps every path within MAX_DEPTH bits.
const MEDIAN_MARGIN: u32 = 8;

fn ceil_log2(n: usize) -> u32 {
    usize::BITS - (n.max(1) - 1).leading_zeros()
}

impl Bounds {
    /// The orientation measure of the bounds' cone of emission (Conty Estevez & Kulla
    /// 2018): the solid angle of the normals' cone widened by the emission's spread,
    /// weighted by cosine beyond θo.
    fn orientation_measure(&self) -> f32 {
        use std::f32::consts::PI;
        let theta_o = self.theta_o.min(PI);
        let theta_w = (theta_o + self.theta_e).min(PI);
        let (sin_o, cos_o) = theta_o.sin_cos();
        2.0 * PI * (1.0 - cos_o)
            + 0.5
                * PI
                * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                    + cos_o)
    }

    fn surface_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3::ZERO);
        2.0 * (d.x * d.y + d.y * d.z + d.z * d.x)
    }
}

/// The surface-area-orientation cost of a child with bounds `b` under a node of extent
/// `extent`, split along `axis` (pbrt-v4's form: flux × orientation measure × area,
/// stretched by how thin the node is along the split axis).
fn saoh_cost(b: &Bounds, extent: Vec3, axis: usize) -> f64 {
    let kr = extent.max_element() / extent[axis].max(1e-30);
    kr as f64 * b.power * b.orientation_measure() as f64 * b.surface_area() as f64
}

/// The union of two optional bounds (None: empty).
fn union(x: Option<Bounds>, y: Option<Bounds>) -> Option<Bounds> {
    match (x, y) {
        (Some(x), Some(y)) => Some(x.union(&y)),
        (x, None) => x,
        (None, y) => y,
    }
}

/// Where the heuristic splits `items` (as (axis, how many go left once sorted along it)),
/// or None where it finds no split that separates them (all centroids in one bucket).
fn saoh_split(
    items: &[(u32, Bounds)],
    node: &Bounds,
    lo: Vec3,
    hi: Vec3,
) -> Option<(usize, usize)> {
    let extent = node.max - node.min;
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        let (a, b) = (lo[axis], hi[axis]);
        if b <= a {
            continue;
        }
        let bucket = |c: Vec3| {
            (((c[axis] - a) / (b - a) * SAOH_BUCKETS as f32) as usize).min(SAOH_BUCKETS - 1)
        };
        let mut buckets: [Option<Bounds>; SAOH_BUCKETS] = [None; SAOH_BUCKETS];
        let mut counts = [0usize; SAOH_BUCKETS];
        for (_, lb) in items {
            let k = bucket(lb.centroid());
            counts[k] += 1;
            buckets[k] = union(buckets[k], Some(*lb));
        }
        // Costs of the buckets right of each boundary, then a sweep from the left.
        let mut right = [0.0f64; SAOH_BUCKETS];
        let mut acc = None;
        for k in (1..SAOH_BUCKETS).rev() {
            acc = union(acc, buckets[k]);
            right[k] = acc.map_or(0.0, |x| saoh_cost(&x, extent, axis));
        }
        let (mut acc, mut left_count) = (None, 0usize);
        for k in 0..SAOH_BUCKETS - 1 {
            acc = union(acc, buckets[k]);
            left_count += counts[k];
            if left_count == 0 || left_count == items.len() {
                continue;
            }
            let cost = acc.map_or(0.0, |x| saoh_cost(&x, extent, axis)) + right[k + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, left_count));
            }
        }
    }
    best.map(|(_, axis, count)| (axis, count))
}

/// Finite lights: split where the surface-area-orientation heuristic (Conty Estevez &
/// Kulla 2018) puts the least flux × orientation × area on the two sides, among splits
/// between buckets of the centroids along each axis; at the median of the centroids along
/// their widest axis where it finds none, or deep in the tree (MEDIAN_MARGIN).
fn build_finite(tree: &mut LightTree, at: u32, items: &mut [(u32, Bounds)], path: u32, depth: u32) {
    let bounds = items[1..].iter().fold(items[0].1, |b, (_, o)| b.union(o));
    if items.len() == 1 {
        tree.nodes[at as usize] = bounds.node(gpu::INVALID_INDEX, items[0].0);
        set_path(tree, items[0].0, path, depth);
        return;
    }
    let (lo, hi) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (_, b)| {
            (lo.min(b.centroid()), hi.max(b.centroid()))
        });
    let extent = hi - lo;
    let widest = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let heuristic = if depth + ceil_log2(items.len()) + MEDIAN_MARGIN <= MAX_DEPTH {
        saoh_split(items, &bounds, lo, hi)
    } else {
        None
    };
    let (axis, half) = heuristic.unwrap_or((widest, items.len() / 2));
    // Ties broken by model index, so the build does not depend on the sort's stability.
    // (Splits between buckets keep every centroid of a bucket on one side, so sorting
    // along the axis and cutting at the count reproduces them.)
    items.sort_by(|(ia, a), (ib, b)| {
        a.centroid()[axis]
            .total_cmp(&b.centroid()[axis])
            .then(ia.cmp(ib))
    });
    let children = push_pair(tree);
    tree.nodes[at as usize] = bounds.node(children, gpu::INVALID_INDEX);
    let (left, right) = items.split_at_mut(half);
    build_finite(tree, children, left, path, depth + 1);
    build_finite(tree, children + 1, right, path | (1 << depth), depth + 1);
}

// ---- the kernels' arithmetic (inc/light_tree.glsl), for the tests ---------------------

/// An upper bound on what the node's emitters send toward `p`, up to a common factor:
/// flux × cos θ′ / d², where θ′ is the least angle that a direction from the node's
/// bounding sphere toward p can make with an emitter's normal less the emission's spread,
/// and d the distance to the box's centre, at least the sphere's radius. With a
/// `receiver` normal (zero for none: a surface that transmits, or no surface) the bound
/// also takes cos θi′, the least angle between that normal and a direction from p into
/// the sphere, and is zero for a node wholly below p's tangent plane (where an opaque
/// surface's BSDF is zero). Zero where nothing under the node can emit toward p.
pub fn importance(n: &gpu::LightTreeNode, p: Vec3, receiver: Vec3) -> f32 {
    if n.power <= 0.0 {
        return 0.0;
    }
    let (bmin, bmax) = (Vec3::from(n.bounds_min), Vec3::from(n.bounds_max));
    let c = 0.5 * (bmin + bmax);
    let h = 0.5 * (bmax - bmin);
    let r2 = h.dot(h);
    let v = p - c;
    let d2 = v.dot(v);
    let mut cos_t = 1.0f32;
    let mut cos_i = 1.0f32;
    if d2 > r2 {
        let d = d2.sqrt();
        // θb, the half-angle of the bounding sphere seen from p: sin θb = r / d.
        let sin_b2 = r2 / d2;
        let cos_b = (1.0 - sin_b2).max(0.0).sqrt();
        let sin_b = sin_b2.sqrt();
        // max(θ − θb, 0) for an angle θ given by its cosine and sine.
        let less_b = |cos: f32, sin: f32| {
            if cos >= cos_b {
                1.0
            } else {
                cos * cos_b + sin * sin_b
            }
        };
        if n.cos_normals > -1.0 {
            let cos_w = Vec3::from(n.axis).dot(v / d);
            let sin_w = (1.0 - cos_w * cos_w).max(0.0).sqrt();
            let cos_o = n.cos_normals;
            let sin_o = (1.0 - cos_o * cos_o).max(0.0).sqrt();
            // θx = max(θw − θo, 0)
            let (cos_x, sin_x) = if cos_w >= cos_o {
                (1.0, 0.0)
            } else {
                (cos_w * cos_o + sin_w * sin_o, sin_w * cos_o - cos_w * sin_o)
            };
            // θ′ = max(θx − θb, 0)
            cos_t = less_b(cos_x, sin_x);
            if cos_t <= n.cos_emission {
                return 0.0;
            }
        }
        if receiver != Vec3::ZERO {
            // θi′ = max(θi − θb, 0), θi the angle between the receiver's normal and the
            // direction toward the box's centre.
            let cos_r = -receiver.dot(v / d);
            cos_i = less_b(cos_r, (1.0 - cos_r * cos_r).max(0.0).sqrt());
            if cos_i <= 0.0 {
                return 0.0;
            }
        }
    }
    n.power * cos_t.max(0.0) * cos_i / d2.max(r2).max(1e-30)
}

/// The probability of the left child at inner node `n`, seen from `p`.
pub fn left_probability(
    nodes: &[gpu::LightTreeNode],
    n: &gpu::LightTreeNode,
    p: Vec3,
    receiver: Vec3,
) -> f32 {
    if n.flags & gpu::LIGHT_TREE_FIXED_SPLIT != 0 {
        return n.power;
    }
    let a = importance(&nodes[n.child as usize], p, receiver);
    let b = importance(&nodes[n.child as usize + 1], p, receiver);
    if a + b > 0.0 {
        a / (a + b)
    } else {
        0.5
    }
}

/// The tree's probability of `model` at `p` (without the uniform share).
pub fn pmf(tree: &LightTree, model: u32, p: Vec3, receiver: Vec3) -> f32 {
    let (path, depth) = tree.paths[model as usize];
    let mut n = 0usize;
    let mut pmf = 1.0f32;
    for k in 0..depth {
        let node = &tree.nodes[n];
        let pl = left_probability(&tree.nodes, node, p, receiver);
        let right = (path >> k) & 1 != 0;
        pmf *= if right { 1.0 - pl } else { pl };
        n = node.child as usize + right as usize;
    }
    pmf
}

/// The model the tree chooses at `p` with the uniform number `u`, and its probability.
pub fn sample(tree: &LightTree, p: Vec3, receiver: Vec3, mut u: f32) -> (u32, f32) {
    let mut n = 0usize;
    let mut pmf = 1.0f32;
    loop {
        let node = &tree.nodes[n];
        if node.child == gpu::INVALID_INDEX {
            return (node.model, pmf);
        }
        let pl = left_probability(&tree.nodes, node, p, receiver);
        if u < pl {
            u /= pl;
            pmf *= pl;
            n = node.child as usize;
        } else {
            u = (u - pl) / (1.0 - pl);
            pmf *= 1.0 - pl;
            n = node.child as usize + 1;
        }
        u = u.min(1.0 - f32::EPSILON / 2.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(first: u32, count: u32, punctual: u32, power: f32) -> gpu::LightModel {
        gpu::LightModel {
            first_triangle: first,
            triangle_count: count,
            punctual,
            power,
            tree_path: 0,
            tree_depth: 0,
        }
    }

    fn triangle(p0: Vec3, p1: Vec3, p2: Vec3, model: u32, two_sided: bool) -> gpu::LightTriangle {
        let cross = (p1 - p0).cross(p2 - p0);
        gpu::LightTriangle {
            p0: p0.into(),
            p1: p1.into(),
            p2: p2.into(),
            normal: cross.normalize().into(),
            area: 0.5 * cross.length(),
            material: 0,
            model,
            two_sided: two_sided as u32,
            uv0: [0.0; 2],
            uv1: [0.0; 2],
            uv2: [0.0; 2],
            power: 0.5 * cross.length(),
            instance: gpu::INVALID_INDEX,
            primitive: 0,
        }
    }

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn vec(&mut self, s: f32) -> Vec3 {
            Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * s
        }
    }

    /// Random emitters: small triangles facing random ways (some two-sided, several per
    /// model), points, spots and two directional lights.
    fn scene(
        seed: u64,
    ) -> (
        Vec<gpu::LightModel>,
        Vec<gpu::LightTriangle>,
        Vec<gpu::PunctualLight>,
    ) {
        let mut r = Rng(seed);
        let mut models = Vec::new();
        let mut tris = Vec::new();
        for m in 0..40u32 {
            let first = tris.len() as u32;
            let centre = r.vec(20.0);
            let n = 1 + (r.next() * 3.0) as u32;
            let two_sided = r.next() < 0.2;
            for _ in 0..n {
                let a = centre + r.vec(0.5);
                tris.push(triangle(a, a + r.vec(0.4), a + r.vec(0.4), m, two_sided));
            }
            let power = tris[first as usize..].iter().map(|t| t.power).sum();
            models.push(model(first, n, gpu::INVALID_INDEX, power));
        }
        let mut punctual = Vec::new();
        for k in 0..8u32 {
            let kind = [
                gpu::PUNCTUAL_POINT,
                gpu::PUNCTUAL_SPOT,
                gpu::PUNCTUAL_SPOT,
                gpu::PUNCTUAL_DIRECTIONAL,
            ][k as usize % 4];
            let cos_outer = 0.3 + 0.6 * r.next();
            punctual.push(gpu::PunctualLight {
                position: r.vec(20.0).into(),
                kind,
                direction: r.vec(2.0).normalize().into(),
                range: 0.0,
                intensity: [1.0; 3],
                cos_inner: cos_outer + 0.5 * (1.0 - cos_outer),
                cos_outer,
                profile: gpu::INVALID_INDEX,
                tangent: [0.0; 3],
            });
            models.push(model(0, 0, k, 1.0 + r.next()));
        }
        (models, tris, punctual)
    }

    /// A profile from its angles in degrees and its candela, a column per horizontal
    /// angle.
    fn table(
        photometry: crate::scene::ies::Photometry,
        vertical: &[f32],
        horizontal: &[f32],
        columns: &[&[f32]],
    ) -> crate::scene::ies::IesProfile {
        crate::scene::ies::IesProfile {
            photometry,
            vertical: vertical.iter().map(|a| a.to_radians()).collect(),
            horizontal: horizontal.iter().map(|a| a.to_radians()).collect(),
            candela: columns.concat(),
        }
    }

    #[test]
    fn probabilities_sum_to_one_and_sampling_follows_them() {
        let (models, tris, punctual) = scene(7);
        let tree = build(&models, &tris, &punctual, &[]);
        let mut r = Rng(3);
        for i in 0..20 {
            let p = r.vec(30.0);
            // Half the points on a surface (a receiver normal), half not.
            let receiver = if i % 2 == 0 {
                r.vec(2.0).normalize()
            } else {
                Vec3::ZERO
            };
            let pmfs: Vec<f32> = (0..models.len() as u32)
                .map(|m| pmf(&tree, m, p, receiver))
                .collect();
            let total: f32 = pmfs.iter().sum();
            assert!((total - 1.0).abs() < 1e-4, "pmf sums to {total} at {p}");
            // Sampling returns each model's own pmf, and picks it that often.
            let n = 20_000;
            let mut counts = vec![0u32; models.len()];
            for i in 0..n {
                let (m, q) = sample(&tree, p, receiver, (i as f32 + 0.5) / n as f32);
                assert!(
                    (q - pmfs[m as usize]).abs() <= 1e-5 * pmfs[m as usize].max(1e-3),
                    "pmf {q} against {}",
                    pmfs[m as usize]
                );
                counts[m as usize] += 1;
            }
            for (m, &c) in counts.iter().enumerate() {
                // Stratified u: each model takes its pmf's share within a stratum or two.
                let expected = pmfs[m] * n as f32;
                assert!(
                    (c as f32 - expected).abs() <= 2.0 + 1e-3 * expected,
                    "model {m}: {c} of {n}, expected {expected}"
                );
            }
        }
    }

    /// An IES light's bound is its lit vertical angles' cone: wherever its profile
    /// sends light toward p (a downlight, an uplight, a band between 40° and 120°, a
    /// Type B floodlight), the tree gives it a positive probability; and the cone does
    /// prune (a downlight has none above it).
    #[test]
    fn ies_bounds_never_rule_out_their_light() {
        use crate::scene::ies::Photometry::{TypeB, TypeC};
        let profiles = [
            table(
                TypeC,
                &[0.0, 30.0, 60.0, 90.0],
                &[0.0],
                &[&[5.0, 3.0, 1.0, 0.0]],
            ),
            table(TypeC, &[90.0, 120.0, 180.0], &[0.0], &[&[0.0, 2.0, 4.0]]),
            table(
                TypeC,
                &[0.0, 40.0, 80.0, 120.0, 180.0],
                &[0.0, 180.0, 360.0],
                &[
                    &[0.0, 0.0, 3.0, 0.0, 0.0],
                    &[0.0, 0.0, 1.0, 0.0, 0.0],
                    &[0.0, 0.0, 3.0, 0.0, 0.0],
                ],
            ),
            // A Type B floodlight lit over V −20–25° and H −30–30° only: its cone must
            // reach the corner, cos θ = cos 25° cos 30°.
            table(
                TypeB,
                &[-20.0, 0.0, 25.0],
                &[-30.0, -15.0, 0.0, 15.0, 30.0],
                &[&[1.0f32; 3][..]; 5],
            ),
        ];
        let mut packed = Vec::new();
        let mut offsets = Vec::new();
        for p in &profiles {
            offsets.push(packed.len() as u32);
            p.pack(&mut packed);
        }
        let mut r = Rng(77);
        let mut punctual = Vec::new();
        let mut models = Vec::new();
        for k in 0..16u32 {
            let d = r.vec(2.0).normalize();
            let t = d.any_orthonormal_vector();
            punctual.push(gpu::PunctualLight {
                position: r.vec(20.0).into(),
                kind: gpu::PUNCTUAL_POINT,
                direction: d.into(),
                range: 0.0,
                intensity: [1.0; 3],
                cos_inner: 1.0,
                cos_outer: 1.0,
                profile: offsets[k as usize % profiles.len()],
                tangent: t.into(),
            });
            models.push(model(0, 0, k, 1.0 + r.next()));
        }
        let tree = build(&models, &[], &punctual, &packed);
        let (mut lit, mut pruned) = (0, 0);
        for _ in 0..2000 {
            let p = r.vec(30.0);
            for (m, l) in punctual.iter().enumerate() {
                let w = (p - Vec3::from(l.position)).normalize();
                let d = Vec3::from(l.direction);
                let x = Vec3::from(l.tangent);
                let y = (-d).cross(x);
                let theta = w.dot(d).clamp(-1.0, 1.0).acos();
                let phi = w.dot(y).atan2(w.dot(x)).rem_euclid(std::f32::consts::TAU);
                let emits = profiles[m % profiles.len()].eval(theta, phi) > 0.0;
                let probability = pmf(&tree, m as u32, p, Vec3::ZERO);
                if emits {
                    lit += 1;
                    assert!(
                        probability > 0.0,
                        "light {m} emits toward {p} (θ {}°) but has pmf 0",
                        theta.to_degrees()
                    );
                } else if probability == 0.0 {
                    pruned += 1;
                }
            }
        }
        assert!(lit > 1000 && pruned > 1000, "lit {lit}, pruned {pruned}");
    }

    /// A lamp's importance is nowhere below π × what it sends (I / d²), as an emitting
    /// triangle's is toward its normal: a lamp still lit toward the edge of its cone (a
    /// bare hemisphere, a hard-edged wide spot, a Type B floodlight cut off at 60°) gets
    /// no vanishing probability there, which made heavy tails when the importance fell
    /// as the cosine from the axis alone, nor does a lamp whose flux is small beside its
    /// peak (here every lamp's: its model's power is 1). Lamps peaked on their axis keep
    /// the cosine (θo 0, or within a band of it).
    #[test]
    fn lamp_importance_never_falls_below_its_emission() {
        use crate::scene::ies::Photometry::{TypeB, TypeC};
        let deg = |a: f32| a.to_radians();
        let profiles = [
            // A bare lamp under a shade: flat over the lower hemisphere.
            table(TypeC, &[0.0, 45.0, 90.0], &[0.0], &[&[1.0; 3]]),
            // Brightest toward the edge of its cone, lopsided in φ.
            table(
                TypeC,
                &[0.0, 30.0, 60.0, 70.0],
                &[0.0, 90.0, 180.0],
                &[
                    &[1.0, 2.0, 4.0, 0.0],
                    &[1.0, 1.0, 1.0, 0.0],
                    &[1.0, 3.0, 5.0, 0.0],
                ],
            ),
            // An uplight lit from 100° to 180°, brightest at 110°.
            table(TypeC, &[90.0, 110.0, 180.0], &[0.0], &[&[0.0, 6.0, 1.0]]),
            // A Type B floodlight, flat over V −60–60° and H −45–45°.
            table(
                TypeB,
                &[-60.0, 0.0, 60.0],
                &[-45.0, 0.0, 45.0],
                &[&[2.0f32; 3][..]; 3],
            ),
            // A downlight peaked on its axis: the cosine from the axis holds it.
            table(
                TypeC,
                &[0.0, 30.0, 60.0, 90.0],
                &[0.0],
                &[&[8.0, 5.0, 1.0, 0.0]],
            ),
        ];
        let d = Vec3::new(0.3, -1.0, 0.2).normalize();
        let x = d.any_orthonormal_vector();
        let lamp = |profile: u32, cos_inner: f32, cos_outer: f32| gpu::PunctualLight {
            position: [0.0; 3],
            kind: if profile == gpu::INVALID_INDEX {
                gpu::PUNCTUAL_SPOT
            } else {
                gpu::PUNCTUAL_POINT
            },
            direction: d.into(),
            range: 0.0,
            intensity: [2.0, 1.0, 0.5],
            cos_inner,
            cos_outer,
            profile,
            tangent: x.into(),
        };
        let mut packed = Vec::new();
        let mut lamps = Vec::new();
        for p in &profiles {
            lamps.push(lamp(packed.len() as u32, 1.0, 1.0));
            p.pack(&mut packed);
        }
        // Spots: hard-edged at 80°, a soft 60° one, and glTF's default (0°–45°).
        for (inner, outer) in [(79.9f32, 80.0f32), (20.0, 60.0), (0.0, 45.0)] {
            lamps.push(lamp(gpu::INVALID_INDEX, deg(inner).cos(), deg(outer).cos()));
        }
        let mut r = Rng(5);
        let mut theta_o = Vec::new();
        for (k, l) in lamps.iter().enumerate() {
            let tree = build(&[model(0, 0, 0, 1.0)], &[], &[*l], &packed);
            let node = &tree.nodes[0];
            theta_o.push(node.cos_normals.clamp(-1.0, 1.0).acos().to_degrees());
            let lum = crate::lights::luminance(l.intensity);
            // Candela toward w.
            let emission = |w: Vec3| -> f32 {
                let cos = w.dot(d).clamp(-1.0, 1.0);
                lum * match profiles.get(k) {
                    Some(p) => {
                        let y = (-d).cross(x);
                        let phi = w.dot(y).atan2(w.dot(x)).rem_euclid(std::f32::consts::TAU);
                        p.eval(cos.acos(), phi)
                    }
                    None => crate::lights::spot_falloff(l, cos),
                }
            };
            for _ in 0..20_000 {
                let w = r.vec(1.0).normalize();
                let p = 2.0 * w;
                // At distance 2: the importance against π I / 2².
                let promised = importance(node, p, Vec3::ZERO);
                let sent = std::f32::consts::PI * emission(w) / 4.0;
                assert!(
                    promised >= sent * 0.999,
                    "lamp {k}: importance {promised} below emission {sent} at θ {}°",
                    w.dot(d).clamp(-1.0, 1.0).acos().to_degrees()
                );
            }
        }
        // The peaked downlight and glTF's default spot keep a cosine from (about) the
        // axis; the flat hemisphere takes its whole cone.
        assert!(theta_o[4] < 2.0 && theta_o[7] < 2.0, "θo {theta_o:?}");
        assert!(theta_o[0] > 89.0, "θo {theta_o:?}");
    }

    /// Wherever a model's light can reach p from above its receiver's tangent plane, the
    /// tree gives it a positive probability: the bounds never rule out an emitter that
    /// emits toward the point.
    #[test]
    fn bounds_never_rule_out_light_that_reaches_the_point() {
        for seed in 1..6 {
            let (models, tris, punctual) = scene(seed);
            let tree = build(&models, &tris, &punctual, &[]);
            let mut r = Rng(seed + 100);
            for i in 0..400 {
                let p = r.vec(30.0);
                let receiver = if i % 2 == 0 {
                    r.vec(2.0).normalize()
                } else {
                    Vec3::ZERO
                };
                let above = |y: Vec3| receiver.dot(y - p) > 1e-4 || receiver == Vec3::ZERO;
                for (m, model) in models.iter().enumerate() {
                    let emits = if model.punctual != gpu::INVALID_INDEX {
                        let l = &punctual[model.punctual as usize];
                        if l.kind == gpu::PUNCTUAL_DIRECTIONAL {
                            // Under the fixed split: every receiver sees them.
                            true
                        } else {
                            let w = (p - Vec3::from(l.position)).normalize();
                            (l.kind != gpu::PUNCTUAL_SPOT
                                || w.dot(Vec3::from(l.direction)) > l.cos_outer)
                                && above(Vec3::from(l.position))
                        }
                    } else {
                        (0..model.triangle_count).any(|k| {
                            let t = &tris[(model.first_triangle + k) as usize];
                            // Any of a few points of the triangle facing p.
                            [
                                (0.2, 0.2),
                                (0.6, 0.2),
                                (0.2, 0.6),
                                (0.0, 0.0),
                                (1.0, 0.0),
                                (0.0, 1.0),
                            ]
                            .iter()
                            .any(|&(a, b)| {
                                let (p0, p1, p2) =
                                    (Vec3::from(t.p0), Vec3::from(t.p1), Vec3::from(t.p2));
                                let y = p0 + a * (p1 - p0) + b * (p2 - p0);
                                (t.two_sided != 0 || Vec3::from(t.normal).dot(p - y) > 1e-4)
                                    && above(y)
                            })
                        })
                    };
                    if emits {
                        assert!(
                            pmf(&tree, m as u32, p, receiver) > 0.0,
                            "seed {seed}: model {m} emits toward {p} but has pmf 0"
                        );
                    }
                }
            }
        }
    }

    /// A point light of unit intensity at `p`.
    fn point_light(p: Vec3) -> gpu::PunctualLight {
        gpu::PunctualLight {
            position: p.into(),
            kind: gpu::PUNCTUAL_POINT,
            direction: [0.0, 0.0, -1.0],
            range: 0.0,
            intensity: [1.0; 3],
            cos_inner: 1.0,
            cos_outer: 1.0,
            profile: gpu::INVALID_INDEX,
            tangent: [0.0; 3],
        }
    }

    #[test]
    fn nearby_lights_are_favoured() {
        // Two equal point lights: the near one gets most of the probability.
        let punctual = vec![
            point_light(Vec3::ZERO),
            point_light(Vec3::new(10.0, 0.0, 0.0)),
        ];
        let models = vec![model(0, 0, 0, 1.0), model(0, 0, 1, 1.0)];
        let tree = build(&models, &[], &punctual, &[]);
        let p = Vec3::new(1.0, 0.0, 0.0);
        // 1/1² against 1/9²: 81/82.
        assert!((pmf(&tree, 0, p, Vec3::ZERO) - 81.0 / 82.0).abs() < 1e-5);
        // On a surface facing the far light, the near one is below its tangent plane.
        assert_eq!(pmf(&tree, 0, p, Vec3::X), 0.0);
        assert!((pmf(&tree, 1, p, Vec3::X) - 1.0).abs() < 1e-6);
    }

    /// Lights spaced ever wider apart along a line put nearly all centroids in the first
    /// bucket of every split, so the heuristic peels off a few per level: the build
    /// falls back to median splits in time and every path fits its 32 bits.
    #[test]
    fn lopsided_splits_stay_within_the_path_bits() {
        let n = 2000;
        let punctual: Vec<_> = (0..n)
            .map(|k| point_light(Vec3::new(1.02f32.powi(k), 0.0, 0.0)))
            .collect();
        let models: Vec<_> = (0..n as u32).map(|k| model(0, 0, k, 1.0)).collect();
        let tree = build(&models, &[], &punctual, &[]);
        let deepest = tree.paths.iter().map(|&(_, d)| d).max().unwrap();
        assert!(
            deepest > ceil_log2(n as usize),
            "the heuristic's splits were taken"
        );
        assert!(deepest <= MAX_DEPTH, "depth {deepest}");
        let p = Vec3::new(3.0, 1.0, 0.0);
        let total: f32 = (0..n as u32).map(|m| pmf(&tree, m, p, Vec3::ZERO)).sum();
        assert!((total - 1.0).abs() < 1e-4, "pmf sums to {total}");
    }

    #[test]
    fn lights_at_grazing_angles_count_less() {
        // Two equal point lights at equal distances, one straight above the receiver and
        // one 60° off its normal: cos θi weighs them 1 : 1/2.
        let s3 = 3f32.sqrt() / 2.0;
        let punctual = vec![point_light(Vec3::Y), point_light(Vec3::new(s3, 0.5, 0.0))];
        let models = vec![model(0, 0, 0, 1.0), model(0, 0, 1, 1.0)];
        let tree = build(&models, &[], &punctual, &[]);
        assert!((pmf(&tree, 0, Vec3::ZERO, Vec3::Y) - 2.0 / 3.0).abs() < 1e-5);
    }
}
