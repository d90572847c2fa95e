// Ray traversal: the closest hit and visibility, with alpha-masked (MASK) and stochastic
// (BLEND) geometry resolved in the candidate loop, for camera, bounce and shadow rays.
// Ray queries here, or (LANTERNA_SOFTWARE_TRAVERSAL) the software traversal of inc/bvh.glsl
// behind the same interface: trace_ray(o, d, tmax, any_hit, probe, probe_blocked), which
// the path loop calls from one place for every ray, and its two wrappers trace_closest
// and visible.
#ifndef INC_TRACE_GLSL
#define INC_TRACE_GLSL

#include "common.glsl"
#include "scene_data.glsl"
#include "geometry.glsl"
#include "random.glsl"

struct Hit {
    bool valid;
    uint instance;
    uint primitive;
    vec2 bary;        // barycentrics of vertices 1 and 2
    float t;
};

// A ray to trace: from `o` along `d` over [0, tmax], t in units of `d` (which need not
// be unit length).
struct Ray {
    vec3 o;
    vec3 d;
    float tmax;
};

#ifndef LANTERNA_SOFTWARE_TRAVERSAL
// Instance index of the candidate (C = false) or committed (C = true) intersection: the
// TLAS instance's custom index plus the geometry's index in its BLAS. (A macro: the
// `committed` argument of the ray-query getters must be a compile-time constant.)
#define HIT_INSTANCE(rq, C) \
    (rayQueryGetIntersectionInstanceCustomIndexEXT(rq, C) + uint(rayQueryGetIntersectionGeometryIndexEXT(rq, C)))
#endif

// Does a candidate hit on non-opaque geometry count? MASK compares alpha with the
// cutoff; BLEND keeps the hit with probability alpha, decided by a hash of the ray and
// the triangle so that the decision is deterministic.
bool alpha_passes(uint instance, uint primitive, vec2 bary, uvec4 ray_key) {
    // The surface's coverage there (inc/geometry.glsl): 1 or 0 where opaque or masked.
    float c = geometry_coverage(instance, primitive, bary);
    if (c >= 1.0 || c <= 0.0) return c > 0.0;
    return hash_to_float(ray_key ^ uvec4(instance, primitive, floatBitsToUint(bary.x), 0x9e3779b9u)) < c;
}

uvec4 ray_key(vec3 o, vec3 d) {
    return uvec4(floatBitsToUint(o.x) ^ floatBitsToUint(d.z), floatBitsToUint(o.y) ^ floatBitsToUint(d.x),
                 floatBitsToUint(o.z) ^ floatBitsToUint(d.y), 0u);
}

#ifdef LANTERNA_SOFTWARE_TRAVERSAL
#include "bvh.glsl"
// Software traversal tests a bounce ray's probe in the bounce ray's own walk of the tree.
const bool TRACE_TESTS_PROBE = true;
#else
// Ray queries trace the probe as a ray of its own (the path loop's probe step).
const bool TRACE_TESTS_PROBE = false;

// The closest hit (any_hit = false) or the first accepted hit (any_hit = true) on
// [0, tmax]: one function for both, so that a kernel that traces every ray through one
// call site holds one copy of the traversal. (`probe` is for software traversal, which
// tests it in the same walk; see inc/bvh.glsl.)
Hit trace_ray(vec3 origin, vec3 dir, float tmax, bool any_hit, Ray probe, out bool probe_blocked) {
    probe_blocked = false;
    rayQueryEXT rq;
    uint flags = any_hit ? gl_RayFlagsTerminateOnFirstHitEXT : gl_RayFlagsNoneEXT;
    rayQueryInitializeEXT(rq, tlas, flags, 0xffu, origin, 0.0, dir, tmax);
    uvec4 key = ray_key(origin, dir);
    while (rayQueryProceedEXT(rq)) {
        if (rayQueryGetIntersectionTypeEXT(rq, false) == gl_RayQueryCandidateIntersectionTriangleEXT) {
            uint inst = HIT_INSTANCE(rq, false);
            uint prim = rayQueryGetIntersectionPrimitiveIndexEXT(rq, false);
            vec2 bary = rayQueryGetIntersectionBarycentricsEXT(rq, false);
            if (alpha_passes(inst, prim, bary, key)) rayQueryConfirmIntersectionEXT(rq);
        }
    }
    Hit h;
    h.valid = rayQueryGetIntersectionTypeEXT(rq, true) == gl_RayQueryCommittedIntersectionTriangleEXT;
    h.instance = INVALID_INDEX;
    h.primitive = INVALID_INDEX;
    h.bary = vec2(0.0);
    h.t = tmax;
    if (h.valid) {
        h.instance = HIT_INSTANCE(rq, true);
        h.primitive = rayQueryGetIntersectionPrimitiveIndexEXT(rq, true);
        h.bary = rayQueryGetIntersectionBarycentricsEXT(rq, true);
        h.t = rayQueryGetIntersectionTEXT(rq, true);
    }
    return h;
}
#endif

