// Software ray traversal (inc/bvh.glsl) over a BVH built on the CPU (src/render/bvh.rs),
// and the ray/hit records of the traversal test and bench kernel (tests/trace.comp).
#ifndef LANTERNA_TRAVERSAL_H
#define LANTERNA_TRAVERSAL_H

// A child reference in a BvhNode: an inner node's index, or a leaf (BVH_LEAF_BIT set)
// holding BVH_LEAF_COUNT_MASK + 1 ≥ count ≥ 1 triangles from a first triangle index.
// BVH_EMPTY marks a missing child (its box is empty, so it is never entered).
#define BVH_LEAF_BIT 0x80000000u
#define BVH_LEAF_COUNT_SHIFT 27
#define BVH_LEAF_COUNT_MASK 15u
#define BVH_LEAF_FIRST_MASK 0x07ffffffu
#define BVH_EMPTY 0xffffffffu
// Entries of the traversal stack; the builder keeps the tree shallower than this.
#define BVH_STACK_SIZE 64

// Triangle flags.
#define BVH_TRIANGLE_OPAQUE 1u

// A BVH2 node with both children's boxes (Aila & Laine's layout: one node read tests
// two boxes).
struct BvhNode {
    vec3 a_min;
    uint a_ref;
    vec3 a_max;
    uint b_ref;
    vec3 b_min;
    uint pad0;
    vec3 b_max;
    uint pad1;
};

// A world-space triangle prepared for Möller–Trumbore: v0 and the edges v1 − v0,
// v2 − v0, with the instance index (as ray queries report it: the TLAS instance's custom
// index + the geometry index) and the triangle's index within its geometry.
struct BvhTriangle {
    vec3 v0;
    uint instance;
    vec3 e1;
    uint primitive;
    vec3 e2;
    uint flags;
};

// Ray kinds of the trace kernel. TRACE_PROBED: the closest hit of a bounce ray whose
// origin was moved along its line, and whether its probe (the segment probe_origin →
// probe_origin + probe_dir, t ∈ [0, 1)) is blocked; as the path loop traces it
// (bounce_origin in inc/trace.glsl).
#define TRACE_CLOSEST 0u
#define TRACE_VISIBLE 1u
#define TRACE_PROBED 2u
// The `primitive` of a TRACE_PROBED ray's hit (instance INVALID_INDEX) whose probe is
// blocked.
#define TRACE_PROBE_BLOCKED 0xfffffffeu

struct TraceRay {
    vec3 origin;
    float tmax;
    vec3 dir;
    uint kind;       // TRACE_CLOSEST, TRACE_VISIBLE or TRACE_PROBED
    vec3 probe_origin;
    vec3 probe_dir;  // TRACE_PROBED only; zero otherwise
};

struct TraceHit {
    uint instance;   // INVALID_INDEX: no hit (closest) / 1 visible, 0 occluded in `primitive`
    uint primitive;  // (TRACE_PROBE_BLOCKED: a TRACE_PROBED ray's probe is blocked)
    float t;
    float bary_u;
    float bary_v;
};

#endif
