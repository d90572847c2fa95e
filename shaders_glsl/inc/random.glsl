// Counter-based random numbers: every value is a hash of (pixel, sample index, seed,
// counter), so a sample can be recomputed alone (`--pixel X,Y --sample K`) and renders
// split into ranges of samples reproduce a one-shot render exactly.
#ifndef INC_RANDOM_GLSL
#define INC_RANDOM_GLSL

#include "common.glsl"

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

// ---- stratified pixel positions ---------------------------------------------------------
// The first two dimensions of Sobol' (van der Corput and its Pascal-matrix partner) with
// hash-based Owen scrambling (Burley 2020, "Practical Hash-based Owen Scrambling"),
// seeded per pixel and indexed by the global sample index: any power-of-two run of
// aligned samples of a pixel is stratified over the pixel, the positions stay a
// deterministic function of (seed, pixel, sample index), and sample ranges still merge
// exactly. Small bright emitters seen directly converge much faster than with
// independent jitter.

uint sobol_dim1(uint i) {
    uint v = 0x80000000u;
    uint r = 0u;
    for (; i != 0u; i >>= 1u, v ^= v >> 1u)
        if ((i & 1u) != 0u) r ^= v;
    return r;
}

uint laine_karras_permutation(uint x, uint seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

uint nested_uniform_scramble(uint x, uint seed) {
    return bitfieldReverse(laine_karras_permutation(bitfieldReverse(x), seed));
}

vec2 stratified_pixel_sample(uint pixel, uint sample_index, uint seed) {
    uvec4 h = pcg4d(uvec4(pixel, seed, 0x5eed5eedu, 0x0b0eu));
    uint i = nested_uniform_scramble(sample_index, h.x);  // shuffle (keeps prefixes stratified)
    uint x = nested_uniform_scramble(bitfieldReverse(i), h.y);
    uint y = nested_uniform_scramble(sobol_dim1(i), h.z);
    return vec2(uvec2(x, y) >> 8u) * (1.0 / 16777216.0);
}

// A float in [0, 1) hashed from arbitrary data (stochastic alpha).
float hash_to_float(uvec4 v) {
    return float(pcg4d(v).x >> 8u) * (1.0 / 16777216.0);
}

#endif
