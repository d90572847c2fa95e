// Body of the trace kernels (trace.comp: ray queries, trace_sw.comp: software traversal):
// one invocation per ray of the rays buffer, through the renderer's own trace_closest,
// visible or (bounce rays with their probes) trace_ray, with the renderer's descriptor
// set. Used by the traversal tests (hits of the two traversals compared) and by
// `lanterna bench --suite traversal` (rays per second).
// The push constants' sample_begin/sample_count give the range of rays.
#include "../inc/common.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "../inc/random.glsl"
#include "../inc/scene_data.glsl"
#include "../inc/geometry.glsl"
#include "../inc/trace.glsl"

layout(set = 0, binding = BINDING_TRACE_RAYS, scalar) readonly buffer TraceRayBuffer { TraceRay trace_rays[]; };
layout(set = 0, binding = BINDING_TRACE_HITS, scalar) writeonly buffer TraceHitBuffer { TraceHit trace_hits[]; };

void main() {
    uint i = pc.sample_begin + gl_GlobalInvocationID.x;
    if (gl_GlobalInvocationID.x >= pc.sample_count) return;
    TraceRay r = trace_rays[i];
    TraceHit out_hit = TraceHit(INVALID_INDEX, INVALID_INDEX, 0.0, 0.0, 0.0);
    if (r.kind == TRACE_VISIBLE) {
        out_hit.primitive = visible(r.origin, r.dir, r.tmax) ? 1u : 0u;
    } else if (r.kind == TRACE_PROBED) {
        // As the path loop does: the probe in the ray's own walk (software traversal),
        // or as a ray of its own (ray queries).
        Ray probe = Ray(r.probe_origin, r.probe_dir, 1.0);
        bool blocked;
        Hit h = trace_ray(r.origin, r.dir, r.tmax, false, probe, blocked);
        if (!TRACE_TESTS_PROBE) blocked = !visible(probe.o, probe.d, probe.tmax);
        if (blocked) out_hit.primitive = TRACE_PROBE_BLOCKED;
        else if (h.valid) out_hit = TraceHit(h.instance, h.primitive, h.t, h.bary.x, h.bary.y);
    } else {
        Hit h = trace_closest(r.origin, r.dir, r.tmax);
        if (h.valid) out_hit = TraceHit(h.instance, h.primitive, h.t, h.bary.x, h.bary.y);
    }
    trace_hits[i] = out_hit;
}
