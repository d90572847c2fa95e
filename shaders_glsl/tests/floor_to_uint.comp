// floor_to_uint (inc/common.glsl) of each input float, for the test that compares it
// with the CPU's floor over 0 ≤ x < 2³².
#version 460
#include "../inc/common.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { float xs[]; };
layout(set = 0, binding = TEST_BINDING_OUT, scalar) buffer Out { uint floors[]; };
layout(push_constant, scalar) uniform Push { uint count; } pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.count) return;
    floors[t] = floor_to_uint(xs[t]);
}
