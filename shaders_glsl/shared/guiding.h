// SD-tree (Müller et al. 2017, "Practical Path Guiding") as flat arrays. The CPU refits
// the tree between passes (src/guiding/) and uploads four buffers:
//   BINDING_GUIDE_SPATIAL   GuideHeader, then GuideSpatialNode[] (one buffer block)
//   BINDING_GUIDE_LEAVES    GuideLeaf[]
//   BINDING_GUIDE_SAMPLING  GuideQuadNode[]: every leaf's sampling quadtree (read-only)
//   BINDING_GUIDE_TRAINING  GuideQuadNode[]: every leaf's training quadtree, each preceded
//                           by one header node whose sum.x collects the leaf's statistical
//                           weight and sum.y the squared NEE estimates of learned light
//                           selection (atomic float adds); read back after a pass.
// Directions live on the square ((cosθ+1)/2, φ/2π) with z the polar axis; the map is
// area-preserving, so pdf(ω) = quadtree density / 4π.
#ifndef LANTERNA_GUIDING_H
#define LANTERNA_GUIDING_H

// GuideHeader.flags.
#define GUIDE_FLAG_RECORD_NEE 1u
#define GUIDE_FLAG_SPATIAL_JITTER 2u
#define GUIDE_FLAG_DIRECTIONAL_BOX 4u
#define GUIDE_FLAG_LEARN_LIGHTS 8u
// Learned BSDF-vs-guide selection: sample with GuideLeaf.bsdf_fraction, and training
// passes append GuideSelectionRecords (else GuideHeader.bsdf_fraction everywhere).
#define GUIDE_FLAG_LEARN_SELECTION 16u
// What the training records measure (GuideHeader.flags; neither bit: all incident
// radiance, the paper's). INDIRECT: light reflected at the next vertex only (no NEE
// records, no emission reached by the sampled direction). CONTRIBUTION: what the
// direction sampler's estimate carries: the MIS-weighted emission it reaches plus the
// reflected light, no NEE records.
#define GUIDE_FLAG_TARGET_INDIRECT 32u
#define GUIDE_FLAG_TARGET_CONTRIBUTION 64u
// Variance-aware density (Rath et al. 2020): records carry the second moment of the
// target, L²/pdf instead of L/pdf, and the refit takes the square root of each cell's
// mean (the density then follows √E[L²] rather than E[L]).
#define GUIDE_FLAG_SECOND_MOMENT 128u
// Learned light mix (with GUIDE_FLAG_LEARN_LIGHTS): NEE records also sum their squares,
// per light training slot and per leaf, for the CPU's choice of each leaf's light_mix;
// with a fixed mix nothing reads them and they are not recorded.
#define GUIDE_FLAG_LEARN_LIGHT_MIX 256u

// Learned light selection: per spatial leaf, a table of GUIDE_LIGHT_SLOTS light models
// (open addressing, GUIDE_LIGHT_PROBES probes) with the NEE contribution each delivered.
#define GUIDE_LIGHT_SLOTS 16
#define GUIDE_LIGHT_PROBES 4
#define GUIDE_LIGHT_EMPTY 0xffffffffu
// The same tables once more, after all leaves' packed tables in BINDING_GUIDE_LIGHTS, as
// open-addressing hashes for looking up a model's probability (guide_light_pmf, once per
// RIS candidate): GUIDE_LIGHT_HASH_SLOTS slots per leaf (at most half full), a model's
// first slot the top GUIDE_LIGHT_HASH_BITS bits of model · 2654435761 (Knuth's
// multiplicative hash), linear probing to the next empty slot.
#define GUIDE_LIGHT_HASH_SLOTS 32
#define GUIDE_LIGHT_HASH_BITS 5
// And after the hashes, as alias tables (Walker/Vose) over each leaf's GUIDE_LIGHT_SLOTS
// packed slots, for drawing from it (guide_light_sample): slot i's `model` is its alias
// slot and `value` its threshold.

// GuideSpatialNode.axis of a leaf.
#define GUIDE_SPATIAL_LEAF 3u
// Loop bounds of the kernels' tree walks; the CPU never builds deeper trees.
#define GUIDE_MAX_SPATIAL_DEPTH 48
#define GUIDE_MAX_QUAD_DEPTH 20
// Path vertices a training path records (raygen.glsl); the renderer refuses guided
// methods with max_depth > GUIDE_MAX_RECORDED_VERTICES + 1.
#define GUIDE_MAX_RECORDED_VERTICES 16
// Tries guide_sample makes to keep a direction inside its cell (see there).
#define GUIDE_SAMPLE_ATTEMPTS 6

// Start of the spatial buffer: the cube the spatial tree subdivides, and options.
struct GuideHeader {
    vec3 origin;          // cube corner (scene bbox min)
    float size;           // cube edge (largest bbox extent)
    uint flags;           // GUIDE_FLAG_*
    uint leaf_count;
    float bsdf_fraction;  // probability of sampling the BSDF instead of the quadtree
};

