// SIMD lane utilisation, measured by the lane-statistics kernels (render_lanes.comp,
// render_lanes_sw.comp; `lanterna render --lane-stats`, bench profile suite). A CPU
// device such as lavapipe runs a subgroup (8 lanes with AVX2) in lockstep: a loop runs
// until its slowest lane is done, and the other lanes' slots in those steps are wasted.
// Two loops are counted, as steps taken by lanes against lane slots of the subgroup
// steps (a step counts gl_SubgroupSize slots however many lanes were active in it):
//  * the software traversal loop (inc/bvh.glsl), one step per node or leaf visited, for
//    every ray of every kind;
//  * the path loop: a sample's vertices (its camera ray and each bounce), against the
//    vertices of the subgroup's longest path of that sample (the sample loop is uniform).
// Utilisation = steps / slots. Elsewhere (the regular kernels) all of it compiles to
// nothing.
#ifndef INC_LANE_STATS_GLSL
#define INC_LANE_STATS_GLSL

#include "common.glsl"
#include "scene_data.glsl"

#ifdef LANTERNA_LANE_STATS
uint g_traversal_lane_steps = 0u;
uint g_traversal_lane_slots = 0u;
uint g_path_lane_steps = 0u;
uint g_path_lane_slots = 0u;

// One step of the traversal loop by this lane.
void lane_stats_traversal_step() {
    g_traversal_lane_steps += 1u;
    if (subgroupElect()) g_traversal_lane_slots += gl_SubgroupSize;
}

// A finished sample whose path loop took `steps` steps in this lane.
void lane_stats_path(uint steps) {
    g_path_lane_steps += steps;
    uint longest = subgroupMax(steps);
    if (subgroupElect()) g_path_lane_slots += longest * gl_SubgroupSize;
}

// Add this invocation's counts to the stats buffer (end of the kernel).
void lane_stats_flush() {
    atomicAdd(stats[STAT_TRAVERSAL_LANE_STEPS], uint64_t(g_traversal_lane_steps));
    atomicAdd(stats[STAT_TRAVERSAL_LANE_SLOTS], uint64_t(g_traversal_lane_slots));
    atomicAdd(stats[STAT_PATH_LANE_STEPS], uint64_t(g_path_lane_steps));
    atomicAdd(stats[STAT_PATH_LANE_SLOTS], uint64_t(g_path_lane_slots));
}
#else
void lane_stats_traversal_step() {}
void lane_stats_path(uint steps) {}
void lane_stats_flush() {}
#endif

#endif
