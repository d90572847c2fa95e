// The path-tracing kernel with software traversal (inc/bvh.glsl) instead of ray queries:
// for CPU devices and for devices without VK_KHR_ray_query (see render_main.glsl).
#version 460
#define LANTERNA_SOFTWARE_TRAVERSAL 1
#include "render_main.glsl"
