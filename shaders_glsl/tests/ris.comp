// RIS (inc/ris.glsl) against a stub scene: a discrete set of lights with target values
// p̂_i (input buffer) drawn from a source pmf q_i (aux buffer). Writes, per invocation,
// the selected light and its contribution weight W.
#version 460
#include "../inc/common.glsl"
#include "../inc/random.glsl"
#include "../inc/reservoir.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { float target[]; };
layout(set = 0, binding = TEST_BINDING_AUX, scalar) readonly buffer Aux { float source_pmf[]; };
struct Selection { uint index; float W; };
layout(set = 0, binding = TEST_BINDING_OUT, scalar) buffer Out { Selection selections[]; };
layout(push_constant, scalar) uniform Push { uint count; uint trials; uint seed; uint candidates; uint stratified; } pc;

struct RisContext { uint light_count; };
struct RisCandidate { uint index; float q; };

RisCandidate ris_draw(RisContext ctx, vec4 u4) {
    float u = u4.x;
    float cdf = 0.0;
    uint i = 0u;
    for (; i + 1u < ctx.light_count; ++i) {
        cdf += source_pmf[i];
        if (u < cdf) break;
    }
    return RisCandidate(i, source_pmf[i]);
}

float ris_target(RisContext ctx, inout RisCandidate c) { return target[c.index]; }

float ris_denominator(RisContext ctx, RisCandidate c, uint M) { return float(M) * c.q; }

void ris_keep_target(inout RisCandidate into, RisCandidate c) {}  // ris_target caches nothing

#include "../inc/ris.glsl"

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.trials) return;
    Rng rng = rng_init(t, 1u, pc.seed);
    RisCandidate none = RisCandidate(0u, 0.0);
    float strata_offset = pc.stratified != 0u ? rng_next(rng) : -1.0;
    RisResult r = ris_resample(RisContext(pc.count), pc.candidates, rng, false, none, strata_offset);
    selections[t] = Selection(r.found ? r.y.index : INVALID_INDEX, r.W);
}
