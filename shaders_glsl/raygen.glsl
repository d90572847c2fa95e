// Raygen part of the path tracer (OptiX-style): camera rays, the path loop, film
// accumulation, and the records that train the SD-tree.
//
// Depth counts path segments like Mitsuba's max_depth: the camera ray is segment 1
// (emitters seen directly), NEE and direction sampling at the vertex ending segment k
// create paths of k + 1 segments, which is allowed while k < max_depth.
#ifndef RAYGEN_GLSL
#define RAYGEN_GLSL

#include "inc/common.glsl"
#include "inc/specialization.glsl"
#include "inc/random.glsl"
#include "inc/sampling.glsl"
#include "inc/scene_data.glsl"
#include "inc/debug.glsl"
#include "inc/lane_stats.glsl"
#include "inc/trace.glsl"
#include "inc/material.glsl"
#include "inc/guiding.glsl"
#include "inc/guiding_selection.glsl"
#include "inc/lights.glsl"
#include "closesthit.glsl"

struct RayCounts {
    uint camera;
    uint bounce;
    uint shadow;
    uint probe;
};

// What a path remembers of each vertex to estimate the incident radiance along the
// sampled direction once the path is done (guiding records).
struct VertexRecord {
    vec3 p;
    vec3 wi;
    float pdf;        // mixture pdf of wi (0: no direction record)
    vec3 weight;      // f·cos/pdf (with Russian roulette folded in)
    vec3 nee;         // NEE contribution at this vertex
    vec3 emitted;     // emission arriving along wi that this vertex's record counts
    vec3 emitted_mis; // emission arriving along wi as the image counts it (MIS-weighted)
    uint leaf;        // SD-tree leaf whose selection probability drew wi (guided vertices)
    uint pos_leaf;    // SD-tree leaf of p where the direction sampler found it, else INVALID_INDEX
    float bsdf_pdf;   // the two pdfs the mixture pdf `pdf` mixes
    float guide_pdf;
    vec3 nee_dir;
    float nee_value;  // NEE record value (0: none)
    float nee_pdf;    // solid-angle pdf of nee_dir (for second-moment records)
    uint nee_model;   // light model NEE picked, for learned light selection
    float nee_lum;    // luminance of the NEE contribution
    uint light_leaf;  // SD-tree leaf of the vertex when light selection is learned
};

// The camera ray through image point pixel + jitter, from the camera's near clip plane
// to its far one (both along the view axis, glTF's znear and zfar, as a rasteriser and
// Mitsuba's sensors clip): it starts at near / −d.z along its unit view direction d and
// reaches tmax further. `near_t` is the distance from the eye (or the image plane of an
// orthographic camera) to the ray's origin.
void camera_ray(uvec2 pixel, vec2 jitter, out vec3 origin, out vec3 dir, out float tmax, out float near_t) {
    vec2 ndc = (vec2(pixel) + jitter) / vec2(params.width, params.height) * 2.0 - 1.0;
    ndc.y = -ndc.y;
    float aspect = float(params.width) / float(params.height);
    vec3 o = vec3(0.0);
    vec3 d;
    if (params.camera_type == CAMERA_ORTHOGRAPHIC) {
        o = vec3(ndc * params.ortho_half_extent, 0.0);
        d = vec3(0.0, 0.0, -1.0);
    } else {
        d = normalize(vec3(ndc.x * params.tan_half_fov_y * aspect, ndc.y * params.tan_half_fov_y, -1.0));
    }
    float per_depth = 1.0 / -d.z;  // ray length per unit of view depth
    near_t = params.clip_near * per_depth;
    tmax = params.clip_far >= FLT_MAX ? FLT_MAX : params.clip_far * per_depth - near_t;
    dir = normalize(mat3(params.camera_to_world) * d);
    origin = (params.camera_to_world * vec4(o, 1.0)).xyz + dir * near_t;
}

