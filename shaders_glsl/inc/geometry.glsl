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

#endif
