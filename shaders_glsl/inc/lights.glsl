// Light sampling from the source distribution q: a light model (uniformly, by power
// through an alias table, or by the light tree at the shading point), then one of its
// triangles (uniformly, or by power), then a uniform point on it — or the punctual light
// the model stands for. Also the density q
// of a given light point (for MIS), and emitted radiance at a light point.
#ifndef INC_LIGHTS_GLSL
#define INC_LIGHTS_GLSL

#include "specialization.glsl"
#include "common.glsl"
#include "scene_data.glsl"
#include "guiding.glsl"
#include "geometry.glsl"
#include "sampling.glsl"
#include "random.glsl"
#include "light_tree.glsl"

// A light point seen from a shading point x.
struct LightSample {
    vec3 wi;        // unit direction x → light
    float dist;     // distance (FLT_MAX for directional)
    vec3 Le_G;      // emitted radiance × geometry without cos at x: Le·|cosθy|/d² (area),
                    // I/d² (point, spot), E (directional)
    float pdf;      // source density: per area (area lights) or pmf (punctual)
    float cos_y;    // |cosθ| at the light (area lights), 1 otherwise
    bool area;      // area light (MIS applies); false for delta lights
    uint tri;       // light triangle, INVALID_INDEX for punctual
    uint model;     // the light model it belongs to (area and punctual lights alike)
    vec3 p;         // the light point (area and positional lights)
    vec3 n;         // geometric normal at the light point, on the side facing x (area
                    // lights; shadow rays start their far end off the light along it)
    vec2 bary;      // barycentrics of the point on triangle `tri` (of its corners 1, 2)
    bool textured;  // Le_G holds the stand-in of a textured or alpha-masked emitter or
                    // of an IES light (sample_light without exact emission;
                    // light_sample_complete)
};

uint alias_sample(uint begin, uint count, float u, bool models) {
    float scaled = u * float(count);
    uint i = min(floor_to_uint(scaled), count - 1u);
    float frac = scaled - float(i);
    // Two reads rather than a ?: over two buffers: glslang types that select badly.
    float threshold;
    uint alias;
    if (models) {
        threshold = model_alias(begin + i).threshold;
        alias = model_alias(begin + i).alias;
    } else {
        threshold = triangle_alias(begin + i).threshold;
        alias = triangle_alias(begin + i).alias;
    }
    return frac < threshold ? i : alias;
}

// The source's probability of light model `model` at shading point p with receiver
// normal nr (LightContext.n). The tree source is the tree mixed with the uniform one
// (LIGHT_TREE_UNIFORM_SHARE).
float source_model_pmf(vec3 p, vec3 nr, uint model) {
    if (params.ris_source == RIS_SOURCE_POWER) return model_alias(model).pmf;
    float uniform_pmf = 1.0 / float(params.light_model_count);
    if (params.ris_source == RIS_SOURCE_TREE)
        return LIGHT_TREE_UNIFORM_SHARE * uniform_pmf
            + (1.0 - LIGHT_TREE_UNIFORM_SHARE) * light_tree_pmf(light_models(model), p, nr);
    return uniform_pmf;
}

// Learned light selection (guided methods with GUIDE_FLAG_LEARN_LIGHTS): at a shading
// point whose SD-tree leaf has a learned table, light models are chosen from the
// defensive mixture (1 − mix)·source + mix·table, with the leaf's mix (chosen per leaf
// between passes, src/guiding/light_mix.rs, or fixed by --light-mix). The source term
// keeps every light samplable (mix ≤ 0.95), and every pdf below is the mixture's, so
// NEE, RIS and MIS stay unbiased.
//
// What light sampling depends on at a shading point, passed explicitly to every
// sampling and pdf function (pbrt's LightSampleContext).
struct LightContext {
    vec3 p;       // the shading point
    vec3 n;       // its receiver normal for the light tree's bound: the geometric normal
                  // of an opaque surface (nothing below its tangent plane can light it),
                  // zero where light arrives from every side (a surface that transmits)
    uint leaf;    // its SD-tree leaf when light selection is learned, else INVALID_INDEX
    float mix;    // probability of choosing the model from that table (0: source only)
    uvec4 models; // filter of the models that table holds (guide_light_filter); all set: probe every model
};

