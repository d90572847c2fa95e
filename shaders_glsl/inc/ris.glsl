// Resampled importance sampling (Talbot et al. 2005) in one streaming pass, generalised
// to candidates from several strategies (Lin et al. 2022's GRIS with balance-heuristic
// resampling weights).
//
// Written against a small interface that the including file defines first:
//   struct RisContext;                         the shading point
//   struct RisCandidate;                       a candidate (payload kept by the reservoir)
//   RisCandidate ris_draw(RisContext ctx, vec4 u);   the draw from the source q that the
//        uniform numbers u make (a pure function of u: see below)
//   float ris_target(RisContext ctx, inout RisCandidate c);     target p̂(c) ≥ 0
//   float ris_denominator(RisContext ctx, RisCandidate c, uint M);
//        Σ over candidate slots of their source densities at c: M·q(c) for M light
//        candidates, plus q_extra(c) when an extra candidate takes part.
//   void ris_keep_target(inout RisCandidate into, RisCandidate c);
//        copies what ris_target cached in c into `into` (the same candidate)
// ris_target is called on a candidate before ris_denominator, which may use what the
// former cached in it.
// A candidate's resampling weight is w = p̂ / denominator; the selected y gets the
// contribution weight W = Σw / p̂(y), so f(y)·W is an unbiased estimate of ∫f. With no
// extra candidate this is the paper's w = p̂/q and W = (Σw/M)/p̂(y).
//
// The reservoir keeps the kept candidate's four numbers, not the candidate: the one it
// ends with is drawn again from them after the stream (ris_draw and ris_target are
// deterministic, so it is the same candidate with the same p̂). Carrying a whole
// candidate through the loop (a light sample, f and its pdf: ~24 values selected per
// candidate) made `ris` 3–7 % slower on lavapipe.
#ifndef INC_RIS_GLSL
#define INC_RIS_GLSL

#include "random.glsl"
#include "reservoir.glsl"

#include "debug.glsl"

struct RisResult {
    RisCandidate y;     // the kept candidate
    float p_hat;        // p̂(y)
    float W;            // contribution weight Σw / p̂(y) (0 when nothing was kept)
    bool found;
    bool extra_chosen;  // the extra candidate was kept
};

// With strata_offset in [0, 1), candidate i's first number u.x is drawn in stratum i of
// [0, 1) rotated by the offset, fract(offset + (i + ξ)/M): each candidate's u.x is still
// uniform (the offset is), so the estimate stays unbiased (its expectation is the mean
// over candidates of E[f(x_i)/q(x_i)] whatever their joint distribution), while the M
// candidates cover the range of u.x evenly. A negative offset draws them independently.
RisResult ris_resample(RisContext ctx, uint M, inout Rng rng, bool has_extra, RisCandidate extra,
                       float strata_offset) {
    Reservoir r = reservoir_empty();
    RisResult res;
    res.found = false;
    res.extra_chosen = false;
    res.p_hat = 0.0;
    uint slots = M;
    vec4 u_kept = vec4(0.0);
    // The extra candidate takes the stream's last slot, M, in the same loop body as the
    // light candidates, so that ris_target and ris_denominator are inlined once for both
    // (the driver's compile time grows faster than the kernel's size). Each slot draws a
    // light candidate and the extra one replaces it by a select, not a branch: a branch
    // would merge the whole candidate at its end, which costs SIMD devices a masked copy
    // of it in every slot. What the stream keeps of the extra candidate is what
    // ris_target adds to it. (The extra slot's draw is wasted and takes no numbers.)
    uint n = M + (has_extra ? 1u : 0u);
    for (uint i = 0u; i < n; ++i) {
        bool is_extra = i == M;
        vec4 u = vec4(0.0);
        if (!is_extra) {
            u = rng_next4(rng);
            if (strata_offset >= 0.0) u.x = fract(strata_offset + (float(i) + u.x) / float(M));
        }
        RisCandidate drawn = ris_draw(ctx, u);
        RisCandidate c = is_extra ? extra : drawn;
        float p = ris_target(ctx, c);
        float w = p > 0.0 ? p / ris_denominator(ctx, c, slots) : 0.0;
        bool kept = reservoir_update(r, w, rng_next(rng));
        TRACE4("    candidate %u: p_hat=%f w=%f kept=%u\n", i, p, w, uint(kept));
        if (is_extra) ris_keep_target(extra, c);
        if (kept) {
            u_kept = u;
            res.p_hat = p;
            res.found = true;
            res.extra_chosen = is_extra;
        }
    }
    if (res.extra_chosen) {
        res.y = extra;
    } else if (res.found) {
        res.y = ris_draw(ctx, u_kept);
        ris_target(ctx, res.y);  // f and its pdf for the caller; p̂ is the one kept above
    }
    res.W = res.found && res.p_hat > 0.0 ? r.w_sum / res.p_hat : 0.0;
    return res;
}

#endif