// Small emitters seen directly (src/render/pixel_emitters.rs). Their emission through a
// pixel is ∫ Le·V over the part of their image inside it; the pixel's list holds that
// part as triangles. One is chosen (by its cdf), a point drawn uniformly inside it, and
// the camera ray through the point counts Le · area / probability if it reaches that
// very light triangle first. Camera rays that hit such a triangle count nothing, so each
// emitter's share is estimated once. Bulbs far smaller than a pixel then cost one ray
// and no coverage noise.
bool is_pixel_emitter(uint light_tri) {
    return params.pixel_emitters != 0u && light_tri != INVALID_INDEX &&
           (pixel_emitter_flags[light_tri >> 5u] & (1u << (light_tri & 31u))) != 0u;
}

// The pixel's piece for sample `key` and the image point inside it; false: no pieces.
bool pixel_emitter_point(uint pixel_index, uvec3 key, out PixelEmitter piece, out vec2 point) {
    piece = PixelEmitter(vec2(0.0), vec2(0.0), vec2(0.0), 0.0, 0.0, INVALID_INDEX);
    point = vec2(0.0);
    if (params.pixel_emitters == 0u || params.hide_emitters != 0u) return false;
    uint lo = pixel_emitter_offsets[pixel_index];
    uint hi = pixel_emitter_offsets[pixel_index + 1u];
    if (lo == hi) return false;
    float u = float(pcg4d(uvec4(key, 0x91ec5e7u)).x >> 8u) * (1.0 / 16777216.0);
    while (hi - lo > 1u) {  // the first piece whose cdf exceeds u
        uint mid = (lo + hi) / 2u;
        if (pixel_emitters[mid - 1u].cdf > u) hi = mid;
        else lo = mid;
    }
    piece = pixel_emitters[lo];
    vec2 v = stratified_sample_2d(key.x, key.y, key.z, PIXEL_EMITTER_DIM);
    float r = sqrt(v.x);
    point = (1.0 - r) * piece.a + r * (1.0 - v.y) * piece.b + r * v.y * piece.c;
    return true;
}

void record_path(VertexRecord rec[GUIDE_MAX_RECORDED_VERTICES], uint count, inout Rng rng) {
    // Incident radiance along each vertex's direction, from the back of the path:
    // L_in(k) = emitted(k) + nee(k+1) + weight(k+1) · L_in(k+1). Two versions: l_rec
    // with `emitted` (what the paper's target records), l_act with the MIS-weighted
    // emission (what the direction sample contributes to the image).
    uint target = guide_header.flags & (GUIDE_FLAG_TARGET_INDIRECT | GUIDE_FLAG_TARGET_CONTRIBUTION);
    bool learn_selection = (guide_header.flags & GUIDE_FLAG_LEARN_SELECTION) != 0u;
    bool second_moment = (guide_header.flags & GUIDE_FLAG_SECOND_MOMENT) != 0u;
    vec3 l_rec = vec3(0.0);
    vec3 l_act = vec3(0.0);
    for (int k = int(count) - 1; k >= 0; --k) {
        if (k + 1 < int(count)) {
            l_rec = rec[k].emitted + rec[k + 1].nee + rec[k + 1].weight * l_rec;
            l_act = rec[k].emitted_mis + rec[k + 1].nee + rec[k + 1].weight * l_act;
        } else {
            l_rec = rec[k].emitted;
            l_act = rec[k].emitted_mis;
        }
        vec3 l = target == 0u ? l_rec
            : target == GUIDE_FLAG_TARGET_INDIRECT ? l_act - rec[k].emitted_mis
            : l_act;
        // The vertex's direction record carries its statistical weight (value 0 when no
        // direction was sampled); its NEE record only adds the light NEE found (see
        // GuideRecord in shared/guiding.h). Both go through one guide_record call site.
        bool nee_record = target == 0u && (guide_header.flags & GUIDE_FLAG_RECORD_NEE) != 0u && rec[k].nee_value > 0.0;
        [[dont_unroll]] for (uint j = 0u; j < (nee_record ? 2u : 1u); ++j) {
            GuideRecord r;
            r.pos = rec[k].p;
            if (j == 0u) {
                r.dir = rec[k].wi;
                r.value = rec[k].pdf > 0.0 ? max(l.x + l.y + l.z, 0.0) / (3.0 * rec[k].pdf) : 0.0;
                // Second moment: (L/p)²·p = L²/p, an estimate of ∫ L² over the cell.
                if (second_moment) r.value *= r.value * rec[k].pdf;
                r.weight = 1.0;
            } else {
                r.dir = rec[k].nee_dir;
                r.value = rec[k].nee_value;
                if (second_moment) r.value *= r.value * rec[k].nee_pdf;
                r.weight = 0.0;
            }
            guide_record(r, vec3(rng_next2(rng), rng_next(rng)), rec[k].pos_leaf);
        }
        if (learn_selection && rec[k].leaf != INVALID_INDEX && rec[k].pdf > 0.0) {
            // f·cos·L_in = weight · pdf · L_in: the direction estimate times its pdf.
            vec3 product = rec[k].weight * l_act * rec[k].pdf;
            GuideSelectionRecord sel;
            sel.leaf = rec[k].leaf;
            sel.bsdf_pdf = rec[k].bsdf_pdf;
            sel.guide_pdf = rec[k].guide_pdf;
            sel.wo_pdf = rec[k].pdf;
            sel.product = max((product.x + product.y + product.z) / 3.0, 0.0);
            guide_selection_record(sel, rng_next(rng));
        }
        // The light table of the leaf whose table NEE sampled from (the vertex's leaf).
        if (rec[k].light_leaf != INVALID_INDEX && rec[k].nee_model != INVALID_INDEX && rec[k].nee_lum > 0.0)
            guide_light_record(rec[k].light_leaf, rec[k].nee_model, rec[k].nee_lum);
    }
}

