// Closest-hit part of the path tracer (OptiX-style): what happens at a surface.
// Turning a hit into a Surface (inc/material.glsl), choosing the next direction from the
// one-sample MIS mixture of BSDF and guiding distributions, and next-event estimation
// with either the source distribution directly (`pt`, power-heuristic MIS) or RIS.
//
// MIS between NEE and emission found by direction sampling:
//  * NEE_UNIFORM: classic two-strategy power heuristic; the light density of a point is
//    its source density converted to solid angle.
//  * NEE_RIS: the exact density of a RIS-selected light is not available, so instead the
//    direction sample at this vertex is fed to RIS as one extra candidate (as RTXDI
//    does). With balance-heuristic resampling weights over all M + 1 candidate slots the
//    RIS estimate alone accounts for all direct light from emitters that NEE can sample;
//    emission hit by the direction sample then adds nothing on its own. Every path is
//    counted exactly once and the resampling weights form a partition of unity.
#ifndef CLOSESTHIT_GLSL
#define CLOSESTHIT_GLSL

#include "inc/common.glsl"
#include "inc/specialization.glsl"
#include "inc/random.glsl"
#include "inc/sampling.glsl"
#include "inc/scene_data.glsl"
#include "inc/debug.glsl"
#include "inc/geometry.glsl"
#include "inc/trace.glsl"
#include "inc/bsdf.glsl"
#include "inc/material.glsl"
#include "inc/guiding.glsl"
#include "inc/lights.glsl"
#include "inc/reservoir.glsl"
#include "inc/light_visibility.glsl"

// ---- direction sampling: BSDF / guiding mixture -----------------------------------------

struct DirectionSampler {
    BsdfWo bsdf;           // the BSDF's terms that depend on wo alone
    float bsdf_fraction;   // probability of sampling the BSDF (1: no guiding here)
    uint leaf;             // SD-tree leaf of the vertex
    LightContext lights;   // light selection at the vertex (NEE, RIS, MIS weights)
};

struct DirectionSample {
    vec3 wi;
    vec3 weight;   // f·cos / pdf
    float pdf;     // mixture pdf (solid angle)
    float bsdf_pdf;   // its two parts: the BSDF's pdf of wi,
    float guide_pdf;  // and the leaf quadtree's (0 where the vertex is not guided)
    bool valid;
    bool guided;   // drawn from the SD-tree rather than the BSDF
};

DirectionSampler direction_sampler(Surface s) {
    DirectionSampler d;
    d.bsdf = surface_bsdf_at(s);
    d.bsdf_fraction = 1.0;
    d.leaf = INVALID_INDEX;
    if (GUIDING) {
        // Nearly specular lobes (reflection or transmission) are not guided: the BSDF
        // already samples them well.
        float diffuse_prob = bsdf_diffuse_probability(s.bsdf, d.bsdf);
        bool nearly_specular = s.bsdf.alpha < GUIDING_MIN_ALPHA && diffuse_prob <= 0.1;
        if (!nearly_specular) {
            d.leaf = guide_find_leaf(s.p);
            // Learned per leaf (Müller et al. 2019), or the fixed --bsdf-fraction.
            d.bsdf_fraction = (guide_header.flags & GUIDE_FLAG_LEARN_SELECTION) != 0u
                ? guide_leaves(d.leaf).bsdf_fraction
                : guide_header.bsdf_fraction;
            // A nearly specular transmission lobe beside a diffuse one (a clear pane in a
            // partly diffuse material, or a solid's clear interface): the quadtree cannot
            // find it, so the BSDF keeps at least its share of the samples. (Measured on glass.gltf's half-transmitting
            // partition: without it, the lamp seen through it at 64 spp is a few rare,
            // large samples.) Opaque glossy surfaces keep the selection they had.
            if (s.bsdf.alpha < GUIDING_MIN_ALPHA)
                d.bsdf_fraction = max(d.bsdf_fraction, bsdf_glass_probability(s.bsdf, d.bsdf));
        }
    }
    d.lights = light_context(s.p, surface_transmits(s) ? vec3(0.0) : s.ng, d.leaf);
    return d;
}

