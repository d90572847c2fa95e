// Scene data as the kernels see it. All buffers use the scalar block layout.
#ifndef LANTERNA_SCENE_H
#define LANTERNA_SCENE_H

// One vertex of the global vertex buffer (object space).
struct Vertex {
    vec3 position;
    vec3 normal;
    vec4 tangent;  // xyz tangent, w handedness; zero when the mesh has none
    vec2 uv0;
    vec2 uv1;
};

// A mesh primitive placed by a node. Small instances are flattened into world-space
// geometries of shared BLASes (lavapipe traverses many small TLAS instances slowly); a
// hit's instance is the TLAS instance's custom index plus the geometry index within its
// BLAS, and its object-to-world transform is stored here rather than taken from the ray
// query (which is the identity for flattened geometry).
struct Instance {
    vec4 to_world_row0;       // object-to-world, rows of a 3×4 matrix
    vec4 to_world_row1;
    vec4 to_world_row2;
    uint vertex_offset;       // added to every index of the primitive
    uint index_offset;        // first index (3 per triangle) in the index buffer
    uint triangle_count;
    uint material;
    uint light_index_offset;  // into the triangle→light map, INVALID_INDEX if not emissive
    uint light_model;         // INVALID_INDEX if not emissive
    uint flags;               // INSTANCE_FLAG_*
    uint color_offset;        // into vertex_colors for the primitive's first vertex
                              // (COLOR_0), INVALID_INDEX without vertex colours
};

// A texture reference with its KHR_texture_transform.
struct TextureRef {
    int index;       // bindless texture slot, -1 for none
    uint uv_set;     // 0 or 1
    vec2 offset;
    vec2 scale;
    float rotation;
};

// glTF metallic-roughness material (plus KHR_materials_specular / emissive_strength).
struct Material {
    vec4 base_color;       // linear RGBA factor
    vec3 emission;         // emissiveFactor × emissive_strength (linear radiance)
    float metallic;
    float roughness;
    float specular;        // KHR_materials_specular specularFactor (1 by default)
    vec3 specular_color;   // KHR_materials_specular specularColorFactor
    float normal_scale;
    float alpha_cutoff;
    uint alpha_mode;       // ALPHA_MODE_*
    uint flags;            // MATERIAL_FLAG_*
    float ior;
    TextureRef base_color_tex;
    TextureRef metallic_roughness_tex;
    TextureRef normal_tex;
    TextureRef emissive_tex;
    // KHR_materials_transmission (thin-walled): the share of the dielectric's diffuse
    // lobe replaced by a base-colour-tinted GGX transmission lobe (factor × texture R).
    // Last, so that the content hash of scenes without it is that of older builds.
    float transmission;
    TextureRef transmission_tex;
    // KHR_materials_volume (MATERIAL_FLAG_VOLUME): the absorption coefficient of the solid
    // the surface bounds, per world unit (−ln(attenuationColor) / attenuationDistance; 0:
    // clear). Counted in the content hash with the transmission fields.
    vec3 attenuation;
    // KHR_materials_clearcoat: a GGX coat over the whole material (clearcoat = factor ×
    // texture R, its roughness = factor × texture G, its own normal map; none: the
    // surface's normal before the base's normal map). Counted in the content hash only
    // where a material has a coat.
    float clearcoat;
    float clearcoat_roughness;
    float clearcoat_normal_scale;
    TextureRef clearcoat_tex;
    TextureRef clearcoat_roughness_tex;
    TextureRef clearcoat_normal_tex;
    // KHR_materials_sheen: a Charlie sheen lobe over the base (colour = factor × texture
    // RGB, roughness = factor × texture A; black: none). Counted in the content hash only
    // where a material has a sheen.
    vec3 sheen_color;
    float sheen_roughness;
    TextureRef sheen_color_tex;
    TextureRef sheen_roughness_tex;
    // KHR_materials_anisotropy: the base's GGX α along the anisotropy direction is
    // mix(α, 1, strength²), across it α (strength = factor × texture B). The direction is
    // (cos, sin) of the rotation in the tangent frame (tangent, bitangent), or the
    // texture's RG mapped to [−1, 1]² and turned by the rotation. Counted in the content
    // hash only where a material has anisotropy.
    float anisotropy_strength;
    vec2 anisotropy_rotation;
    TextureRef anisotropy_tex;
    // KHR_materials_diffuse_transmission: the share of the dielectric's diffuse lobe (what
    // thin transmission leaves of it) that leaves on the other side of the surface, as a
    // Lambertian lobe tinted by its colour (share = factor × texture A; colour = factor ×
    // texture RGB, sRGB). Counted in the content hash only where a material has it.
    float diffuse_transmission;
    vec3 diffuse_transmission_color;
    TextureRef diffuse_transmission_tex;
    TextureRef diffuse_transmission_color_tex;
    // KHR_materials_iridescence: a thin dielectric film over the base whose Fresnel term
    // (Belcour & Barla 2017, as the extension simplifies it) replaces Schlick's by this
    // weight (factor × texture R); the film's index and its thickness in nanometres (the
    // maximum, or mix(minimum, maximum, thickness texture G)). Counted in the content
    // hash only where a material has it.
    float iridescence;
    float iridescence_ior;
    float iridescence_thickness_min;
    float iridescence_thickness_max;
    TextureRef iridescence_tex;
    TextureRef iridescence_thickness_tex;
    // KHR_materials_dispersion, on the boundary of a solid: 20 / the Abbe number. The red,
    // green and blue channels refract with indices n − s, n and n + s, s = (n − 1)·0.025·
    // dispersion (the extension's recipe for RGB renderers; red at least 1). Counted in
    // the content hash only where a material has it.
    float dispersion;
};

