// The BSDF (inc/bsdf.glsl) of one material at one outgoing direction, for the tests in
// tests/bsdf.rs: mode 0 samples a direction from each input's uniform numbers (xyz; w: the
// choice of a coat, then of reflection or refraction on a solid's boundary) and
// returns it with the density and f·|cosθ| that bsdf_eval_pdf gives it; mode 1 evaluates
// f·|cosθ| and the density at each input direction. Modes 2 and 3 do the same with the
// Lambertian lobe alone (bsdf_at_lambertian, lambertian_sample, lambertian_eval_pdf).
#version 460
#include "../inc/bsdf.glsl"

struct BsdfCase {
    vec3 base_color;
    float metallic;
    vec3 f0_dielectric;
    float alpha;
    vec3 wo;
    float specular;
    float transmission;
    float eta;
    float coat;
    float coat_alpha;
    vec3 coat_n;
    vec3 sheen_color;
    float sheen_roughness;
    float alpha_t;
    float diffuse_transmission;
    vec3 diffuse_transmission_color;
    float iridescence;
    float iridescence_ior;
    float iridescence_thickness;
    float dispersion;
};

layout(local_size_x = 64) in;
layout(set = 0, binding = TEST_BINDING_IN, scalar) readonly buffer In { vec4 items[]; };
layout(set = 0, binding = TEST_BINDING_AUX, scalar) readonly buffer Aux { BsdfCase bsdf_case; };
layout(set = 0, binding = TEST_BINDING_OUT, scalar) buffer Out { vec4 results[]; };
layout(push_constant, scalar) uniform Push { uint count; uint mode; } pc;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.count) return;
    BsdfParams p;
    p.base_color = bsdf_case.base_color;
    p.metallic = bsdf_case.metallic;
    p.alpha = bsdf_case.alpha;
    p.alpha_t = bsdf_case.alpha_t;
    p.specular = bsdf_case.specular;
    p.f0_dielectric = bsdf_case.f0_dielectric;
    p.transmission = bsdf_case.transmission;
    p.eta = bsdf_case.eta;
    p.coat = bsdf_case.coat;
    p.coat_alpha = bsdf_case.coat_alpha;
    p.coat_n = bsdf_case.coat_n;
    p.sheen_color = bsdf_case.sheen_color;
    p.sheen_roughness = bsdf_case.sheen_roughness;
    p.diffuse_transmission = bsdf_case.diffuse_transmission;
    p.diffuse_transmission_color = bsdf_case.diffuse_transmission_color;
    p.iridescence = bsdf_case.iridescence;
    p.iridescence_ior = bsdf_case.iridescence_ior;
    p.iridescence_thickness = bsdf_case.iridescence_thickness;
    p.dispersion = bsdf_case.dispersion;
    bool lambertian = pc.mode >= 2u;
    BsdfWo c = lambertian ? bsdf_at_lambertian(bsdf_case.wo) : bsdf_at(p, bsdf_case.wo);
    vec3 wi = items[t].xyz;
    bool valid = true;
    if (pc.mode % 2u == 0u) {
        valid = lambertian ? lambertian_sample(c, items[t].xyz, wi) : bsdf_sample(p, c, items[t].xyz, items[t].w, wi);
    }
    float pdf;
    vec3 f = lambertian ? lambertian_eval_pdf(p, c, wi, pdf) : bsdf_eval_pdf(p, c, wi, pdf);
    results[2u * t] = vec4(wi, valid ? pdf : -1.0);
    results[2u * t + 1u] = vec4(f, 0.0);
}
