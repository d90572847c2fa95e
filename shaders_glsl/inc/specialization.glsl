// The path-tracing kernel's specialization constants: each method compiles to its own
// pipeline without dead branches (render/kernel.rs sets them per variant).
#ifndef INC_SPECIALIZATION_GLSL
#define INC_SPECIALIZATION_GLSL

#include "common.glsl"

layout(constant_id = 0) const uint NEE_MODE = NEE_UNIFORM;  // NEE_UNIFORM (pt) or NEE_RIS
layout(constant_id = 1) const bool GUIDING = false;         // sample directions from the SD-tree
layout(constant_id = 2) const bool TRAINING = false;        // record training data
layout(constant_id = 3) const bool AOVS = false;            // write first-hit AOVs and outliers
// The scene has solids (KHR_materials_volume): without, refraction and absorption compile
// away (lavapipe: 2-3 % of a `pt` sample).
layout(constant_id = 4) const bool SOLIDS = false;
// The scene has coated materials (KHR_materials_clearcoat): without, the coat compiles
// away.
layout(constant_id = 5) const bool CLEARCOAT = false;
// The scene has sheen (KHR_materials_sheen): without, the sheen lobe compiles away.
layout(constant_id = 6) const bool SHEEN = false;
// (constant_id 7 is SCENE_ADDRESSES, inc/scene_data.glsl; 9 LIGHT_REUSE,
// inc/light_reuse.glsl; 10 LIGHT_VISIBILITY, inc/light_visibility.glsl.)
// The scene has anisotropic materials (KHR_materials_anisotropy) that are not Lambertian:
// without, the anisotropy's frame compiles away (lavapipe: 8 % of a `pt` sample on
// `cornell-lights`, whose kernels are otherwise the Lambertian lobe alone).
layout(constant_id = 11) const bool ANISOTROPY = false;
// The scene has diffusely transmitting materials (KHR_materials_diffuse_transmission):
// without, that lobe compiles away.
layout(constant_id = 12) const bool DIFFUSE_TRANSMISSION = false;
// The scene has iridescent materials (KHR_materials_iridescence): without, the thin
// film's Fresnel term compiles away.
layout(constant_id = 13) const bool IRIDESCENCE = false;
// The scene has dispersive solids (KHR_materials_dispersion): without, the interface's
// per-channel indices compile away.
layout(constant_id = 14) const bool DISPERSION = false;
// Where the kernels take the Lambertian lobe alone (BSDF_KERNEL_*): at Lambertian
// surfaces (metallic 0, specular 0, no transmission of either kind, coat or sheen), or everywhere when
// every material the scene uses is (`Scene::only_lambertian`), the other lobes then
// compiled away. The same image either way (lavapipe: `ris` 1.08–1.09× as fast on the
// street and `bistro-night` per surface, 1.14–1.17× on `cornell-lights` everywhere).
layout(constant_id = 8) const uint BSDF_KERNEL = BSDF_KERNEL_GENERAL;

#endif