// One emissive triangle in world space.
struct LightTriangle {
    vec3 p0;
    vec3 p1;
    vec3 p2;
    vec3 normal;       // unit front-face normal
    float area;
    uint material;
    uint model;        // index of its light model
    uint two_sided;    // emits from both faces (double-sided material)
    vec2 uv0;          // emissive texture coordinates at the corners (untransformed)
    vec2 uv1;
    vec2 uv2;
    float power;       // emitted flux (luminance), for the power source
    uint instance;     // its instance (kernel order) where its material is not opaque or its
                       // vertex colours tint its emission, else INVALID_INDEX
    uint primitive;    // its triangle in that instance
};

// What drawing a point on an emissive triangle reads (light sampling for NEE and every
// RIS candidate): one 56-byte record instead of LightTriangle's corners and normal plus
// the material's emission behind a second, dependent load. Same index as
// light_triangles. The emission of a textured emitter needs the full LightTriangle and a
// texture lookup; RIS does that for the candidate it keeps only (see nee_ris).
struct LightCandidateTriangle {
    vec3 p0;
    float inv_area;    // 1 / area
    vec3 e1;           // p1 − p0
    uint flags;        // LIGHT_CANDIDATE_*; the front-face normal is cross(e1, e2)
                       // normalised, negated with LIGHT_CANDIDATE_FLIPPED
    vec3 e2;           // p2 − p0
    vec3 emission;     // the material's emission; for a textured one, times the texture's
                       // mean luminance over the triangle (RIS's target uses it)
};

// A light model: one emissive mesh instance, or one punctual light.
struct LightModel {
    uint first_triangle;   // into the light triangle buffer
    uint triangle_count;   // 0 for a punctual light
    uint punctual;         // punctual light index, INVALID_INDEX for emissive geometry
    float power;           // emitted flux (luminance)
    uint tree_path;        // the light tree's turns from its root to this model's leaf
                           // (bit k set: right child at depth k; --source tree)
    uint tree_depth;       // how many turns (0: the tree's root is this model's leaf)
};

// A node of the light tree (--source tree; src/lights/tree.rs builds it, the kernels walk
// it in inc/light_tree.glsl). Every node bounds the light models below it: where they
// are, how much they emit, and toward which directions. Inner nodes have their two
// children at `child` and `child + 1`; a leaf holds one model.
struct LightTreeNode {
    vec3 bounds_min;       // box around the models' emitting points
    float power;           // their emitted flux (luminance); with LIGHT_TREE_FIXED_SPLIT
                           // the left child's probability instead
    vec3 bounds_max;
    float cos_normals;     // cos θo: every emitter's normal lies within θo of `axis`
    vec3 axis;             // (−1: any direction, two-sided emitters and point lights)
    float cos_emission;    // cos θe: emission leaves within θe of a normal (0 for area
                           // lights, the outer cone for spots)
    uint child;            // first child, INVALID_INDEX for a leaf
    uint model;            // the leaf's light model, INVALID_INDEX for inner nodes
    uint flags;            // LIGHT_TREE_*
};

// Alias-table entry (Walker/Vose). pmf is the entry's own probability.
struct AliasEntry {
    float threshold;
    uint alias;
    float pmf;
};

// KHR_lights_punctual or EXT_lights_ies light, in world space.
struct PunctualLight {
    vec3 position;
    uint kind;          // PUNCTUAL_*
    vec3 direction;     // direction the light travels (spot, directional); an IES
                        // profile's vertical angle 0 (the node's −Z)
    float range;        // 0 = infinite
    vec3 intensity;     // colour × intensity (W/sr for point/spot, W/m² for directional;
                        // an IES light's colour × multiplier, times its profile's candela)
    float cos_inner;
    float cos_outer;
    uint profile;       // EXT_lights_ies: offset of its profile in the light profile
                        // array (bit 31: a mirrored frame), INVALID_INDEX without one
    vec3 tangent;       // the profile's horizontal angle 0 (the node's +X), ⟂ direction
};

