// SD-tree path guiding on the GPU: find the spatial leaf of a point, sample a direction
// from its sampling quadtree and evaluate that quadtree's pdf, and record training data
// into the training quadtrees with float atomics. Layout and conventions are in
// shared/guiding.h; the CPU mirror of every function here is src/guiding/ (quadtree.rs,
// sphere.rs, sdtree.rs), which the tests compare against.
//
// Exactness: guide_sample returns exactly guide_pdf(leaf, dir) of the direction it
// returns. Both walk the tree with the same helper functions, the sampled direction is
// kept inside the sampled cell (see guide_sample), and should that fail the pdf is
// guide_pdf's own.
#ifndef LANTERNA_GUIDING_GLSL
#define LANTERNA_GUIDING_GLSL

#include "shared/constants.h"
#include "guiding_buffers.glsl"

const float GUIDE_PI = 3.14159265358979323846;
const float GUIDE_INV_4PI = 0.0795774715459476679;
const float GUIDE_ONE_MINUS_EPS = 0.99999994;  // largest float below 1

// ---- direction <-> square ((cosθ+1)/2, φ/2π), z the polar axis ------------------------

vec2 guide_dir_to_square(vec3 d) {
    precise float cos_theta = clamp(d.z, -1.0, 1.0);
    precise float phi = atan(d.y, d.x);
    if (isnan(phi)) {
        phi = 0.0;  // atan(0, 0) at the poles is undefined in GLSL
    }
    if (phi < 0.0) {
        phi += 2.0 * GUIDE_PI;
    }
    precise vec2 p = vec2((cos_theta + 1.0) * 0.5, phi * (0.5 / GUIDE_PI));
    p = clamp(p, vec2(0.0), vec2(1.0));
    // Non-finite directions land in a fixed cell instead of walking the tree with NaN.
    return any(isnan(p)) ? vec2(0.0) : p;
}

vec3 guide_square_to_dir(vec2 p) {
    precise float cos_theta = 2.0 * p.x - 1.0;
    precise float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    // φ reduced to [-π, π] first: v - roundEven(v) is exact (Sterbenz), and the smaller angle
    // keeps more absolute precision than 2πv near 2π.
    precise float phi = (2.0 * GUIDE_PI) * (p.y - roundEven(p.y));
    return vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta);
}

// ---- quadtree walk helpers (shared by sampling and pdf so both do the same float ops) --

// Quadrant of `p` (in its node's [0,1]² frame); `p` becomes its position in the
// quadrant's frame. Exact in float: scaling by 2 and subtracting 0.5 from [0.5, 1] are.
uint guide_quadrant(inout vec2 p) {
    uint q = 0u;
    if (p.x < 0.5) {
        p.x = p.x * 2.0;
    } else {
        p.x = (p.x - 0.5) * 2.0;
        q |= 1u;
    }
    if (p.y < 0.5) {
        p.y = p.y * 2.0;
    } else {
        p.y = (p.y - 0.5) * 2.0;
        q |= 2u;
    }
    return q;
}

float guide_node_total(vec4 s) {
    precise float t = (s.x + s.y) + (s.z + s.w);
    return t;
}

// Density factor of quadrant q: 4 sum[q] / total, or 1 in a node without energy (which
// both sampling and pdf treat as uniform).
float guide_quadrant_factor(vec4 s, uint q) {
    precise float total = guide_node_total(s);
    precise float f = total > 0.0 ? (4.0 * s[q]) / total : 1.0;
    return f;
}

bool guide_tree_is_empty(uint root) {
    return !(guide_node_total(guide_sampling_sum(root)) > 0.0);
}

// ---- sampling and pdf -----------------------------------------------------------------

