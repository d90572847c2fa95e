// Descriptor bindings of the path-tracing kernel (set 0) and the test kernels.
// Single source of truth: build.rs turns every #define here into a Rust constant.
#ifndef LANTERNA_BINDINGS_H
#define LANTERNA_BINDINGS_H

#define BINDING_TLAS 0
#define BINDING_PARAMS 1
#define BINDING_VERTICES 2
#define BINDING_INDICES 3
#define BINDING_INSTANCES 4
#define BINDING_MATERIALS 5
#define BINDING_TEXTURES 6
#define BINDING_LIGHT_TRIANGLES 7
#define BINDING_LIGHT_MODELS 8
#define BINDING_MODEL_ALIAS 9
#define BINDING_TRIANGLE_ALIAS 10
#define BINDING_PUNCTUAL_LIGHTS 11
#define BINDING_TRIANGLE_LIGHT_INDEX 12
#define BINDING_FILM 13
#define BINDING_AOV 14
#define BINDING_STATS 15
#define BINDING_GUIDE_SPATIAL 16
#define BINDING_GUIDE_LEAVES 17
#define BINDING_GUIDE_SAMPLING 18
#define BINDING_GUIDE_TRAINING 19
#define BINDING_OUTLIERS 20
#define BINDING_GUIDE_LIGHTS 21
#define BINDING_GUIDE_LIGHT_TRAINING 22
// Records of the learned BSDF/guide selection probability (training passes).
#define BINDING_GUIDE_SELECTION 23
// Software traversal (the ray-query kernels bind BINDING_TLAS instead).
#define BINDING_BVH_NODES 24
#define BINDING_BVH_TRIANGLES 25
// The trace kernel's rays and hits (tests/trace.comp).
#define BINDING_TRACE_RAYS 26
#define BINDING_TRACE_HITS 27
// Compact light-triangle records for light sampling (LightCandidateTriangle).
#define BINDING_LIGHT_CANDIDATES 28
// Small emitters seen directly, sampled inside the pixels they cover (pixel_emitters.rs):
// per pixel an offset into the pieces, the pieces, and a bit per light triangle.
#define BINDING_PIXEL_EMITTER_OFFSETS 29
#define BINDING_PIXEL_EMITTERS 30
#define BINDING_PIXEL_EMITTER_FLAGS 31
// Vertex colours (glTF COLOR_0, linear RGBA) of the primitives that have them.
#define BINDING_VERTEX_COLORS 32
// World-space light reuse (--light-reuse world): the hash grid's two halves of ReuseCell.
#define BINDING_REUSE_CELLS 33
// Learned light visibility (--light-visibility learned): a snapshot half and a live half
// of per-(cell, light model) shadow-ray counts.
#define BINDING_LIGHT_VISIBILITY 34
// The light tree's nodes (--source tree, LightTreeNode).
#define BINDING_LIGHT_TREE 35
// IES light profiles (EXT_lights_ies; PunctualLight.profile, src/scene/ies.rs).
#define BINDING_LIGHT_PROFILES 36
#define BINDING_COUNT 37

// Upper bound on bindless textures in one scene.
#define MAX_TEXTURES 8192

// Test kernels use their own small layout: one uniform-free set of storage buffers.
#define TEST_BINDING_IN 0
#define TEST_BINDING_OUT 1
#define TEST_BINDING_AUX 2

#endif
