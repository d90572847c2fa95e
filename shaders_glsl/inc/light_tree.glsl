// The light tree of `--source tree` (src/lights/tree.rs builds it and mirrors these
// functions for its tests): choose a light model in proportion to a bound of what it can
// send toward the shading point, walking from the root; find a given model's probability
// by walking its stored path. Nodes are read through `light_tree(i)` (inc/scene_data.glsl).
#ifndef INC_LIGHT_TREE_GLSL
#define INC_LIGHT_TREE_GLSL

#include "common.glsl"
#include "scene_data.glsl"

// An upper bound, up to a common factor, on what node `n`'s emitters send toward p:
// flux × cos θ′ / d². θ′ is the least angle that a direction from the node's bounding
// sphere toward p can make with an emitter's normal, less the emission's spread
// (Conty Estevez & Kulla 2018); d the distance to the box's centre, at least the
// sphere's radius. With a receiver normal nr (zero for none: a surface that transmits)
// also cos θi′, the least angle between nr and a direction from p into the sphere, so
// that a node wholly below p's tangent plane, where an opaque BSDF is zero, gets
// nothing. Zero only where nothing under the node can emit toward p.
float light_tree_importance(LightTreeNode n, vec3 p, vec3 nr) {
    if (!(n.power > 0.0)) return 0.0;
    vec3 c = 0.5 * (n.bounds_min + n.bounds_max);
    vec3 h = 0.5 * (n.bounds_max - n.bounds_min);
    float r2 = dot(h, h);
    vec3 v = p - c;
    float d2 = dot(v, v);
    float cos_t = 1.0, cos_i = 1.0;
    if (d2 > r2) {
        float d = sqrt(d2);
        vec3 w = v / d;
        // θb, the sphere's half-angle seen from p: sin θb = r / d.
        float sin_b2 = r2 / d2;
        float cos_b = sqrt(max(1.0 - sin_b2, 0.0));
        float sin_b = sqrt(sin_b2);
        if (n.cos_normals > -1.0) {
            float cos_w = dot(n.axis, w);
            float sin_w = sqrt(max(1.0 - cos_w * cos_w, 0.0));
            float cos_o = n.cos_normals;
            float sin_o = sqrt(max(1.0 - cos_o * cos_o, 0.0));
            // θx = max(θw − θo, 0)
            float cos_x = 1.0, sin_x = 0.0;
            if (cos_w < cos_o) {
                cos_x = cos_w * cos_o + sin_w * sin_o;
                sin_x = sin_w * cos_o - cos_w * sin_o;
            }
            // θ′ = max(θx − θb, 0)
            if (cos_x < cos_b) cos_t = cos_x * cos_b + sin_x * sin_b;
            if (cos_t <= n.cos_emission) return 0.0;
        }
        // θi′ = max(θi − θb, 0), θi between nr and the direction toward the centre.
        if (nr != vec3(0.0)) {
            float cos_r = -dot(nr, w);
            if (cos_r < cos_b) cos_i = cos_r * cos_b + sqrt(max(1.0 - cos_r * cos_r, 0.0)) * sin_b;
            if (cos_i <= 0.0) return 0.0;
        }
    }
    return n.power * max(cos_t, 0.0) * cos_i / max(max(d2, r2), 1e-30);
}

// The probability of inner node n's left child, seen from p.
float light_tree_left(LightTreeNode n, vec3 p, vec3 nr) {
    if ((n.flags & LIGHT_TREE_FIXED_SPLIT) != 0u) return n.power;
    float a = light_tree_importance(light_tree(n.child), p, nr);
    float b = light_tree_importance(light_tree(n.child + 1u), p, nr);
    return a + b > 0.0 ? a / (a + b) : 0.5;
}

// The tree's probability of light model `m` (whose record is `lm`) at p, whose receiver
// normal is nr (see light_tree_importance).
float light_tree_pmf(LightModel lm, vec3 p, vec3 nr) {
    uint n = 0u;
    float pmf = 1.0;
    [[dont_unroll]] for (uint k = 0u; k < lm.tree_depth; ++k) {
        LightTreeNode node = light_tree(n);
        float left = light_tree_left(node, p, nr);
        bool right = ((lm.tree_path >> k) & 1u) != 0u;
        pmf *= right ? 1.0 - left : left;
        n = node.child + (right ? 1u : 0u);
    }
    return pmf;
}

// The model the tree chooses at p with the uniform number u, and its probability (the
// same products light_tree_pmf finds along the model's path).
uint light_tree_sample(vec3 p, vec3 nr, float u, out float pmf) {
    uint n = 0u;
    pmf = 1.0;
    [[dont_unroll]] for (uint k = 0u; k <= 32u; ++k) {
        LightTreeNode node = light_tree(n);
        if (node.child == INVALID_INDEX) return node.model;
        float left = light_tree_left(node, p, nr);
        if (u < left) {
            u = u / left;
            pmf *= left;
            n = node.child;
        } else {
            u = (u - left) / (1.0 - left);
            pmf *= 1.0 - left;
            n = node.child + 1u;
        }
        u = min(u, 0.99999994);
    }
    pmf = 0.0;
    return INVALID_INDEX;
}

#endif