// Guided directions are folded onto the upper hemisphere of the geometric normal where
// the surface is opaque. There the BSDF is zero below s.ng, and a leaf's quadtree covers
// the whole sphere (a leaf holds surfaces of many orientations), so a quadtree sample
// below the surface would be wasted; it is reflected about the tangent plane instead.
// Reflection preserves solid angle, so the folded density is q(wi) + q(reflected wi)
// above the surface and zero below: still normalised, and exact. A transmitting
// surface (surface_transmits) takes the quadtree's directions as they are.
vec3 fold_above(Surface s, vec3 w) {
    float c = dot(w, s.ng);
    return c < 0.0 && !surface_transmits(s) ? w - 2.0 * c * s.ng : w;
}

float guide_pdf_folded(Surface s, uint leaf, vec3 wi) {
    if (surface_transmits(s)) return guide_pdf(leaf, wi);
    float c = dot(wi, s.ng);
    if (c <= 0.0) return 0.0;
    return guide_pdf(leaf, wi) + guide_pdf(leaf, wi - 2.0 * c * s.ng);
}

// Mixture pdf of wi given the BSDF's pdf of it, with the (folded) quadtree's pdf it
// mixes in.
float direction_pdf_mix(Surface s, DirectionSampler d, vec3 wi, float bsdf_pdf, out float tree_pdf) {
    tree_pdf = d.bsdf_fraction < 1.0 ? guide_pdf_folded(s, d.leaf, wi) : 0.0;
    float p = d.bsdf_fraction * bsdf_pdf;
    if (d.bsdf_fraction < 1.0) p += (1.0 - d.bsdf_fraction) * tree_pdf;
    return p;
}

// The direction strategy's density as RIS's resampling weights see it: the BSDF part
// exact, the guided part replaced by the uniform density over the upper hemisphere
// (where the folded guided density lives; the sphere where the surface transmits), so
// that the M light
// candidates do not each walk the leaf's quadtree. Balance-heuristic weights built from
// any such stand-in still sum to one over the strategies, so RIS stays unbiased as long
// as the direction candidate's weight divides by its true density (ris_denominator).
// `bsdf_pdf` is the BSDF's density of the candidate's direction `wi`.
float direction_pdf_for_ris(Surface s, DirectionSampler d, vec3 wi, float bsdf_pdf) {
    float p = d.bsdf_fraction * bsdf_pdf;
    if (d.bsdf_fraction < 1.0) {
        if (surface_transmits(s)) p += (1.0 - d.bsdf_fraction) * INV_FOUR_PI;
        else if (dot(wi, s.ng) > 0.0) p += (1.0 - d.bsdf_fraction) * INV_TWO_PI;
    }
    return p;
}

// A uniform number u that chose between two ranges at p (u < p or u ≥ p), rescaled to a
// uniform number in [0, 1) within the range it fell in.
float reuse_choice(float u, float p, bool upper) {
    float r = upper ? (u - p) / max(1.0 - p, 1e-30) : u / max(p, 1e-30);
    return clamp(r, 0.0, 0.99999994);
}

