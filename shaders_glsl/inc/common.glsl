// Extensions, shared headers and small math helpers every kernel includes first.
#ifndef INC_COMMON_GLSL
#define INC_COMMON_GLSL

#extension GL_EXT_scalar_block_layout : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_nonuniform_qualifier : require
#extension GL_EXT_control_flow_attributes : require

#include "../shared/bindings.h"
#include "../shared/constants.h"
#include "../shared/scene.h"
#include "../shared/guiding.h"
#include "../shared/traversal.h"

const float PI = 3.14159265358979323846;
const float TWO_PI = 6.28318530717958647692;
const float INV_PI = 0.31830988618379067154;
const float INV_TWO_PI = 0.15915494309189533577;
const float INV_FOUR_PI = 0.07957747154594766788;
const float FLT_MAX = 3.402823466e38;

float luminance(vec3 c) { return dot(c, vec3(0.2126, 0.7152, 0.0722)); }
float max3(vec3 v) { return max(v.x, max(v.y, v.z)); }
float sqr(float x) { return x * x; }
bool all_finite(vec3 v) { return !any(isnan(v)) && !any(isinf(v)); }

// Power heuristic (β = 2) for two strategies with pdfs a and b.
float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

#endif
