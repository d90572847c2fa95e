// Touches every shared struct so that build.rs checks their SPIR-V offsets.
#version 460
#extension GL_EXT_scalar_block_layout : require
#include "shared/bindings.h"
#include "shared/constants.h"
#include "shared/scene.h"
#include "shared/guiding.h"
layout(local_size_x = 1) in;
layout(set = 0, binding = 0, scalar) buffer B0 { Vertex vertices[]; };
layout(set = 0, binding = 1, scalar) buffer B1 { Instance instances[]; };
layout(set = 0, binding = 2, scalar) buffer B2 { Material materials[]; };
layout(set = 0, binding = 3, scalar) buffer B3 { LightTriangle light_triangles[]; };
layout(set = 0, binding = 4, scalar) buffer B4 { LightModel light_models[]; };
layout(set = 0, binding = 5, scalar) buffer B5 { AliasEntry alias[]; };
layout(set = 0, binding = 6, scalar) buffer B6 { PunctualLight punctual[]; };
layout(set = 0, binding = 7, scalar) buffer B7 { FrameParams params; };
layout(set = 0, binding = 8, scalar) buffer B8 { GuideSpatialNode spatial[]; };
layout(set = 0, binding = 9, scalar) buffer B9 { GuideLeaf leaves[]; };
layout(set = 0, binding = 10, scalar) buffer B10 { GuideQuadNode quads[]; };
layout(set = 0, binding = 12, scalar) buffer B12 { GuideHeader guide_header; GuideRecord guide_records[]; };
layout(set = 0, binding = 13, scalar) buffer B13 { GuideTestSample guide_test_samples[]; };
layout(set = 0, binding = 14, scalar) buffer B14 { GuideTestResult guide_test_results[]; };
layout(set = 0, binding = 15, scalar) buffer B15 { GuideTestRecord guide_test_records[]; };
layout(set = 0, binding = 16, scalar) buffer B16 { LightCandidateTriangle light_candidates[]; };
layout(push_constant, scalar) uniform Push { PushConstants pc; };
layout(set = 0, binding = 11, scalar) buffer Out { float result[]; };
void main() {
    result[0] = vertices[0].uv1.y + float(instances[0].flags) + materials[0].emissive_tex.rotation
        + light_triangles[0].power + light_candidates[0].emission.z + light_models[0].power + alias[0].pmf
        + punctual[0].cos_outer
        + params.scene_radius + float(spatial[0].child) + leaves[0].box_size.z + quads[0].sum.w
        + float(pc.sample_count) + guide_header.bsdf_fraction + guide_records[0].weight
        + float(guide_test_samples[0].mode) + guide_test_results[0].pdf_eval
        + float(guide_test_records[0].pad);
}