// The direction of the vertex's sample, without its value: wi, and whether the tree or
// the BSDF drew it (valid false where the BSDF could not sample). direction_complete
// adds the value once the BSDF has been evaluated at wi.
DirectionSample direction_choose(Surface s, DirectionSampler d, inout Rng rng) {
    DirectionSample ds;
    ds.pdf = 0.0;
    ds.bsdf_pdf = 0.0;
    ds.guide_pdf = 0.0;
    ds.weight = vec3(0.0);
    ds.valid = true;
    // Both choices (BSDF or guided, then the BSDF's lobe) are made on the warp's first
    // number, which is then rescaled to [0, 1) within the chosen range: the samples of a
    // pixel that take one strategy or lobe are then themselves stratified, as they would
    // not be with the choice drawn independently of the warp.
    vec2 warp = rng_stratified2(rng, RNG_PAIR_DIRECTION);
    ds.guided = warp.x >= d.bsdf_fraction;
    warp.x = reuse_choice(warp.x, d.bsdf_fraction, ds.guided);
    float lobe = warp.x;  // bsdf_sample takes the specular lobe when lobe < spec_prob
    warp.x = reuse_choice(warp.x, d.bsdf.spec_prob, lobe >= d.bsdf.spec_prob);
    vec3 u = vec3(lobe, warp);
    if (!ds.guided) {
        vec3 wi_local;
        // A solid's boundary chooses between reflection and refraction after drawing its
        // microfacet normal, with a number of its own; a coat and a sheen are chosen with
        // it too.
        float u_fresnel = s.bsdf.eta > 0.0 || d.bsdf.coat_prob > 0.0 || d.bsdf.sheen_prob > 0.0 ? rng_next(rng) : 0.0;
        ds.valid = surface_bsdf_sample(s, d.bsdf, u, u_fresnel, wi_local);
        ds.wi = ds.valid ? surface_to_world(s, wi_local) : s.n;
    } else {
        float unused_pdf;
        ds.wi = fold_above(s, guide_sample(d.leaf, u.yz, unused_pdf));  // the warp pair
    }
    return ds;
}

// The sample's value from the BSDF's f·cos and density at ds.wi and the mixture's
// density there (direction_pdf_mix).
void direction_complete(inout DirectionSample ds, DirectionSampler d, vec3 f, float bsdf_pdf, float pdf, float tree_pdf) {
    ds.bsdf_pdf = bsdf_pdf;
    ds.pdf = pdf;
    ds.guide_pdf = tree_pdf;
    ds.valid = ds.pdf > 0.0 && max3(f) > 0.0;
    ds.weight = ds.valid ? f / ds.pdf : vec3(0.0);
    TRACE6("  direction (guided=%u) wi=%v3f pdf=%f (bsdf pdf %f, guide share %f) weight=%v3f\n", uint(ds.guided),
           ds.wi, ds.pdf, ds.bsdf_pdf, 1.0 - d.bsdf_fraction, ds.weight);
}

DirectionSample sample_direction(Surface s, DirectionSampler d, inout Rng rng) {
    DirectionSample ds = direction_choose(s, d, rng);
    if (!ds.valid) return ds;
    float bsdf_pdf, tree_pdf;
    vec3 f = surface_bsdf_eval_pdf(s, d.bsdf, ds.wi, bsdf_pdf);
    float pdf = direction_pdf_mix(s, d, ds.wi, bsdf_pdf, tree_pdf);
    direction_complete(ds, d, f, bsdf_pdf, pdf, tree_pdf);
    return ds;
}

// ---- next-event estimation ----------------------------------------------------------------

// What NEE contributes at a vertex, and what it tells the guiding records.
struct NeeResult {
    vec3 contribution;   // radiance toward wo (not multiplied by the path throughput)
    vec3 record_dir;     // direction of the light sample
    float record_value;  // mean-RGB incident radiance / pdf along record_dir (0: none)
    float record_pdf;    // solid-angle pdf of record_dir, as the record's value divides by
    uint chosen_model;   // light model NEE picked (AOV), INVALID_INDEX if none
    uvec2 vis_cell;      // RIS's cell of learned light visibility (LIGHT_VISIBILITY)
    bool connected;      // the shadow ray found the light visible
    float ris_weight;    // RIS contribution weight W (0 without RIS)
    // The shadow ray that decides it, when one does: the path loop traces it (raygen's
    // one trace_ray call site) and passes the answer to nee_resolve.
    bool needs_shadow_ray;
    Ray shadow;
};

