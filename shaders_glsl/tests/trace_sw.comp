// Rays through the software traversal (see trace_main.glsl).
#version 460
#define LANTERNA_SOFTWARE_TRAVERSAL 1
#include "trace_main.glsl"
