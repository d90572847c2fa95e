// Rays through ray queries (see trace_main.glsl).
#version 460
#include "trace_main.glsl"
