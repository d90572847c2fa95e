// render_debug.comp with software traversal (inc/bvh.glsl) instead of ray queries.
#version 460
#extension GL_EXT_debug_printf : require
#define LANTERNA_DEBUG_PRINTF 1
#define LANTERNA_SOFTWARE_TRAVERSAL 1
#include "render_main.glsl"
