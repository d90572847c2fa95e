// Body of the path-tracing kernels (render.comp, render_debug.comp): one invocation per
// pixel of a tile, looping over a range of sample indices. Methods are specialization
// constants, so each method compiles to its own pipeline without dead branches.
#include "inc/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(constant_id = 0) const uint NEE_MODE = NEE_UNIFORM;  // NEE_UNIFORM (pt) or NEE_RIS
layout(constant_id = 1) const bool GUIDING = false;         // sample directions from the SD-tree
layout(constant_id = 2) const bool TRAINING = false;        // record training data
layout(constant_id = 3) const bool AOVS = false;            // write first-hit AOVs and outliers

#include "inc/random.glsl"
#include "inc/sampling.glsl"
#include "inc/scene_data.glsl"
#include "inc/debug.glsl"
#include "inc/geometry.glsl"
#include "inc/trace.glsl"
#include "inc/bsdf.glsl"
#include "inc/material.glsl"
#include "inc/guiding.glsl"
#include "inc/guiding_selection.glsl"
#include "inc/lights.glsl"
#include "inc/reservoir.glsl"
#include "closesthit.glsl"
#include "raygen.glsl"
