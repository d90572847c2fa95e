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
vec3 normalize_or_zero(vec3 v) {
    float l2 = dot(v, v);
    return l2 > 1e-30 ? v * inversesqrt(l2) : vec3(0.0);
}

// floor(x) as an unsigned integer, for 0 ≤ x < 2³², by integer operations on x's bits.
// On CPU devices (lavapipe, LLVM 15) a float-to-integer conversion is a saturating one,
// which LLVM expands lane by lane into scalar code (about six instructions per lane);
// this stays in vector registers. Exact: it drops x's significand bits below the binary
// point. RIS picks two indices this way for each of its 32 candidates per vertex.
uint floor_to_uint(float x) {
    uint b = floatBitsToUint(x);
    int e = int(b >> 23u) - 127;  // x < 1 (including +0 and denormals): e < 0
    uint m = (b & 0x7FFFFFu) | 0x800000u;
    uint r = e <= 23 ? m >> uint(clamp(23 - e, 0, 31)) : m << uint(min(e - 23, 31));
    return e < 0 ? 0u : r;
}

// Power heuristic (β = 2) for two strategies with pdfs a and b.
float power_heuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 > 0.0 ? a2 / (a2 + b2) : 0.0;
}

#endif