Hit trace_closest(vec3 origin, vec3 dir, float tmax) {
    bool blocked;
    return trace_ray(origin, dir, tmax, false, Ray(origin, vec3(0.0), 0.0), blocked);
}

// True when nothing blocks the segment origin → origin + dir·tmax (`dir` need not be
// unit length: t is measured in multiples of it, as for every ray query).
bool visible(vec3 origin, vec3 dir, float tmax) {
    bool blocked;
    return !trace_ray(origin, dir, tmax, true, Ray(origin, vec3(0.0), 0.0), blocked).valid;
}

// The length that offsets near the world's origin are fractions of: the scene's radius,
// at most 1. Wächter & Binder's constants (below) are for scenes about a unit across; in
// a scene far smaller (a box 0.2 mm wide) their 2^-16 is 7 % of it, and its image was
// 2.3 % bright. Larger scenes keep the constants as they are.
float offset_unit() {
    return min(params.scene_radius, 1.0);
}

// Offset a ray origin off the surface along the geometric normal, scaled to the
// position's magnitude (Wächter & Binder, Ray Tracing Gems ch. 6): 256 ulps of each
// coordinate, or 2^-16 of offset_unit() where the coordinate is within offset_unit()/32
// of the origin. `n` picks the side to move to.
vec3 offset_ray(vec3 p, vec3 n) {
    float origin = offset_unit() / 32.0;
    float float_scale = offset_unit() / 65536.0;
    const float int_scale = 256.0;
    ivec3 of_i = ivec3(int_scale * n);
    vec3 p_i = vec3(intBitsToFloat(floatBitsToInt(p.x) + ((p.x < 0.0) ? -of_i.x : of_i.x)),
                    intBitsToFloat(floatBitsToInt(p.y) + ((p.y < 0.0) ? -of_i.y : of_i.y)),
                    intBitsToFloat(floatBitsToInt(p.z) + ((p.z < 0.0) ? -of_i.z : of_i.z)));
    return vec3(abs(p.x) < origin ? p.x + float_scale * n.x : p_i.x,
                abs(p.y) < origin ? p.y + float_scale * n.y : p_i.y,
                abs(p.z) < origin ? p.z + float_scale * n.z : p_i.z);
}



// Shadow rays to a point in free space stop this fraction of their length short of it.
const float SHADOW_EPSILON = 1e-4;

