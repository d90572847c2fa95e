// Training records of the learned BSDF-vs-guide selection probability (layout and
// meaning: GuideSelectionRecord in shared/guiding.h; the optimiser is on the CPU,
// src/guiding/selection.rs). Only the path-tracing kernel binds this buffer.
#ifndef LANTERNA_GUIDING_SELECTION_GLSL
#define LANTERNA_GUIDING_SELECTION_GLSL

#include "guiding_buffers.glsl"

layout(set = 0, binding = BINDING_GUIDE_SELECTION, scalar) buffer GuideSelectionBuffer {
    GuideSelectionHead guide_selection_head;
    GuideSelectionRecord guide_selection[];
};

// Append `r` with probability guide_selection_head.rate (u uniform in [0, 1)): a
// uniform thinning, so the records stay an unbiased sample of the pass's directions.
void guide_selection_record(GuideSelectionRecord r, float u) {
    if (!(u < guide_selection_head.rate)) return;
    // Records without light carry no gradient (as in the reference implementation).
    if (!(r.wo_pdf > 0.0) || !(r.product > 0.0) || isinf(r.product)) return;
    uint i = atomicAdd(guide_selection_head.count, 1u);
    if (i < guide_selection_head.capacity) guide_selection[i] = r;
}

#endif