// Solid-angle pdf of `dir` under leaf `leaf`'s sampling quadtree (uniform 1/4π when the
// tree has learned nothing yet).
float guide_pdf(uint leaf, vec3 dir) {
    uint n = guide_leaves(leaf).sampling_root;
    if (guide_tree_is_empty(n)) {
        return GUIDE_INV_4PI;
    }
    vec2 p = guide_dir_to_square(dir);
    precise float density = 1.0;
    [[dont_unroll]] for (int level = 0; level < GUIDE_MAX_QUAD_DEPTH; ++level) {
        uint q = guide_quadrant(p);
        density = density * guide_quadrant_factor(guide_sampling_sum(n), q);
        n = guide_sampling_child(n, q);
        if (n == 0u) {
            break;
        }
    }
    precise float pdf = density * GUIDE_INV_4PI;
    return pdf;
}

// Whether walking the tree with `p` ends in the cell at `origin` of edge `size` (the
// walk's arithmetic is exact; cells at the square's upper border include it).
bool guide_in_cell(vec2 p, vec2 origin, float size) {
    vec2 end = origin + vec2(size);
    return all(greaterThanEqual(p, origin)) && (p.x < end.x || end.x == 1.0)
        && (p.y < end.y || end.y == 1.0);
}

// Rescale a uniform number that fell in [lo, lo + width) of [0, 1) back to [0, 1).
float guide_rescale(float u, float lo, float width) {
    return min((u - lo) / width, GUIDE_ONE_MINUS_EPS);
}

// Sample a direction from leaf `leaf`'s sampling quadtree with the uniform pair `u`
// (hierarchical sample warping: each level reuses the rescaled numbers). `pdf` is the
// solid-angle pdf of the returned direction, bitwise equal to guide_pdf(leaf, dir).
vec3 guide_sample(uint leaf, vec2 u, out float pdf) {
    uint n = guide_leaves(leaf).sampling_root;
    u = min(u, vec2(GUIDE_ONE_MINUS_EPS));
    if (guide_tree_is_empty(n)) {
        pdf = GUIDE_INV_4PI;
        return guide_square_to_dir(u);
    }
    vec2 origin = vec2(0.0);
    float size = 1.0;
    precise float density = 1.0;
    [[dont_unroll]] for (int level = 0; level < GUIDE_MAX_QUAD_DEPTH; ++level) {
        vec4 s = guide_sampling_sum(n);
        float total = guide_node_total(s);
        uint q;
        if (total > 0.0) {
            // Column by its marginal, then the row within the column. A quadrant without
            // energy gets a split of exactly 0 or 1 and so is never chosen.
            // (Explicit 1 for an empty side: a division by reciprocal could give 1 - ε.)
            float lo = s.x + s.z;
            float split = lo == total ? 1.0 : lo / total;
            if (u.x < split) {
                u.x = guide_rescale(u.x, 0.0, split);
                q = 0u;
            } else {
                u.x = guide_rescale(u.x, split, 1.0 - split);
                q = 1u;
            }
            float a = s[q];
            float b = s[q + 2u];
            float split_y = b == 0.0 ? 1.0 : a / (a + b);
            if (u.y < split_y) {
                u.y = guide_rescale(u.y, 0.0, split_y);
            } else {
                u.y = guide_rescale(u.y, split_y, 1.0 - split_y);
                q |= 2u;
            }
        } else {
            q = guide_quadrant(u);
        }
        density = density * guide_quadrant_factor(s, q);
        size *= 0.5;
        origin += vec2(float(q & 1u), float(q >> 1u)) * size;
        n = guide_sampling_child(n, q);
        if (n == 0u) {
            break;
        }
    }
    // Deep cells are only a few float steps wide, and the round trip through a direction
    // can move a point near a border into the next cell (whose density may be far
    // lower). A point that does not map back into its cell is pulled halfway to the
    // cell's centre and tried again, so the direction lies in the cell that was sampled.
    vec2 p = origin + u * size;
    vec2 centre = origin + 0.5 * size;
    vec3 dir;
    bool inside = false;
    [[dont_unroll]] for (int attempt = 0; attempt < GUIDE_SAMPLE_ATTEMPTS && !inside; ++attempt) {
        dir = guide_square_to_dir(p);
        inside = guide_in_cell(guide_dir_to_square(dir), origin, size);
        p = 0.5 * (p + centre);
    }
    if (inside) {
        precise float result = density * GUIDE_INV_4PI;
        pdf = result;
    } else {
        pdf = guide_pdf(leaf, dir);
    }
    return dir;
}

