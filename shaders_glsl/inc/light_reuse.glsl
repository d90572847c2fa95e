// World-space reuse of RIS light samples between paths (`--light-reuse world`; beyond
// the paper, whose future work names it). Part of the closest-hit side: included by
// closesthit.glsl after its RIS interface (RisContext, RisCandidate, ris_target).
//
// Every RIS vertex of a dispatch writes the reservoir it ended with into a cell of a
// hash grid over the scene (positions quantized to cells of a few pixels' footprint at
// their distance from the camera, split by the geometric normal's dominant axis), with
// the vertex itself: its hit and the direction it was seen from, from which a reader
// rebuilds its Surface and so its target p̂₁. A vertex of a later dispatch near that
// cell combines its own reservoir (canonical: y₀, W₀, p̂) with that one (y₁, W₁) by
// generalized RIS (Lin et al. 2022) with the identity shift: a light point is the same
// point whoever sampled it, and
//     m₀(y) = c₀·p̂(y) / (c₀·p̂(y) + c₁·p̂₁(y)),   m₁(y) = c₁·p̂₁(y) / (c₀·p̂(y) + c₁·p̂₁(y)),
//     w_i = m_i(y_i)·p̂(y_i)·W_i,   y = y_i with probability w_i / Σw,   W = Σw / p̂(y).
// The weights sum to one for every light point, and m₁ is positive only where p̂₁ is,
// where the writer's reservoir can hold the point (its RIS draws from the whole
// source), so W is again an unbiased contribution weight, with no visibility in either
// target: the shadow ray toward the kept point decides, as for RIS alone. c₀ = 1 and c₁
// is the number of canonical reservoirs the cell's reservoir stands for, capped
// (FrameParams.reuse_confidence_cap), which bounds how far old samples outweigh new.
//
// Unbiasedness needs the reused reservoir to be independent of the vertex reading it.
// So a dispatch reads only the half of the grid that earlier dispatches wrote and writes
// the other (the renderer swaps them per range of samples and renders one sample per
// dispatch with reuse): nothing a path does can come back to it. Every RIS vertex
// writes, found a light or not, and a cell keeps the writer with the highest ticket, a
// hash of the vertex that does not depend on its reservoir's values, so that no
// reservoir is kept for what it holds. Two writers whose tickets both lead when they
// write can interleave their words; the checksum turns such a torn cell into an empty
// one.
#ifndef INC_LIGHT_REUSE_GLSL
#define INC_LIGHT_REUSE_GLSL

#include "common.glsl"
#include "scene_data.glsl"
#include "random.glsl"
#include "debug.glsl"
#include "trace.glsl"
#include "material.glsl"
#include "lights.glsl"
#include "ris.glsl"
#include "world_grid.glsl"
#include "light_visibility.glsl"

layout(constant_id = 9) const bool LIGHT_REUSE = false;
layout(set = 0, binding = BINDING_REUSE_CELLS, scalar) buffer ReuseCellBuffer { ReuseCell reuse_cells[]; };
// The same buffer as 64-bit words: the word at index 8·cell + 7 is the cell's ticket
// (ReuseCell.ticket_lo/hi, bytes 56–63 of its 64).
layout(set = 0, binding = BINDING_REUSE_CELLS, scalar) buffer ReuseTicketBuffer { uint64_t reuse_tickets[]; };

// The cell of shading point p with geometric normal ng (on the side it was seen from),
// moved by `jitter` cell edges along the tangents t and b (inc/world_grid.glsl): x its
// index in a half of the grid, y its fingerprint (never 0, which marks empty).
uvec2 reuse_cell_of(vec3 p, vec3 ng, vec3 t, vec3 b, vec2 jitter) {
    uvec4 h = world_cell_hash(p, ng, t, b, jitter, params.reuse_cell_pixels);
    return uvec2(h.x & (params.reuse_cells - 1u), h.y | 1u);
}

uint reuse_checksum(ReuseCell c) {
    uvec4 h = pcg4d(uvec4(c.key, c.instance, c.primitive, c.light));
    h = pcg4d(h ^ uvec4(floatBitsToUint(c.bary), floatBitsToUint(c.light_bary)));
    h = pcg4d(h ^ uvec4(floatBitsToUint(c.wo), floatBitsToUint(c.weight)));
    h = pcg4d(h ^ uvec4(floatBitsToUint(c.confidence), 0u, 0u, 0x7e05eu));
    return h.x;
}

// A stored light (ReuseCell.light, with barycentrics b on a triangle) seen from x, with
// the emission RIS's target uses (the record's stand-in on textured emitters and IES
// lights).
LightSample reuse_light_at(uint light, vec2 b, vec3 x) {
    if ((light & REUSE_PUNCTUAL) != 0u) {
        uint model = light & ~REUSE_PUNCTUAL;
        LightSample s = sample_punctual(light_models(model).punctual, x, false);
        s.model = model;
        return s;
    }
    return light_point(light_candidates(light), light, light_triangles(light).model, b, x, false);
}

RisCandidate reuse_candidate(LightSample ls) {
    RisCandidate c;
    c.ls = ls;
    c.f = vec3(0.0);
    c.bsdf_pdf = 0.0;
    c.from_direction = false;
    c.direction_pdf = 0.0;
    return c;
}