// One slot of a leaf's light table (BINDING_GUIDE_LIGHTS): value = the model's selection
// probability; the slots of a leaf sum to 1 or are all empty. The buffer holds
// leaf_count × GUIDE_LIGHT_SLOTS packed slots (entries first, largest first), then
// leaf_count × GUIDE_LIGHT_HASH_SLOTS hash slots of the same entries, then
// leaf_count × GUIDE_LIGHT_SLOTS alias slots.
struct GuideLightSlot {
    uint model;
    float value;
};

// One slot of a leaf's light training table (BINDING_GUIDE_LIGHT_TRAINING): the NEE
// estimates v (luminance) that chose `model` in the leaf, summed (`value`, the model's
// contribution) and squared and summed (`second`, for choosing the leaf's light_mix:
// src/guiding/light_mix.rs). The leaf's training header node sums v² over all its NEE
// estimates in sum.y, those whose model found no slot included.
struct GuideLightTrainingSlot {
    uint model;
    float value;
    float second;
};

// Spatial binary tree node. Interior: `axis` (0 x, 1 y, 2 z) splits the node's box in
// half, children are `child` (low half) and `child + 1` (high half). Leaf: axis ==
// GUIDE_SPATIAL_LEAF and `child` is the leaf index.
struct GuideSpatialNode {
    uint axis;
    uint child;
};

// Per spatial leaf: its quadtrees and its box. The training header node (statistical
// weight) is the training node training_root - 1.
struct GuideLeaf {
    uint sampling_root;   // node index in the sampling array
    uint training_root;   // node index in the training array
    vec3 box_min;
    vec3 box_size;
    float sampling_weight;  // statistical weight the sampling quadtree was learned from
    float bsdf_fraction;    // learned probability of sampling the BSDF (GUIDE_FLAG_LEARN_SELECTION)
    float light_mix;        // probability of choosing a light model from the leaf's table
                            // (GUIDE_FLAG_LEARN_LIGHTS; 0 when the table is empty)
};

// Directional quadtree node. Child order: 0 = (lo u, lo v), 1 = (hi u, lo v),
// 2 = (lo u, hi v), 3 = (hi u, hi v), u = (cosθ+1)/2, v = φ/2π. child[i] is an index into
// the same array, 0 when quadrant i is a leaf cell (index 0 is never a child: it is a
// root in the sampling array and a header in the training array). sum[i] is the energy
// of quadrant i. In a training tree, sum[i] of an interior quadrant holds only energy
// deposited uniformly over the whole quadrant (box splats covering it); the CPU pushes it
// down to the leaves when it builds the tree.
struct GuideQuadNode {
    vec4 sum;
    uvec4 child;
};

// One training record (Müller's DTreeRecord, reduced to what the tree uses):
//   value   the radiance arriving at `pos` from `dir` divided by the pdf of `dir`,
//           averaged over RGB, with any MIS weight applied; splatted into the quadtree
//           cell of `dir` as it is (never scaled by `weight`);
//   weight  the statistical weight: how many samples of the incident radiance this
//           record stands for; added to the leaf's sample count (split decisions).
// A path vertex takes one MIS-combined sample of its incident radiance with two
// techniques: its direction record (weight 1; value 0 when no direction was sampled)
// and its NEE record (weight 0). Their MIS-weighted values add up to one unbiased
// estimate, so every vertex counts once and direct light once. (Müller et al.'s
// reference gives each half the weight and scales the splats by it, which counts the
// vertex once too but halves the estimate of the radiance.)
struct GuideRecord {
    vec3 pos;
    float value;
    vec3 dir;
    float weight;
};

// Learned selection probability (Müller et al. 2019; BINDING_GUIDE_SELECTION): a
// training pass appends, with probability `rate`, one record per guided direction
// sample; the CPU runs Adam on each leaf's logit over them between passes
// (src/guiding/selection.rs). Records past `capacity` are dropped (count keeps counting).
struct GuideSelectionHead {
    uint count;
    uint capacity;
    float rate;
    uint pad;
};
struct GuideSelectionRecord {
    uint leaf;        // the leaf whose bsdf_fraction drew the sample
    float bsdf_pdf;   // solid-angle pdfs of the sampled direction: the BSDF's,
    float guide_pdf;  //   the leaf quadtree's,
    float wo_pdf;     //   and the mixture's that drew it
    float product;    // mean RGB of f·cos·L_in along it (the direction estimate × wo_pdf)
};

// Test kernel tests/guiding_sample: one input and its result. Mode GUIDE_TEST_SAMPLE
// samples with the uniform pair u; GUIDE_TEST_EVAL evaluates guide_pdf at the direction
// of square point u (for integrating the pdf over the sphere on the device).
#define GUIDE_TEST_SAMPLE 0u
#define GUIDE_TEST_EVAL 1u
struct GuideTestSample {
    vec2 u;
    uint leaf;
    uint mode;
};
struct GuideTestResult {
    vec3 dir;
    float pdf;        // returned by guide_sample
    float pdf_eval;   // guide_pdf(leaf, dir)
    vec2 square;      // guide_dir_to_square(dir): the cell the kernel's own walk sees
};

// Test kernel tests/guiding_record: a record with the random numbers of its jitter.
struct GuideTestRecord {
    GuideRecord record;
    vec3 u;
    uint pad;
};

#endif