// ---- spatial tree -----------------------------------------------------------------------

// The spatial leaf holding `p` (points outside the cube use the nearest leaf).
uint guide_find_leaf(vec3 p) {
    vec3 x = clamp((p - guide_header.origin) / guide_header.size, vec3(0.0), vec3(1.0));
    uint n = 0u;
    [[dont_unroll]] for (int level = 0; level <= GUIDE_MAX_SPATIAL_DEPTH; ++level) {
        GuideSpatialNode node = guide_spatial(n);
        if (node.axis == GUIDE_SPATIAL_LEAF) {
            break;
        }
        float c = x[node.axis];
        if (c < 0.5) {
            x[node.axis] = c * 2.0;
            n = node.child;
        } else {
            x[node.axis] = (c - 0.5) * 2.0;
            n = node.child + 1u;
        }
    }
    return guide_spatial(n).child;
}

// ---- recording ----------------------------------------------------------------------------

// Add v to the cell holding p, `levels` levels deep at most: the leaf cell holding p,
// or, where the tree is finer, the node's quadrant at that depth (its own sum, which the
// CPU spreads evenly over the quadrant's subtree before the refit).
void guide_splat_to_depth(uint root, vec2 p, float v, uint levels) {
    uint n = root;
    [[dont_unroll]] for (uint level = 0u; level < GUIDE_MAX_QUAD_DEPTH; ++level) {
        uint q = guide_quadrant(p);
        uint c = guide_training_child(n, q);
        if (c == 0u || level + 1u >= levels) {
            guide_training_add(n, q, v);
            return;
        }
        n = c;
    }
}

// Nearest directional filter: everything goes to the leaf cell holding p.
void guide_splat_nearest(uint root, vec2 p, float v) {
    guide_splat_to_depth(root, p, v, GUIDE_MAX_QUAD_DEPTH);
}

// Depth of the training tree's leaf cell holding p (the root's quadrants are depth 1;
// edge length 2^-depth), and the node and quadrant whose sum is that cell.
uint guide_training_leaf(uint root, vec2 p, out uint node, out uint quadrant) {
    uint n = root;
    uint depth = 1u;
    [[dont_unroll]] for (int level = 0; level < GUIDE_MAX_QUAD_DEPTH; ++level) {
        uint q = guide_quadrant(p);
        uint c = guide_training_child(n, q);
        if (c == 0u) {
            node = n;
            quadrant = q;
            return depth;
        }
        n = c;
        ++depth;
    }
    // Not reached: the CPU builds no tree deeper than GUIDE_MAX_QUAD_DEPTH levels.
    node = n;
    quadrant = guide_quadrant(p);
    return depth;
}

// Box directional filter: a box of the size of the training leaf cell holding p (depth
// k), centred on p, shifted inside the square along u = (cosθ+1)/2 and wrapped around
// along φ, spreads v over the (at most four) cells of the depth-k grid it overlaps, by
// the area it covers of each. A grid cell the tree holds as a leaf, or inside a coarser
// leaf, takes its share there, as an exact box filter would; a grid cell the tree has
// refined further takes it in its own sum, spread evenly over its subtree at the refit
// rather than over the covered part alone. Four walks and no stack: the depth-first
// walk over the box it replaced kept a stack per SIMD lane, and on lavapipe made a
// path's records cost 0.7 of a render-phase sample, against 0.3 now (README, Path
// guiding: directional filter).
void guide_splat_box(uint root, vec2 p, float v) {
    uint leaf_node, leaf_quadrant;
    uint depth = guide_training_leaf(root, p, leaf_node, leaf_quadrant);
    float cells = float(1u << depth);
    // The grid cell holding p: its share goes straight to the leaf just found.
    vec2 own = min(floor(p * cells), vec2(cells - 1.0));
    // The box's lower corner in grid cells (scaling by a power of two is exact).
    precise vec2 lo = p * cells - 0.5;
    lo.x = clamp(lo.x, 0.0, cells - 1.0);
    vec2 base = floor(lo);
    vec2 f = lo - base;
    [[dont_unroll]] for (uint i = 0u; i < 4u; ++i) {
        uvec2 corner = uvec2(i & 1u, i >> 1u);
        precise float w = (corner.x == 0u ? 1.0 - f.x : f.x) * (corner.y == 0u ? 1.0 - f.y : f.y);
        if (!(w > 0.0)) {
            continue;
        }
        vec2 cell = base + vec2(corner);
        cell.y = cell.y < 0.0 ? cell.y + cells : cell.y >= cells ? cell.y - cells : cell.y;
        if (cell == own) {
            guide_training_add(leaf_node, leaf_quadrant, v * w);
        } else {
            guide_splat_to_depth(root, (cell + 0.5) / cells, v * w, depth);
        }
    }
}