NeeResult nee_none() {
    NeeResult r;
    r.contribution = vec3(0.0);
    r.record_dir = vec3(0.0);
    r.record_value = 0.0;
    r.record_pdf = 0.0;
    r.chosen_model = INVALID_INDEX;
    r.vis_cell = uvec2(0u);
    r.connected = false;
    r.ris_weight = 0.0;
    r.needs_shadow_ray = false;
    r.shadow = Ray(vec3(0.0), vec3(0.0), 0.0);
    return r;
}

// Light carried over distance t through a medium of absorption coefficient σ.
vec3 transmittance(vec3 sigma, float t) { return exp(-sigma * t); }

// NEE's contribution, and its record, seen through a medium of absorption `sigma` over
// the distance to the light (solids' interiors, KHR_materials_volume).
void nee_absorb(inout NeeResult r, vec3 sigma, float dist) {
    if (max3(sigma) <= 0.0) return;
    vec3 tr = transmittance(sigma, dist);
    r.contribution *= tr;
    r.record_value *= (tr.x + tr.y + tr.z) / 3.0;
}

// The NEE result once its shadow ray is answered: it counts only when the light is
// visible. (Results whose visibility is known, or that found nothing, pass unchanged.)
void nee_resolve(inout NeeResult r, bool visible) {
    if (!r.needs_shadow_ray || visible) return;
    r.connected = false;
    r.contribution = vec3(0.0);
    r.record_dir = vec3(0.0);
    r.record_value = 0.0;
    r.record_pdf = 0.0;
}

// The shadow ray that decides whether the light point of `ls` is visible from the
// surface point; the result counts as connected until nee_resolve hears otherwise. The
// origin moves off the surface on the side of the light (the side of wo unless the
// surface transmits: an opaque BSDF is zero toward lights below it), the far end off the
// light toward the shading point (segment_between in inc/trace.glsl).
void shadow_ray(Surface s, LightSample ls, inout NeeResult r) {
    r.needs_shadow_ray = true;
    r.connected = true;
    vec3 side = surface_side_normal(s, ls.wi);
    if (ls.dist >= FLT_MAX) r.shadow = ray_to_infinity(s.p, side, ls.wi);
    else if (!ls.area) r.shadow = segment_to_point(s.p, side, ls.p);
    else r.shadow = segment_between(s.p, side, ls.p, ls.n);
}

// NEE with the source distribution, in two halves around the BSDF's evaluation at the
// light sample's direction (sample_vertex evaluates it). nee_single_choose draws the light
// sample; it returns whether the BSDF is needed there (a light with positive pdf and
// emission toward the vertex).
bool nee_single_choose(Surface s, DirectionSampler d, inout Rng rng, out NeeResult r, out LightSample ls) {
    r = nee_none();
    if (params.strategy == STRATEGY_BSDF_ONLY) return false;
    vec4 u = vec4(rng_stratified2(rng, RNG_PAIR_LIGHT), rng_stratified2(rng, RNG_PAIR_LIGHT_POINT));
    ls = sample_light(d.lights, u, true);
    r.chosen_model = ls.model;
    return ls.pdf > 0.0 && max3(ls.Le_G) > 0.0;
}

// Whether NEE's MIS weight needs the direction mixture's density at the light sample.
bool nee_single_needs_mix(LightSample ls) { return ls.area && params.strategy == STRATEGY_MIS; }

