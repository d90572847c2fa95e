// Learned light visibility (`--light-visibility learned`; beyond the paper, whose future
// work names visibility-aware light selection). Part of the closest-hit side: RIS's
// target (closesthit.glsl's ris_target) takes a factor per light model from here.
//
// The paper's target p̂ = Le·f·G has no visibility, so RIS spends its one shadow ray on
// lights behind walls as readily as on visible ones: on the street and `bistro-night`
// about half of them are occluded. Here every RIS vertex counts, per cell of a world-space
// hash grid (inc/world_grid.glsl) and per light model, how often the shadow ray toward
// the light it kept was unoccluded, and the target becomes
//     p̂'(y) = p̂(y) · v(cell, model(y)),   v = max((hits + 1) / (trials + 1), floor),
// an optimistic estimate (1 for a light never tried) kept at least `floor`
// (FrameParams.visibility_floor), so that p̂' is positive wherever p̂ is.
//
// Why it is unbiased: RIS is unbiased for any target that is positive wherever the
// integrand is, provided the resampling weights and W use the same target and the
// candidates are drawn independently of it. So the counts a vertex reads must not depend
// on its own random numbers: kernels read a snapshot half of the table, which the
// renderer refreshes from the live half (where every vertex adds its count) only between
// dispatches; a dispatch never reads what its own samples learned. The target is then a
// fixed function for each dispatch, the light samples stay unbiased, and the shadow ray
// still decides each sample's visibility: a learned visibility only moves where samples
// go, never what they count.
//
// An entry packs a fingerprint of (cell, model) (12 bits, never 0: 0 is empty), the
// unoccluded count (10 bits) and the trial count (10 bits); both counts are halved when
// the trials reach 1023, so old counts fade. Keys that share a slot evict each other; a
// light whose entry is missing counts as visible.
#ifndef INC_LIGHT_VISIBILITY_GLSL
#define INC_LIGHT_VISIBILITY_GLSL

#include "common.glsl"
#include "scene_data.glsl"
#include "world_grid.glsl"

layout(constant_id = 10) const bool LIGHT_VISIBILITY = false;
layout(set = 0, binding = BINDING_LIGHT_VISIBILITY, scalar) buffer LightVisibilityBuffer { uint light_visibility[]; };
// The snapshot is read once per RIS candidate: through its address on CPU devices, where
// lavapipe gathers it instead of loading lane by lane (inc/scene_data.glsl).
SCENE_REFERENCE(LightVisibilityRef, uint);

const uint VISIBILITY_COUNT_MASK = 1023u;

// The cell of a shading point (its position and geometric normal on the side it was
// seen from): two hash words that visibility_slot mixes with a light model.
uvec2 visibility_cell(vec3 p, vec3 ng) {
    return world_cell_hash(p, ng, vec3(0.0), vec3(0.0), vec2(0.0), params.visibility_cell_pixels).xy;
}

// The table slot (in one half) and the 12-bit fingerprint of (cell, model). The cell's
// words are already well mixed (pcg4d), so one multiply-xorshift round per word mixes
// the model in: this runs for every RIS candidate, so it is kept cheap.
uvec2 visibility_slot(uvec2 cell, uint model) {
    uvec2 h = cell + model * uvec2(0x9e3779b1u, 0x85ebca77u);
    h ^= h >> 15u;
    h *= uvec2(0x2c1b3c6du, 0x297a2d39u);
    h ^= h >> 12u;
    uint tag = h.y >> 20u;
    return uvec2(h.x & (params.visibility_slots - 1u), tag == 0u ? 1u : tag);
}

// The factor v of the light model `model` seen from `cell`, from the snapshot half.
float visibility_factor(uvec2 cell, uint model) {
    if (model == INVALID_INDEX) return 1.0;
    uvec2 slot = visibility_slot(cell, model);
    uint e = SCENE_ADDRESSES ? LightVisibilityRef(params.visibility_address).v[slot.x] : light_visibility[slot.x];
    if ((e >> 20u) != slot.y) return 1.0;
    float trials = float(e & VISIBILITY_COUNT_MASK);
    float hits = float((e >> 10u) & VISIBILITY_COUNT_MASK);
    return max((hits + 1.0) / (trials + 1.0), params.visibility_floor);
}

// Count one shadow ray from `cell` toward a light of `model` into the live half.
void visibility_learn(uvec2 cell, uint model, bool visible) {
    if (model == INVALID_INDEX) return;
    uvec2 slot = visibility_slot(cell, model);
    uint i = params.visibility_slots + slot.x;
    uint e = light_visibility[i];
    // A few tries: a lost race costs one count, never a wrong entry.
    for (uint k = 0u; k < 4u; ++k) {
        uint trials = 0u, hits = 0u;
        if ((e >> 20u) == slot.y) {
            trials = e & VISIBILITY_COUNT_MASK;
            hits = (e >> 10u) & VISIBILITY_COUNT_MASK;
        }
        if (trials == VISIBILITY_COUNT_MASK) {
            trials = (trials + 1u) / 2u;
            hits = (hits + 1u) / 2u;
        }
        trials += 1u;
        if (visible) hits += 1u;
        uint n = (slot.y << 20u) | (hits << 10u) | trials;
        uint seen = atomicCompSwap(light_visibility[i], e, n);
        if (seen == e) break;
        e = seen;
    }
}

#endif
