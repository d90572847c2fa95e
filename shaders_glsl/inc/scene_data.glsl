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
// the other branch away when the pipeline is made.
layout(constant_id = 7) const bool SCENE_ADDRESSES = false;
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#define SCENE_REFERENCE(Ref, T) layout(buffer_reference, scalar, buffer_reference_align = 4) readonly buffer Ref { T v[]; }
// One read-only scene array: its storage buffer (`Block` at binding `B`, the array
// `bound`), its buffer reference `Ref`, and the accessor `name(i)` reading one or the
// other (the address is FrameParams.`address`). Structs are returned from two branches,
// since the two blocks' structs are distinct SPIR-V types that only a return converts;
// plain values (SCENE_VALUES) are selected with `?:`.
#define SCENE_BUFFERS(T, Block, bound, B, Ref) \
    layout(set = 0, binding = B, scalar) readonly buffer Block { T bound[]; }; \
    SCENE_REFERENCE(Ref, T);
#define SCENE_ARRAY(T, name, Block, bound, B, Ref, address) \
    SCENE_BUFFERS(T, Block, bound, B, Ref) \
    T name(uint i) { \
        if (SCENE_ADDRESSES) return Ref(params.address).v[i]; \
        return bound[i]; \
    }
#define SCENE_VALUES(T, name, Block, bound, B, Ref, address) \
    SCENE_BUFFERS(T, Block, bound, B, Ref) \
    T name(uint i) { return SCENE_ADDRESSES ? Ref(params.address).v[i] : bound[i]; }
SCENE_ARRAY(Vertex, vertices, VertexBuffer, vertices_bound, BINDING_VERTICES, VertexRef, vertices_address)
SCENE_VALUES(vec4, vertex_colors, VertexColorBuffer, vertex_colors_bound, BINDING_VERTEX_COLORS, VertexColorRef, vertex_colors_address)
SCENE_VALUES(uint, indices, IndexBuffer, indices_bound, BINDING_INDICES, IndexRef, indices_address)
SCENE_ARRAY(Instance, instances, InstanceBuffer, instances_bound, BINDING_INSTANCES, InstanceRef, instances_address)
SCENE_ARRAY(Material, materials, MaterialBuffer, materials_bound, BINDING_MATERIALS, MaterialRef, materials_address)
SCENE_ARRAY(LightTriangle, light_triangles, LightTriangleBuffer, light_triangles_bound, BINDING_LIGHT_TRIANGLES, LightTriangleRef, light_triangles_address)
SCENE_ARRAY(LightCandidateTriangle, light_candidates, LightCandidateBuffer, light_candidates_bound, BINDING_LIGHT_CANDIDATES, LightCandidateRef, light_candidates_address)
SCENE_ARRAY(LightModel, light_models, LightModelBuffer, light_models_bound, BINDING_LIGHT_MODELS, LightModelRef, light_models_address)
SCENE_ARRAY(AliasEntry, model_alias, ModelAliasBuffer, model_alias_bound, BINDING_MODEL_ALIAS, ModelAliasRef, model_alias_address)
SCENE_ARRAY(AliasEntry, triangle_alias, TriangleAliasBuffer, triangle_alias_bound, BINDING_TRIANGLE_ALIAS, TriangleAliasRef, triangle_alias_address)
SCENE_ARRAY(LightTreeNode, light_tree, LightTreeBuffer, light_tree_bound, BINDING_LIGHT_TREE, LightTreeRef, light_tree_address)
SCENE_ARRAY(PunctualLight, punctual_lights, PunctualBuffer, punctual_lights_bound, BINDING_PUNCTUAL_LIGHTS, PunctualLightRef, punctual_lights_address)
SCENE_VALUES(float, light_profiles, LightProfileBuffer, light_profiles_bound, BINDING_LIGHT_PROFILES, LightProfileRef, light_profiles_address)
SCENE_VALUES(uint, triangle_light_index, TriangleLightIndexBuffer, triangle_light_index_bound, BINDING_TRIANGLE_LIGHT_INDEX, TriangleLightIndexRef, triangle_light_index_address)
#ifdef LANTERNA_SOFTWARE_TRAVERSAL
SCENE_ARRAY(BvhNode, bvh_nodes, BvhNodeBuffer, bvh_nodes_bound, BINDING_BVH_NODES, BvhNodeRef, bvh_nodes_address)
SCENE_ARRAY(BvhTriangle, bvh_triangles, BvhTriangleBuffer, bvh_triangles_bound, BINDING_BVH_TRIANGLES, BvhTriangleRef, bvh_triangles_address)
#endif
layout(set = 0, binding = BINDING_PIXEL_EMITTER_OFFSETS, scalar) readonly buffer PixelEmitterOffsetBuffer { uint pixel_emitter_offsets[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTERS, scalar) readonly buffer PixelEmitterBuffer { PixelEmitter pixel_emitters[]; };
layout(set = 0, binding = BINDING_PIXEL_EMITTER_FLAGS, scalar) readonly buffer PixelEmitterFlagBuffer { uint pixel_emitter_flags[]; };
layout(set = 0, binding = BINDING_FILM, scalar) buffer FilmBuffer { uint64_t film[]; };
layout(set = 0, binding = BINDING_AOV, scalar) buffer AovBuffer { float aov[]; };
layout(set = 0, binding = BINDING_STATS, scalar) buffer StatsBuffer { uint64_t stats[]; };
layout(set = 0, binding = BINDING_OUTLIERS, scalar) buffer OutlierBuffer { float outliers[]; };

layout(push_constant, scalar) uniform Push { PushConstants pc; };

// The SD-tree's arrays follow the scene's: with SCENE_ADDRESSES, through the addresses
// in the push constants (inc/guiding_buffers.glsl).
#ifdef LANTERNA_GUIDING_BUFFERS_GLSL
#error "inc/scene_data.glsl must be included before inc/guiding_buffers.glsl"
#endif
#define GUIDE_ADDRESSES SCENE_ADDRESSES
#define GUIDE_ADDRESS(name) pc.name

#endif
