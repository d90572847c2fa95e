// Constants shared by the host and the kernels.
#ifndef LANTERNA_CONSTANTS_H
#define LANTERNA_CONSTANTS_H

#define INVALID_INDEX 0xffffffffu

// Instance flags.
#define INSTANCE_FLAG_OPAQUE 1u
#define INSTANCE_FLAG_FLIPPED 2u

// Material alpha modes (glTF).
#define ALPHA_MODE_OPAQUE 0u
#define ALPHA_MODE_MASK 1u
#define ALPHA_MODE_BLEND 2u

// Material flags.
#define MATERIAL_FLAG_DOUBLE_SIDED 1u
// KHR_materials_volume with a thickness: the surface bounds a refracting solid (the
// transmitted share is a rough dielectric interface, Walter et al. 2007), not a thin wall.
#define MATERIAL_FLAG_VOLUME 2u
// KHR_materials_unlit: the vertex colour (COLOR_0) multiplies the emission, which is the
// base colour (src/scene/material.rs).
#define MATERIAL_FLAG_VERTEX_COLOR_EMISSION 4u

// LightCandidateTriangle flags.
#define LIGHT_CANDIDATE_TWO_SIDED 1u
// Textured or tinted by vertex colours: the candidate's emission is a stand-in (its mean).
#define LIGHT_CANDIDATE_TEXTURED 2u
#define LIGHT_CANDIDATE_FLIPPED 4u
// Alpha-masked or blended (alphaMode MASK or BLEND): the emission at a point is scaled by
// the surface's coverage there (geometry_coverage), so the candidate's is a stand-in.
#define LIGHT_CANDIDATE_ALPHA 8u

// Camera projections.
#define CAMERA_PERSPECTIVE 0u
#define CAMERA_ORTHOGRAPHIC 1u

// Punctual light types (KHR_lights_punctual).
#define PUNCTUAL_POINT 0u
#define PUNCTUAL_SPOT 1u
#define PUNCTUAL_DIRECTIONAL 2u

// How the kernels take the BSDF (specialization constant BSDF_KERNEL): the general BSDF
// everywhere; the Lambertian lobe alone at surfaces whose material is Lambertian (a
// branch per surface); the Lambertian lobe alone everywhere (every material the scene
// uses is Lambertian, so the other lobes compile away). The image is the same.
#define BSDF_KERNEL_GENERAL 0u
#define BSDF_KERNEL_PER_SURFACE 1u
#define BSDF_KERNEL_LAMBERTIAN 2u

// ReuseCell.light of a punctual light: this bit with its light model's index (a light
// triangle's index otherwise; INVALID_INDEX: the reservoir holds no light).
#define REUSE_PUNCTUAL 0x80000000u

// NEE light selection (specialization constant NEE_MODE).
#define NEE_UNIFORM 0u
#define NEE_RIS 1u

// Direct-light estimation (FrameParams.strategy): both techniques MIS-combined, or NEE
// alone, or direction sampling alone. All three converge to the same image.
#define STRATEGY_MIS 0u
#define STRATEGY_NEE_ONLY 1u
#define STRATEGY_BSDF_ONLY 2u

// RIS candidate sources (FrameParams.ris_source).
#define RIS_SOURCE_UNIFORM 0u
#define RIS_SOURCE_POWER 1u
// The light tree (src/lights/tree.rs, inc/light_tree.glsl): models by a bound of what
// they can send toward the shading point, mixed with the uniform source (below).
#define RIS_SOURCE_TREE 2u

// The uniform source's share of the tree source: every light model keeps at least this
// share of the uniform probability wherever the tree's bounds rule it out or undervalue it.
#define LIGHT_TREE_UNIFORM_SHARE 0.1

// LightTreeNode.flags: an inner node whose left child's probability is the fixed
// `power` field (the directional lights against the rest, and within the directional
// lights), not the children's importance at the shading point.
#define LIGHT_TREE_FIXED_SPLIT 1u

// Film accumulation is fixed point so that sums are exact and order-independent:
// a sample value v adds floor(v * FILM_FIXED_SCALE + ξ) to a 64-bit integer, ξ a uniform
// dither of the sample's own (stochastic rounding: its expectation is v * FILM_FIXED_SCALE).
#define FILM_FIXED_SCALE 1048576.0
// Largest sample value the film takes (1e9 · 2²⁰ < 2⁶⁴ / 2¹⁴ leaves room for 16k
// samples of it per pixel per channel); larger ones are clamped and counted.
#define FILM_MAX_SAMPLE 1e9

// Stats counters (BINDING_STATS, uint64_t each: bounce rays alone pass 2³² at
// 1080p × 1024 spp).
#define STAT_CAMERA_RAYS 0
#define STAT_BOUNCE_RAYS 1
#define STAT_SHADOW_RAYS 2
#define STAT_NONFINITE_SAMPLES 3
#define STAT_GUIDE_RECORDS 4
#define STAT_CLAMPED_SAMPLES 5
// SIMD lane utilisation (the lane-statistics kernel only, inc/lane_stats.glsl): steps
// taken by lanes, and lane slots of the subgroup steps they took them in.
#define STAT_TRAVERSAL_LANE_STEPS 6
#define STAT_TRAVERSAL_LANE_SLOTS 7
#define STAT_PATH_LANE_STEPS 8
#define STAT_PATH_LANE_SLOTS 9
#define STAT_PROBE_RAYS 10
#define STAT_COUNT 11

// AOV channels (BINDING_AOV holds AOV_CHANNELS floats per pixel, summed over samples).
#define AOV_ALBEDO 0          // 3: base colour at the first hit
#define AOV_NORMAL 3          // 3: shading normal at the first hit (world space)
#define AOV_DEPTH 6           // 1: distance from the camera to the first hit
#define AOV_POSITION 7        // 3: world position of the first hit
#define AOV_LIGHT_COUNT 10    // 1: unoccluded NEE connections along the path
#define AOV_RIS_WEIGHT 11     // 1: RIS contribution weight W at the first hit
#define AOV_SELECTED_LIGHT 12 // 1: light model NEE picked at the first hit, first sample only
#define AOV_GUIDE_FRACTION 13 // 1: share of the path's directions drawn from the SD-tree
#define AOV_CHANNELS 14

// Outliers (BINDING_OUTLIERS): per pixel the largest single-sample luminance, its sample
// index (as float bits) and its RGB.
#define OUTLIER_FLOATS 5

// GGX α (roughness²) is clamped to this: roughness 0 (glTF's perfectly smooth glass and
// mirrors) renders as a GGX lobe this narrow. GGX's tail carries a share of about
// α²/θ² of the light beyond θ from the mirror direction, so bright emitters seen through
// such glass or in such mirrors get a halo of that share: at 0.0016 (roughness 0.04) it
// was 1–3 % of a lamp's radiance in the pixels next to it at 48×36 (README, Materials);
// at 1e-4 it is 256 times less. Below about 2.4e-4 the GGX terms need care in float
// (ggx_d_cos_sin2).
#define MIN_GGX_ALPHA 0.0001
// Lobes with alpha below this are not guided (nearly specular).
#define GUIDING_MIN_ALPHA 0.05

#endif