// The light sample's contribution, MIS-weighted against direction sampling (power
// heuristic; `mix_pdf` is the direction mixture's density at ls.wi), as if the light
// were visible, and the shadow ray that decides it. `f` is the BSDF's f·cos toward ls.wi.
// `medium`: the absorption where the path reached s (raygen's path state), which the
// light is seen through unless the shadow ray crosses into a solid or out of it.
void nee_single_complete(inout NeeResult r, Surface s, LightSample ls, vec3 f, float mix_pdf, vec3 medium) {
    if (max3(f) <= 0.0) return;
    float w = 1.0;
    if (nee_single_needs_mix(ls)) {
        float p_light = ls.pdf * ls.dist * ls.dist / max(ls.cos_y, 1e-12);
        w = power_heuristic(p_light, mix_pdf);
    }
    shadow_ray(s, ls, r);
    TRACE5("  nee light model %u tri %u pdf=%f mis=%f f=%v3f\n", r.chosen_model, ls.tri, ls.pdf, w, f);
    vec3 Li_over_pdf = ls.Le_G * (w / ls.pdf);
    r.contribution = f * Li_over_pdf;
    TRACE1("  nee contribution if visible=%v3f\n", r.contribution);
    if (ls.area) {
        r.record_dir = ls.wi;
        r.record_value = (Li_over_pdf.x + Li_over_pdf.y + Li_over_pdf.z) / 3.0;
        r.record_pdf = ls.pdf * ls.dist * ls.dist / max(ls.cos_y, 1e-12);
    }
    nee_absorb(r, medium_toward(s, ls.wi, medium), ls.dist);
}

// `pt` and `guided` (NEE with the source distribution): a vertex's direction sample and
// its NEE light sample, drawn as sample_direction and a one-sample NEE would draw them,
// with both BSDF evaluations, and both mixture densities, through one two-iteration
// loop. The kernel then holds one inlined copy of each instead of two; lavapipe's cold
// compile grows faster than the code (bench/README.md, "where a cold kernel compile
// goes"). NEE does not depend on where the direction sample's ray lands, so both are
// known here; raygen traces the direction ray, then NEE's shadow ray.
void sample_vertex(Surface s, DirectionSampler d, vec3 medium, inout Rng rng, out DirectionSample ds, out NeeResult nee) {
    ds = direction_choose(s, d, rng);
    LightSample ls;
    bool nee_eval = nee_single_choose(s, d, rng, nee, ls);
    vec3 f_dir = vec3(0.0), f_nee = vec3(0.0);
    float bsdf_pdf_dir = 0.0, mix_dir = 0.0, tree_dir = 0.0, mix_nee = 0.0;
    [[dont_unroll]] for (uint j = 0u; j < 2u; ++j) {
        bool dir = j == 0u;
        if (dir ? !ds.valid : !nee_eval) continue;
        vec3 wi = dir ? ds.wi : ls.wi;
        float bsdf_pdf, tree_pdf = 0.0;
        vec3 f = surface_bsdf_eval_pdf(s, d.bsdf, wi, bsdf_pdf);
        float mix = 0.0;
        if (dir || (max3(f) > 0.0 && nee_single_needs_mix(ls))) mix = direction_pdf_mix(s, d, wi, bsdf_pdf, tree_pdf);
        if (dir) {
            f_dir = f;
            bsdf_pdf_dir = bsdf_pdf;
            mix_dir = mix;
            tree_dir = tree_pdf;
        } else {
            f_nee = f;
            mix_nee = mix;
        }
    }
    if (ds.valid) direction_complete(ds, d, f_dir, bsdf_pdf_dir, mix_dir, tree_dir);
    if (nee_eval) nee_single_complete(nee, s, ls, f_nee, mix_nee, medium);
}

// RIS over the scene's lights, implementing the interface of inc/ris.glsl.
struct RisContext {
    Surface s;
    DirectionSampler d;
    uvec2 vis_cell;  // the shading point's cell of learned light visibility (LIGHT_VISIBILITY)
};

// The RIS context of shading point s.
RisContext ris_context(Surface s, DirectionSampler d) {
    return RisContext(s, d, LIGHT_VISIBILITY ? visibility_cell(s.p, s.ng) : uvec2(0u));
}

struct RisCandidate {
    LightSample ls;    // Le_G: the target's emission (see ris_target)
    vec3 f;            // BSDF f·cos toward ls.wi, cached by ris_target
    float bsdf_pdf;    // the BSDF's density of ls.wi, cached by ris_target
    bool from_direction;
    float direction_pdf;  // the direction candidate's true density (its sample's mixture pdf)
};

