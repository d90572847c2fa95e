// The path-tracing kernel with SIMD lane-utilisation counters (inc/lane_stats.glsl), for
// `lanterna render --lane-stats` and the bench's profile suite. Kept separate because the
// counters need subgroup operations and cost time.
#version 460
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#define LANTERNA_LANE_STATS 1
#include "render_main.glsl"
