// Surface interaction at a hit: position, geometric and shading frames (vertex normals,
// normal maps), material parameters from factors and textures, and emitted radiance.
#ifndef INC_MATERIAL_GLSL
#define INC_MATERIAL_GLSL

#include "trace.glsl"

#include "common.glsl"
#include "specialization.glsl"
#include "scene_data.glsl"
#include "geometry.glsl"
#include "bsdf.glsl"

struct Surface {
    vec3 p;            // world position
    vec3 ng;           // geometric normal, on the side of wo
    vec3 n;            // shading normal, on the side of wo
    vec3 t;            // shading tangent
    vec3 b;            // shading bitangent
    vec3 wo;           // unit direction toward the previous vertex
    bool front;        // the ray hit the triangle's front face
    uint instance;
    uint primitive;
    uint material;
    vec2 uv0;
    vec2 uv1;
    BsdfParams bsdf;
    bool lambertian;   // every lobe but the Lambertian one has weight 0 here (textures included)
    float roughness;   // perceptual roughness (AOVs)
    vec3 emission;     // radiance emitted toward wo
    uint light_tri;    // light triangle index, INVALID_INDEX if not a sampled light
};

// The material's emission at a point with texture coordinates uv0, uv1 and interpolated
// vertex colour `color` (which tints only unlit materials' emission).
vec3 material_emission(Material m, vec2 uv0, vec2 uv1, vec4 color) {
    vec3 e = m.emission;
    if (m.emissive_tex.index >= 0 && max3(e) > 0.0)
        e *= sample_texture(m.emissive_tex, m.emissive_tex.uv_set == 1u ? uv1 : uv0).rgb;
    if ((m.flags & MATERIAL_FLAG_VERTEX_COLOR_EMISSION) != 0u) e *= max(color.rgb, vec3(0.0));
    return e;
}

mat3 inverse_transpose3(mat3 m) {
    return transpose(inverse(m));
}

// The tangent (xyz, world space) and bitangent sign (w) of a normal map read from UV set
// `uv_set`, for normal_mapped's bitangent cross(n, tangent)·w with n the front face's
// normal. The map's +x is the direction of increasing u, its +y the image's up, that is
// of decreasing v (glTF's texture coordinates start at the image's top left). From the
// TANGENT attribute, else derived from the UV parameterisation (∂P/∂u, and w so that the
// bitangent is −∂P/∂v, which MikkTSpace's tangents give where a file has them).
// `flipped`: the instance's transform mirrors (INSTANCE_FLAG_FLIPPED), which turns
// cross(n, tangent) around, so a mirrored copy shows the mirror image of the relief.
vec4 normal_map_tangent(uint uv_set, vec3 w, Vertex v0, Vertex v1, Vertex v2, mat4x3 object_to_world,
                        bool flipped, vec3 p0, vec3 p1, vec3 p2) {
    float mirror = flipped ? -1.0 : 1.0;
    vec4 tv = w.x * v0.tangent + w.y * v1.tangent + w.z * v2.tangent;
    if (dot(tv.xyz, tv.xyz) > 1e-12) return vec4(mat3(object_to_world) * tv.xyz, (tv.w < 0.0 ? -1.0 : 1.0) * mirror);
    vec2 uva = uv_set == 1u ? v0.uv1 : v0.uv0;
    vec2 uvb = uv_set == 1u ? v1.uv1 : v1.uv0;
    vec2 uvc = uv_set == 1u ? v2.uv1 : v2.uv0;
    vec2 d1 = uvb - uva;
    vec2 d2 = uvc - uva;
    float det = d1.x * d2.y - d1.y * d2.x;
    vec3 tangent = abs(det) > 1e-20 ? ((p1 - p0) * d2.y - (p2 - p0) * d1.y) / det : vec3(0.0);
    // cross(∂P/∂u, ∂P/∂v) = cross(p1 − p0, p2 − p0) / det, which is the front normal's
    // direction for det > 0 unless the instance mirrors: then cross(n, ∂P/∂u) is +∂P/∂v.
    return vec4(tangent, (det < 0.0 ? 1.0 : -1.0) * mirror);
}

