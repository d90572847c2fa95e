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

// Concentric disk (Shirley & Chiu), used by the cosine warp.
vec2 square_to_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    float r, theta;
    if (abs(o.x) > abs(o.y)) { r = o.x; theta = (PI / 4.0) * (o.y / o.x); }
    else { r = o.y; theta = (PI / 2.0) - (PI / 4.0) * (o.x / o.y); }
    return r * vec2(cos(theta), sin(theta));
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