// First-hit data and path statistics for AOVs.
struct PathInfo {
    vec3 albedo;
    vec3 normal;
    float depth;
    vec3 position;
    float lights_connected;
    float ris_weight;
    uint selected_light;
    float guided;
    float directions;
    uint camera_rays;  // emission and pixel-emitter rays too (each a path-loop step)
};

vec3 trace_path(uvec2 pixel, inout Rng rng, inout RayCounts rays, out PathInfo info) {
    info = PathInfo(vec3(0.0), vec3(0.0), 0.0, vec3(0.0), 0.0, 0.0, INVALID_INDEX, 0.0, 0.0, 0u);
    vec3 origin, dir;
    // K camera rays (--emission-rays): ray k of sample i is at position K·i + k of the
    // pixel's stratified sequence, so the K·N rays of N samples are one stratified set.
    // Rays 1 … K−1 come first and add only the emission they see; ray 0 then starts
    // the path. The emission seen directly is their mean: each ray's is an unbiased
    // estimate of it, and the path from ray 0 one of the light it reflects. K = 1 is
    // the plain estimator, with the same pixel positions.
    uint emission_rays = max(params.emission_rays, 1u);
    uint camera_k = emission_rays > 1u ? 1u : 0u;  // the next camera ray to trace
    vec3 seen_emission = vec3(0.0);                  // emission rays 1 … K−1 saw
    // The pixel-emitter ray comes first, where the pixel has small emitters.
    PixelEmitter piece;
    vec2 piece_point;
    bool emitter_ray = pixel_emitter_point(pixel.y * params.width + pixel.x, rng.key, piece, piece_point);
    vec3 seen_pieces = vec3(0.0);  // what it found, weighted

    VertexRecord rec[GUIDE_MAX_RECORDED_VERTICES];
    uint recorded = 0u;
    bool record_nee = TRAINING && (guide_header.flags & GUIDE_FLAG_RECORD_NEE) != 0u;

    vec3 L = vec3(0.0);
    vec3 beta = vec3(1.0);
    Surface s;
    Hit s_hit;  // the hit that made s
    DirectionSampler d;
    DirectionSample ds;
    ds.valid = true;
    Hit next;
    Surface ns;
    NeeResult nee = nee_none();
    // Absorption (KHR_materials_volume) of the medium the vertex s was reached through,
    // and of the one its direction sample's ray crosses. Paths start in clear air.
    vec3 medium = vec3(0.0);
    vec3 ray_medium = vec3(0.0);
    // Every ray of the path goes through the one trace_ray call below: step 0 is the
    // camera ray; then each vertex takes two steps, its direction sample's closest hit
    // (odd steps) and its NEE shadow ray (even steps). One call site keeps one copy of
    // the traversal in the kernel (every call is inlined): lavapipe compiles it about 4×
    // faster than with a call per ray kind, at the same speed (bench/README.md).
    // `stay`: the step is not over (the camera step traces its K rays in turn).
    bool stay = false;
    float camera_tmax = FLT_MAX;  // the camera ray's extent and start (camera_ray)
    float camera_near = 0.0;
    // How far along its direction a bounce ray's origin lies from the vertex it leaves
    // (bounce_origin): its hit's t is made the distance from the vertex, which RIS's
    // extra candidate, MIS and absorption take.
    float origin_t = 0.0;
    // The bounce ray's probe (bounce_origin in inc/trace.glsl), where the ray's origin was
    // moved along its line: traced before the bounce ray as a step of its own (ray
    // queries), or tested in the bounce ray's own walk of the tree (software traversal,
    // TRACE_TESTS_PROBE), which then traces the ray again from offset_ray's origin where
    // the probe is blocked.
    bool probe_pending = false;
    Ray probe = Ray(vec3(0.0), vec3(0.0), 0.0);
    for (uint step = 0u;; step += stay ? 0u : 1u) {
        stay = false;
        if (step == 0u) {
            if (emitter_ray) {
                camera_ray(uvec2(0u), piece_point, origin, dir, camera_tmax, camera_near);
                TRACE3("pixel-emitter ray: light triangle %u point %v2f d=%v3f\n", piece.light_tri, piece_point, dir);
            } else {
                camera_ray(pixel, stratified_pixel_sample(rng.key.x, emission_rays * rng.key.y + camera_k, rng.key.z),
                           origin, dir, camera_tmax, camera_near);
                TRACE3("camera ray %u o=%v3f d=%v3f\n", camera_k, origin, dir);
            }
            rays.camera += 1u;
            info.camera_rays += 1u;
        }
        bool shadow_step = step > 0u && (step & 1u) == 0u;
        bool probe_step = probe_pending && !shadow_step && !TRACE_TESTS_PROBE;
        bool probe_along = probe_pending && !shadow_step && TRACE_TESTS_PROBE;
        uint depth = (step + 1u) / 2u;  // the vertex whose rays these are (0: the camera)
        Ray ray = probe_step ? probe : shadow_step ? nee.shadow : Ray(origin, dir, step == 0u ? camera_tmax : FLT_MAX);
        Hit hit;
        hit.valid = false;
        hit.t = FLT_MAX;
        bool probe_blocked = false;
        if (probe_step || (shadow_step ? nee.needs_shadow_ray : ds.valid)) {
            if (probe_step || probe_along) rays.probe += 1u;
            if (shadow_step) rays.shadow += 1u;
            else if (depth > 0u && !probe_step) rays.bounce += 1u;
            hit = trace_ray(ray.o, ray.d, ray.tmax, shadow_step || probe_step,
                            probe_along ? probe : Ray(ray.o, vec3(0.0), 0.0), probe_blocked);
        }
        if (probe_step) probe_blocked = hit.valid;
        if (probe_step || probe_along) {
            probe_pending = false;
            TRACE1("  bounce probe blocked: %u\n", uint(probe_blocked));
        }
        if (probe_blocked || probe_step) {
            // Something crosses the stretch the origin skipped: the bounce ray leaves
            // from offset_ray's origin instead, which skips nothing beside the surface.
            if (probe_blocked) {
                origin = probe.o;
                origin_t = dot(origin - s.p, dir);
            }
            stay = true;
            continue;
        }
        if (!shadow_step) {
            next = hit;
            if (step > 0u) next.t += origin_t;
            if (hit.valid) ns = make_surface(hit, dir);
        }
        if (step == 0u && emitter_ray) {
            // The pixel-emitter ray counts only the light triangle it aimed at.
            bool reached = next.valid && ns.light_tri == piece.light_tri;
            if (reached) seen_pieces = ns.emission * piece.scale;
            TRACE2("  reached its emitter: %u, contribution %v3f\n", uint(reached), seen_pieces);
            emitter_ray = false;
            stay = true;
            continue;
        }
        // Emission seen by camera rays, less the small emitters' (the ray above has them).
        vec3 seen_here = vec3(0.0);
        if (step == 0u && next.valid && !is_pixel_emitter(ns.light_tri)) seen_here = ns.emission;
        if (step == 0u && camera_k != 0u) {
            // An emission ray: what it sees directly, then the next camera ray.
            seen_emission += seen_here;
            camera_k = (camera_k + 1u) % emission_rays;
            stay = true;
            continue;
        }
        if (step == 0u) {
            vec3 seen = params.hide_emitters != 0u ? vec3(0.0) : (seen_emission + seen_here) / float(emission_rays) + seen_pieces;
            if (!next.valid) {
                TRACE0("  miss\n");
                return seen;
            }
            info.albedo = ns.bsdf.base_color;
            // The shading normal as authored (make_surface turns it over, below the
            // geometric normal, where the view is below it).
            info.normal = dot(ns.n, ns.ng) < 0.0 ? -ns.n : ns.n;
            info.depth = camera_near + next.t;
            info.position = ns.p;
            L = seen;
        } else if (!shadow_step) {
            // The direction sample's hit is known: RIS chooses NEE's light now (it takes
            // an emitter hit there as a candidate; without RIS, sample_vertex chose it
            // with the direction). Its shadow ray is the next step.
            rng.vertex = depth;
            if (NEE_MODE == NEE_RIS) nee = nee_ris(s, s_hit, d, ds, next.valid, ns, next.t, next.bary, medium, rng);
            continue;
        } else {
            bool hit_next = next.valid;
            nee_resolve(nee, !hit.valid);
            // Learned light visibility counts what the shadow ray toward RIS's light said.
            if (LIGHT_VISIBILITY && NEE_MODE == NEE_RIS && nee.chosen_model != INVALID_INDEX)
                visibility_learn(nee.vis_cell, nee.chosen_model, nee.connected);
            TRACE2("  nee visible=%u contribution=%v3f\n", uint(nee.connected), nee.contribution);
            L += beta * nee.contribution;
            if (nee.connected) info.lights_connected += 1.0;
            if (depth == 1u) {
                info.ris_weight = nee.ris_weight;
                info.selected_light = nee.chosen_model;
            }

            // What the direction sample's ray lost to absorption on its way to the hit.
            vec3 absorbed = hit_next && max3(ray_medium) > 0.0 ? transmittance(ray_medium, next.t) : vec3(1.0);
            vec3 emitted = vec3(0.0);
            vec3 emitted_recorded = vec3(0.0);
            if (hit_next && max3(ns.emission) > 0.0) {
                float w = emission_weight(d.lights, ns, ds.wi, next.t, ds.pdf);
                emitted = ns.emission * w * absorbed;
                // Without NEE records, direct light reaches the guide through hits alone.
                emitted_recorded = record_nee ? emitted : ns.emission * absorbed;
                TRACE3("  direction hit emitter: Le=%v3f mis=%f contribution=%v3f\n", ns.emission, w, beta * ds.weight * emitted);
            }
            L += beta * ds.weight * emitted;

            // Russian roulette (off unless rr_depth > 0).
            vec3 weight = ds.weight * absorbed;
            bool alive = ds.valid && hit_next;
            if (alive && params.rr_depth > 0u && depth >= params.rr_depth) {
                float q = min(max3(beta * weight), 0.95);
                if (rng_next(rng) >= q) alive = false;
                else weight /= q;
            }

            if (TRAINING && recorded < GUIDE_MAX_RECORDED_VERTICES) {
                VertexRecord r;
                r.p = s.p;
                r.wi = ds.wi;
                r.pdf = ds.valid ? ds.pdf : 0.0;
                r.weight = weight;
                r.nee = nee.contribution;
                r.emitted = emitted_recorded;
                r.emitted_mis = emitted;
                r.leaf = d.bsdf_fraction < 1.0 ? d.leaf : INVALID_INDEX;
                r.pos_leaf = d.leaf;
                r.bsdf_pdf = ds.bsdf_pdf;
                r.guide_pdf = ds.guide_pdf;
                r.nee_dir = nee.record_dir;
                r.nee_value = nee.record_value;
                r.nee_pdf = nee.record_pdf;
                r.nee_model = nee.connected ? nee.chosen_model : INVALID_INDEX;
                r.nee_lum = luminance(nee.contribution);
                r.light_leaf = d.lights.leaf;
                rec[recorded++] = r;
            }
            if (!alive) {
                TRACE1("  path ends (the direction sample hit a surface: %u)\n", uint(hit_next));
                break;
            }
            beta *= weight;
        }
        // The next vertex: sample its direction, if the path may grow from it. It was
        // reached through the medium the ray crossed.
        s = ns;
        s_hit = next;
        medium = ray_medium;
        if (depth + 1u >= params.max_depth) break;
        TRACE6("vertex %u p=%v3f n=%v3f material %u front=%u emission=%v3f\n", depth + 1u, s.p, s.n, s.material, uint(s.front),
               s.emission);
        TRACE4("  base colour %v3f metallic %f alpha %f throughput %v3f\n", s.bsdf.base_color, s.bsdf.metallic, s.bsdf.alpha,
               beta);
        d = direction_sampler(s);
        rng.vertex = depth + 1u;
        if (NEE_MODE == NEE_RIS) ds = sample_direction(s, d, rng);
        else sample_vertex(s, d, medium, rng, ds, nee);
        info.directions += 1.0;
        if (ds.guided) info.guided += 1.0;
        vec3 side = surface_side_normal(s, ds.wi);
        origin = bounce_origin(s.p, side, ds.wi, probe);
        dir = ds.wi;
        origin_t = dot(origin - s.p, dir);
        probe_pending = ds.valid && probe.tmax > 0.0;
        ray_medium = medium_toward(s, ds.wi, medium);
    }
    if (TRAINING) record_path(rec, recorded, rng);
    TRACE1("sample radiance L=%v3f\n", L);
    return L;
}