// The shadow ray of the segment between two surface points (after pbrt-v4's SpawnRayTo).
//
// A point computed on a triangle (from barycentrics, or sampled on a light) is only
// known to within a few ulps of its coordinates, so a ray that starts or ends exactly
// there may hit the surface it belongs to. Both ends are therefore moved off their own
// surfaces, each along its geometric normal toward the other end (`origin_n`,
// `target_n` must already point that way), and the ray is aimed from the moved origin
// at the moved target, so that its direction and its length describe the same segment.
// Moving only the origin while keeping the direction and length computed from the
// unmoved points shifts the segment's far end by the same offset; where the origin
// moves toward the light (a lamp facing a wall, a lamp on a ledge) that end lands
// behind the light's face, and the light occludes itself.
//
// The target moves straight along its normal, by 2^-15 of its largest coordinate
// (256 ulps of it; offset_ray's per-axis ulps would move it sideways too) plus 2^-16 of
// offset_unit(), and the ray stops an eighth of that short of it: an absolute margin,
// not a fraction of the length. A relative stop (pbrt's and Mitsuba's) ends a long ray
// a few tenths of a millimetre early; near the edge of a closed emitter's face that faces away from the
// shading point, the face toward it is crossed within that last stretch, so light
// emitted inside a two-sided closed lamp leaked out (a 2 cm two-sided box 2–3 m away:
// +1.1 % of its light; Mitsuba 3's relative stop of 8.9·10⁻⁴ gives +9 % there).
Ray segment_between(vec3 origin_p, vec3 origin_n, vec3 target_p, vec3 target_n) {
    vec3 o = offset_ray(origin_p, origin_n);
    float offset = max3(abs(target_p)) * (1.0 / 32768.0) + offset_unit() / 65536.0;
    vec3 d = target_p + target_n * offset - o;
    return Ray(o, d, 1.0 - min(SHADOW_EPSILON, 0.125 * offset / max(length(d), 1e-30)));
}

// The shadow ray from a surface point to a point in free space (a punctual light).
Ray segment_to_point(vec3 origin_p, vec3 origin_n, vec3 target_p) {
    vec3 o = offset_ray(origin_p, origin_n);
    return Ray(o, target_p - o, 1.0 - SHADOW_EPSILON);
}

// The shadow ray from a surface point toward a light at infinity (direction `wi`).
Ray ray_to_infinity(vec3 origin_p, vec3 origin_n, vec3 wi) {
    return Ray(offset_ray(origin_p, origin_n), wi, FLT_MAX);
}

// Where a bounce ray leaving surface point p in unit direction w starts (`n`: the unit
// geometric normal on w's side), and the probe the path loop traces before it (tmax 0:
// none).
//
// offset_ray's origin moves the ray's whole line sideways by its distance off the
// surface times sin θ, so a ray that grazes toward a nearby surface lands up to tan θ
// times that distance further on: with a lamp 1 mm in front of a wall 2 m from the
// world's origin (where offset_ray moves 0.06 mm), the wall beside the lamp, lit by its
// back face and by what bounces out of the gap, came out 2.7 % dark; 4 m out, 5 %, and
// still 2.7 % there with rays within 60° of the normal left on offset_ray's origin
// (tests/core_render.rs). So the ray starts on its own line instead, as far along it as
// puts it at offset_ray's distance off the surface, but at most GRAZING_STRETCH times
// that distance (within 1/64 of grazing, the rest of the height comes from offset_ray's
// move). The path loop adds the stretch to the hit's t, which is then the distance
// from p.
//
// That stretch skips whatever crosses it: where another surface meets this one (a wall
// on a floor, a box on a table), a ray that would hit it lower than the distance started
// past it, and light from behind leaked in along every concave corner (a closed room lit
// by a lamp of 100 outside, seen at 0.6 mm a pixel: the pixels along the corner at 0.59,
// where the truth is black; tests/core_render.rs). The probe is the
// segment from offset_ray's origin to the moved one, both that far off the surface,
// traced as a shadow ray: where it is blocked the ray leaves from offset_ray's origin.
// On lavapipe the probes cost 5–17 % of the samples per second (README, Rendering).
const float GRAZING_STRETCH = 64.0;
vec3 bounce_origin(vec3 p, vec3 n, vec3 w, out Ray probe) {
    vec3 lifted = offset_ray(p, n);
    probe = Ray(lifted, vec3(0.0), 0.0);
    float clearance = dot(lifted - p, n);
    float cos_w = dot(w, n);
    if (cos_w <= 0.0 || clearance <= 0.0) return lifted;
    float t = cos_w * GRAZING_STRETCH >= 1.0 ? clearance / cos_w : GRAZING_STRETCH * clearance;
    vec3 along = p + w * t + n * (clearance - t * cos_w);
    probe.d = along - lifted;
    probe.tmax = dot(probe.d, probe.d) > 0.0 ? 1.0 : 0.0;
    return along;
}

#endif
