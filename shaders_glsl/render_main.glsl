// Body of the path-tracing kernels (render.comp, render_debug.comp): one invocation per
// pixel of a tile, looping over a range of sample indices. Methods are specialization
// constants (inc/specialization.glsl). The kernel is two parts, as in OptiX: raygen.glsl
// (camera rays, the path loop, film, guiding records) calls into closesthit.glsl
// (surfaces, direction sampling, NEE); each includes what it uses.
#include "inc/common.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "closesthit.glsl"
#include "raygen.glsl"
