//! The SD-tree as the four GPU buffers of shaders_glsl/shared/guiding.h, and back:
//! flattening for upload, taking in the training buffer read back after a pass, and
//! rebuilding a tree from arrays (the file format stores exactly these arrays).
//!
//! Layout: the spatial buffer is a `GuideHeader` followed by the `GuideSpatialNode`s
//! (node 0 is the root); `GuideLeaf` i describes leaf i; the sampling buffer holds each
//! distinct sampling tree once, contiguously, root first; the training buffer holds, per
//! leaf in order, one header node (sum.x = statistical weight) and then its training
//! tree, root first. Child indices are absolute indices into their own array.

use super::light_mix::{choose_mix, LightSums};
use super::quadtree::{QuadNode, QuadTree};
use super::sdtree::{Leaf, SdTree, SpatialNode};
use super::{GuidingConfig, GuidingError};
use crate::gpu::{
    GuideHeader, GuideLeaf, GuideLightSlot, GuideLightTrainingSlot, GuideQuadNode,
    GuideSpatialNode, GUIDE_LIGHT_EMPTY, GUIDE_LIGHT_HASH_BITS, GUIDE_LIGHT_HASH_SLOTS,
    GUIDE_LIGHT_SLOTS, GUIDE_SPATIAL_LEAF,
};
use glam::Vec3;
use std::collections::{HashMap, HashSet};
use std::sync::Arc;

pub(crate) const HEADER_BYTES: u64 = std::mem::size_of::<GuideHeader>() as u64;
pub(crate) const SPATIAL_NODE_BYTES: u64 = std::mem::size_of::<GuideSpatialNode>() as u64;
pub(crate) const LEAF_BYTES: u64 = std::mem::size_of::<GuideLeaf>() as u64;
pub(crate) const QUAD_NODE_BYTES: u64 = std::mem::size_of::<GuideQuadNode>() as u64;
pub(crate) const LIGHT_SLOT_BYTES: u64 = std::mem::size_of::<GuideLightSlot>() as u64;
pub(crate) const LIGHT_TRAINING_SLOT_BYTES: u64 =
    std::mem::size_of::<GuideLightTrainingSlot>() as u64;
const SLOTS: usize = GUIDE_LIGHT_SLOTS as usize;
/// The guiding buffers a tree fills (`SdTree::write_gpu_buffers`).
pub const GUIDE_BUFFERS: usize = 6;
const HASH_SLOTS: usize = GUIDE_LIGHT_HASH_SLOTS as usize;
/// Slots of the light-table buffer per leaf: its packed table, hash copy and alias table.
const LIGHT_BUFFER_SLOTS: usize = 2 * SLOTS + HASH_SLOTS;
/// GPU bytes one leaf adds besides its quadtrees: its record and its light tables (the
/// packed one and its hash copy, and the training table).
pub(crate) const LEAF_TOTAL_BYTES: u64 = LEAF_BYTES
    + LIGHT_SLOT_BYTES * LIGHT_BUFFER_SLOTS as u64
    + LIGHT_TRAINING_SLOT_BYTES * SLOTS as u64;

/// The contents of the four guiding buffers.
#[derive(Clone, Debug, PartialEq)]
pub struct GuideArrays {
    pub header: GuideHeader,
    pub spatial: Vec<GuideSpatialNode>,
    pub leaves: Vec<GuideLeaf>,
    pub sampling: Vec<GuideQuadNode>,
    /// Initial contents of the training buffer (sums as the CPU has them: zero right
    /// after a refit).
    pub training: Vec<GuideQuadNode>,
    /// Learned light tables (BINDING_GUIDE_LIGHTS): GUIDE_LIGHT_SLOTS per leaf, entries
    /// first, then empty slots.
    pub lights: Vec<GuideLightSlot>,
    /// Initial contents of the light training buffer: all slots empty.
    pub light_training: Vec<GuideLightTrainingSlot>,
}

const EMPTY_SLOT: GuideLightSlot = GuideLightSlot {
    model: GUIDE_LIGHT_EMPTY,
    value: 0.0,
};

const EMPTY_TRAINING_SLOT: GuideLightTrainingSlot = GuideLightTrainingSlot {
    model: GUIDE_LIGHT_EMPTY,
    value: 0.0,
    second: 0.0,
};