// Record `r` into the training tree of leaf `leaf`: its weight into the leaf's
// statistical weight, its value into the cell(s) of its direction (see GuideRecord).
void guide_record_into(uint leaf, GuideRecord r) {
    uint root = guide_leaves(leaf).training_root;
    if (r.weight > 0.0) guide_training_add(root - 1u, 0u, r.weight);
    if (!(r.value > 0.0) || isinf(r.value)) {
        return;
    }
    vec2 p = guide_dir_to_square(r.dir);
    if ((guide_header.flags & GUIDE_FLAG_DIRECTIONAL_BOX) != 0u) {
        guide_splat_box(root, p, r.value);
    } else {
        guide_splat_nearest(root, p, r.value);
    }
}

// Record one training sample taken at r.pos. `u` (uniform in [0,1)³) jitters the
// position within its leaf's box when the stochastic spatial filter is on: the leaf of
// r.pos gives the box, the leaf of the jittered point takes the record (both through one
// guide_find_leaf call site, so that the kernel holds one copy of the descent here).
// `leaf` is r.pos's leaf when the caller found it already (the path's direction sampler
// did, in the same tree), else INVALID_INDEX; it spares a descent per record.
void guide_record(GuideRecord r, vec3 u, uint leaf) {
    // A weight that is not a finite number ≥ 0 marks a broken record: drop it whole.
    if (!(r.weight >= 0.0) || isinf(r.weight)) {
        return;
    }
    bool counts = r.weight > 0.0;
    bool splats = r.value > 0.0 && !isinf(r.value);
    if (!counts && !splats) {
        return;
    }
    bool jitter = (guide_header.flags & GUIDE_FLAG_SPATIAL_JITTER) != 0u;
    vec3 q = r.pos;
    [[dont_unroll]] for (uint pass = 0u;; ++pass) {
        if (pass > 0u || leaf == INVALID_INDEX) leaf = guide_find_leaf(q);
        if (!jitter || pass == 1u) break;
        // precise: no fused multiply-add, so the CPU mirror picks the same leaf.
        precise vec3 j = r.pos + (u - 0.5) * guide_leaves(leaf).box_size;
        q = clamp(j, guide_header.origin, guide_header.origin + guide_header.size);
    }
    guide_record_into(leaf, r);
}

// ---- learned light selection -------------------------------------------------------------
#ifndef GUIDE_NO_LIGHT_TABLES

// A 128-bit filter of the models in leaf `leaf`'s table: bit h(model) for each (a Bloom
// filter with one hash, no false negatives). Built once per RIS call from the packed
// table (at most GUIDE_LIGHT_SLOTS reads), it lets a candidate whose model the table
// does not hold skip the hash probe: with 16 models in 128 bits, about 12 % of absent
// models still probe. Those probes were 13–15 % of a `guided-ris` sample on the street
// (README, "Where the guiding goals stand").
// Knuth's multiplicative hash of a model; its top bits pick the model's first hash slot
// and its filter bit (src/guiding/flat.rs mirrors the former).
uint guide_light_hash(uint model) {
    return model * 2654435761u;
}

uint guide_light_filter_bit(uint model) {
    return guide_light_hash(model) >> 25u;  // top 7 bits: 0..127
}

