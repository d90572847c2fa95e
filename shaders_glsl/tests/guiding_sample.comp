// Test kernel: guide_sample and guide_pdf of the real GLSL. For each input (u, leaf) it
// writes the sampled direction (mode GUIDE_TEST_SAMPLE; with GUIDE_TEST_EVAL the
// direction of square point u, and pdf 0), the pdf guide_sample returned, guide_pdf of
// that direction, and the direction's square coordinates as the kernel computes them (the
// device's atan/sin/cos differ from the CPU's by more than the deepest cells are wide,
// so the tests bin samples by the kernel's own coordinates). Buffers: TEST_BINDING_IN GuideTestSample[], TEST_BINDING_OUT
// GuideTestResult[] (same length), and the four SD-tree buffers at their usual bindings.
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/bindings.h"
#include "shared/guiding.h"
#include "inc/guiding.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { GuideTestSample inputs[]; };
layout(set = 0, binding = TEST_BINDING_OUT, scalar) writeonly buffer Out { GuideTestResult results[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(inputs.length())) {
        return;
    }
    GuideTestSample s = inputs[i];
    float pdf = 0.0;
    vec3 dir;
    if (s.mode == GUIDE_TEST_EVAL) {
        dir = guide_square_to_dir(s.u);
    } else {
        dir = guide_sample(s.leaf, s.u, pdf);
    }
    GuideTestResult r;
    r.dir = dir;
    r.pdf = pdf;
    r.pdf_eval = guide_pdf(s.leaf, dir);
    r.square = guide_dir_to_square(dir);
    results[i] = r;
}
