// Test kernel: guide_record of the real GLSL. Every input record is recorded into the
// training buffer (float atomics), which the test reads back and compares with the CPU
// mirror (SdTree::record). Buffers: TEST_BINDING_IN GuideTestRecord[], and the four
// SD-tree buffers at their usual bindings (the training buffer is the output).
// Odd records come with their leaf already found, as the path kernel passes it.
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/bindings.h"
#include "shared/guiding.h"
#include "inc/guiding.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { GuideTestRecord inputs[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= uint(inputs.length())) {
        return;
    }
    GuideTestRecord t = inputs[i];
    // Odd records pass their leaf as the path kernel does (found beforehand), even ones
    // let guide_record find it: both must match the CPU mirror.
    uint hint = (i & 1u) == 1u ? guide_find_leaf(t.record.pos) : INVALID_INDEX;
    guide_record(t.record, t.u, hint);
}