RisCandidate ris_draw(RisContext ctx, vec4 u) {
    RisCandidate c;
    c.ls = sample_light(ctx.d.lights, u, false);
    c.f = vec3(0.0);
    c.bsdf_pdf = 0.0;
    c.from_direction = false;
    c.direction_pdf = 0.0;
    return c;
}

// The target p̂ = luminance(f·Le·G), where Le is the emitted radiance, except on textured
// emitters: there Le is the material's emission times the texture's mean luminance over
// the triangle (LightCandidateTriangle.emission), so that no candidate samples a texture.
// RIS is unbiased for any target that is positive wherever the integrand is (here: the
// emission factor is positive wherever the textured emission is) as long as the
// resampling weights and W use the same p̂ — both come from this function, for the light
// candidates and the direction candidate alike — and the kept candidate's contribution
// uses its true emission (nee_ris, light_sample_complete). For untextured emitters Le is
// exact. The BSDF's wo terms come from the vertex (ctx.d.bsdf), so a candidate costs only
// its own direction's part; f and its pdf are kept for the contribution and
// ris_denominator.
float ris_target(RisContext ctx, inout RisCandidate c) {
    c.f = surface_bsdf_eval_pdf(ctx.s, ctx.d.bsdf, c.ls.wi, c.bsdf_pdf);
    float p = luminance(c.f * c.ls.Le_G);
    // Learned light visibility (inc/light_visibility.glsl): a factor in [floor, 1] per
    // light model, fixed for the dispatch.
    if (LIGHT_VISIBILITY && p > 0.0) p *= visibility_factor(ctx.vis_cell, c.ls.model);
    return p;
}

void ris_keep_target(inout RisCandidate into, RisCandidate c) {
    into.f = c.f;
    into.bsdf_pdf = c.bsdf_pdf;
}

// Source densities of all candidate slots at c, in the candidate's measure: area for
// area lights (direction pdf converted with cosθy/d²), pmf for punctual lights (which
// direction sampling cannot produce). The direction slot's density is the stand-in of
// direction_pdf_for_ris; the direction candidate itself is further scaled by its true
// density over the stand-in, so that its weight is m_direction·p̂/q_direction. (Its
// ls.pdf is the light source's density of its point and its direction_pdf the mixture
// density its direction was sampled with, both set by nee_ris: the loop that calls this
// for every candidate walks no table or quadtree for them.)
float ris_denominator(RisContext ctx, RisCandidate c, uint M) {
    float denominator = float(M) * c.ls.pdf;
    // The direction candidate only exists for area lights under MIS.
    if (c.ls.area && params.strategy == STRATEGY_MIS) {
        float stand_in = direction_pdf_for_ris(ctx.s, ctx.d, c.ls.wi, c.bsdf_pdf);
        denominator += stand_in * c.ls.cos_y / max(c.ls.dist * c.ls.dist, 1e-20);
        if (c.from_direction && ctx.d.bsdf_fraction < 1.0 && stand_in > 0.0) {
            denominator *= c.direction_pdf / stand_in;
        }
    }
    return denominator;
}

#include "inc/ris.glsl"
#include "inc/light_reuse.glsl"

