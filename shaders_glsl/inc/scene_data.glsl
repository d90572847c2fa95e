// The scene's buffers and textures as the path-tracing kernel binds them (set 0).
#ifndef INC_SCENE_DATA_GLSL
#define INC_SCENE_DATA_GLSL

#include "common.glsl"

// The traversal variant: ray queries against the TLAS, or (LANTERNA_SOFTWARE_TRAVERSAL,
// the *_sw kernels) inc/bvh.glsl over the CPU-built BVH. The software variant declares no
// acceleration structure, so it needs neither VK_KHR_ray_query nor its SPIR-V capability.
#ifndef LANTERNA_SOFTWARE_TRAVERSAL
#extension GL_EXT_ray_query : require
layout(set = 0, binding = BINDING_TLAS) uniform accelerationStructureEXT tlas;
#endif
layout(set = 0, binding = BINDING_PARAMS, scalar) readonly buffer ParamsBuffer { FrameParams params; };
layout(set = 0, binding = BINDING_TEXTURES) uniform sampler2D textures[];

// The scene's read-only arrays, read as `vertices(i)`: from the bound storage buffer, or
// with SCENE_ADDRESSES (CPU devices) through a buffer reference at the device address
// FrameParams holds. Lavapipe loads a storage buffer at an index that differs between
// lanes one lane at a time (the lane's descriptor, a bounds check and a branch, per lane
// and per component) and a buffer reference with one masked gather per component:
// `pt` 1.1–1.7×, `ris` 1.5–2× as fast there. On NVIDIA's H200 the storage buffers are
// faster (the references: `pt` ×0.88, `ris` ×0.90; bench/README.md). The constant folds
// the other branch away when the pipeline is made. (Functions, not `?:` on the arrays:
// the two blocks' structs are distinct SPIR-V types, which only a return converts.)
layout(constant_id = 7) const bool SCENE_ADDRESSES = false;
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#define SCENE_REFERENCE(Ref, T) layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Ref { T v[]; }
layout(set = 0, binding = BINDING_VERTICES, scalar) readonly buffer VertexBuffer { Vertex vertices_bound[]; };
SCENE_REFERENCE(VertexRef, Vertex);
Vertex vertices(uint i) {
    if (SCENE_ADDRESSES) return VertexRef(params.vertices_address).v[i];
    return vertices_bound[i];
}
layout(set = 0, binding = BINDING_VERTEX_COLORS, scalar) readonly buffer VertexColorBuffer { vec4 vertex_colors_bound[]; };
SCENE_REFERENCE(VertexColorRef, vec4);
vec4 vertex_colors(uint i) { return SCENE_ADDRESSES ? VertexColorRef(params.vertex_colors_address).v[i] : vertex_colors_bound[i]; }
layout(set = 0, binding = BINDING_INDICES, scalar) readonly buffer IndexBuffer { uint indices_bound[]; };
SCENE_REFERENCE(IndexRef, uint);
uint indices(uint i) { return SCENE_ADDRESSES ? IndexRef(params.indices_address).v[i] : indices_bound[i]; }
layout(set = 0, binding = BINDING_INSTANCES, scalar) readonly buffer InstanceBuffer { Instance instances_bound[]; };
SCENE_REFERENCE(InstanceRef, Instance);
Instance instances(uint i) {
    if (SCENE_ADDRESSES) return InstanceRef(params.instances_address).v[i];
    return instances_bound[i];
}
layout(set = 0, binding = BINDING_MATERIALS, scalar) readonly buffer MaterialBuffer { Material materials_bound[]; };
SCENE_REFERENCE(MaterialRef, Material);
Material materials(uint i) {
    if (SCENE_ADDRESSES) return MaterialRef(params.materials_address).v[i];
    return materials_bound[i];
}
layout(set = 0, binding = BINDING_LIGHT_TRIANGLES, scalar) readonly buffer LightTriangleBuffer { LightTriangle light_triangles_bound[]; };
SCENE_REFERENCE(LightTriangleRef, LightTriangle);
LightTriangle light_triangles(uint i) {
    if (SCENE_ADDRESSES) return LightTriangleRef(params.light_triangles_address).v[i];
    return light_triangles_bound[i];
}
layout(set = 0, binding = BINDING_LIGHT_CANDIDATES, scalar) readonly buffer LightCandidateBuffer { LightCandidateTriangle light_candidates_bound[]; };
SCENE_REFERENCE(LightCandidateRef, LightCandidateTriangle);
LightCandidateTriangle light_candidates(uint i) {
    if (SCENE_ADDRESSES) return LightCandidateRef(params.light_candidates_address).v[i];
    return light_candidates_bound[i];
}
layout(set = 0, binding = BINDING_LIGHT_MODELS, scalar) readonly buffer LightModelBuffer { LightModel light_models_bound[]; };
SCENE_REFERENCE(LightModelRef, LightModel);
LightModel light_models(uint i) {
    if (SCENE_ADDRESSES) return LightModelRef(params.light_models_address).v[i];
    return light_models_bound[i];
}
layout(set = 0, binding = BINDING_MODEL_ALIAS, scalar) readonly buffer ModelAliasBuffer { AliasEntry model_alias_bound[]; };
SCENE_REFERENCE(ModelAliasRef, AliasEntry);
AliasEntry model_alias(uint i) {
    if (SCENE_ADDRESSES) return ModelAliasRef(params.model_alias_address).v[i];
    return model_alias_bound[i];
}
layout(set = 0, binding = BINDING_TRIANGLE_ALIAS, scalar) readonly buffer TriangleAliasBuffer { AliasEntry triangle_alias_bound[]; };
SCENE_REFERENCE(TriangleAliasRef, AliasEntry);
AliasEntry triangle_alias(uint i) {
    if (SCENE_ADDRESSES) return TriangleAliasRef(params.triangle_alias_address).v[i];
    return triangle_alias_bound[i];
}
layout(set = 0, binding = BINDING_PUNCTUAL_LIGHTS, scalar) readonly buffer PunctualBuffer { PunctualLight punctual_lights_bound[]; };
SCENE_REFERENCE(PunctualLightRef, PunctualLight);
PunctualLight punctual_lights(uint i) {
    if (SCENE_ADDRESSES) return PunctualLightRef(params.punctual_lights_address).v[i];
    return punctual_lights_bound[i];
}
layout(set = 0, binding = BINDING_TRIANGLE_LIGHT_INDEX, scalar) readonly buffer TriangleLightIndexBuffer { uint triangle_light_index_bound[]; };
SCENE_REFERENCE(TriangleLightIndexRef, uint);
uint triangle_light_index(uint i) { return SCENE_ADDRESSES ? TriangleLightIndexRef(params.triangle_light_index_address).v[i] : triangle_light_index_bound[i]; }
#ifdef LANTERNA_SOFTWARE_TRAVERSAL
layout(set = 0, binding = BINDING_BVH_NODES, scalar) readonly buffer BvhNodeBuffer { BvhNode bvh_nodes_bound[]; };
SCENE_REFERENCE(BvhNodeRef, BvhNode);
BvhNode bvh_nodes(uint i) {
    if (SCENE_ADDRESSES) return BvhNodeRef(params.bvh_nodes_address).v[i];
    return bvh_nodes_bound[i];
}
layout(set = 0, binding = BINDING_BVH_TRIANGLES, scalar) readonly buffer BvhTriangleBuffer { BvhTriangle bvh_triangles_bound[]; };
SCENE_REFERENCE(BvhTriangleRef, BvhTriangle);
BvhTriangle bvh_triangles(uint i) {
    if (SCENE_ADDRESSES) return BvhTriangleRef(params.bvh_triangles_address).v[i];
    return bvh_triangles_bound[i];
}
#endif
layout(set = 0, binding = BINDING_PIXEL_EMITTER_OFFSETS, scalar) readonly buffer PixelEmitterOffsetBuffer { uint pixel_emitter_offsets[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTERS, scalar) readonly buffer PixelEmitterBuffer { PixelEmitter pixel_emitters[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTER_FLAGS, scalar) readonly buffer PixelEmitterFlagBuffer { uint pixel_emitter_flags[]; };
layout(set = 0, binding = BINDING_FILM, scalar) buffer FilmBuffer { uint64_t film[]; };
layout(set = 0, binding = BINDING_AOV, scalar) buffer AovBuffer { float aov[]; };
layout(set = 0, binding = BINDING_STATS, scalar) buffer StatsBuffer { uint64_t stats[]; };
layout(set = 0, binding = BINDING_OUTLIERS, scalar) buffer OutlierBuffer { float outliers[]; };

layout(push_constant, scalar) uniform Push { PushConstants pc; };

#endif