// Whether RIS builds and tests the filter of a leaf table's models: with few models
// (cornell-lights: 16) a table holds most of them, and the filter rules out too few to
// repay building it (2–4 % slower there). Uniform, so scenes with few models skip the
// bit test too.
bool light_filter_pays() {
    return params.light_model_count > 4u * GUIDE_LIGHT_SLOTS;
}

// The light-sampling context of shading point p with receiver normal n (see
// LightContext; `leaf`: its SD-tree leaf if known).
LightContext light_context(vec3 p, vec3 n, uint leaf) {
    LightContext c = LightContext(p, n, INVALID_INDEX, 0.0, uvec4(~0u));
    if (!GUIDING || (guide_header.flags & GUIDE_FLAG_LEARN_LIGHTS) == 0u) return c;
    if (leaf == INVALID_INDEX) leaf = guide_find_leaf(p);
    c.leaf = leaf;
    c.mix = guide_leaves(leaf).light_mix;  // the CPU writes 0 for an empty table
    return c;
}

// The context for RIS's candidates: with the filter of the models the leaf's table holds,
// so that a candidate drawn from the source skips the table's hash probe when its model
// is ruled out. Built here, not in light_context: kept alive through the whole path the
// filter's registers made `guided` 5–10 % slower.
LightContext light_context_for_ris(LightContext c) {
    if (GUIDING && c.mix > 0.0 && light_filter_pays()) c.models = guide_light_filter(c.leaf);
    return c;
}

// The probability of light model `model` at ctx, whose source probability is `p`.
float model_pmf_given_source(LightContext ctx, uint model, float p) {
    if (GUIDING && ctx.mix > 0.0) {
        // Models the filter rules out are not in the table: their table pmf is 0.
        bool ruled_out = false;
        if (light_filter_pays()) ruled_out = !guide_light_filter_may_hold(ctx.models, model);
        float table = ruled_out ? 0.0 : guide_light_pmf(ctx.leaf, model);
        p = (1.0 - ctx.mix) * p + ctx.mix * table;
    }
    return p;
}

float model_pmf(LightContext ctx, uint model) {
    return model_pmf_given_source(ctx, model, source_model_pmf(ctx.p, ctx.n, model));
}

float triangle_pmf(uint tri, LightModel m) {
    if (params.ris_source != RIS_SOURCE_UNIFORM) return triangle_alias(tri).pmf;
    return 1.0 / float(m.triangle_count);
}

// Source density (per unit area) of a point on light triangle `tri`, seen from ctx.p.
float light_source_pdf(LightContext ctx, uint tri) {
    if (tri == INVALID_INDEX) return 0.0;
    uint model = light_triangles(tri).model;
    return model_pmf(ctx, model) * triangle_pmf(tri, light_models(model)) * light_candidates(tri).inv_area;
}

// Radiance leaving light triangle `lt` at barycentrics (b1, b2) in direction `dir`: the
// emission (textured or not, tinted by the vertex colour where the material says so, as
// material_emission) times the surface's coverage there where its material is not
// opaque. The light table gives such triangles their instance.
vec3 light_triangle_radiance(LightTriangle lt, vec2 b, vec3 dir) {
    if (lt.two_sided == 0u && dot(lt.normal, dir) <= 0.0) return vec3(0.0);
    Material m = materials(lt.material);
    vec3 e = m.emission;
    if (m.emissive_tex.index >= 0) {
        vec2 uv = (1.0 - b.x - b.y) * lt.uv0 + b.x * lt.uv1 + b.y * lt.uv2;
        e *= sample_texture(m.emissive_tex, uv).rgb;
    }
    if (lt.instance != INVALID_INDEX) {
        if ((m.flags & MATERIAL_FLAG_VERTEX_COLOR_EMISSION) != 0u) {
            Instance inst = instances(lt.instance);
            vec3 w = vec3(1.0 - b.x - b.y, b.x, b.y);
            e *= max(interpolate_color(inst, triangle_vertices(inst, lt.primitive), w).rgb, vec3(0.0));
        }
        e *= geometry_coverage(lt.instance, lt.primitive, b);
    }
    return e;
}

