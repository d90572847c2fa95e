// Streaming weighted reservoir sampling (one item): after a stream of candidates with
// weights w_i, the kept candidate is x_i with probability w_i / Σw. The candidate is
// replaced when u < w_i / w_sum — the paper's Algorithm 1, line 10, has the comparison
// reversed; this is the correct form. The payload is kept by the caller.
#ifndef INC_RESERVOIR_GLSL
#define INC_RESERVOIR_GLSL

#include "common.glsl"

struct Reservoir {
    float w_sum;    // sum of the candidates' resampling weights
    uint count;     // candidates seen (M)
};

Reservoir reservoir_empty() { return Reservoir(0.0, 0u); }

// Stream one candidate of weight w (≥ 0); returns true when it becomes the kept one.
bool reservoir_update(inout Reservoir r, float w, float u) {
    r.count += 1u;
    if (!(w > 0.0)) return false;
    r.w_sum += w;
    return u * r.w_sum < w;
}

#endif
