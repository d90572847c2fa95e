// The scene's buffers and textures as the path-tracing kernel binds them (set 0).
#ifndef INC_SCENE_DATA_GLSL
#define INC_SCENE_DATA_GLSL

#include "common.glsl"

// The traversal variant: ray queries against the TLAS, or (LANTERNA_SOFTWARE_TRAVERSAL,
// the *_sw kernels) inc/bvh.glsl over the CPU-built BVH. The software variant declares no
// acceleration structure, so it needs neither VK_KHR_ray_query nor its SPIR-V capability.
#ifdef LANTERNA_SOFTWARE_TRAVERSAL
layout(set = 0, binding = BINDING_BVH_NODES, scalar) readonly buffer BvhNodeBuffer { BvhNode bvh_nodes[]; };
layout(set = 0, binding = BINDING_BVH_TRIANGLES, scalar) readonly buffer BvhTriangleBuffer { BvhTriangle bvh_triangles[]; };
#else
#extension GL_EXT_ray_query : require
layout(set = 0, binding = BINDING_TLAS) uniform accelerationStructureEXT tlas;
#endif
layout(set = 0, binding = BINDING_PARAMS, scalar) readonly buffer ParamsBuffer { FrameParams params; };
layout(set = 0, binding = BINDING_VERTICES, scalar) readonly buffer VertexBuffer { Vertex vertices[]; };
layout(set = 0, binding = BINDING_VERTEX_COLORS, scalar) readonly buffer VertexColorBuffer { vec4 vertex_colors[]; };
layout(set = 0, binding = BINDING_INDICES, scalar) readonly buffer IndexBuffer { uint indices[]; };
layout(set = 0, binding = BINDING_INSTANCES, scalar) readonly buffer InstanceBuffer { Instance instances[]; };
layout(set = 0, binding = BINDING_MATERIALS, scalar) readonly buffer MaterialBuffer { Material materials[]; };
layout(set = 0, binding = BINDING_TEXTURES) uniform sampler2D textures[];
layout(set = 0, binding = BINDING_LIGHT_TRIANGLES, scalar) readonly buffer LightTriangleBuffer { LightTriangle light_triangles[]; };
layout(set = 0, binding = BINDING_LIGHT_CANDIDATES, scalar) readonly buffer LightCandidateBuffer { LightCandidateTriangle light_candidates[]; };
layout(set = 0, binding = BINDING_LIGHT_MODELS, scalar) readonly buffer LightModelBuffer { LightModel light_models[]; };
layout(set = 0, binding = BINDING_MODEL_ALIAS, scalar) readonly buffer ModelAliasBuffer { AliasEntry model_alias[]; };
layout(set = 0, binding = BINDING_TRIANGLE_ALIAS, scalar) readonly buffer TriangleAliasBuffer { AliasEntry triangle_alias[]; };
layout(set = 0, binding = BINDING_PUNCTUAL_LIGHTS, scalar) readonly buffer PunctualBuffer { PunctualLight punctual_lights[]; };
layout(set = 0, binding = BINDING_TRIANGLE_LIGHT_INDEX, scalar) readonly buffer TriangleLightIndexBuffer { uint triangle_light_index[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTER_OFFSETS, scalar) readonly buffer PixelEmitterOffsetBuffer { uint pixel_emitter_offsets[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTERS, scalar) readonly buffer PixelEmitterBuffer { PixelEmitter pixel_emitters[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTER_FLAGS, scalar) readonly buffer PixelEmitterFlagBuffer { uint pixel_emitter_flags[]; };
layout(set = 0, binding = BINDING_FILM, scalar) buffer FilmBuffer { uint64_t film[]; };
layout(set = 0, binding = BINDING_AOV, scalar) buffer AovBuffer { float aov[]; };
layout(set = 0, binding = BINDING_STATS, scalar) buffer StatsBuffer { uint64_t stats[]; };
layout(set = 0, binding = BINDING_OUTLIERS, scalar) buffer OutlierBuffer { float outliers[]; };

layout(push_constant, scalar) uniform Push { PushConstants pc; };

#endif