// The interval of the `n` increasing angles at light_profiles(first …) that holds x
// (clamped to the ends), and where in it x lies.
uint profile_bracket(uint first, uint n, float x, out float t) {
    uint lo = 0u;
    uint hi = n - 1u;
    while (hi - lo > 1u) {  // angles[lo] ≤ x < angles[hi]
        uint mid = (lo + hi) / 2u;
        if (light_profiles(first + mid) <= x) lo = mid;
        else hi = mid;
    }
    float a = light_profiles(first + lo);
    float b = light_profiles(first + lo + 1u);
    t = clamp((x - a) / max(b - a, 1e-12), 0.0, 1.0);
    return lo;
}

// Candela of light l's IES profile toward the unit direction w it emits along
// (EXT_lights_ies; src/scene/ies.rs packs the profile and says both frames). Type C:
// vertical angle θ from l.direction, horizontal angle φ from l.tangent, counter-clockwise
// about −direction. Type B (the top bit of the horizontal count): V = atan2(w·tangent,
// w·direction), H = asin(−w·y), so only the hemisphere the light faces is lit.
// Bilinear in the profile's own two angles between the file's; 0 outside them.
float punctual_profile(PunctualLight l, vec3 w) {
    uint o = l.profile & 0x7fffffffu;
    uint nv = floatBitsToUint(light_profiles(o));
    uint nh_bits = floatBitsToUint(light_profiles(o + 1u));
    uint nh = nh_bits & 0x7fffffffu;
    uint vertical = o + 2u;
    uint horizontal = vertical + nv;
    uint table = horizontal + nh;
    // The frame: x along the tangent, z against the light's direction, y = z × x
    // (turned over for a mirrored node).
    vec3 y = cross(-l.direction, l.tangent);
    if ((l.profile & 0x80000000u) != 0u) y = -y;
    bool type_b = (nh_bits & 0x80000000u) != 0u;
    float theta;  // the profile's vertical angle
    float phi = 0.0;  // its horizontal angle
    if (type_b) {
        float x = dot(w, l.tangent);
        float z = dot(w, l.direction);
        theta = (x == 0.0 && z == 0.0) ? 0.0 : atan(x, z);  // on the lateral axis V is moot
        phi = asin(clamp(-dot(w, y), -1.0, 1.0));
        if (phi < light_profiles(horizontal) - 1e-6 || phi > light_profiles(horizontal + nh - 1u) + 1e-6) return 0.0;
    } else {
        theta = acos(clamp(dot(w, l.direction), -1.0, 1.0));
        if (nh > 1u) {
            phi = atan(dot(w, y), dot(w, l.tangent));
            if (phi < 0.0) phi += 2.0 * PI;
        }
    }
    if (theta < light_profiles(vertical) - 1e-6 || theta > light_profiles(vertical + nv - 1u) + 1e-6) return 0.0;
    float tv = 0.0;
    uint iv = nv > 1u ? profile_bracket(vertical, nv, theta, tv) : 0u;
    uint iv1 = min(iv + 1u, nv - 1u);
    float th = 0.0;
    uint ih = nh > 1u ? profile_bracket(horizontal, nh, phi, th) : 0u;
    uint ih1 = min(ih + 1u, nh - 1u);
    float c0 = mix(light_profiles(table + ih * nv + iv), light_profiles(table + ih * nv + iv1), tv);
    float c1 = mix(light_profiles(table + ih1 * nv + iv), light_profiles(table + ih1 * nv + iv1), tv);
    return mix(c0, c1, th);
}

// The stand-in of punctual_profile that RIS's candidates weigh: the profile's largest
// candela over a cell of a 16 × 32 grid in (cos θ, φ) (src/scene/ies.rs, IesProfile::bounds),
// so positive wherever the profile is; one read instead of two searches of the table.
float punctual_profile_bound(PunctualLight l, vec3 w) {
    uint o = l.profile & 0x7fffffffu;
    uint nv = floatBitsToUint(light_profiles(o));
    uint nh = floatBitsToUint(light_profiles(o + 1u)) & 0x7fffffffu;  // the top bit: Type B
    uint grid = o + 2u + nv + nh + nv * nh;
    vec3 y = cross(-l.direction, l.tangent);
    if ((l.profile & 0x80000000u) != 0u) y = -y;
    float phi = atan(dot(w, y), dot(w, l.tangent));
    if (phi < 0.0) phi += 2.0 * PI;
    // Rows uniform in cos θ, from the light's direction (1) to its opposite (−1).
    uint row = min(uint(max(1.0 - dot(w, l.direction), 0.0) * 8.0), 15u);
    uint column = min(uint(phi * (32.0 / (2.0 * PI))), 31u);
    return light_profiles(grid + row * 32u + column);
}