impl GuideArrays {
    /// Bytes of the spatial buffer (BINDING_GUIDE_SPATIAL): header, then nodes.
    pub fn spatial_buffer(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.spatial_buffer_len() as usize);
        out.extend_from_slice(bytemuck::bytes_of(&self.header));
        out.extend_from_slice(bytemuck::cast_slice(&self.spatial));
        out
    }

    pub fn spatial_buffer_len(&self) -> u64 {
        HEADER_BYTES + SPATIAL_NODE_BYTES * self.spatial.len() as u64
    }

    /// Bytes of all four buffers.
    pub fn byte_size(&self) -> u64 {
        self.spatial_buffer_len()
            + LEAF_BYTES * self.leaves.len() as u64
            + QUAD_NODE_BYTES * (self.sampling.len() + self.training.len()) as u64
            + LIGHT_SLOT_BYTES * self.light_buffer_len() as u64
            + LIGHT_TRAINING_SLOT_BYTES * self.light_training.len() as u64
    }

    /// Slots of the light-table buffer (BINDING_GUIDE_LIGHTS): the packed tables, their
    /// hash copies, their alias tables.
    pub fn light_buffer_len(&self) -> usize {
        self.lights.len() / SLOTS * LIGHT_BUFFER_SLOTS
    }

    /// Contents of the light-table buffer: every leaf's packed table (`lights`), then
    /// every leaf's table as an open-addressing hash (shared/guiding.h), which
    /// `guide_light_pmf` probes instead of scanning the packed table, then every leaf's
    /// alias table over its packed slots, which `guide_light_sample` draws from.
    pub fn light_buffer(&self) -> Vec<GuideLightSlot> {
        let leaves = self.lights.len() / SLOTS;
        let mut out = vec![EMPTY_SLOT; self.light_buffer_len()];
        for (leaf, table) in self.lights.chunks_exact(SLOTS).enumerate() {
            let table: &[GuideLightSlot; SLOTS] = table.try_into().expect("whole tables");
            write_leaf_lights(table, leaf, leaves, &mut out);
        }
        out
    }
}

/// Write leaf `leaf`'s light tables into the light-table buffer `out` of `leaf_count`
/// leaves (`GuideArrays::light_buffer`): its packed table, its hash copy and its alias
/// table, each slot written once and none read (`out` may be write-combined memory).
fn write_leaf_lights(
    table: &[GuideLightSlot; SLOTS],
    leaf: usize,
    leaf_count: usize,
    out: &mut [GuideLightSlot],
) {
    out[leaf * SLOTS..][..SLOTS].copy_from_slice(table);
    let mut hash = [EMPTY_SLOT; HASH_SLOTS];
    for entry in table.iter().take_while(|e| e.model != GUIDE_LIGHT_EMPTY) {
        let mut i = light_hash_slot(entry.model);
        while hash[i].model != GUIDE_LIGHT_EMPTY {
            i = (i + 1) % HASH_SLOTS;
        }
        hash[i] = *entry;
    }
    out[leaf_count * SLOTS + leaf * HASH_SLOTS..][..HASH_SLOTS].copy_from_slice(&hash);
    let weights = table.map(|e| match e.model {
        GUIDE_LIGHT_EMPTY => 0.0,
        _ => f64::from(e.value.max(0.0)),
    });
    let alias = &mut out[leaf_count * (SLOTS + HASH_SLOTS) + leaf * SLOTS..][..SLOTS];
    match crate::lights::alias::build(&weights) {
        Some(entries) => {
            for (slot, a) in alias.iter_mut().zip(entries) {
                *slot = GuideLightSlot {
                    model: a.alias,
                    value: a.threshold,
                };
            }
        }
        // An empty table: every slot leads to its first, empty, packed slot.
        None => alias.fill(GuideLightSlot {
            model: 0,
            value: 0.0,
        }),
    }
}

/// A light model's first slot in a leaf's hash table (the kernel's `guide_light_pmf`).
pub(crate) fn light_hash_slot(model: u32) -> usize {
    (model.wrapping_mul(2_654_435_761) >> (32 - GUIDE_LIGHT_HASH_BITS)) as usize
}

