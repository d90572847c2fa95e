// Software traversal: trace_closest and visible over the BVH2 built on the CPU
// (src/render/bvh.rs), for devices without ray queries and for CPU devices, where it is
// faster than the driver's ray queries (lavapipe builds a BVH2 with one triangle per leaf
// split at the index median; `lanterna bench --suite traversal` measures both).
//
// It reports what a ray query reports: the instance index (custom index + geometry
// index), the triangle's index within its geometry, barycentrics of vertices 1 and 2 and
// t in units of `dir`, over [0, tmax]; non-opaque triangles are resolved by the same
// alpha_passes call (inc/trace.glsl) with the same ray key, so MASK and stochastic BLEND
// decide alike. Triangles are stored in world space (instances are flattened), which
// moves t and the barycentrics by rounding only.
#ifndef INC_BVH_GLSL
#define INC_BVH_GLSL

#include "lane_stats.glsl"

// Entry distance of the ray into a box, or FLT_MAX when it misses it or enters beyond
// `tmax`. The exit distance is widened by 2·γ₃ (Ize, "Robust BVH ray traversal") so that
// rounding cannot make a ray miss the box of a triangle it hits (flat boxes of
// axis-aligned walls included).
float bvh_box_entry(vec3 bmin, vec3 bmax, vec3 o, vec3 inv_d, float tmax) {
    vec3 t0 = (bmin - o) * inv_d;
    vec3 t1 = (bmax - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float tnear = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float tfar = min(min(tf.x, tf.y), tf.z) * 1.0000004;
    return (tnear <= tfar && tnear <= tmax) ? tnear : FLT_MAX;
}

// 1/d for the slab test, with each zero component made a tiny one of the same sign:
// 1/±0 = ±inf would make 0·inf = NaN there when the origin lies on a box's plane.
vec3 bvh_safe_inverse(vec3 d) {
    return 1.0 / mix(d, mix(vec3(-1e-30), vec3(1e-30), greaterThanEqual(d, vec3(0.0))), lessThan(abs(d), vec3(1e-30)));
}

// Does the ray o + t·d hit the triangle at t ∈ [0, tmax), and does the hit count
// (alpha_passes, with the ray's `key`)? Möller–Trumbore; `uvt` is (u, v, t) of the hit.
bool bvh_triangle_hit(BvhTriangle tri, vec3 o, vec3 d, float tmax, uvec4 key, out vec3 uvt) {
    vec3 pvec = cross(d, tri.e2);
    float det = dot(tri.e1, pvec);
    float inv_det = 1.0 / det;
    vec3 tvec = o - tri.v0;
    float u = dot(tvec, pvec) * inv_det;
    vec3 qvec = cross(tvec, tri.e1);
    float v = dot(d, qvec) * inv_det;
    float t = dot(tri.e2, qvec) * inv_det;
    uvt = vec3(u, v, t);
    return det != 0.0 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= 0.0 && t < tmax &&
           ((tri.flags & BVH_TRIANGLE_OPAQUE) != 0u || alpha_passes(tri.instance, tri.primitive, vec2(u, v), key));
}

// The closest hit (any_hit = false) or the first accepted hit (any_hit = true) on
// [0, tmax], and, in the same walk of the tree, whether anything blocks the bounce
// ray's probe (bounce_origin in inc/trace.glsl; probe.tmax 0: none). A blocked probe
// ends the walk at once (`probe_blocked`; the hit is then void, and the path loop traces
// the ray again from offset_ray's origin). Traced on its own, a probe walked the tree
// from its root to the few leaves around the bounce ray's origin, which the bounce ray
// walks through too: one walk for both loads those nodes once.
Hit trace_ray(vec3 o, vec3 d, float tmax, bool any_hit, Ray probe, out bool probe_blocked) {
    probe_blocked = false;
    Hit h;
    h.valid = false;
    h.instance = INVALID_INDEX;
    h.primitive = INVALID_INDEX;
    h.bary = vec2(0.0);
    h.t = tmax;
    uvec4 key = ray_key(o, d);
    vec3 inv_d = bvh_safe_inverse(d);
    float best = tmax;
    // The probe, tested only in the nodes its segment meets: `probe_in` for the node at
    // hand, bit k of `probe_flags` for the stack's entry k.
    vec3 probe_inv_d = bvh_safe_inverse(probe.d);
    uvec4 probe_key = ray_key(probe.o, probe.d);
    bool probe_in = probe.tmax > 0.0;
    uint64_t probe_flags = 0ul;

    // The stack's newest four entries live in registers (top0 the newest), older ones in
    // the array (entry k of the whole stack at stack[k]; the array holds sp − 4 of them):
    // on CPU devices every access to a per-lane array with a per-lane index is a loop
    // over the SIMD lanes, and most rays never need more than four pending far children.
    // lavapipe: `pt` 3–5 % faster on cornell-lights and the street, 8–10 % on
    // bistro-night (two to eight registers measured: four is best).
    uint stack[BVH_STACK_SIZE];
    uint sp = 0u;
    uint top0 = 0u, top1 = 0u, top2 = 0u, top3 = 0u;
    uint ref = 0u;  // the root is always inner node 0
    while (true) {
        lane_stats_traversal_step();
        if ((ref & BVH_LEAF_BIT) == 0u) {
            BvhNode n = bvh_nodes(ref);
            float ta = bvh_box_entry(n.a_min, n.a_max, o, inv_d, best);
            float tb = bvh_box_entry(n.b_min, n.b_max, o, inv_d, best);
            bool pa = probe_in && bvh_box_entry(n.a_min, n.a_max, probe.o, probe_inv_d, probe.tmax) < FLT_MAX;
            bool pb = probe_in && bvh_box_entry(n.b_min, n.b_max, probe.o, probe_inv_d, probe.tmax) < FLT_MAX;
            bool ha = ta < FLT_MAX;
            bool hb = tb < FLT_MAX;
            bool va = ha || pa;
            bool vb = hb || pb;
            if (va || vb) {
                // The ray's nearer child first; a child only the probe meets after one
                // the ray enters.
                bool a_first = va && (!vb || (ha && (!hb || ta <= tb)));
                if (va && vb) {
                    if (sp >= 4u) stack[sp - 4u] = top3;
                    top3 = top2;
                    top2 = top1;
                    top1 = top0;
                    top0 = a_first ? n.b_ref : n.a_ref;
                    if (a_first ? pb : pa) probe_flags |= 1ul << sp;
                    else probe_flags &= ~(1ul << sp);
                    sp++;
                }
                ref = a_first ? n.a_ref : n.b_ref;
                probe_in = a_first ? pa : pb;
                continue;
            }
        } else if (ref != BVH_EMPTY) {
            uint first = ref & BVH_LEAF_FIRST_MASK;
            uint end = first + ((ref >> BVH_LEAF_COUNT_SHIFT) & BVH_LEAF_COUNT_MASK) + 1u;
            for (uint i = first; i < end; ++i) {
                BvhTriangle tri = bvh_triangles(i);
                vec3 uvt;
                if (bvh_triangle_hit(tri, o, d, best, key, uvt)) {
                    best = uvt.z;
                    h.valid = true;
                    h.instance = tri.instance;
                    h.primitive = tri.primitive;
                    h.bary = uvt.xy;
                    h.t = uvt.z;
                    if (any_hit) return h;
                }
                if (probe_in && bvh_triangle_hit(tri, probe.o, probe.d, probe.tmax, probe_key, uvt)) {
                    probe_blocked = true;
                    return h;
                }
            }
        }
        if (sp == 0u) break;
        ref = top0;
        top0 = top1;
        top1 = top2;
        top2 = top3;
        sp--;
        probe_in = ((probe_flags >> sp) & 1ul) != 0ul;
        if (sp >= 4u) top3 = stack[sp - 4u];
    }
    return h;
}

#endif