// Punctual light `index` seen from x. With exact_emission false an IES light's Le_G is
// the stand-in of punctual_profile_bound (`textured` set: light_sample_complete makes it
// exact), as sample_light gives RIS's candidates.
LightSample sample_punctual(uint index, vec3 x, const bool exact_emission) {
    PunctualLight l = punctual_lights(index);
    LightSample s;
    s.area = false;
    s.tri = INVALID_INDEX;
    s.model = INVALID_INDEX;  // sample_light sets it
    s.cos_y = 1.0;
    s.n = vec3(0.0);
    s.bary = vec2(0.0);
    s.textured = false;
    if (l.kind == PUNCTUAL_DIRECTIONAL) {
        s.wi = -l.direction;
        s.dist = FLT_MAX;
        s.Le_G = l.intensity;
        s.p = x + s.wi * 2.0 * params.scene_radius;
    } else {
        vec3 d = l.position - x;
        float d2 = max(dot(d, d), 1e-12);
        s.dist = sqrt(d2);
        s.wi = d / s.dist;
        s.p = l.position;
        float falloff = 1.0;
        if (l.kind == PUNCTUAL_SPOT) {
            float c = dot(-s.wi, l.direction);
            float t = clamp((c - l.cos_outer) / max(l.cos_inner - l.cos_outer, 1e-4), 0.0, 1.0);
            falloff = t * t;
        }
        if (l.profile != INVALID_INDEX) {
            s.textured = !exact_emission;
            falloff = exact_emission ? punctual_profile(l, -s.wi) : punctual_profile_bound(l, -s.wi);
        }
        s.Le_G = l.intensity * falloff / d2;
    }
    return s;
}

// The point with barycentrics b (of corners 1, 2) on light triangle `tri`, whose record
// is `lt` and whose light model is `model`, seen from x: its emission exact or the
// record's stand-in as sample_light says. The source density is the caller's (pdf 0).
LightSample light_point(LightCandidateTriangle lt, uint tri, uint model, vec2 b, vec3 x, const bool exact_emission) {
    vec3 p = lt.p0 + b.x * lt.e1 + b.y * lt.e2;
    // |e1 × e2| = 2·area.
    vec3 normal = cross(lt.e1, lt.e2) * (0.5 * lt.inv_area);
    if ((lt.flags & LIGHT_CANDIDATE_FLIPPED) != 0u) normal = -normal;
    LightSample s;
    s.area = true;
    s.tri = tri;
    s.model = model;
    s.p = p;
    s.bary = b;
    vec3 d = p - x;
    float d2 = dot(d, d);
    s.dist = sqrt(d2);
    s.wi = d / max(s.dist, 1e-20);
    float cos_signed = dot(normal, s.wi);
    s.cos_y = abs(cos_signed);
    s.n = cos_signed > 0.0 ? -normal : normal;
    // One-sided emitters emit on the front face only (toward x: cos_signed < 0).
    bool emits = (lt.flags & LIGHT_CANDIDATE_TWO_SIDED) != 0u || cos_signed < 0.0;
    vec3 Le = emits ? lt.emission : vec3(0.0);
    // Textured and alpha-masked emitters: the record's emission is a stand-in.
    s.textured = (lt.flags & (LIGHT_CANDIDATE_TEXTURED | LIGHT_CANDIDATE_ALPHA)) != 0u;
    if (exact_emission && s.textured && emits) {
        Le = light_triangle_radiance(light_triangles(tri), b, -s.wi);
        s.textured = false;
    }
    s.Le_G = d2 > 0.0 ? Le * s.cos_y / d2 : vec3(0.0);
    s.pdf = 0.0;
    return s;
}