/// The light model (and its probability) that leaf `leaf`'s alias table draws with u in
/// [0, 1), as the kernel's `guide_light_sample` does; GUIDE_LIGHT_EMPTY for an empty
/// table.
pub fn light_alias_sample(
    buffer: &[GuideLightSlot],
    leaf_count: usize,
    leaf: usize,
    u: f32,
) -> (u32, f32) {
    let alias = &buffer[leaf_count * (SLOTS + HASH_SLOTS) + leaf * SLOTS..][..SLOTS];
    let scaled = u * SLOTS as f32;
    let i = (scaled as usize).min(SLOTS - 1);
    let k = if scaled - (i as f32) < alias[i].value {
        i
    } else {
        alias[i].model as usize
    };
    let s = buffer[leaf * SLOTS + k];
    (s.model, s.value)
}

/// A light model's probability in leaf `leaf`'s hash table as the kernel looks it up
/// (0 when absent): probes from its first slot to the next empty one.
pub fn light_hash_lookup(
    buffer: &[GuideLightSlot],
    leaf_count: usize,
    leaf: usize,
    model: u32,
) -> f32 {
    let hash = &buffer[leaf_count * SLOTS + leaf * HASH_SLOTS..][..HASH_SLOTS];
    let first = light_hash_slot(model);
    for k in 0..HASH_SLOTS {
        let s = hash[(first + k) % HASH_SLOTS];
        if s.model == model {
            return s.value;
        }
        if s.model == GUIDE_LIGHT_EMPTY {
            break;
        }
    }
    0.0
}

fn to_gpu_node(n: &QuadNode, base: u32) -> GuideQuadNode {
    GuideQuadNode {
        sum: n.sum,
        child: n.child.map(|c| if c == 0 { 0 } else { base + c }),
    }
}

/// The tree rooted at absolute index `root` of `nodes`, renumbered root first and then
/// in array order (so a contiguous root-first tree keeps its numbering).
/// Also returns the absolute indices the tree occupies.
fn unflatten(
    nodes: &[GuideQuadNode],
    root: u32,
    what: &str,
) -> Result<(QuadTree, Vec<u32>), GuidingError> {
    let bad = |m: String| GuidingError::BadArrays(format!("{what}: {m}"));
    let len = nodes.len();
    if root as usize >= len {
        return Err(bad(format!("root {root} out of range ({len} nodes)")));
    }
    let mut reached = vec![root];
    let mut seen = HashSet::from([root]);
    let mut i = 0;
    while i < reached.len() {
        for &c in &nodes[reached[i] as usize].child {
            if c == 0 {
                continue;
            }
            if c as usize >= len || !seen.insert(c) {
                return Err(bad(format!("bad child index {c}")));
            }
            reached.push(c);
        }
        i += 1;
    }
    reached[1..].sort_unstable();
    let index: HashMap<u32, u32> = reached
        .iter()
        .enumerate()
        .map(|(r, &a)| (a, r as u32))
        .collect();
    let local = reached
        .iter()
        .map(|&a| {
            let n = &nodes[a as usize];
            QuadNode {
                sum: n.sum,
                child: n.child.map(|c| if c == 0 { 0 } else { index[&c] }),
            }
        })
        .collect();
    Ok((QuadTree::from_nodes(local).map_err(bad)?, reached))
}

/// Where each leaf's trees go in the flat arrays: (sampling root per leaf, number of
/// sampling nodes, training root per leaf, number of training nodes).
type FlatLayout = (Vec<u32>, usize, Vec<u32>, usize);

/// The arrays being written by `SdTree::write_flat`, the light tables whole (packed,
/// hash, alias).
struct FlatOut<'a> {
    header: &'a mut GuideHeader,
    spatial: &'a mut [GuideSpatialNode],
    leaves: &'a mut [GuideLeaf],
    sampling: &'a mut [GuideQuadNode],
    training: &'a mut [GuideQuadNode],
    lights: &'a mut [GuideLightSlot],
    light_training: &'a mut [GuideLightTrainingSlot],
}

