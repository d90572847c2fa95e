// Writes stratified_pixel_sample(pixel, k, seed) for k in [0, count) of each of `pixels`
// pixels, for the test that the first 2^m samples of a pixel form a (0, m, 2)-net.
#version 460
#include "../inc/common.glsl"
#include "../inc/random.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_OUT, scalar) buffer Out { vec2 positions[]; };
layout(push_constant, scalar) uniform Push { uint pixels; uint count; uint seed; } pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.pixels * pc.count) return;
    positions[t] = stratified_pixel_sample(t / pc.count, t % pc.count, pc.seed);
}