// Combine the canonical RIS result `res` of the vertex (ctx; its hit `s_hit`) with the
// reservoir of its cell in the read half, and write the outcome to the write half.
// `extra_bary`: barycentrics of the direction candidate's point on its light triangle
// (the reservoir stores light points by triangle and barycentrics). On return `res` is
// the combined reservoir: its y (f cached at this vertex), p̂(y) and W.
void reuse_resample(RisContext ctx, Hit s_hit, vec2 extra_bary, inout RisResult res, inout Rng rng) {
    // The vertex writes its own cell and reads one within half a cell's edge of it in
    // the tangent plane: successive samples of a pixel then read different neighbours'
    // reservoirs (at 256 spp on lavapipe: `cornell-lights` 1.03 → 0.99× `ris`'s MAE,
    // the streets within ±0.02; README, "World-space light reuse").
    uvec2 cell = reuse_cell_of(ctx.s.p, ctx.s.ng, ctx.s.t, ctx.s.b, vec2(0.0));
    uvec2 read_cell = reuse_cell_of(ctx.s.p, ctx.s.ng, ctx.s.t, ctx.s.b, rng_next2(rng) - 0.5);
    uint light = INVALID_INDEX;
    vec2 light_bary = vec2(0.0);
    if (res.found) {
        if (res.y.ls.area) {
            light = res.y.ls.tri;
            light_bary = res.extra_chosen ? extra_bary : res.y.ls.bary;
        } else {
            light = REUSE_PUNCTUAL | res.y.ls.model;
        }
    }
    float confidence = 1.0;
    ReuseCell n = reuse_cells[pc.reuse_read + read_cell.x];
    if (n.key == read_cell.y && n.check == reuse_checksum(n)) {
        float c1 = min(n.confidence, params.reuse_confidence_cap);
        confidence += c1;
        // The writer's shading point and its target p̂₁ (ris_target reads s and d.bsdf).
        Hit h1;
        h1.valid = true;
        h1.instance = n.instance;
        h1.primitive = n.primitive;
        h1.bary = n.bary;
        h1.t = 0.0;
        RisContext ctx1;
        ctx1.s = make_surface(h1, -n.wo);
        ctx1.d.bsdf = surface_bsdf_at(ctx1.s);
        ctx1.vis_cell = LIGHT_VISIBILITY ? visibility_cell(ctx1.s.p, ctx1.s.ng) : uvec2(0u);
        float w0 = 0.0;
        if (res.found && res.W > 0.0) {
            RisCandidate y0_there = reuse_candidate(reuse_light_at(light, light_bary, ctx1.s.p));
            float p1 = ris_target(ctx1, y0_there);
            w0 = res.p_hat * res.p_hat * res.W / (res.p_hat + c1 * p1);
        }
        float w1 = 0.0;
        RisCandidate y1;
        float p_hat1 = 0.0;
        if (n.light != INVALID_INDEX && n.weight > 0.0) {
            y1 = reuse_candidate(reuse_light_at(n.light, n.light_bary, ctx.s.p));
            p_hat1 = ris_target(ctx, y1);
            RisCandidate y1_there = reuse_candidate(reuse_light_at(n.light, n.light_bary, ctx1.s.p));
            float p11 = ris_target(ctx1, y1_there);
            float den = p_hat1 + c1 * p11;
            if (den > 0.0) w1 = c1 * p11 * p_hat1 * n.weight / den;
        }
        float w_sum = w0 + w1;
        TRACE5("  reuse: cell %u confidence %f w0=%f w1=%f (neighbour light %u)\n", cell.x, c1, w0, w1, n.light);
        if (w1 > 0.0 && rng_next(rng) * w_sum < w1) {
            res.y = y1;
            res.p_hat = p_hat1;
            res.extra_chosen = false;
            light = n.light;
            light_bary = n.light_bary;
        }
        res.found = w_sum > 0.0 && res.p_hat > 0.0;
        res.W = res.found ? w_sum / res.p_hat : 0.0;
        if (!res.found) light = INVALID_INDEX;
    }
    ReuseCell o;
    o.key = cell.y;
    o.instance = s_hit.instance;
    o.primitive = s_hit.primitive;
    o.light = light;
    o.bary = s_hit.bary;
    o.light_bary = light_bary;
    o.wo = ctx.s.wo;
    o.weight = res.found ? res.W : 0.0;
    o.confidence = min(confidence, params.reuse_confidence_cap);
    o.ticket_lo = 0u;
    o.ticket_hi = 0u;
    o.check = reuse_checksum(o);
    // Which of a cell's writers it keeps: the one with the highest ticket, this
    // dispatch's generation over a hash of the vertex (its pixel, sample and depth). The
    // device's order would keep the last, the same pixel's every sample on a device that
    // runs workgroups in order, and chain a pixel's samples to one writer's reservoirs
    // (per-pixel variance of `ris` with reuse on a small street's direct light: 0.97× that
    // of `ris` alone with one lavapipe thread, 0.88× with two, 0.97–0.99× with four or
    // eight). The ticket does not depend on the reservoir, so neither does the choice.
    uint slot = pc.reuse_write + cell.x;
    uint64_t ticket = pack64(uvec2(pcg4d(uvec4(rng.key, rng.vertex ^ 0x71c4e7u)).x, pc.reuse_generation));
    if (atomicMax(reuse_tickets[8u * slot + 7u], ticket) < ticket) {
        // Word by word, leaving the ticket as the atomic left it.
        reuse_cells[slot].key = o.key;
        reuse_cells[slot].instance = o.instance;
        reuse_cells[slot].primitive = o.primitive;
        reuse_cells[slot].light = o.light;
        reuse_cells[slot].bary = o.bary;
        reuse_cells[slot].light_bary = o.light_bary;
        reuse_cells[slot].wo = o.wo;
        reuse_cells[slot].weight = o.weight;
        reuse_cells[slot].confidence = o.confidence;
        reuse_cells[slot].check = o.check;
    }
}

#endif