void main() {
    uvec2 local = gl_GlobalInvocationID.xy;
    if (local.x >= pc.tile_size.x || local.y >= pc.tile_size.y) return;
    uvec2 pixel = pc.tile_origin + local;
    if (pixel.x >= params.width || pixel.y >= params.height) return;
    uint pixel_index = pixel.y * params.width + pixel.x;

    RayCounts rays = RayCounts(0u, 0u, 0u, 0u);
    uint nonfinite = 0u;
    uint clamped = 0u;
    u64vec3 sum = u64vec3(0ul);
    float aov_sum[AOV_CHANNELS];
    for (uint c = 0u; c < AOV_CHANNELS; ++c) aov_sum[c] = 0.0;
    float outlier_lum = -1.0;
    uint outlier_index = 0u;
    vec3 outlier_rgb = vec3(0.0);
    uint selected = INVALID_INDEX;
    for (uint i = 0u; i < pc.sample_count; ++i) {
        uint sample_index = pc.sample_begin + i;
        Rng rng = rng_init(pixel_index, sample_index, params.seed);
        g_trace = pixel_index == params.debug_pixel && (params.debug_sample == INVALID_INDEX || sample_index == params.debug_sample);
        TRACE3("--- pixel (%u, %u) sample %u\n", pixel.x, pixel.y, sample_index);
        PathInfo info;
        vec3 L = trace_path(pixel, rng, rays, info);
        lane_stats_path(info.camera_rays + uint(info.directions));
        if (!all_finite(L) || any(lessThan(L, vec3(0.0)))) {
            nonfinite += 1u;
            continue;
        }
        // Fixed point: each sample is rounded alone, so sums do not depend on how the
        // samples were split into dispatches. A sample above the fixed-point range is
        // clamped and counted (the render reports how many). The rounding is stochastic,
        // a uniform dither from the sample's own hash added before truncation, so that
        // the expected sum is the sum of the values however small they are: rounding to
        // nearest lost every value below half a unit (2⁻²¹), and an image of radiance
        // 10⁻⁶ came out 4 % dark.
        if (any(greaterThan(L, vec3(FILM_MAX_SAMPLE)))) clamped += 1u;
        vec3 dither = vec3(pcg4d(uvec4(rng.key, 0xd1700e5u)).xyz >> 8u) * (1.0 / 16777216.0);
        sum += u64vec3(min(L, vec3(FILM_MAX_SAMPLE)) * FILM_FIXED_SCALE + dither);
        if (AOVS) {
            aov_sum[AOV_ALBEDO + 0] += info.albedo.x;
            aov_sum[AOV_ALBEDO + 1] += info.albedo.y;
            aov_sum[AOV_ALBEDO + 2] += info.albedo.z;
            aov_sum[AOV_NORMAL + 0] += info.normal.x;
            aov_sum[AOV_NORMAL + 1] += info.normal.y;
            aov_sum[AOV_NORMAL + 2] += info.normal.z;
            aov_sum[AOV_DEPTH] += info.depth;
            aov_sum[AOV_POSITION + 0] += info.position.x;
            aov_sum[AOV_POSITION + 1] += info.position.y;
            aov_sum[AOV_POSITION + 2] += info.position.z;
            aov_sum[AOV_LIGHT_COUNT] += info.lights_connected;
            aov_sum[AOV_RIS_WEIGHT] += info.ris_weight;
            aov_sum[AOV_GUIDE_FRACTION] += info.directions > 0.0 ? info.guided / info.directions : 0.0;
            if (sample_index == params.aov_first_sample) selected = info.selected_light;
            float lum = luminance(L);
            if (lum > outlier_lum) {
                outlier_lum = lum;
                outlier_index = sample_index;
                outlier_rgb = L;
            }
        }
    }
    uint base = 3u * pixel_index;
    film[base + 0u] += sum.x;
    film[base + 1u] += sum.y;
    film[base + 2u] += sum.z;
    if (AOVS) {
        uint a = AOV_CHANNELS * pixel_index;
        for (uint c = 0u; c < AOV_CHANNELS; ++c)
            if (c != AOV_SELECTED_LIGHT) aov[a + c] += aov_sum[c];
        // Only the dispatch holding aov_first_sample writes it (-1: NEE picked nothing).
        if (pc.sample_begin <= params.aov_first_sample && params.aov_first_sample - pc.sample_begin < pc.sample_count)
            aov[a + AOV_SELECTED_LIGHT] = selected == INVALID_INDEX ? -1.0 : float(selected);
        uint o = OUTLIER_FLOATS * pixel_index;
        if (outlier_lum > outliers[o]) {
            outliers[o] = outlier_lum;
            outliers[o + 1u] = uintBitsToFloat(outlier_index);
            outliers[o + 2u] = outlier_rgb.x;
            outliers[o + 3u] = outlier_rgb.y;
            outliers[o + 4u] = outlier_rgb.z;
        }
    }

    atomicAdd(stats[STAT_CAMERA_RAYS], uint64_t(rays.camera));
    atomicAdd(stats[STAT_BOUNCE_RAYS], uint64_t(rays.bounce));
    atomicAdd(stats[STAT_SHADOW_RAYS], uint64_t(rays.shadow));
    atomicAdd(stats[STAT_PROBE_RAYS], uint64_t(rays.probe));
    if (nonfinite > 0u) atomicAdd(stats[STAT_NONFINITE_SAMPLES], uint64_t(nonfinite));
    if (clamped > 0u) atomicAdd(stats[STAT_CLAMPED_SAMPLES], uint64_t(clamped));
    lane_stats_flush();
}

#endif
