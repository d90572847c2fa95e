// Streams a fixed list of weights through the reservoir once per invocation and writes
// the index it kept, so the test can compare selection frequencies with w_i / Σw.
#version 460
#include "../inc/common.glsl"
#include "../inc/random.glsl"
#include "../inc/reservoir.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { float weights[]; };
layout(set = 0, binding = TEST_BINDING_OUT, scalar) buffer Out { uint kept[]; };
layout(push_constant, scalar) uniform Push { uint count; uint trials; uint seed; } pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.trials) return;
    Rng rng = rng_init(t, 0u, pc.seed);
    Reservoir r = reservoir_empty();
    uint chosen = INVALID_INDEX;
    for (uint i = 0u; i < pc.count; ++i)
        if (reservoir_update(r, weights[i], rng_next(rng))) chosen = i;
    kept[t] = chosen;
}