// RIS-selected light. `ds` is this vertex's direction sample and `next` the surface it
// hit (valid when hit_next, at barycentrics next_bary of its triangle); an emitter there
// joins as the extra candidate. `s_hit` is the hit that made s (world-space light reuse
// stores it).
NeeResult nee_ris(Surface s, Hit s_hit, DirectionSampler d, DirectionSample ds, bool hit_next, Surface next, float next_t,
                  vec2 next_bary, vec3 medium, inout Rng rng) {
    NeeResult r = nee_none();
    if (params.strategy == STRATEGY_BSDF_ONLY) return r;
    d.lights = light_context_for_ris(d.lights);
    RisContext ctx = ris_context(s, d);
    RisCandidate extra;
    // Emitters NEE cannot sample (not in the light table) stay with direction sampling.
    bool has_extra = params.strategy == STRATEGY_MIS && ds.valid && hit_next && max3(next.emission) > 0.0
        && next.light_tri != INVALID_INDEX;
    if (has_extra) {
        extra.ls.wi = ds.wi;
        extra.ls.dist = next_t;
        extra.ls.cos_y = abs(dot(next.ng, ds.wi));
        // The target's emission, as sample_light(…, false) gives it for this point.
        extra.ls.Le_G = light_candidates(next.light_tri).emission * extra.ls.cos_y / max(next_t * next_t, 1e-20);
        extra.ls.pdf = light_source_pdf(d.lights, next.light_tri);
        extra.ls.area = true;
        extra.ls.tri = next.light_tri;
        extra.ls.model = light_triangles(next.light_tri).model;
        extra.ls.p = next.p;
        extra.ls.n = next.ng;  // on the side of this vertex, as sample_light's
        extra.ls.bary = vec2(0.0);
        extra.ls.textured = false;
        extra.f = vec3(0.0);
        extra.bsdf_pdf = 0.0;
        extra.from_direction = true;
        // ds.pdf is direction_pdf_mix at ds.wi with the BSDF density ris_target finds.
        extra.direction_pdf = ds.pdf;
    }
    // The candidates' model numbers are stratified over [0, 1) (strata offset: this
    // vertex's stratified light pair), so that they spread over the light list.
    float strata_offset = rng_stratified2(rng, RNG_PAIR_LIGHT).x;
    RisResult res = ris_resample(ctx, params.ris_candidates, rng, has_extra, extra, strata_offset);
    TRACE4("  ris: %u candidates + %u direction candidate, kept=%u (direction candidate: %u)\n", params.ris_candidates,
           uint(has_extra), uint(res.found), uint(res.extra_chosen));
    if (LIGHT_REUSE) reuse_resample(ctx, s_hit, next_bary, res, rng);
    if (!res.found) return r;
    r.chosen_model = res.y.ls.model;
    r.vis_cell = ctx.vis_cell;
    r.ris_weight = res.W;
    // The extra candidate's visibility is known: its ray hit it.
    if (res.extra_chosen) r.connected = true;
    else shadow_ray(s, res.y.ls, r);
    // The kept candidate's true emission (the target's differs on textured emitters).
    LightSample y = res.y.ls;
    if (res.extra_chosen) y.Le_G = next.emission * y.cos_y / max(next_t * next_t, 1e-20);
    else light_sample_complete(y);
    TRACE6("  ris chosen model %u tri %u p_hat=%f W=%f shadow ray=%u Le_G=%v3f\n", r.chosen_model, y.tri, res.p_hat, res.W,
           uint(r.needs_shadow_ray), y.Le_G);
    r.contribution = res.y.f * y.Le_G * res.W;
    if (y.area) {
        vec3 Li_over_pdf = y.Le_G * res.W;
        r.record_dir = y.wi;
        r.record_value = (Li_over_pdf.x + Li_over_pdf.y + Li_over_pdf.z) / 3.0;
        // W stands for 1/pdf in area measure.
        r.record_pdf = y.dist * y.dist / max(y.cos_y * res.W, 1e-20);
    }
    nee_absorb(r, medium_toward(s, y.wi, medium), y.dist);
    return r;
}

// MIS weight of emission reached by direction sampling from a vertex whose light
// context was `lights` and direction pdf `dir_pdf` (see the header comment).
float emission_weight(LightContext lights, Surface next, vec3 wi, float t, float dir_pdf) {
    float q = light_source_pdf(lights, next.light_tri);
    // Emitters NEE cannot sample are found by direction sampling alone.
    if (q <= 0.0 || params.strategy == STRATEGY_BSDF_ONLY) return 1.0;
    if (params.strategy == STRATEGY_NEE_ONLY || NEE_MODE == NEE_RIS) return 0.0;
    float cos_y = abs(dot(next.ng, wi));
    float p_light = q * t * t / max(cos_y, 1e-12);
    return power_heuristic(dir_pdf, p_light);
}

#endif