// The unit normal `n` (world space) perturbed by the tangent-space normal map `tex` at
// `uv`, its xy scaled by `scale`; `n` itself where the frame degenerates.
vec3 normal_mapped(TextureRef tex, float scale, vec3 n, vec4 tangent_sign, vec2 uv) {
    vec3 tn = sample_texture(tex, uv).xyz * 2.0 - 1.0;
    tn.xy *= scale;
    vec3 tangent = tangent_sign.xyz - n * dot(n, tangent_sign.xyz);
    if (dot(tangent, tangent) <= 1e-20) return n;
    tangent = normalize(tangent);
    vec3 bitangent = cross(n, tangent) * tangent_sign.w;
    vec3 mapped = normalize(tangent * tn.x + bitangent * tn.y + n * max(tn.z, 1e-4));
    return all_finite(mapped) ? mapped : n;
}

Surface make_surface(Hit h, vec3 ray_dir) {
    Surface s;
    Instance inst = instances(h.instance);
    mat4x3 object_to_world = transpose(mat3x4(inst.to_world_row0, inst.to_world_row1, inst.to_world_row2));
    uvec3 vi = triangle_vertices(inst, h.primitive);
    vec3 w = vec3(1.0 - h.bary.x - h.bary.y, h.bary.x, h.bary.y);
    Vertex v0 = vertices(vi.x);
    Vertex v1 = vertices(vi.y);
    Vertex v2 = vertices(vi.z);
    vec3 p0 = object_to_world * vec4(v0.position, 1.0);
    vec3 p1 = object_to_world * vec4(v1.position, 1.0);
    vec3 p2 = object_to_world * vec4(v2.position, 1.0);
    s.p = w.x * p0 + w.y * p1 + w.z * p2;
    vec3 ng = normalize(cross(p1 - p0, p2 - p0));
    bool flipped = (inst.flags & INSTANCE_FLAG_FLIPPED) != 0u;
    if (flipped) ng = -ng;
    s.wo = -ray_dir;
    s.front = dot(ng, s.wo) > 0.0;
    s.instance = h.instance;
    s.primitive = h.primitive;
    s.material = inst.material;
    s.uv0 = w.x * v0.uv0 + w.y * v1.uv0 + w.z * v2.uv0;
    s.uv1 = w.x * v0.uv1 + w.y * v1.uv1 + w.z * v2.uv1;
    Material m = materials(inst.material);

    // Shading normal: interpolated vertex normals (zero = flat), then the normal map.
    // Each vertex normal goes to world space and to unit length before the interpolation,
    // as a mesh with the transform applied to it (and Mitsuba 3, and the glTF sample
    // viewer) has them: under a non-uniform scale interpolating in object space weighs
    // the corners differently (shading normals up to 13° apart on a squashed sphere).
    mat3 normal_to_world = inverse_transpose3(mat3(object_to_world));
    vec3 nv = w.x * normalize_or_zero(normal_to_world * v0.normal) + w.y * normalize_or_zero(normal_to_world * v1.normal) +
              w.z * normalize_or_zero(normal_to_world * v2.normal);
    vec3 n = dot(nv, nv) > 1e-12 ? normalize(nv) : ng;
    if (dot(n, ng) < 0.0) n = -n;  // authored normals agree with the winding
    // The clearcoat's normal: its own map, else the normal before the base's map.
    bool coated = CLEARCOAT && m.clearcoat > 0.0;
    vec3 coat_n = n;
    if (coated && m.clearcoat_normal_tex.index >= 0) {
        TextureRef t = m.clearcoat_normal_tex;
        coat_n = normal_mapped(t, m.clearcoat_normal_scale, n, normal_map_tangent(t.uv_set, w, v0, v1, v2, object_to_world, flipped, p0, p1, p2),
                               t.uv_set == 1u ? s.uv1 : s.uv0);
    }
    if (m.normal_tex.index >= 0) {
        TextureRef t = m.normal_tex;
        n = normal_mapped(t, m.normal_scale, n, normal_map_tangent(t.uv_set, w, v0, v1, v2, object_to_world, flipped, p0, p1, p2),
                          t.uv_set == 1u ? s.uv1 : s.uv0);
    }
    // KHR_materials_anisotropy: the direction of the larger α, in world space, from the
    // tangent frame of the front face (the anisotropy texture's UV set, else the normal
    // texture's): zero where the frame or the direction degenerates (isotropic then).
    float anisotropy = ANISOTROPY ? m.anisotropy_strength : 0.0;
    vec3 anisotropy_dir = vec3(0.0);
    if (ANISOTROPY && anisotropy > 0.0) {
        TextureRef t = m.anisotropy_tex.index >= 0 ? m.anisotropy_tex : m.normal_tex;
        uint uv_set = t.index >= 0 ? t.uv_set : 0u;
        vec2 dir = m.anisotropy_rotation;
        if (m.anisotropy_tex.index >= 0) {
            vec3 a = sample_texture(m.anisotropy_tex, uv_set == 1u ? s.uv1 : s.uv0).rgb;
            vec2 d = a.rg * 2.0 - 1.0;
            d = dot(d, d) > 1e-12 ? normalize(d) : vec2(1.0, 0.0);
            dir = vec2(dir.x * d.x - dir.y * d.y, dir.y * d.x + dir.x * d.y);
            anisotropy *= a.b;
        }
        vec4 ts = normal_map_tangent(uv_set, w, v0, v1, v2, object_to_world, flipped, p0, p1, p2);
        vec3 tangent = ts.xyz - n * dot(n, ts.xyz);
        if (dot(tangent, tangent) > 1e-20) {
            tangent = normalize(tangent);
            anisotropy_dir = tangent * dir.x + cross(n, tangent) * (ts.w * dir.y);
        }
    }
    // Two-sided BSDF: work on the side the ray came from.
    if (!s.front) {
        ng = -ng;
        n = -n;
        coat_n = -coat_n;
    }
    if (dot(n, ng) <= 1e-4) n = ng;
    if (dot(coat_n, ng) <= 1e-4) coat_n = ng;
    // A view from below the shading surface (the silhouette of a coarse smooth mesh, a
    // texel tilted away at a grazing view) sees its other side, the shading frame turned
    // over, as Mitsuba 3's `twosided` and pbrt-v4 decide sides in the shading frame: light
    // then reflects between the two surfaces (above the geometric one, below the shading
    // one; surface_bsdf_eval_pdf keeps directions below the geometric surface dark, so
    // nothing leaks through it). Transmitting surfaces keep the frame of their side.
    if (dot(n, s.wo) < 0.0 && m.transmission <= 0.0 && !(DIFFUSE_TRANSMISSION && m.diffuse_transmission > 0.0)) {
        n = -n;
        coat_n = -coat_n;
    }
    s.ng = ng;
    s.n = n;
    // The local frame's x along the anisotropy direction (the BSDF's alpha_t), else any.
    vec3 anisotropy_t = ANISOTROPY ? anisotropy_dir - n * dot(n, anisotropy_dir) : vec3(0.0);
    if (ANISOTROPY && dot(anisotropy_t, anisotropy_t) > 1e-12) {
        s.t = normalize(anisotropy_t);
        s.b = cross(n, s.t);
    } else {
        make_basis(n, s.t, s.b);
    }

    // Material.
    vec4 vertex_color = interpolate_color(inst, vi, w);
    vec4 base = m.base_color * vertex_color;
    if (m.base_color_tex.index >= 0)
        base *= sample_texture(m.base_color_tex, m.base_color_tex.uv_set == 1u ? s.uv1 : s.uv0);
    float metallic = m.metallic;
    float roughness = m.roughness;
    if (m.metallic_roughness_tex.index >= 0) {
        vec4 mr = sample_texture(m.metallic_roughness_tex, m.metallic_roughness_tex.uv_set == 1u ? s.uv1 : s.uv0);
        roughness *= mr.g;
        metallic *= mr.b;
    }
    s.roughness = roughness;
    s.bsdf.base_color = clamp(base.rgb, 0.0, 1.0);
    s.bsdf.metallic = clamp(metallic, 0.0, 1.0);
    s.bsdf.alpha = max(roughness * roughness, MIN_GGX_ALPHA);
    s.bsdf.alpha_t = s.bsdf.alpha;
    if (ANISOTROPY && dot(anisotropy_t, anisotropy_t) > 1e-12)
        s.bsdf.alpha_t = max(mix(roughness * roughness, 1.0, sqr(clamp(anisotropy, 0.0, 1.0))), MIN_GGX_ALPHA);
    s.bsdf.specular = m.specular;
    float f0 = sqr((m.ior - 1.0) / (m.ior + 1.0));
    s.bsdf.f0_dielectric = min(f0 * m.specular_color, vec3(1.0)) * m.specular;
    float transmission = m.transmission;
    if (transmission > 0.0 && m.transmission_tex.index >= 0)
        transmission *= sample_texture(m.transmission_tex, m.transmission_tex.uv_set == 1u ? s.uv1 : s.uv0).r;
    // Metals do not transmit: the lobe is part of the dielectric (the BSDF weighs it by
    // 1 − metallic), so a fully metallic surface stays opaque for the path's geometry too.
    s.bsdf.transmission = s.bsdf.metallic < 1.0 ? clamp(transmission, 0.0, 1.0) : 0.0;
    // KHR_materials_diffuse_transmission: a share of the diffuse lobe that the
    // transmission leaves goes through the surface, tinted by its colour (metals: none,
    // as above).
    s.bsdf.diffuse_transmission = 0.0;
    s.bsdf.diffuse_transmission_color = vec3(1.0);
    if (DIFFUSE_TRANSMISSION && m.diffuse_transmission > 0.0 && s.bsdf.metallic < 1.0) {
        float dt = m.diffuse_transmission;
        if (m.diffuse_transmission_tex.index >= 0)
            dt *= sample_texture(m.diffuse_transmission_tex, m.diffuse_transmission_tex.uv_set == 1u ? s.uv1 : s.uv0).a;
        vec3 color = m.diffuse_transmission_color;
        if (m.diffuse_transmission_color_tex.index >= 0)
            color *= sample_texture(m.diffuse_transmission_color_tex,
                                    m.diffuse_transmission_color_tex.uv_set == 1u ? s.uv1 : s.uv0).rgb;
        s.bsdf.diffuse_transmission = clamp(dt, 0.0, 1.0);
        s.bsdf.diffuse_transmission_color = clamp(color, 0.0, 1.0);
    }
    // The boundary of a solid (KHR_materials_volume) that light enters, refracted or
    // diffusely: the index ratio across it seen from wo; the solid lies behind the front
    // face (its outward side).
    bool solid = SOLIDS && (s.bsdf.transmission > 0.0 || s.bsdf.diffuse_transmission > 0.0)
        && (m.flags & MATERIAL_FLAG_VOLUME) != 0u;
    float ior = max(m.ior, 1.0);
    s.bsdf.eta = solid ? (s.front ? ior : 1.0 / ior) : 0.0;
    s.bsdf.dispersion = DISPERSION && solid ? max(m.dispersion, 0.0) : 0.0;
    // KHR_materials_clearcoat.
    s.bsdf.coat = 0.0;
    s.bsdf.coat_alpha = 1.0;
    s.bsdf.coat_n = vec3(0.0, 0.0, 1.0);
    if (coated) {
        float coat = m.clearcoat;
        if (m.clearcoat_tex.index >= 0)
            coat *= sample_texture(m.clearcoat_tex, m.clearcoat_tex.uv_set == 1u ? s.uv1 : s.uv0).r;
        float coat_roughness = m.clearcoat_roughness;
        if (m.clearcoat_roughness_tex.index >= 0)
            coat_roughness *= sample_texture(m.clearcoat_roughness_tex, m.clearcoat_roughness_tex.uv_set == 1u ? s.uv1 : s.uv0).g;
        s.bsdf.coat = clamp(coat, 0.0, 1.0);
        s.bsdf.coat_alpha = max(sqr(clamp(coat_roughness, 0.0, 1.0)), MIN_GGX_ALPHA);
        s.bsdf.coat_n = normalize(to_local(coat_n, s.t, s.b, s.n));
    }
    // KHR_materials_sheen.
    s.bsdf.sheen_color = vec3(0.0);
    s.bsdf.sheen_roughness = 1.0;
    if (SHEEN && max3(m.sheen_color) > 0.0) {
        vec3 sheen = m.sheen_color;
        if (m.sheen_color_tex.index >= 0)
            sheen *= sample_texture(m.sheen_color_tex, m.sheen_color_tex.uv_set == 1u ? s.uv1 : s.uv0).rgb;
        float r = m.sheen_roughness;
        if (m.sheen_roughness_tex.index >= 0)
            r *= sample_texture(m.sheen_roughness_tex, m.sheen_roughness_tex.uv_set == 1u ? s.uv1 : s.uv0).a;
        s.bsdf.sheen_color = clamp(sheen, 0.0, 1.0);
        s.bsdf.sheen_roughness = clamp(r, 0.0, 1.0);
    }
    // KHR_materials_iridescence: the thin film's weight (factor × texture R) and thickness
    // (the maximum, or mix(minimum, maximum, texture G)).
    s.bsdf.iridescence = 0.0;
    s.bsdf.iridescence_ior = 1.3;
    s.bsdf.iridescence_thickness = 0.0;
    if (IRIDESCENCE && m.iridescence > 0.0) {
        float weight = m.iridescence;
        if (m.iridescence_tex.index >= 0)
            weight *= sample_texture(m.iridescence_tex, m.iridescence_tex.uv_set == 1u ? s.uv1 : s.uv0).r;
        float thickness = m.iridescence_thickness_max;
        if (m.iridescence_thickness_tex.index >= 0)
            thickness = mix(m.iridescence_thickness_min, m.iridescence_thickness_max,
                            sample_texture(m.iridescence_thickness_tex,
                                           m.iridescence_thickness_tex.uv_set == 1u ? s.uv1 : s.uv0).g);
        s.bsdf.iridescence = clamp(weight, 0.0, 1.0);
        s.bsdf.iridescence_ior = m.iridescence_ior;
        s.bsdf.iridescence_thickness = max(thickness, 0.0);
    }
    // With these at 0 every lobe but the Lambertian one has weight 0 (inc/bsdf.glsl).
    s.lambertian = s.bsdf.metallic == 0.0 && s.bsdf.specular == 0.0 && s.bsdf.transmission == 0.0
        && s.bsdf.diffuse_transmission == 0.0 && s.bsdf.coat == 0.0 && max3(s.bsdf.sheen_color) == 0.0
        && s.bsdf.iridescence == 0.0;

    // Emission: front face only unless the material is double-sided.
    bool emits = s.front || (m.flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u;
    s.emission = emits ? material_emission(m, s.uv0, s.uv1, vertex_color) : vec3(0.0);
    s.light_tri = inst.light_index_offset == INVALID_INDEX ? INVALID_INDEX
                                                           : triangle_light_index(inst.light_index_offset + h.primitive);
    return s;
}

vec3 surface_to_local(Surface s, vec3 v) { return to_local(v, s.t, s.b, s.n); }
vec3 surface_to_world(Surface s, vec3 v) { return to_world(v, s.t, s.b, s.n); }

// The surface's BSDF goes through these functions, which take the Lambertian lobe alone
// (inc/bsdf.glsl: the same bits as the general BSDF there) where BSDF_KERNEL says.
bool surface_lambertian(Surface s) {
    return BSDF_KERNEL == BSDF_KERNEL_LAMBERTIAN || (BSDF_KERNEL == BSDF_KERNEL_PER_SURFACE && s.lambertian);
}

// What the BSDF needs of the surface's wo, once per shading point (see BsdfWo).
BsdfWo surface_bsdf_at(Surface s) {
    vec3 wo = surface_to_local(s, s.wo);
    return surface_lambertian(s) ? bsdf_at_lambertian(wo) : bsdf_at(s.bsdf, wo);
}

// Whether light can go through the surface (KHR_materials_transmission or
// KHR_materials_diffuse_transmission): directions below the geometric surface then
// carry light too.
bool surface_transmits(Surface s) {
    return BSDF_KERNEL != BSDF_KERNEL_LAMBERTIAN && (s.bsdf.transmission > 0.0 || s.bsdf.diffuse_transmission > 0.0);
}

// Sample a local direction (bsdf_sample's arguments; `c` is surface_bsdf_at(s)).
bool surface_bsdf_sample(Surface s, BsdfWo c, vec3 u, float u_fresnel, out vec3 wi_local) {
    if (surface_lambertian(s)) return lambertian_sample(c, u, wi_local);
    return bsdf_sample(s.bsdf, c, u, u_fresnel, wi_local);
}

// The absorption coefficient along a ray leaving the surface toward w, for a path that
// reached it through a medium of coefficient `here` (the side of wo): crossing a solid's
// boundary enters the solid (from its front) or leaves it for the outside (clear; solids
// do not nest).
vec3 medium_toward(Surface s, vec3 w, vec3 here) {
    if (s.bsdf.eta <= 0.0 || dot(w, s.ng) > 0.0) return here;
    return s.front ? materials(s.material).attenuation : vec3(0.0);
}

// The geometric normal on the side of direction w (the side a ray toward w leaves from).
vec3 surface_side_normal(Surface s, vec3 w) { return dot(w, s.ng) < 0.0 ? -s.ng : s.ng; }

// f·|cos| for world directions and the BSDF's sampling density of wi. A direction must
// lie on the same side of the geometric and the shading surface (no light leaks through
// shading normals): above both, or below both for a transmitting surface; zero otherwise.
// (Where the view is below the shading normal, make_surface has turned the shading frame
// over: "above" it is then the wedge between the two surfaces.)
// `c` is surface_bsdf_at(s).
vec3 surface_bsdf_eval_pdf(Surface s, BsdfWo c, vec3 wi, out float pdf) {
    pdf = 0.0;
    float cg = dot(wi, s.ng);
    if (cg == 0.0 || (cg < 0.0 && !surface_transmits(s))) return vec3(0.0);
    vec3 local = surface_to_local(s, wi);
    if ((local.z < 0.0) != (cg < 0.0)) return vec3(0.0);
    if (surface_lambertian(s)) return lambertian_eval_pdf(s.bsdf, c, local, pdf);
    return bsdf_eval_pdf(s.bsdf, c, local, pdf);
}

vec3 surface_bsdf_eval(Surface s, vec3 wi) {
    float unused_pdf;
    return surface_bsdf_eval_pdf(s, surface_bsdf_at(s), wi, unused_pdf);
}

float surface_bsdf_pdf(Surface s, vec3 wi) {
    float pdf;
    surface_bsdf_eval_pdf(s, surface_bsdf_at(s), wi, pdf);
    return pdf;
}

#endif
