// Counter-based random numbers: every value is a hash of (pixel, sample index, seed,
// counter), so a sample can be recomputed alone (`--pixel X,Y --sample K`) and renders
// split into ranges of samples reproduce a one-shot render exactly.
#ifndef INC_RANDOM_GLSL
#define INC_RANDOM_GLSL

// Jarzynski & Olano 2020, "Hash Functions for GPU Rendering": pcg4d.
uvec4 pcg4d(uvec4 v) {
    v = v * 1664525u + 1013904223u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    v ^= v >> 16u;
    v.x += v.y * v.w; v.y += v.z * v.x; v.z += v.x * v.y; v.w += v.y * v.z;
    return v;
}

struct Rng {
    uvec3 key;      // pixel, sample, seed
    uint counter;
};

Rng rng_init(uint pixel, uint sample_index, uint seed) {
    return Rng(uvec3(pixel, sample_index, seed), 0u);
}

// Uniform float in [0, 1) with 24 random bits.
float rng_next(inout Rng r) {
    uvec4 h = pcg4d(uvec4(r.key, r.counter++));
    return float(h.x >> 8u) * (1.0 / 16777216.0);
}

vec2 rng_next2(inout Rng r) {
    uvec4 h = pcg4d(uvec4(r.key, r.counter++));
    return vec2(uvec2(h.x, h.y) >> 8u) * (1.0 / 16777216.0);
}

vec4 rng_next4(inout Rng r) {
    uvec4 h = pcg4d(uvec4(r.key, r.counter++));
    return vec4(h >> 8u) * (1.0 / 16777216.0);
}

// A float in [0, 1) hashed from arbitrary data (stochastic alpha).
float hash_to_float(uvec4 v) {
    return float(pcg4d(v).x >> 8u) * (1.0 / 16777216.0);
}

#endif
