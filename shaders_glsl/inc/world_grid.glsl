// Hash grids over the scene's surfaces, in world space: what world-space light reuse
// (inc/light_reuse.glsl) and learned light visibility (inc/light_visibility.glsl) key
// their tables by. A cell is a few pixels' footprint wide at its distance from the
// camera, rounded to a power of two in world units (the level is part of the key), and
// split by the geometric normal's dominant axis and sign, so that a thin wall's two sides
// and a corner's faces are different cells.
#ifndef INC_WORLD_GRID_GLSL
#define INC_WORLD_GRID_GLSL

#include "common.glsl"
#include "scene_data.glsl"
#include "random.glsl"

// The cell of shading point p with geometric normal ng (on the side it was seen from),
// `cell_pixels` pixel footprints wide, moved by `jitter` cell edges along the tangents t
// and b: four well-mixed hash words (a table takes its index from some and a fingerprint
// from others).
uvec4 world_cell_hash(vec3 p, vec3 ng, vec3 t, vec3 b, vec2 jitter, float cell_pixels) {
    vec3 eye = params.camera_to_world[3].xyz;
    float footprint = params.camera_type == CAMERA_ORTHOGRAPHIC
        ? 2.0 * params.ortho_half_extent.y / float(params.height)
        : 2.0 * params.tan_half_fov_y * distance(p, eye) / float(params.height);
    float size = max(footprint * cell_pixels, 1e-6 * params.scene_radius);
    // Power-of-two edges: neighbouring points at slightly different distances share a
    // cell, and the level is part of the key.
    int level = clamp(int(ceil(log2(max(size, 1e-30)))), -120, 120);
    float edge = exp2(float(level));
    p += edge * (jitter.x * t + jitter.y * b);
    vec3 q = clamp(floor(p * exp2(float(-level))), vec3(-1073741824.0), vec3(1073741824.0));
    vec3 a = abs(ng);
    uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
    uint side = axis * 2u + (ng[axis] < 0.0 ? 1u : 0u);
    return pcg4d(uvec4(uvec3(ivec3(q)), uint(level + 128) * 8u + side));
}

#endif
