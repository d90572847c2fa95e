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

// Camera projections.
#define CAMERA_PERSPECTIVE 0u
#define CAMERA_ORTHOGRAPHIC 1u

// Punctual light types (KHR_lights_punctual).
#define PUNCTUAL_POINT 0u
#define PUNCTUAL_SPOT 1u
#define PUNCTUAL_DIRECTIONAL 2u

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

// Film accumulation is fixed point so that sums are exact and order-independent:
// a sample value v adds round(v * FILM_FIXED_SCALE) to a 64-bit integer.
#define FILM_FIXED_SCALE 1048576.0

// Stats counters (BINDING_STATS, uint each).
#define STAT_CAMERA_RAYS 0
#define STAT_BOUNCE_RAYS 1
#define STAT_SHADOW_RAYS 2
#define STAT_NONFINITE_SAMPLES 3
#define STAT_GUIDE_RECORDS 4
#define STAT_COUNT 8

// GGX roughness is clamped to this alpha: lobes narrower than it are numerically delta.
#define MIN_GGX_ALPHA 0.0016
// Lobes with alpha below this are not guided (nearly specular).
#define GUIDING_MIN_ALPHA 0.05

#endif
