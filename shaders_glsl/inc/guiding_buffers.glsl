// The SD-tree buffers (layout: shared/guiding.h). A test kernel may define
// GUIDE_SET and GUIDE_BINDING_* before including this file to move them.
#ifndef LANTERNA_GUIDING_BUFFERS_GLSL
#define LANTERNA_GUIDING_BUFFERS_GLSL

#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_atomic_float : require
#extension GL_EXT_control_flow_attributes : require

#include "shared/bindings.h"
#include "shared/guiding.h"

#ifndef GUIDE_SET
#define GUIDE_SET 0
#endif
#ifndef GUIDE_BINDING_SPATIAL
#define GUIDE_BINDING_SPATIAL BINDING_GUIDE_SPATIAL
#endif
#ifndef GUIDE_BINDING_LEAVES
#define GUIDE_BINDING_LEAVES BINDING_GUIDE_LEAVES
#endif
#ifndef GUIDE_BINDING_SAMPLING
#define GUIDE_BINDING_SAMPLING BINDING_GUIDE_SAMPLING
#endif
#ifndef GUIDE_BINDING_TRAINING
#define GUIDE_BINDING_TRAINING BINDING_GUIDE_TRAINING
#endif
#ifndef GUIDE_BINDING_LIGHTS
#define GUIDE_BINDING_LIGHTS BINDING_GUIDE_LIGHTS
#endif
#ifndef GUIDE_BINDING_LIGHT_TRAINING
#define GUIDE_BINDING_LIGHT_TRAINING BINDING_GUIDE_LIGHT_TRAINING
#endif

// Read through accessors: `guide_leaves(i)`, `guide_training_add(n, q, v)`, … From the
// bound storage buffers, or, where the includer defines GUIDE_ADDRESSES (scene_data.glsl:
// the render kernels on CPU devices, specialization constant 7) and GUIDE_ADDRESS(name),
// through buffer references at the addresses the push constants hold (they change when
// a refit regrows a buffer, so they travel with every dispatch). Lavapipe loads a
// storage buffer at an index that differs between lanes one lane at a time, a buffer
// reference with one gather (inc/scene_data.glsl). The header stays in its bound buffer:
// every lane reads the same one.
#ifndef GUIDE_ADDRESSES
#define GUIDE_ADDRESSES false
// Never read (the branch folds away). A variable: glslang crashed on a constant
// converted to a buffer reference here.
uvec2 guide_no_address;
#define GUIDE_ADDRESS(name) guide_no_address
#endif
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(set = GUIDE_SET, binding = GUIDE_BINDING_SPATIAL, scalar) readonly buffer GuideSpatialBuffer {
    GuideHeader guide_header;
    GuideSpatialNode guide_spatial_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer GuideSpatialRef {
    GuideHeader header;
    GuideSpatialNode v[];
};
GuideSpatialNode guide_spatial(uint i) {
    if (GUIDE_ADDRESSES) return GuideSpatialRef(GUIDE_ADDRESS(guide_spatial_address)).v[i];
    return guide_spatial_bound[i];
}

layout(set = GUIDE_SET, binding = GUIDE_BINDING_LEAVES, scalar) readonly buffer GuideLeafBuffer {
    GuideLeaf guide_leaves_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer GuideLeafRef { GuideLeaf v[]; };
GuideLeaf guide_leaves(uint i) {
    if (GUIDE_ADDRESSES) return GuideLeafRef(GUIDE_ADDRESS(guide_leaves_address)).v[i];
    return guide_leaves_bound[i];
}

layout(set = GUIDE_SET, binding = GUIDE_BINDING_SAMPLING, scalar) readonly buffer GuideSamplingBuffer {
    GuideQuadNode guide_sampling_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer GuideSamplingRef { GuideQuadNode v[]; };
// A node's sums and one child, apart: glslang fails on a struct returned by a function in
// the `precise` arithmetic of guide_pdf and guide_sample.
vec4 guide_sampling_sum(uint i) {
    if (GUIDE_ADDRESSES) return GuideSamplingRef(GUIDE_ADDRESS(guide_sampling_address)).v[i].sum;
    return guide_sampling_bound[i].sum;
}
uint guide_sampling_child(uint i, uint q) {
    if (GUIDE_ADDRESSES) return GuideSamplingRef(GUIDE_ADDRESS(guide_sampling_address)).v[i].child[q];
    return guide_sampling_bound[i].child[q];
}

// The training quadtrees: their children are read, their sums only added to.
layout(set = GUIDE_SET, binding = GUIDE_BINDING_TRAINING, scalar) buffer GuideTrainingBuffer {
    GuideQuadNode guide_training_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer GuideTrainingRef { GuideQuadNode v[]; };
uint guide_training_child(uint n, uint q) {
    if (GUIDE_ADDRESSES) return GuideTrainingRef(GUIDE_ADDRESS(guide_training_address)).v[n].child[q];
    return guide_training_bound[n].child[q];
}
void guide_training_add(uint n, uint q, float v) {
    if (GUIDE_ADDRESSES) {
        atomicAdd(GuideTrainingRef(GUIDE_ADDRESS(guide_training_address)).v[n].sum[q], v);
    } else {
        atomicAdd(guide_training_bound[n].sum[q], v);
    }
}

#ifndef GUIDE_NO_LIGHT_TABLES
layout(set = GUIDE_SET, binding = GUIDE_BINDING_LIGHTS, scalar) readonly buffer GuideLightBuffer {
    GuideLightSlot guide_lights_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer GuideLightRef { GuideLightSlot v[]; };
GuideLightSlot guide_lights(uint i) {
    if (GUIDE_ADDRESSES) return GuideLightRef(GUIDE_ADDRESS(guide_lights_address)).v[i];
    return guide_lights_bound[i];
}

// The light training tables: a slot is claimed for a model (compare-and-swap from
// GUIDE_LIGHT_EMPTY; returns the model it held) and then added to.
layout(set = GUIDE_SET, binding = GUIDE_BINDING_LIGHT_TRAINING, scalar) buffer GuideLightTrainingBuffer {
    GuideLightTrainingSlot guide_light_training_bound[];
};
layout(buffer_reference, scalar, buffer_reference_align = 4) buffer GuideLightTrainingRef { GuideLightTrainingSlot v[]; };
uint guide_light_training_claim(uint i, uint model) {
    if (GUIDE_ADDRESSES) {
        return atomicCompSwap(GuideLightTrainingRef(GUIDE_ADDRESS(guide_light_training_address)).v[i].model, GUIDE_LIGHT_EMPTY, model);
    }
    return atomicCompSwap(guide_light_training_bound[i].model, GUIDE_LIGHT_EMPTY, model);
}
void guide_light_training_add(uint i, float value, float second, bool with_second) {
    if (GUIDE_ADDRESSES) {
        GuideLightTrainingRef t = GuideLightTrainingRef(GUIDE_ADDRESS(guide_light_training_address));
        atomicAdd(t.v[i].value, value);
        if (with_second) atomicAdd(t.v[i].second, second);
    } else {
        atomicAdd(guide_light_training_bound[i].value, value);
        if (with_second) atomicAdd(guide_light_training_bound[i].second, second);
    }
}
#endif

#endif
