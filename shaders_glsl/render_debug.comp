// The path-tracing kernel with per-vertex traces through GL_EXT_debug_printf, for
// `lanterna render --pixel X,Y`: only the traced pixel prints. Kept separate because
// debug printf needs VK_KHR_shader_non_semantic_info, which not every driver has.
#version 460
#extension GL_EXT_debug_printf : require
#define LANTERNA_DEBUG_PRINTF 1
#include "render_main.glsl"