// Draw a light point for shading point ctx.p with four uniform numbers. A point on an
// emissive triangle reads the triangle's compact record alone (LightCandidateTriangle).
// With `exact_emission` false the emission of a textured emitter is left at the record's
// untextured stand-in and `textured` is set (RIS evaluates its 32 candidates that way and
// the texture for the one it keeps: light_sample_complete); with it true, Le_G is exact.
LightSample sample_light(LightContext ctx, vec4 u, const bool exact_emission) {
    vec3 x = ctx.p;
    uint count = params.light_model_count;
    float um = u.x;
    uint model = INVALID_INDEX;
    float table_pmf = -1.0;  // the table's probability of `model`, when it chose it
    if (GUIDING && ctx.mix > 0.0) {
        // Reuse u.x: the first `mix` of its range picks from the table, the rest, rescaled,
        // from the source.
        if (um < ctx.mix) {
            model = guide_light_sample(ctx.leaf, um / ctx.mix, table_pmf);
        } else {
            um = (um - ctx.mix) / (1.0 - ctx.mix);
        }
    }
    float source_pmf = -1.0;  // the source's probability of `model`, when it chose it
    if (model == INVALID_INDEX) {
        table_pmf = -1.0;
        if (params.ris_source == RIS_SOURCE_TREE) {
            // The first LIGHT_TREE_UNIFORM_SHARE of u.x's range picks uniformly, the rest,
            // rescaled, walks the tree (which finds the model's tree pmf on the way).
            const float share = LIGHT_TREE_UNIFORM_SHARE;
            if (um < share) {
                model = min(floor_to_uint(um / share * float(count)), count - 1u);
            } else {
                float tree_pmf;
                model = light_tree_sample(x, ctx.n, (um - share) / (1.0 - share), tree_pmf);
                source_pmf = share / float(count) + (1.0 - share) * tree_pmf;
                // A walk that found no leaf (not for a tree the host built) samples nothing.
                if (model >= count) {
                    model = 0u;
                    source_pmf = 0.0;
                }
            }
        } else {
            model = params.ris_source == RIS_SOURCE_POWER ? alias_sample(0u, count, um, true)
                                                           : min(floor_to_uint(um * float(count)), count - 1u);
        }
    }
    LightModel m = light_models(model);
    // A model the table chose needs no second walk of the table for its mixture pmf
    // (the same value model_pmf finds: a table holds each model once), nor one the tree
    // chose a second walk of the tree.
    float pm = GUIDING && table_pmf >= 0.0
        ? (1.0 - ctx.mix) * source_model_pmf(x, ctx.n, model) + ctx.mix * table_pmf
        : source_pmf > 0.0 ? model_pmf_given_source(ctx, model, source_pmf)
        : source_pmf == 0.0 ? 0.0  // the walk found no leaf: not a sample (pdf 0)
        : model_pmf(ctx, model);
    if (m.punctual != INVALID_INDEX) {
        LightSample s = sample_punctual(m.punctual, x, exact_emission);
        s.pdf = pm;
        s.model = model;
        return s;
    }
    uint local = params.ris_source != RIS_SOURCE_UNIFORM ? alias_sample(m.first_triangle, m.triangle_count, u.y, false)
                                                       : min(floor_to_uint(u.y * float(m.triangle_count)), m.triangle_count - 1u);
    uint tri = m.first_triangle + local;
    LightCandidateTriangle lt = light_candidates(tri);
    LightSample s = light_point(lt, tri, model, square_to_triangle(u.zw), x, exact_emission);
    s.pdf = pm * triangle_pmf(tri, m) * lt.inv_area;
    return s;
}

// Replace the stand-in emission of a textured emitter's sample (sample_light without
// exact emission) by the radiance the texture gives at its point.
void light_sample_complete(inout LightSample s) {
    if (!s.textured) return;
    s.textured = false;
    if (max3(s.Le_G) <= 0.0) return;
    if (s.tri == INVALID_INDEX) {
        // An IES light's stand-in: its exact intensity toward the shading point.
        PunctualLight l = punctual_lights(light_models(s.model).punctual);
        s.Le_G = l.intensity * punctual_profile(l, -s.wi) / max(s.dist * s.dist, 1e-12);
        return;
    }
    vec3 Le = light_triangle_radiance(light_triangles(s.tri), s.bary, -s.wi);
    s.Le_G = Le * s.cos_y / max(s.dist * s.dist, 1e-20);
}

#endif