uvec4 guide_light_filter(uint leaf) {
    uvec4 f = uvec4(0u);
    [[dont_unroll]] for (uint i = 0u; i < GUIDE_LIGHT_SLOTS; ++i) {
        uint model = guide_lights(leaf * GUIDE_LIGHT_SLOTS + i).model;
        if (model == GUIDE_LIGHT_EMPTY) break;  // entries come first
        uint b = guide_light_filter_bit(model);
        f[b >> 5u] |= 1u << (b & 31u);
    }
    return f;
}

bool guide_light_filter_may_hold(uvec4 f, uint model) {
    uint b = guide_light_filter_bit(model);
    return (f[b >> 5u] & (1u << (b & 31u))) != 0u;
}

// Probability of light model `model` in leaf `leaf`'s table (0 when absent).
float guide_light_pmf(uint leaf, uint model) {
    // The leaf's hash copy of its table: one or two probes where the linear scan of the
    // packed table read every entry for a model the table does not hold.
    uint base = guide_header.leaf_count * GUIDE_LIGHT_SLOTS + leaf * GUIDE_LIGHT_HASH_SLOTS;
    uint h = guide_light_hash(model) >> (32u - GUIDE_LIGHT_HASH_BITS);
    // At most half the slots are full, so every probe sequence ends at an empty slot.
    [[dont_unroll]] for (uint i = 0u; i < GUIDE_LIGHT_HASH_SLOTS; ++i) {
        GuideLightSlot s = guide_lights(base + ((h + i) & (GUIDE_LIGHT_HASH_SLOTS - 1u)));
        if (s.model == model) return s.value;
        if (s.model == GUIDE_LIGHT_EMPTY) break;
    }
    return 0.0;
}

// Pick a light model from leaf `leaf`'s table with u in [0, 1), through the table's
// alias copy (O(1): one alias slot and one table slot, where a walk of the CDF took up
// to 16 steps in each SIMD lane group); INVALID_INDEX when the table is empty (its alias
// slots lead to an empty slot).
uint guide_light_sample(uint leaf, float u, out float pmf) {
    uint alias_base = guide_header.leaf_count * (GUIDE_LIGHT_SLOTS + GUIDE_LIGHT_HASH_SLOTS) + leaf * GUIDE_LIGHT_SLOTS;
    float scaled = u * float(GUIDE_LIGHT_SLOTS);
    uint i = min(uint(scaled), GUIDE_LIGHT_SLOTS - 1u);
    GuideLightSlot a = guide_lights(alias_base + i);  // model: alias slot, value: threshold
    uint k = scaled - float(i) < a.value ? i : a.model;
    GuideLightSlot s = guide_lights(leaf * GUIDE_LIGHT_SLOTS + k);
    pmf = s.value;
    return s.model;
}

// Add the NEE estimate `value` to light model `model`'s slot of leaf `leaf`'s training
// table (open addressing with atomics; a full neighbourhood drops the record from the
// table, which only affects what is learned, never correctness); with a learned mix
// (GUIDE_FLAG_LEARN_LIGHT_MIX) its square too, there and in the leaf's total (training
// header sum.y).
void guide_light_record(uint leaf, uint model, float value) {
    bool learn_mix = (guide_header.flags & GUIDE_FLAG_LEARN_LIGHT_MIX) != 0u;
    float second = value * value;
    if (learn_mix) guide_training_add(guide_leaves(leaf).training_root - 1u, 1u, second);
    uint base = leaf * GUIDE_LIGHT_SLOTS;
    uint h = (model * 2654435761u) >> 28u;  // top 4 bits: GUIDE_LIGHT_SLOTS = 16
    [[dont_unroll]] for (uint probe = 0u; probe < GUIDE_LIGHT_PROBES; ++probe) {
        uint i = base + ((h + probe) & (GUIDE_LIGHT_SLOTS - 1u));
        uint prev = guide_light_training_claim(i, model);
        if (prev == GUIDE_LIGHT_EMPTY || prev == model) {
            guide_light_training_add(i, value, second, learn_mix);
            return;
        }
    }
}

#endif

#endif