impl SdTree {
    /// Where each leaf's trees go in the flat arrays.
    fn layout(&self) -> FlatLayout {
        let mut bases: HashMap<*const QuadTree, u32> = HashMap::new();
        let mut sampling_roots = Vec::with_capacity(self.leaves.len());
        let mut sampling_len = 0usize;
        let mut training_roots = Vec::with_capacity(self.leaves.len());
        let mut training_len = 0usize;
        for leaf in &self.leaves {
            let base = *bases.entry(Arc::as_ptr(&leaf.sampling)).or_insert_with(|| {
                let base = sampling_len as u32;
                sampling_len += leaf.sampling.node_count();
                base
            });
            sampling_roots.push(base);
            training_roots.push(training_len as u32 + 1);
            training_len += 1 + leaf.training.node_count();
        }
        (sampling_roots, sampling_len, training_roots, training_len)
    }

    /// Bytes of the GPU buffers `gpu_arrays` would fill.
    pub fn gpu_bytes(&self) -> u64 {
        self.gpu_buffer_lens().iter().sum::<usize>() as u64
    }

    /// The GPU buffers' contents.
    pub fn gpu_arrays(&self) -> GuideArrays {
        let layout = self.layout();
        let (n, slots) = (self.leaves.len(), self.leaves.len() * SLOTS);
        let mut header = GuideHeader::default();
        let mut spatial = vec![GuideSpatialNode::default(); self.nodes.len()];
        let mut leaves = vec![GuideLeaf::default(); n];
        let mut sampling = vec![GuideQuadNode::default(); layout.1];
        let mut training = vec![GuideQuadNode::default(); layout.3];
        let mut lights = vec![EMPTY_SLOT; n * LIGHT_BUFFER_SLOTS];
        let mut light_training = vec![EMPTY_TRAINING_SLOT; slots];
        self.write_flat(
            &layout,
            FlatOut {
                header: &mut header,
                spatial: &mut spatial,
                leaves: &mut leaves,
                sampling: &mut sampling,
                training: &mut training,
                lights: &mut lights,
                light_training: &mut light_training,
            },
        );
        // The arrays keep the packed tables; `light_buffer` derives the rest.
        lights.truncate(slots);
        GuideArrays {
            header,
            spatial,
            leaves,
            sampling,
            training,
            lights,
            light_training,
        }
    }

    /// Byte lengths of the six GPU buffers, in the order `write_gpu_buffers` fills them:
    /// spatial (header and nodes), leaves, sampling trees, training trees, light tables
    /// (packed, hash, alias: `GuideArrays::light_buffer`), light training tables.
    pub fn gpu_buffer_lens(&self) -> [usize; GUIDE_BUFFERS] {
        self.buffer_lens(&self.layout())
    }

    /// `gpu_buffer_lens` for the tree's `layout`.
    fn buffer_lens(&self, layout: &FlatLayout) -> [usize; GUIDE_BUFFERS] {
        let (_, sampling, _, training) = *layout;
        let slots = self.leaves.len() * SLOTS;
        [
            HEADER_BYTES as usize + SPATIAL_NODE_BYTES as usize * self.nodes.len(),
            LEAF_BYTES as usize * self.leaves.len(),
            QUAD_NODE_BYTES as usize * sampling,
            QUAD_NODE_BYTES as usize * training,
            LIGHT_SLOT_BYTES as usize * self.leaves.len() * LIGHT_BUFFER_SLOTS,
            LIGHT_TRAINING_SLOT_BYTES as usize * slots,
        ]
    }

    /// Write the six GPU buffers' contents (`gpu_buffer_lens`: each part exactly that
    /// long, 4-byte aligned) straight into upload memory: every byte is written, front
    /// to back, and none is read, so the parts may hold anything before (staging kept
    /// between passes) and may be write-combined. The bytes are those of `gpu_arrays`.
    pub fn write_gpu_buffers(&self, parts: [&mut [u8]; GUIDE_BUFFERS]) {
        let layout = self.layout();
        for (part, len) in parts.iter().zip(self.buffer_lens(&layout)) {
            assert_eq!(part.len(), len, "a GPU buffer part of the wrong length");
        }
        let [spatial, leaves, sampling, training, lights, light_training] = parts;
        let (header, spatial) = spatial.split_at_mut(HEADER_BYTES as usize);
        self.write_flat(
            &layout,
            FlatOut {
                header: bytemuck::from_bytes_mut(header),
                spatial: bytemuck::cast_slice_mut(spatial),
                leaves: bytemuck::cast_slice_mut(leaves),
                sampling: bytemuck::cast_slice_mut(sampling),
                training: bytemuck::cast_slice_mut(training),
                lights: bytemuck::cast_slice_mut(lights),
                light_training: bytemuck::cast_slice_mut(light_training),
            },
        );
    }

