// The four SD-tree buffers (layout: shared/guiding.h). A test kernel may define
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

layout(set = GUIDE_SET, binding = GUIDE_BINDING_SPATIAL, scalar) readonly buffer GuideSpatialBuffer {
    GuideHeader guide_header;
    GuideSpatialNode guide_spatial[];
};
layout(set = GUIDE_SET, binding = GUIDE_BINDING_LEAVES, scalar) readonly buffer GuideLeafBuffer {
    GuideLeaf guide_leaves[];
};
layout(set = GUIDE_SET, binding = GUIDE_BINDING_SAMPLING, scalar) readonly buffer GuideSamplingBuffer {
    GuideQuadNode guide_sampling[];
};

layout(set = GUIDE_SET, binding = GUIDE_BINDING_TRAINING, scalar) buffer GuideTrainingBuffer {
    GuideQuadNode guide_training[];
};

#ifndef GUIDE_NO_LIGHT_TABLES
layout(set = GUIDE_SET, binding = GUIDE_BINDING_LIGHTS, scalar) readonly buffer GuideLightBuffer {
    GuideLightSlot guide_lights[];
};
layout(set = GUIDE_SET, binding = GUIDE_BINDING_LIGHT_TRAINING, scalar) buffer GuideLightTrainingBuffer {
    GuideLightTrainingSlot guide_light_training[];
};
#endif

#endif
