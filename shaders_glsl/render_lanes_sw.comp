// render_lanes.comp with software traversal (inc/bvh.glsl) instead of ray queries.
#version 460
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#define LANTERNA_LANE_STATS 1
#define LANTERNA_SOFTWARE_TRAVERSAL 1
#include "render_main.glsl"