    /// Fill every element of `out` (sized by `layout`) from the tree.
    fn write_flat(&self, layout: &FlatLayout, out: FlatOut<'_>) {
        let (sampling_roots, _, training_roots, _) = layout;
        *out.header = GuideHeader {
            origin: self.origin.to_array(),
            size: self.size,
            flags: self.config.flags(),
            leaf_count: self.leaves.len() as u32,
            bsdf_fraction: self.config.bsdf_fraction,
        };
        for (slot, n) in out.spatial.iter_mut().zip(&self.nodes) {
            *slot = match *n {
                SpatialNode::Interior { axis, first } => GuideSpatialNode { axis, child: first },
                SpatialNode::Leaf { leaf } => GuideSpatialNode {
                    axis: GUIDE_SPATIAL_LEAF,
                    child: leaf,
                },
            };
        }
        let write_tree = |dst: &mut [GuideQuadNode], tree: &QuadTree, base: u32| {
            for (slot, n) in dst.iter_mut().zip(tree.nodes()) {
                *slot = to_gpu_node(n, base);
            }
        };
        let mut sampling_end = 0usize;
        let leaf_count = self.leaves.len();
        for (i, leaf) in self.leaves.iter().enumerate() {
            let base = sampling_roots[i];
            // A shared sampling tree is written where its first leaf put it.
            if base as usize == sampling_end {
                let nodes = leaf.sampling.node_count();
                write_tree(
                    &mut out.sampling[sampling_end..][..nodes],
                    &leaf.sampling,
                    base,
                );
                sampling_end += nodes;
            }
            let root = training_roots[i];
            out.training[root as usize - 1] = GuideQuadNode {
                sum: [leaf.training_weight, 0.0, 0.0, 0.0],
                child: [0; 4],
            };
            let nodes = leaf.training.node_count();
            write_tree(
                &mut out.training[root as usize..][..nodes],
                &leaf.training,
                root,
            );
            out.leaves[i] = GuideLeaf {
                sampling_root: base,
                training_root: root,
                box_min: leaf.box_min.to_array(),
                box_size: leaf.box_size.to_array(),
                sampling_weight: leaf.sampling_weight,
                bsdf_fraction: leaf.selection.fraction(),
                light_mix: match self.config.learn_lights && !leaf.lights.is_empty() {
                    false => 0.0,
                    true if self.config.learn_light_mix => leaf.light_mix,
                    true => self.config.light_mix,
                },
            };
            let mut table = [EMPTY_SLOT; SLOTS];
            for (slot, &(model, p)) in table.iter_mut().zip(leaf.lights.iter()) {
                *slot = GuideLightSlot { model, value: p };
            }
            write_leaf_lights(&table, i, leaf_count, out.lights);
        }
        out.light_training.fill(EMPTY_TRAINING_SLOT);
    }

    /// Take in the light training buffer read back after a pass (learned light
    /// selection): each leaf's recorded sums per light model, and, with a learned mix,
    /// the mix its next table is sampled with (`light_mix::choose_mix`; `source_pmf`:
    /// the source distribution's probability of each light model). Call it after
    /// `load_training_readback`, which brings each leaf's Σ v².
    pub fn load_light_readback(
        &mut self,
        slots: &[GuideLightTrainingSlot],
        source_pmf: &[f32],
    ) -> Result<(), GuidingError> {
        if slots.len() != self.leaves.len() * SLOTS {
            return Err(GuidingError::TrainingMismatch(format!(
                "{} light slots read back, {} uploaded",
                slots.len(),
                self.leaves.len() * SLOTS
            )));
        }
        if let Some(s) = slots
            .iter()
            .find(|s| s.model != GUIDE_LIGHT_EMPTY && s.model as usize >= source_pmf.len())
        {
            return Err(GuidingError::TrainingMismatch(format!(
                "light model {} read back, the scene has {}",
                s.model,
                source_pmf.len()
            )));
        }
        let (learn, initial) = (self.config.learn_light_mix, self.config.light_mix);
        super::parallel::map_mut(&mut self.leaves, |i, leaf| {
            let table = &slots[i * SLOTS..(i + 1) * SLOTS];
            leaf.light_training = table
                .iter()
                .filter(|s| s.model != GUIDE_LIGHT_EMPTY)
                .map(|s| LightSums {
                    model: s.model,
                    value: s.value,
                    second: s.second,
                })
                .collect();
            if !learn {
                return;
            }
            let judged = choose_mix(
                &leaf.lights,
                leaf.light_mix,
                &leaf.light_training,
                leaf.light_second,
                |m| source_pmf[m as usize],
            );
            leaf.light_mix = match judged {
                Some(m) => m,
                // A first table starts at the configured mix; a table no estimate
                // judged keeps the mix it had.
                None if leaf.lights.is_empty() => initial,
                None => leaf.light_mix,
            };
        });
        Ok(())
    }