// Per-frame parameters.
struct FrameParams {
    mat4 camera_to_world;      // camera looks down -Z, +Y up (glTF)
    uint camera_type;          // CAMERA_*
    float tan_half_fov_y;      // perspective
    vec2 ortho_half_extent;    // orthographic xmag, ymag
    uint width;
    uint height;
    uint max_depth;            // path segments (1 = emitters seen directly)
    uint rr_depth;             // Russian roulette from this depth on; 0 = off
    uint seed;
    uint light_model_count;
    uint light_triangle_count;
    uint punctual_count;
    uint ris_candidates;
    uint ris_source;           // RIS_SOURCE_*
    uint debug_pixel;          // y * width + x, INVALID_INDEX when not tracing a pixel
    uint debug_sample;         // sample index to trace, INVALID_INDEX for all
    float scene_radius;
    uint strategy;             // STRATEGY_*: MIS, or one technique alone (debugging, tests)
    uint aov_first_sample;     // the sample whose choices AOV_SELECTED_LIGHT shows
    uint hide_emitters;        // 1: emission seen directly by the camera is not counted
    uint emission_rays;        // camera rays per sample (raygen.glsl; 1: the plain estimator)
    uint pixel_emitters;       // 1: small emitters seen directly are sampled in their pixels
    // Device addresses (low, high) of the scene's read-only arrays, which the kernels
    // read through buffer references (inc/scene_data.glsl); the software traversal's
    // node and triangle buffers are 0 without that traversal.
    uvec2 vertices_address;
    uvec2 vertex_colors_address;
    uvec2 indices_address;
    uvec2 instances_address;
    uvec2 materials_address;
    uvec2 light_triangles_address;
    uvec2 light_candidates_address;
    uvec2 light_models_address;
    uvec2 model_alias_address;
    uvec2 triangle_alias_address;
    uvec2 punctual_lights_address;
    uvec2 triangle_light_index_address;
    uvec2 bvh_nodes_address;
    uvec2 bvh_triangles_address;
    uvec2 light_tree_address;
    uvec2 light_profiles_address;
    // World-space light reuse (inc/light_reuse.glsl): cells in each half of the hash
    // grid (a power of two; 0 without reuse), a cell's edge in pixel footprints at its
    // distance from the camera, and the most canonical reservoirs a cell stands for.
    uint reuse_cells;
    float reuse_cell_pixels;
    float reuse_confidence_cap;
    // Learned light visibility (inc/light_visibility.glsl): the table's device address
    // (0 when read through its binding), its entries per half (a power of two; 0 when
    // off), a cell's edge in pixel footprints, and the least factor a learned visibility
    // gives a light's target.
    uvec2 visibility_address;
    uint visibility_slots;
    float visibility_cell_pixels;
    float visibility_floor;
    // The camera's clip planes (glTF znear, zfar) along the view axis; camera rays see
    // what lies between them (0 and FLT_MAX: everything in front of the camera).
    float clip_near;
    float clip_far;
};

// One cell of the world-space light reuse's hash grid (inc/light_reuse.glsl): the RIS
// reservoir a shading point in the cell ended with, and that point (its hit and the
// direction it was seen from), so that a reader can evaluate the writer's target.
struct ReuseCell {
    uint key;          // the cell's fingerprint (0: empty)
    uint instance;     // the writer's hit: instance, triangle and barycentrics
    uint primitive;
    uint light;        // the reservoir's light: a light triangle, REUSE_PUNCTUAL | model,
                       // or INVALID_INDEX for none
    vec2 bary;
    vec2 light_bary;   // barycentrics of the light point on its triangle
    vec3 wo;           // the writer's Surface.wo
    float weight;      // the reservoir's contribution weight W (for the writer's target)
    float confidence;  // canonical reservoirs it stands for (capped)
    uint check;        // checksum of the words above (a torn write fails it)
    // The writer's ticket, a 64-bit word (low, high) at byte 56 of the 64-byte cell that
    // inc/light_reuse.glsl raises with atomicMax: a write lands only if its ticket is
    // the highest so far, so the cell keeps a writer drawn at random, not the device's
    // last. Not in the checksum.
    uint ticket_lo;
    uint ticket_hi;
};

// The part of a small emissive triangle's image that lies in one pixel, or one triangle
// of it (src/render/pixel_emitters.rs). Corners are in image coordinates: pixel (x, y)
// spans [x, x + 1) × [y, y + 1), y down, as camera_ray reads them.
struct PixelEmitter {
    vec2 a;
    vec2 b;
    vec2 c;
    float cdf;                 // cumulative selection probability in the pixel's list (last: 1)
    float scale;               // the piece's area over its selection probability
    uint light_tri;            // the light triangle it is part of
};

// Push constants of one dispatch: a tile of pixels and a range of sample indices.
struct PushConstants {
    uvec2 tile_origin;
    uvec2 tile_size;
    uint sample_begin;
    uint sample_count;
    // Device addresses of the SD-tree's arrays, read where the scene's arrays are read
    // through theirs (inc/guiding_buffers.glsl); 0 where a buffer has none. Here rather
    // than in FrameParams: a refit that regrows a buffer moves its address.
    uvec2 guide_spatial_address;
    uvec2 guide_leaves_address;
    uvec2 guide_sampling_address;
    uvec2 guide_training_address;
    uvec2 guide_lights_address;
    uvec2 guide_light_training_address;
    // World-space light reuse: the first cell of the half this dispatch reads (written
    // by earlier dispatches) and of the half it writes.
    uint reuse_read;
    uint reuse_write;
    uint reuse_generation;  // counts the dispatches since the grid was cleared, from 1
};

#endif
