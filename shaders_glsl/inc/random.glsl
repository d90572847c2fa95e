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
    uint counter;   // the next independent number (rng_next*)
    uint vertex;    // the path vertex whose decisions rng_stratified2 draws (raygen sets it)
};

Rng rng_init(uint pixel, uint sample_index, uint seed) {
    return Rng(uvec3(pixel, sample_index, seed), 0u, 0u);
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

// Sobol's second dimension: the index's bits times the Pascal matrix mod 2. Read as a
// polynomial over GF(2) (bit j = coefficient of x^j), that product is p(x + 1) with the
// bits reversed, and since (x + 1)^(2^k) = x^(2^k) + 1 the shift by 1 takes five
// shift-and-xor steps instead of a loop over the index's (up to 32, once shuffled) bits.
uint sobol_dim1(uint i) {
    i ^= (i >> 1u) & 0x55555555u;
    i ^= (i >> 2u) & 0x33333333u;
    i ^= (i >> 4u) & 0x0F0F0F0Fu;
    i ^= (i >> 8u) & 0x00FF00FFu;
    i ^= (i >> 16u) & 0x0000FFFFu;
    return bitfieldReverse(i);
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

// Point `sample_index` of a pixel's 2D pair `dim` (dim 0: the position in the pixel):
// every pair shuffles the sample indices and scrambles the two coordinates with its own
// seeds, so different pairs are independent of each other while each is stratified over
// the pixel's samples (padded 2D sequences, as pbrt-v4's PaddedSobolSampler).
vec2 stratified_sample_2d(uint pixel, uint sample_index, uint seed, uint dim) {
    uvec4 h = pcg4d(uvec4(pixel, seed, 0x5eed5eedu + dim, 0x0b0eu));
    uint i = nested_uniform_scramble(sample_index, h.x);  // shuffle (keeps prefixes stratified)
    uint x = nested_uniform_scramble(bitfieldReverse(i), h.y);
    uint y = nested_uniform_scramble(sobol_dim1(i), h.z);
    return vec2(uvec2(x, y) >> 8u) * (1.0 / 16777216.0);
}

vec2 stratified_pixel_sample(uint pixel, uint sample_index, uint seed) {
    return stratified_sample_2d(pixel, sample_index, seed, 0u);
}

// The decisions at a path vertex that matter most are drawn from stratified pairs, the
// rest (RIS's candidates, Russian roulette, training records) from rng_next*. Pair k of
// vertex r.vertex (≥ 1):
const uint RNG_PAIR_DIRECTION = 0u;    // the direction: its warp, and (reused) the choices
                                       // of strategy and lobe (direction_choose)
const uint RNG_PAIR_LIGHT = 1u;        // light model and triangle (RIS: its strata offset)
const uint RNG_PAIR_LIGHT_POINT = 2u;  // the point on the light triangle
const uint RNG_PAIRS_PER_VERTEX = 3u;
// The stratified dimension of the point a pixel-emitter ray aims at (raygen.glsl), far
// from those of the path's vertices.
const uint PIXEL_EMITTER_DIM = 0x7fffffffu;

// Each number is uniform, whatever the vertex and pair, so every estimator stays
// unbiased; across the samples of a pixel they are stratified, which is worth most where
// direct light varies smoothly (cornell-lights `pt` at 256 spp: 0.63× the MAE of
// independent numbers at the same speed).
vec2 rng_stratified2(Rng r, uint pair) {
    return stratified_sample_2d(r.key.x, r.key.y, r.key.z, 1u + RNG_PAIRS_PER_VERTEX * r.vertex + pair);
}

// A float in [0, 1) hashed from arbitrary data (stochastic alpha).
float hash_to_float(uvec4 v) {
    return float(pcg4d(v).x >> 8u) * (1.0 / 16777216.0);
}

#endif