    /// Take in the training buffer read back after a pass: it replaces the training
    /// sums and weights (it started as `gpu_arrays().training`, so records made on the
    /// CPU before the upload are in it). Its topology must be the one uploaded.
    pub fn load_training_readback(
        &mut self,
        training: &[GuideQuadNode],
    ) -> Result<(), GuidingError> {
        let (_, _, roots, len) = self.layout();
        if training.len() != len {
            return Err(GuidingError::TrainingMismatch(format!(
                "{} nodes read back, {len} uploaded",
                training.len()
            )));
        }
        // Per leaf on the host's cores: check every leaf's topology, then (only if all
        // agree, so a refused read-back changes nothing) take the sums.
        let cost = self.training_costs();
        let mismatched = super::parallel::map_mut_by_cost(&mut self.leaves, &cost, |i, leaf| {
            let root = roots[i];
            let nodes = &training[root as usize..root as usize + leaf.training.node_count()];
            let same = nodes
                .iter()
                .zip(leaf.training.nodes())
                .all(|(g, c)| g.child == to_gpu_node(c, root).child);
            (!same).then_some(root)
        });
        if let Some(root) = mismatched.into_iter().flatten().next() {
            return Err(GuidingError::TrainingMismatch(format!(
                "the training tree at node {root} has another topology than the one uploaded"
            )));
        }
        super::parallel::map_mut_by_cost(&mut self.leaves, &cost, |i, leaf| {
            let root = roots[i] as usize;
            leaf.training_weight = training[root - 1].sum[0];
            leaf.light_second = training[root - 1].sum[1];
            let nodes = &training[root..root + leaf.training.node_count()];
            leaf.training.set_sums(nodes.iter().map(|n| n.sum));
        });
        Ok(())
    }

