// Triangle data access: vertex indices, interpolated attributes, texture coordinates.
#ifndef INC_GEOMETRY_GLSL
#define INC_GEOMETRY_GLSL

#include "common.glsl"
#include "scene_data.glsl"

uvec3 triangle_vertices(Instance inst, uint primitive) {
    uint base = inst.index_offset + 3u * primitive;
    return uvec3(indices(base), indices(base + 1u), indices(base + 2u)) + inst.vertex_offset;
}

vec2 interpolate_uv(uvec3 v, vec3 w, uint set) {
    if (set == 1u)
        return w.x * vertices(v.x).uv1 + w.y * vertices(v.y).uv1 + w.z * vertices(v.z).uv1;
    return w.x * vertices(v.x).uv0 + w.y * vertices(v.y).uv0 + w.z * vertices(v.z).uv0;
}

// The interpolated COLOR_0 of an instance's triangle with global vertex indices v (white
// without vertex colours): it multiplies the base colour and its alpha.
vec4 interpolate_color(Instance inst, uvec3 v, vec3 w) {
    if (inst.color_offset == INVALID_INDEX) return vec4(1.0);
    uvec3 c = v - inst.vertex_offset + inst.color_offset;
    return w.x * vertex_colors(c.x) + w.y * vertex_colors(c.y) + w.z * vertex_colors(c.z);
}

// KHR_texture_transform: offset · rotation · scale applied to a UV.
// The rotation (rare) is skipped when it is zero: sin() and cos() are costly on CPU
// devices, and with c = 1, s = 0 the rotation is the identity anyway.
vec2 texture_uv(TextureRef t, vec2 uv) {
    vec2 p = uv * t.scale;
    if (t.rotation != 0.0) {
        float s = sin(t.rotation);
        float c = cos(t.rotation);
        p = vec2(c * p.x + s * p.y, -s * p.x + c * p.y);
    }
    return p + t.offset;
}

vec4 sample_texture(TextureRef t, vec2 uv) {
    return textureLod(textures[nonuniformEXT(uint(t.index))], texture_uv(t, uv), 0.0);
}

// The alpha of an instance's triangle at barycentrics `bary` (of vertices 1 and 2): the
// base colour's, times its texture's and the vertex colour's, as the glTF spec says.
float geometry_alpha(Instance inst, Material m, uint primitive, vec2 bary) {
    float alpha = m.base_color.a;
    if (m.base_color_tex.index >= 0 || inst.color_offset != INVALID_INDEX) {
        uvec3 v = triangle_vertices(inst, primitive);
        vec3 w = vec3(1.0 - bary.x - bary.y, bary.x, bary.y);
        alpha *= interpolate_color(inst, v, w).a;
        if (m.base_color_tex.index >= 0)
            alpha *= sample_texture(m.base_color_tex, interpolate_uv(v, w, m.base_color_tex.uv_set)).a;
    }
    return alpha;
}

// How much of the surface is there at a point, as rays find it (alpha_passes,
// inc/trace.glsl, keeps a hit with this probability; coverage_at in src/lights/mod.rs
// mirrors it for the light table): 1 for opaque materials; for MASK 1 where alpha reaches the cutoff and
// 0 elsewhere; for BLEND alpha, the probability that a ray's stochastic test keeps the
// hit. Light emitted at the point is scaled by it: a light sample on a hole of a masked
// emitter carries nothing, as a ray through that hole finds nothing.
float geometry_coverage(uint instance, uint primitive, vec2 bary) {
    Instance inst = instances(instance);
    Material m = materials(inst.material);
    if (m.alpha_mode == ALPHA_MODE_OPAQUE) return 1.0;
    float alpha = geometry_alpha(inst, m, primitive, bary);
    if (m.alpha_mode == ALPHA_MODE_MASK) return alpha >= m.alpha_cutoff ? 1.0 : 0.0;
    return clamp(alpha, 0.0, 1.0);
}

#endif
