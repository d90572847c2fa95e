// The path-tracing kernel (see render_main.glsl).
#version 460
#include "render_main.glsl"