    /// A tree from GPU arrays (the file format; also the flattening round trip). The
    /// arrays are checked: any inconsistency is an error, never a panic.
    pub fn from_gpu_arrays(
        arrays: &GuideArrays,
        config: &GuidingConfig,
    ) -> Result<SdTree, GuidingError> {
        config.validate()?;
        let bad = |m: String| Err(GuidingError::BadArrays(m));
        let h = &arrays.header;
        let origin = Vec3::from_array(h.origin);
        if !(origin.is_finite() && h.size.is_finite() && h.size > 0.0) {
            return bad(format!("bad cube {:?} size {}", h.origin, h.size));
        }
        if h.leaf_count as usize != arrays.leaves.len() {
            return bad(format!(
                "header says {} leaves, {} given",
                h.leaf_count,
                arrays.leaves.len()
            ));
        }
        if arrays.spatial.is_empty() {
            return bad("no spatial root".into());
        }
        // Spatial tree: every node reached once from the root, every leaf used once.
        let mut nodes = vec![SpatialNode::Leaf { leaf: 0 }; arrays.spatial.len()];
        let mut node_seen = vec![false; arrays.spatial.len()];
        let mut leaf_depth = vec![None; arrays.leaves.len()];
        let mut stack = vec![(0u32, 0u32)];
        node_seen[0] = true;
        while let Some((n, depth)) = stack.pop() {
            let g = arrays.spatial[n as usize];
            if g.axis == GUIDE_SPATIAL_LEAF {
                match leaf_depth.get_mut(g.child as usize) {
                    Some(d @ None) => *d = Some(depth),
                    _ => {
                        return bad(format!(
                            "spatial node {n}: bad or repeated leaf {}",
                            g.child
                        ))
                    }
                }
                nodes[n as usize] = SpatialNode::Leaf { leaf: g.child };
                continue;
            }
            if g.axis > 2 || depth >= crate::gpu::GUIDE_MAX_SPATIAL_DEPTH {
                return bad(format!("spatial node {n}: bad axis {} or too deep", g.axis));
            }
            for c in [g.child, g.child.wrapping_add(1)] {
                match node_seen.get_mut(c as usize) {
                    Some(s @ false) => *s = true,
                    _ => return bad(format!("spatial node {n}: bad child {c}")),
                }
                stack.push((c, depth + 1));
            }
            nodes[n as usize] = SpatialNode::Interior {
                axis: g.axis,
                first: g.child,
            };
        }
        if node_seen.iter().any(|s| !s) || leaf_depth.iter().any(Option::is_none) {
            return bad("unreachable spatial nodes or leaves".into());
        }
        let mut shared: HashMap<u32, Arc<QuadTree>> = HashMap::new();
        // Training trees and their headers must not overlap: the GPU adds into them.
        let mut training_used = vec![false; arrays.training.len()];
        let mut leaves = Vec::with_capacity(arrays.leaves.len());
        for (i, g) in arrays.leaves.iter().enumerate() {
            let what = format!("leaf {i}");
            let (box_min, box_size) = (Vec3::from_array(g.box_min), Vec3::from_array(g.box_size));
            if !(box_min.is_finite() && box_size.is_finite() && box_size.min_element() > 0.0) {
                return bad(format!("{what}: bad box"));
            }
            if !(0.0..=1.0).contains(&g.bsdf_fraction) {
                return bad(format!(
                    "{what}: BSDF fraction {} not in [0, 1]",
                    g.bsdf_fraction
                ));
            }
            let sampling = match shared.get(&g.sampling_root) {
                Some(t) => t.clone(),
                None => {
                    let t = unflatten(&arrays.sampling, g.sampling_root, &what)?.0;
                    t.check_sums_consistent()
                        .map_err(|m| GuidingError::BadArrays(format!("{what}: {m}")))?;
                    let t = Arc::new(t);
                    shared.insert(g.sampling_root, t.clone());
                    t
                }
            };
            if g.training_root == 0 {
                return bad(format!(
                    "{what}: training root 0 leaves no room for its header"
                ));
            }
            let (training, used) = unflatten(&arrays.training, g.training_root, &what)?;
            for a in used.into_iter().chain([g.training_root - 1]) {
                if std::mem::replace(&mut training_used[a as usize], true) {
                    return bad(format!("{what}: training trees overlap at node {a}"));
                }
            }
            let training_weight = arrays.training[g.training_root as usize - 1].sum[0];
            if !(g.sampling_weight.is_finite()
                && g.sampling_weight >= 0.0
                && training_weight.is_finite()
                && training_weight >= 0.0)
            {
                return bad(format!("{what}: negative or non-finite weight"));
            }
            let lights: Vec<(u32, f32)> = arrays
                .lights
                .get(i * SLOTS..(i + 1) * SLOTS)
                .unwrap_or(&[])
                .iter()
                .filter(|s| s.model != GUIDE_LIGHT_EMPTY)
                .map(|s| (s.model, s.value))
                .collect();
            if lights.iter().any(|&(_, p)| !(p.is_finite() && p >= 0.0)) {
                return bad(format!("{what}: bad light table"));
            }
            if !(0.0..=super::config::MAX_LIGHT_MIX).contains(&g.light_mix) {
                return bad(format!(
                    "{what}: light mix {} not in [0, {}]",
                    g.light_mix,
                    super::config::MAX_LIGHT_MIX
                ));
            }
            // What an empty table's leaf holds (`SdTree::refit`); the arrays say 0.
            let light_mix = if lights.is_empty() {
                config.light_mix
            } else {
                g.light_mix
            };
            leaves.push(Leaf {
                box_min,
                box_size,
                depth: leaf_depth[i].unwrap_or(0),
                sampling,
                sampling_weight: g.sampling_weight,
                training,
                training_weight,
                lights: Arc::new(lights),
                light_mix,
                lights_total: 0.0,
                light_training: Vec::new(),
                light_second: 0.0,
                selection: super::SelectionState::restored(g.bsdf_fraction),
            });
        }
        Ok(SdTree {
            config: config.clone(),
            origin,
            size: h.size,
            nodes,
            leaves,
            iterations: 0,
        })
    }
}
