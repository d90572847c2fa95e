// Warps from the unit square and frames.
#ifndef INC_SAMPLING_GLSL
#define INC_SAMPLING_GLSL

#include "common.glsl"

// Orthonormal basis around n (Duff et al. 2017).
void make_basis(vec3 n, out vec3 t, out vec3 b) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

vec3 to_local(vec3 v, vec3 t, vec3 b, vec3 n) { return vec3(dot(v, t), dot(v, b), dot(v, n)); }
vec3 to_world(vec3 v, vec3 t, vec3 b, vec3 n) { return v.x * t + v.y * b + v.z * n; }

// (cos a, sin a) for |a| ≤ π/4 from their Taylor polynomials to degree 10 and 9, whose
// truncation error (below 2·10⁻⁹) is under float rounding. On CPU devices (lavapipe)
// cos() and sin() cost several times as much: they reduce an arbitrary argument first.
vec2 cos_sin_small(float a) {
    float a2 = a * a;
    float c = 1.0 + a2 * (-1.0 / 2.0 + a2 * (1.0 / 24.0 + a2 * (-1.0 / 720.0 + a2 * (1.0 / 40320.0 + a2 * (-1.0 / 3628800.0)))));
    float s = a * (1.0 + a2 * (-1.0 / 6.0 + a2 * (1.0 / 120.0 + a2 * (-1.0 / 5040.0 + a2 * (1.0 / 362880.0)))));
    return vec2(c, s);
}

// (cos φ, sin φ) of φ = 2π·u, u ∈ [0, 1]: the nearest quarter turn k·π/2 and the
// remainder a = φ − k·π/2 ∈ [−π/4, π/4], rotated by k quarter turns exactly.
vec2 cos_sin_turn(float u) {
    float k = floor(4.0 * u + 0.5);
    vec2 cs = cos_sin_small(TWO_PI * (u - 0.25 * k));
    uint q = uint(k) & 3u;
    if (q == 1u) return vec2(-cs.y, cs.x);
    if (q == 2u) return -cs;
    if (q == 3u) return vec2(cs.y, -cs.x);
    return cs;
}

// Concentric disk (Shirley & Chiu), used by the cosine warp. Its angle is π/4·(y/x), or
// π/2 − π/4·(x/y), so cos_sin_small covers it.
vec2 square_to_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    if (abs(o.x) > abs(o.y)) return o.x * cos_sin_small((PI / 4.0) * (o.y / o.x));
    return o.y * cos_sin_small((PI / 4.0) * (o.x / o.y)).yx;  // cos(π/2 − a) = sin a
}

// Cosine-weighted hemisphere around +z; pdf = cos θ / π.
vec3 square_to_cosine_hemisphere(vec2 u) {
    vec2 d = square_to_disk(u);
    float z = sqrt(max(0.0, 1.0 - dot(d, d)));
    return vec3(d, z);
}

// Uniform point on a triangle: barycentrics (b1, b2) of (p1, p2).
vec2 square_to_triangle(vec2 u) {
    float s = sqrt(u.x);
    return vec2(s * (1.0 - u.y), s * u.y);
}

#endif
