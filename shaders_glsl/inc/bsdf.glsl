// The glTF metallic-roughness BSDF in the local shading frame (z = shading normal):
// Lambertian diffuse + GGX specular (height-correlated Smith), mixed as the glTF spec's
// appendix B describes (dielectric = Fresnel mix of diffuse and specular; metal =
// specular tinted by a Schlick conductor Fresnel; metallic blends the two), with
// KHR_materials_specular's factor and colour. Sampling picks the diffuse or specular lobe
// with a probability from the Fresnel weights at ωo; the specular lobe samples visible
// normals (Dupuy & Benyoub 2023, spherical caps). eval() returns f·cosθi.
#ifndef INC_BSDF_GLSL
#define INC_BSDF_GLSL

#include "common.glsl"
#include "sampling.glsl"

struct BsdfParams {
    vec3 base_color;
    float metallic;
    float alpha;           // GGX α = roughness², clamped to MIN_GGX_ALPHA
    float specular;        // KHR_materials_specular factor: dielectric F90
    vec3 f0_dielectric;    // dielectric F0 (ior, specular colour and factor)
};

float ggx_d(vec3 h, float a) {
    float a2 = a * a;
    float d = h.z * h.z * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float ggx_lambda(vec3 v, float a) {
    float c2 = v.z * v.z;
    float t2 = max(0.0, 1.0 - c2) / max(c2, 1e-12);
    return 0.5 * (-1.0 + sqrt(1.0 + a * a * t2));
}

// Probability of sampling the specular lobe for outgoing direction wo.
float bsdf_specular_probability(BsdfParams p, vec3 wo) {
    float w = pow(1.0 - clamp(wo.z, 0.0, 1.0), 5.0);
    vec3 fd = p.f0_dielectric + (vec3(p.specular) - p.f0_dielectric) * w;
    vec3 fm = p.base_color + (1.0 - p.base_color) * w;
    float spec = (1.0 - p.metallic) * max3(fd) + p.metallic * luminance(fm);
    float diff = (1.0 - p.metallic) * luminance(p.base_color) * (1.0 - max3(fd));
    if (spec <= 0.0) return 0.0;
    if (diff <= 0.0) return 1.0;
    return clamp(spec / (spec + diff), 0.1, 0.9);
}

// f(wo, wi)·cosθi.
vec3 bsdf_eval(BsdfParams p, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 h = normalize(wo + wi);
    float w = pow(1.0 - clamp(dot(wo, h), 0.0, 1.0), 5.0);
    float spec = ggx_d(h, p.alpha) / (1.0 + ggx_lambda(wo, p.alpha) + ggx_lambda(wi, p.alpha)) / (4.0 * wo.z * wi.z);
    vec3 fd = p.f0_dielectric + (vec3(p.specular) - p.f0_dielectric) * w;
    vec3 dielectric = p.base_color * INV_PI * (1.0 - max3(fd)) + spec * fd;
    vec3 metal = spec * (p.base_color + (1.0 - p.base_color) * w);
    return mix(dielectric, metal, p.metallic) * wi.z;
}

float ggx_reflection_pdf(BsdfParams p, vec3 wo, vec3 wi) {
    vec3 h = normalize(wo + wi);
    float g1 = 1.0 / (1.0 + ggx_lambda(wo, p.alpha));
    return g1 * ggx_d(h, p.alpha) / (4.0 * wo.z);
}

float bsdf_pdf(BsdfParams p, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    float ps = bsdf_specular_probability(p, wo);
    float pdf = (1.0 - ps) * wi.z * INV_PI;
    if (ps > 0.0) pdf += ps * ggx_reflection_pdf(p, wo, wi);
    return pdf;
}

// Visible GGX normal for wo (Dupuy & Benyoub 2023).
vec3 ggx_sample_visible_normal(vec3 wo, float a, vec2 u) {
    vec3 v = normalize(vec3(wo.xy * a, wo.z));
    float phi = TWO_PI * u.x;
    float z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    float s = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    vec3 h = vec3(s * cos(phi), s * sin(phi), z) + v;
    return normalize(vec3(h.xy * a, max(h.z, 0.0)));
}

// Sample wi; returns false when the sample is invalid (below the surface).
// u.x chooses the lobe, u.yz warps.
bool bsdf_sample(BsdfParams p, vec3 wo, vec3 u, out vec3 wi) {
    wi = vec3(0.0);
    if (wo.z <= 0.0) return false;
    float ps = bsdf_specular_probability(p, wo);
    if (u.x < ps) {
        vec3 h = ggx_sample_visible_normal(wo, p.alpha, u.yz);
        wi = reflect(-wo, h);
    } else {
        wi = square_to_cosine_hemisphere(u.yz);
    }
    return wi.z > 0.0;
}

#endif
