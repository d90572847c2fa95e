// The glTF metallic-roughness BSDF in the local shading frame (z = shading normal):
// Lambertian diffuse + GGX specular (height-correlated Smith), mixed as the glTF spec's
// appendix B describes (dielectric = Fresnel mix of diffuse and specular; metal =
// specular tinted by a Schlick conductor Fresnel; metallic blends the two), with
// KHR_materials_specular's factor and colour, and KHR_materials_transmission for a thin
// wall: a share `transmission` of the dielectric's diffuse lobe becomes a GGX lobe
// through the surface, tinted by the base colour, whose directions are the specular
// lobe's mirrored through the tangent plane (a rough pane scatters light around the
// straight-through direction; as the glTF sample viewer evaluates it). Sampling picks
// the specular lobe with a probability from the Fresnel weights at ωo, else transmission
// or diffuse by the transmission share; the specular and transmission lobes sample
// visible normals (Dupuy & Benyoub 2023, spherical caps). eval() returns f·|cosθi|.
//
// On the boundary of a solid (KHR_materials_volume, eta > 0) the transmitted share is
// instead a rough dielectric interface (Walter et al. 2007, "Microfacet models for
// refraction"): GGX with separable Smith shadowing, reflection weighted by the exact
// dielectric Fresnel term F and refraction by 1 − F tinted by the base colour, radiance
// scaled by 1/η² on the way through (pbrt-v4's and Mitsuba 3's `roughdielectric`). It
// takes the share (1 − metallic)·transmission of the material; the rest is the opaque
// material (diffuse + specular, metal) with that share taken out (volume_rest).
// KHR_materials_dispersion gives each colour channel its own index there (the
// extension's RGB recipe): the interface is then three interfaces, one per channel,
// sampled as their equal mixture.
//
// KHR_materials_diffuse_transmission splits the dielectric's diffuse lobe (what the
// transmission leaves of it, on a thin wall or a solid's boundary alike) into reflection,
// tinted by the base colour, and a share `diffuse_transmission` that leaves below the
// surface, cosine-weighted and tinted by its own colour, both weighted by 1 − max(F) with
// the Fresnel term at wi mirrored above the surface (as the thin transmission lobe).
// Sampling sends that share of the cosine samples below.
//
// KHR_materials_iridescence puts a thin dielectric film on the base: its Fresnel term
// (thin_film_fresnel below) replaces Schlick's, by the weight `iridescence`, for the
// dielectric (whose base F0 is f0_dielectric) and the metal (the base colour), wherever
// the term appears: the specular lobe, the 1 − max(F) of the diffuse and thin
// transmission lobes. Under a coat the film's outside index is the coat's 1.5. A solid's
// refracting interface keeps its exact Fresnel term (the film is on its opaque rest).
//
// KHR_materials_clearcoat lays a GGX coat over all of it (the spec's fresnel_coat): with
// w = clearcoat·F(ωo·nc), F Schlick's with F0 = 0.04 at the coat normal nc, the BSDF is
// (1 − w)·base + w·D·G2/(4|ωo·nc||ωi·nc|) with the coat's own α and normal, the coat's
// value taken with its own cosine |ωi·nc|. Sampling picks the coat with a probability
// from w and the base's albedo (its visible normals about nc), else the base as above.
//
// KHR_materials_sheen lies between the two (the spec's albedo scaling): under the coat
// the material is C·D·V·cosθi + min(1 − max(C)·E(ωo), 1 − max(C)·E(ωi))·base, with the
// Charlie distribution D at α = r² (r ≥ 0.1), Estevez & Kulla's visibility V (clamped to
// 1, as the glTF sample viewer has it), and E the white lobe's directional albedo,
// interpolated from a table (inc/sheen_albedo.glsl). Sampling picks the sheen with a
// probability from max(C)·E(ωo) and the base's albedo, and then samples the cosine.
#ifndef INC_BSDF_GLSL
#define INC_BSDF_GLSL

#include "common.glsl"
#include "sampling.glsl"
#include "sheen_albedo.glsl"

struct BsdfParams {
    vec3 base_color;
    float metallic;
    float alpha;           // GGX α = roughness², clamped to MIN_GGX_ALPHA (along the local y)
    float alpha_t;         // GGX α along the local x: alpha, or larger along the direction of
                           // KHR_materials_anisotropy (make_surface turns the frame to it)
    float specular;        // KHR_materials_specular factor: dielectric F90
    vec3 f0_dielectric;    // dielectric F0 (ior, specular colour and factor)
    float transmission;    // KHR_materials_transmission: share of the dielectric's diffuse
                           // lobe that goes through the surface (0: opaque)
    float eta;             // KHR_materials_volume: the boundary of a refracting solid, the
                           // index of the far side over wo's; 0: a thin or opaque surface
    float dispersion;      // KHR_materials_dispersion on that boundary (20 / Abbe number;
                           // 0: one index for every channel)
    float coat;            // KHR_materials_clearcoat: the coat's weight (0: no coat)
    float coat_alpha;      // its GGX α (clearcoat roughness², clamped to MIN_GGX_ALPHA)
    vec3 coat_n;           // its unit normal in the local frame (upper hemisphere)
    vec3 sheen_color;      // KHR_materials_sheen: the sheen's colour (black: no sheen)
    float sheen_roughness; // its roughness r (α = r², r taken as at least 0.1)
    float diffuse_transmission;       // KHR_materials_diffuse_transmission: share of the
                                      // diffuse lobe (what `transmission` leaves) that
    vec3 diffuse_transmission_color;  // leaves below the surface, tinted by this colour
    float iridescence;            // KHR_materials_iridescence: the thin film's weight (0: none),
    float iridescence_ior;        // its index of refraction
    float iridescence_thickness;  // and its thickness in nanometres
};

// GGX's D of a unit microfacet normal whose cosine from the macro normal is `c` and
// squared sine `s2`: α² / (π (sin²θ + α² cos²θ)²). The common form c²(α² − 1) + 1
// cancels to nothing near the peak once α² is below float's resolution of 1 (α below
// about 2.4e-4; MIN_GGX_ALPHA is 1e-4), so the sine comes from the tangential part.
float ggx_d_cos_sin2(float c, float s2, float a) {
    float a2 = a * a;
    float d = s2 + c * c * a2;
    return d > 0.0 ? a2 / (PI * d * d) : 0.0;
}

// D of a unit microfacet normal in the local frame (z the macro normal), α = a.x along x
// and a.y along y: 1 / (π ax ay (hx²/ax² + hy²/ay² + hz²)²), written as ax·ay / (π (hx²·ay/ax
// + hy²·ax/ay + hz²·ax·ay)²), which is ggx_d_cos_sin2's form where ax = ay (no
// cancellation near the peak).
float ggx_d(vec3 h, vec2 a) {
    if (a.x == a.y) return ggx_d_cos_sin2(h.z, dot(h.xy, h.xy), a.x);
    float k = a.x * a.y;
    float d = h.x * h.x * (a.y / a.x) + h.y * h.y * (a.x / a.y) + h.z * h.z * k;
    return d > 0.0 ? k / (PI * d * d) : 0.0;
}

// The material's (α along x, α along y).
vec2 ggx_alphas(BsdfParams p) { return vec2(p.alpha_t, p.alpha); }

// D of a unit microfacet normal `h` about the unit macro normal `n`.
float ggx_d_about(vec3 h, vec3 n, float a) {
    float c = dot(h, n);
    vec3 t = h - c * n;
    return ggx_d_cos_sin2(c, dot(t, t), a);
}

// Smith's Λ of a direction at cosine `c` from the macro normal.
float ggx_lambda_cos(float c, float a) {
    float c2 = c * c;
    float t2 = max(0.0, 1.0 - c2) / max(c2, 1e-12);
    return 0.5 * (-1.0 + sqrt(1.0 + a * a * t2));
}

// Λ of a local direction v for α = a.x along x and a.y along y: the projected α² tan²θ
// is (ax² vx² + ay² vy²) / vz².
float ggx_lambda(vec3 v, vec2 a) {
    if (a.x == a.y) return ggx_lambda_cos(v.z, a.x);
    float t2 = (sqr(a.x * v.x) + sqr(a.y * v.y)) / max(v.z * v.z, 1e-12);
    return 0.5 * (-1.0 + sqrt(1.0 + t2));
}

// (1 − c)⁵ of Schlick's Fresnel, by multiplication: pow() is exp2(5·log2(x)) on CPU
// devices (lavapipe), several times the cost.
float schlick_weight(float c) {
    float m = 1.0 - clamp(c, 0.0, 1.0);
    float m2 = m * m;
    return m2 * m2 * m;
}

// ---- the thin film (KHR_materials_iridescence, p.iridescence > 0) ----
// Belcour & Barla 2017, "A practical extension to microfacet theory for the modeling of
// varying iridescence", as the extension's implementation notes simplify it: Schlick's
// reflectance at both interfaces of the film, phase shifts of 0 or π (no polarisation),
// the base's index taken from its F0 (a metal's extinction ignored), and the Airy
// series' interference terms up to the second integrated analytically against Gaussian
// fits of the CIE 1931 matching functions, then taken from XYZ to linear Rec. 709.

// The spectral integral of an interference term of optical path difference `opd` (nm) and
// phase shift `shift`, per colour channel.
vec3 thin_film_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1e-9;
    const vec3 amplitude = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    const vec3 centre = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    const vec3 variance = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = amplitude * sqrt(2.0 * PI * variance) * cos(centre * phase + shift) * exp(-phase * phase * variance);
    // X's second lobe.
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x) * exp(-4.5282e+09 * phase * phase);
    xyz /= 1.0685e-7;
    const mat3 xyz_to_rec709 = mat3(3.2404542, -0.9692660, 0.0556434,
                                    -1.5371385, 1.8760108, -0.2040259,
                                    -0.4985314, 0.0415560, 1.0572252);
    return xyz_to_rec709 * xyz;
}

// The film's reflectance at cosine `cos1` (from the microfacet normal) for a film of index
// `film_ior` and `thickness` nm between a medium of index `outside_ior` and a base of
// normal-incidence reflectance `base_f0`, clamped to [0, 1].
vec3 thin_film_fresnel(float outside_ior, float film_ior, float thickness, float cos1, vec3 base_f0) {
    // A film of no thickness is no film: its index goes to the outside's.
    float n2 = mix(outside_ior, film_ior, smoothstep(0.0, 0.03, thickness));
    float sin2_sq = sqr(outside_ior / n2) * (1.0 - cos1 * cos1);
    if (sin2_sq >= 1.0) return vec3(1.0);  // total internal reflection at the film
    float cos2 = sqrt(1.0 - sin2_sq);
    // The outside–film interface, both ways.
    float r0 = sqr((n2 - outside_ior) / (n2 + outside_ior));
    float r12 = r0 + (1.0 - r0) * schlick_weight(cos1);
    float t121 = 1.0 - r12;
    float phi12 = n2 < outside_ior ? PI : 0.0;
    float phi21 = PI - phi12;
    // The film–base interface; the base's index from its F0 (kept below 1).
    vec3 s = sqrt(min(base_f0 + 1e-4, vec3(0.9999)));
    vec3 n3 = (1.0 + s) / (1.0 - s);
    vec3 q = (n3 - n2) / (n3 + n2);
    vec3 r1 = q * q;
    vec3 r23 = r1 + (1.0 - r1) * schlick_weight(cos2);
    vec3 phi23 = vec3(n3.x < n2 ? PI : 0.0, n3.y < n2 ? PI : 0.0, n3.z < n2 ? PI : 0.0);
    vec3 phi = phi21 + phi23;
    float opd = 2.0 * n2 * thickness * cos2;
    // The Airy series: its mean and its first two interference terms.
    vec3 r123 = clamp(r12 * r23, 1e-5, 0.9999);
    vec3 r = sqrt(r123);
    vec3 rs = t121 * t121 * r23 / (1.0 - r123);
    vec3 result = r12 + rs;
    vec3 cm = rs - t121;
    for (int m = 1; m <= 2; ++m) {
        cm *= r;
        result += cm * 2.0 * thin_film_sensitivity(float(m) * opd, float(m) * phi);
    }
    return clamp(result, 0.0, 1.0);
}

// The film's outside index: air, or the coat's 1.5 under a coat.
float thin_film_outside_ior(BsdfParams p) { return p.coat > 0.0 ? 1.5 : 1.0; }

// Probability of sampling the specular lobe for outgoing direction wo.
float bsdf_specular_probability(BsdfParams p, vec3 wo) {
    float w = schlick_weight(wo.z);
    vec3 fd = p.f0_dielectric + (vec3(p.specular) - p.f0_dielectric) * w;
    vec3 fm = p.base_color + (1.0 - p.base_color) * w;
    float spec = (1.0 - p.metallic) * max3(fd) + p.metallic * luminance(fm);
    // The diffuse lobe's albedo: the base colour, and the transmitted colour's share.
    vec3 albedo = p.diffuse_transmission > 0.0 ? mix(p.base_color, p.diffuse_transmission_color, p.diffuse_transmission)
                                               : p.base_color;
    float diff = (1.0 - p.metallic) * luminance(albedo) * (1.0 - max3(fd));
    if (spec <= 0.0) return 0.0;
    if (diff <= 0.0) return 1.0;
    return clamp(spec / (spec + diff), 0.1, 0.9);
}

// What eval() and pdf() need of wo alone, computed once per shading point so that each
// further direction wi (RIS evaluates 32 light candidates per vertex) costs only its own
// part: the half vector, D, Λ(wi) and the Fresnel weight.
struct BsdfWo {
    vec3 wo;            // local outgoing direction
    float lambda_wo;    // Smith Λ(wo)
    float spec_prob;    // bsdf_specular_probability(wo)
    float coat_weight;  // the coat's share w = clearcoat·F(ωo·nc); the base has 1 − w
    float coat_prob;    // probability of sampling the coat (0: no coat lobe toward wo)
    float coat_lambda_wo;  // the coat's Smith Λ(wo)
    float sheen_albedo_wo; // the white sheen lobe's albedo E(ωo)
    float sheen_prob;      // probability of sampling the sheen, below the coat's choice
};

// Visible GGX normal for wo (Dupuy & Benyoub 2023), α = a.x along x and a.y along y (the
// stretch to the unit hemisphere and back is per axis).
vec3 ggx_sample_visible_normal(vec3 wo, vec2 a, vec2 u) {
    vec3 v = normalize(vec3(wo.xy * a, wo.z));
    vec2 cs = cos_sin_turn(u.x);  // of φ = 2π·u.x
    float z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    float s = sqrt(clamp(1.0 - z * z, 0.0, 1.0));
    vec3 h = vec3(s * cs.x, s * cs.y, z) + v;
    return normalize(vec3(h.xy * a, max(h.z, 0.0)));
}

// ---- the boundary of a solid (eta > 0) ----

// Share of the material that is the dielectric interface.
float volume_share(BsdfParams p) { return (1.0 - p.metallic) * p.transmission; }

// The rest of the material, opaque, as BsdfParams whose value times (1 − volume_share)
// is (1 − metallic)(1 − transmission)·dielectric + metallic·metal.
BsdfParams volume_rest(BsdfParams p) {
    BsdfParams q = p;
    float rest = 1.0 - volume_share(p);
    q.metallic = rest > 0.0 ? clamp(p.metallic / rest, 0.0, 1.0) : 0.0;
    q.transmission = 0.0;
    q.eta = 0.0;
    return q;
}

// Fresnel reflectance of a dielectric interface for light arriving at cosine cos_i (> 0)
// on the side of index 1, the far side of index eta (total internal reflection: 1).
float fresnel_dielectric(float cos_i, float eta) {
    float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float r_parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (r_parallel * r_parallel + r_perpendicular * r_perpendicular);
}

// The interface's index ratio for each colour channel (KHR_materials_dispersion): the
// solid's index n (eta seen from outside, 1 / eta from inside) becomes n − s, n and n + s
// for red, green and blue, s = (n − 1)·0.025·dispersion, none below 1.
vec3 interface_etas(BsdfParams p) {
    bool outside = p.eta >= 1.0;
    float n = outside ? p.eta : 1.0 / p.eta;
    float s = (n - 1.0) * 0.025 * p.dispersion;
    vec3 ns = max(vec3(n - s, n, n + s), vec3(1.0));
    return outside ? ns : 1.0 / ns;
}

// The interface of index ratio eta: f·|cosθi| and sampling density of wi (wo.z > 0),
// both sides.
vec3 interface_eval_pdf_eta(BsdfParams p, float eta, vec3 wo, float lambda_wo, vec3 wi, out float pdf) {
    pdf = 0.0;
    bool reflected = wi.z > 0.0;
    float etap = reflected ? 1.0 : eta;
    vec3 h = wi * etap + wo;  // the (generalised) half vector
    if (wi.z == 0.0 || dot(h, h) == 0.0) return vec3(0.0);
    h = normalize(h);
    if (h.z < 0.0) h = -h;
    float ho = dot(wo, h);
    float hi = dot(wi, h);
    // Microfacets seen from behind by either direction carry nothing.
    if (ho <= 0.0 || hi * wi.z <= 0.0) return vec3(0.0);
    float d = ggx_d(h, ggx_alphas(p));
    float g1o = 1.0 / (1.0 + lambda_wo);
    float g1i = 1.0 / (1.0 + ggx_lambda(wi, ggx_alphas(p)));
    float f = fresnel_dielectric(ho, eta);
    // Visible-normal density of h: g1o·D·(wo·h)/cosθo.
    float visible = g1o * d * ho / wo.z;
    if (reflected) {
        pdf = f * visible / (4.0 * ho);
        return vec3(f * d * g1o * g1i / (4.0 * wo.z));
    }
    float denom = sqr(hi + ho / etap);
    pdf = (1.0 - f) * visible * abs(hi) / denom;
    return p.base_color * ((1.0 - f) * d * g1o * g1i * abs(hi) * ho / (denom * wo.z * etap * etap));
}

// The interface's f·|cosθi| and sampling density of wi (wo.z > 0), both sides. With
// dispersion each channel has its own interface (its own Fresnel term, refracted
// direction and 1/η²), and interface_sample draws from the three with equal
// probabilities: the density is their mean.
vec3 interface_eval_pdf(BsdfParams p, vec3 wo, float lambda_wo, vec3 wi, out float pdf) {
    if (p.dispersion <= 0.0) return interface_eval_pdf_eta(p, p.eta, wo, lambda_wo, wi, pdf);
    vec3 etas = interface_etas(p);
    float pdf_g, pdf_b;
    vec3 f = vec3(interface_eval_pdf_eta(p, etas.r, wo, lambda_wo, wi, pdf).r,
                  interface_eval_pdf_eta(p, etas.g, wo, lambda_wo, wi, pdf_g).g,
                  interface_eval_pdf_eta(p, etas.b, wo, lambda_wo, wi, pdf_b).b);
    pdf = (pdf + pdf_g + pdf_b) * (1.0 / 3.0);
    return f;
}

// Sample the interface: a visible normal from u.yz, then reflection with probability F
// (decided by u.x) or refraction. With dispersion u.x first picks the channel whose
// interface is sampled (each with probability 1/3), then, rescaled, decides as above.
bool interface_sample(BsdfParams p, vec3 wo, vec3 u, out vec3 wi) {
    float eta = p.eta;
    float u_fresnel = u.x;
    if (p.dispersion > 0.0) {
        float k = min(floor(u.x * 3.0), 2.0);
        eta = interface_etas(p)[int(k)];
        u_fresnel = min(u.x * 3.0 - k, 0.99999994);
    }
    vec3 h = ggx_sample_visible_normal(wo, ggx_alphas(p), u.yz);
    float ho = dot(wo, h);
    if (u_fresnel < fresnel_dielectric(ho, eta)) {
        wi = reflect(-wo, h);
        return wi.z > 0.0;
    }
    wi = refract(-wo, h, 1.0 / eta);
    return wi.z < 0.0;
}

// ---- the clearcoat (p.coat > 0) ----

// Sampling probability of the coat: its share w against the base's (1 − w) times a rough
// albedo of the base (its lobes scale with the base colour, its dielectric specular about
// 0.04), kept within [0.1, 0.9] so that neither lobe is starved.
float coat_probability(BsdfParams p, float w) {
    if (w <= 0.0) return 0.0;
    float base = max(luminance(p.base_color), 0.04) * (1.0 - w);
    return clamp(w / (w + base), 0.1, 0.9);
}

// The coat's f·|ωi·nc| (its share w not applied) and its visible-normal density of wi.
float coat_eval_pdf(BsdfParams p, BsdfWo c, vec3 wi, out float pdf) {
    pdf = 0.0;
    float co = dot(c.wo, p.coat_n);
    float ci = dot(wi, p.coat_n);
    if (co <= 0.0 || ci <= 0.0 || wi.z <= 0.0) return 0.0;
    float d = ggx_d_about(normalize(c.wo + wi), p.coat_n, p.coat_alpha);
    pdf = d / ((1.0 + c.coat_lambda_wo) * 4.0 * co);
    return d / (1.0 + c.coat_lambda_wo + ggx_lambda_cos(ci, p.coat_alpha)) / (4.0 * co);
}

// A direction reflected by a visible normal of the coat drawn from u.
bool coat_sample(BsdfParams p, vec3 wo, vec2 u, out vec3 wi) {
    vec3 t, b;
    make_basis(p.coat_n, t, b);
    vec3 h = ggx_sample_visible_normal(to_local(wo, t, b, p.coat_n), vec2(p.coat_alpha), u);
    wi = reflect(-wo, to_world(h, t, b, p.coat_n));
    return wi.z > 0.0 && dot(wi, p.coat_n) > 0.0;
}

// ---- the sheen (max3(p.sheen_color) > 0) ----

// Sheen roughness r → the Charlie distribution's α.
float sheen_alpha(float r) { return max(r * r, 0.01); }

// The white sheen lobe's directional albedo E at cosine mu (bilinear in √μ and r).
float sheen_albedo(float mu, float r) {
    float last = float(SHEEN_ALBEDO_N - 1);
    float x = sqrt(clamp(mu, 0.0, 1.0)) * last;
    float y = clamp(r, 0.0, 1.0) * last;
    int i = min(int(x), SHEEN_ALBEDO_N - 2);
    int j = min(int(y), SHEEN_ALBEDO_N - 2);
    float fx = x - float(i);
    float fy = y - float(j);
    int k = j * SHEEN_ALBEDO_N + i;
    float lo = mix(SHEEN_ALBEDO[k], SHEEN_ALBEDO[k + 1], fx);
    float hi = mix(SHEEN_ALBEDO[k + SHEEN_ALBEDO_N], SHEEN_ALBEDO[k + SHEEN_ALBEDO_N + 1], fx);
    return mix(lo, hi, fy);
}

// Estevez & Kulla's fit of the sheen's Λ (their exponent of a rational in cosθ, blended
// between α = 0 and 1 by (1 − α)²).
float sheen_lambda_fit(float x, float a) {
    float t = sqr(1.0 - a);
    float fa = mix(21.5473, 25.3245, t);
    float fb = mix(3.82987, 3.32435, t);
    float fc = mix(0.19823, 0.16801, t);
    float fd = mix(-1.97760, -1.27393, t);
    float fe = mix(-4.32054, -4.85967, t);
    return fa / (1.0 + fb * pow(x, fc)) + fd * x + fe;
}

float sheen_lambda(float c, float a) {
    c = abs(c);
    return c < 0.5 ? exp(sheen_lambda_fit(c, a)) : exp(2.0 * sheen_lambda_fit(0.5, a) - sheen_lambda_fit(1.0 - c, a));
}

// The white sheen lobe's D·V·cosθi toward wi (above the surface).
float sheen_eval(BsdfParams p, vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return 0.0;
    float a = sheen_alpha(p.sheen_roughness);
    vec3 h = normalize(wo + wi);
    float d = (2.0 + 1.0 / a) * pow(max(1.0 - h.z * h.z, 0.0), 0.5 / a) * (0.5 * INV_PI);
    float v = min(1.0 / ((1.0 + sheen_lambda(wo.z, a) + sheen_lambda(wi.z, a)) * 4.0 * wo.z * wi.z), 1.0);
    return d * v * wi.z;
}

BsdfWo bsdf_at(BsdfParams p, vec3 wo) {
    BsdfWo c;
    c.wo = wo;
    c.lambda_wo = ggx_lambda(wo, ggx_alphas(p));
    // On a solid's boundary the specular probability is the opaque rest's.
    c.spec_prob = bsdf_specular_probability(p.eta > 0.0 ? volume_rest(p) : p, wo);
    c.coat_weight = 0.0;
    c.coat_prob = 0.0;
    c.coat_lambda_wo = 0.0;
    if (p.coat > 0.0) {
        float co = dot(wo, p.coat_n);
        c.coat_weight = p.coat * (0.04 + 0.96 * schlick_weight(abs(co)));
        c.coat_prob = co > 0.0 ? coat_probability(p, c.coat_weight) : 0.0;
        c.coat_lambda_wo = ggx_lambda_cos(co, p.coat_alpha);
    }
    c.sheen_albedo_wo = 0.0;
    c.sheen_prob = 0.0;
    float sheen = max3(p.sheen_color);
    if (sheen > 0.0) {
        c.sheen_albedo_wo = sheen_albedo(wo.z, p.sheen_roughness);
        float lobe = sheen * c.sheen_albedo_wo;
        float base = max(luminance(p.base_color), 0.04) * max(1.0 - lobe, 0.0);
        c.sheen_prob = lobe > 0.0 ? clamp(lobe / (lobe + base), 0.1, 0.9) : 0.0;
    }
    return c;
}

// f(wo, wi)·|cosθi| and, in `pdf`, the density of sampling wi (solid angle): both share
// the half vector and D. The single definition of the BSDF: eval() and pdf() call it.
// Below the surface (wi.z < 0) only the transmission lobe lives: the specular lobe's
// value and density at wi mirrored above.
vec3 bsdf_eval_pdf_walls(BsdfParams p, BsdfWo c, vec3 wi, out float pdf) {
    vec3 wo = c.wo;
    pdf = 0.0;
    bool through = wi.z < 0.0;
    if (wo.z <= 0.0 || wi.z == 0.0 || (through && p.transmission <= 0.0 && p.diffuse_transmission <= 0.0))
        return vec3(0.0);
    vec3 wr = through ? vec3(wi.xy, -wi.z) : wi;  // mirrored above the surface
    vec3 h = normalize(wo + wr);
    float d = ggx_d(h, ggx_alphas(p));
    float w = schlick_weight(dot(wo, h));
    float spec = d / (1.0 + c.lambda_wo + ggx_lambda(wr, ggx_alphas(p))) / (4.0 * wo.z * wr.z);
    vec3 fd = p.f0_dielectric + (vec3(p.specular) - p.f0_dielectric) * w;
    vec3 fm = p.base_color + (1.0 - p.base_color) * w;
    if (p.iridescence > 0.0) {
        float outside = thin_film_outside_ior(p);
        float ho = dot(wo, h);
        if (p.metallic < 1.0)
            fd = mix(fd, thin_film_fresnel(outside, p.iridescence_ior, p.iridescence_thickness, ho, p.f0_dielectric),
                     p.iridescence);
        if (p.metallic > 0.0)
            fm = mix(fm, thin_film_fresnel(outside, p.iridescence_ior, p.iridescence_thickness, ho, p.base_color),
                     p.iridescence);
    }
    // Specular and transmission lobes: visible normals, g1·D/(4 cosθo) (reflection of
    // the sampled normal; mirrored below the surface for transmission).
    float ps = c.spec_prob;
    float spec_pdf = d / ((1.0 + c.lambda_wo) * 4.0 * wo.z);
    // The diffuse lobe (what the transmission leaves) splits into reflection and
    // diffuse transmission, each cosine-weighted on its side.
    float dt = p.diffuse_transmission;
    if (through) {
        pdf = (1.0 - ps) * p.transmission * spec_pdf;
        vec3 f = (1.0 - p.metallic) * p.transmission * (1.0 - max3(fd)) * spec * p.base_color * wr.z;
        if (dt > 0.0) {
            float lobe = (1.0 - p.transmission) * dt * wr.z * INV_PI;
            pdf += (1.0 - ps) * lobe;
            f += (1.0 - p.metallic) * (1.0 - max3(fd)) * lobe * p.diffuse_transmission_color;
        }
        return f;
    }
    vec3 diffuse = p.base_color * INV_PI * (1.0 - p.transmission);
    if (dt > 0.0) diffuse *= 1.0 - dt;
    vec3 dielectric = diffuse * (1.0 - max3(fd)) + spec * fd;
    vec3 metal = spec * fm;
    float diffuse_share = dt > 0.0 ? (1.0 - p.transmission) * (1.0 - dt) : 1.0 - p.transmission;
    pdf = (1.0 - ps) * diffuse_share * wi.z * INV_PI + ps * spec_pdf;
    return mix(dielectric, metal, p.metallic) * wi.z;
}

// The base under the coat: bsdf_eval_pdf_walls for thin or opaque surfaces; on a solid's
// boundary the interface with its share, and the opaque rest.
vec3 bsdf_eval_pdf_base(BsdfParams p, BsdfWo c, vec3 wi, out float pdf) {
    if (p.eta <= 0.0) return bsdf_eval_pdf_walls(p, c, wi, pdf);
    pdf = 0.0;
    if (c.wo.z <= 0.0) return vec3(0.0);
    float share = volume_share(p);
    vec3 f = vec3(0.0);
    // (No interface where the solid is entered by diffuse transmission alone.)
    if (share > 0.0) {
        float pdf_interface;
        f = share * interface_eval_pdf(p, c.wo, c.lambda_wo, wi, pdf_interface);
        pdf = share * pdf_interface;
    }
    if (share < 1.0 && (wi.z > 0.0 || p.diffuse_transmission > 0.0)) {
        float pdf_rest;
        f += (1.0 - share) * bsdf_eval_pdf_walls(volume_rest(p), c, wi, pdf_rest);
        pdf += (1.0 - share) * pdf_rest;
    }
    return f;
}

// The whole BSDF: the base, the sheen over it, and the coat over both.
vec3 bsdf_eval_pdf(BsdfParams p, BsdfWo c, vec3 wi, out float pdf) {
    vec3 f = bsdf_eval_pdf_base(p, c, wi, pdf);
    float sheen = max3(p.sheen_color);
    if (sheen > 0.0) {
        float scale = 1.0 - sheen * max(c.sheen_albedo_wo, sheen_albedo(abs(wi.z), p.sheen_roughness));
        f = f * max(scale, 0.0) + p.sheen_color * sheen_eval(p, c.wo, wi);
        pdf = pdf * (1.0 - c.sheen_prob) + c.sheen_prob * max(wi.z, 0.0) * INV_PI;
    }
    if (p.coat <= 0.0) return f;
    float coat_pdf;
    float coat_f = coat_eval_pdf(p, c, wi, coat_pdf);
    f = f * (1.0 - c.coat_weight) + vec3(c.coat_weight * coat_f);
    pdf = pdf * (1.0 - c.coat_prob) + c.coat_prob * coat_pdf;
    return f;
}

// Probability that bsdf_sample draws from the diffuse lobe (the sheen counted with it:
// both sample the cosine).
float bsdf_diffuse_probability(BsdfParams p, BsdfWo c) {
    float under = 1.0 - c.coat_prob;
    float base = under * (1.0 - c.sheen_prob);
    if (p.eta > 0.0) return under * c.sheen_prob + base * (1.0 - volume_share(p)) * (1.0 - c.spec_prob);
    return under * c.sheen_prob + base * (1.0 - c.spec_prob) * (1.0 - p.transmission);
}

// Probability that bsdf_sample draws from the lobe through a thin wall, or from a
// solid's interface (both of its sides).
float bsdf_glass_probability(BsdfParams p, BsdfWo c) {
    float base = (1.0 - c.coat_prob) * (1.0 - c.sheen_prob);
    if (p.eta > 0.0) return base * volume_share(p);
    return base * (1.0 - c.spec_prob) * p.transmission;
}

// f(wo, wi)·cosθi.
vec3 bsdf_eval(BsdfParams p, vec3 wo, vec3 wi) {
    float unused_pdf;
    return bsdf_eval_pdf(p, bsdf_at(p, wo), wi, unused_pdf);
}

float bsdf_pdf(BsdfParams p, vec3 wo, vec3 wi) {
    float pdf;
    bsdf_eval_pdf(p, bsdf_at(p, wo), wi, pdf);
    return pdf;
}

// Sample wi; returns false when the sample is invalid (a visible normal that reflects
// wo below the surface). u.x chooses the specular lobe (u.x < spec_prob), u.y then the
// transmission lobe (u.y < transmission, rescaled), and the rest warps.
//
// On a solid's boundary u.x < volume_share picks the interface, which then takes u.x
// rescaled as its visible normal's first number, u.z as the second, and `u_fresnel` to
// choose between reflection and refraction (which depends on the normal drawn); the
// opaque rest takes u.x rescaled and u.z as above. (u.y is not used there: the caller
// derives it from u.x for the lobe choice of the walls' case.)
//
// With a coat or a sheen, `u_fresnel` first chooses the coat (u_fresnel < coat_prob),
// which then takes u.yz as its visible normal's numbers, then, rescaled, the sheen
// (below sheen_prob), which takes u.yz for the cosine; otherwise, rescaled again, it goes
// on to the base.
bool bsdf_sample(BsdfParams p, BsdfWo c, vec3 u, float u_fresnel, out vec3 wi) {
    wi = vec3(0.0);
    vec3 wo = c.wo;
    if (wo.z <= 0.0) return false;
    if (c.coat_prob > 0.0) {
        if (u_fresnel < c.coat_prob) return coat_sample(p, wo, u.yz, wi);
        u_fresnel = min((u_fresnel - c.coat_prob) / (1.0 - c.coat_prob), 0.99999994);
    }
    if (c.sheen_prob > 0.0) {
        if (u_fresnel < c.sheen_prob) {
            wi = square_to_cosine_hemisphere(u.yz);
            return wi.z > 0.0;
        }
        u_fresnel = min((u_fresnel - c.sheen_prob) / (1.0 - c.sheen_prob), 0.99999994);
    }
    if (p.eta > 0.0) {
        float share = volume_share(p);
        if (u.x < share) {
            float x = min(u.x / share, 0.99999994);
            return interface_sample(p, wo, vec3(u_fresnel, x, u.z), wi);
        }
        float x = min((u.x - share) / (1.0 - share), 0.99999994);
        float ps_rest = c.spec_prob;
        float y = ps_rest > 0.0 && x < ps_rest ? x / ps_rest : (x - ps_rest) / max(1.0 - ps_rest, 1e-30);
        p = volume_rest(p);
        u = vec3(x, min(y, 0.99999994), u.z);
    }
    float ps = c.spec_prob;
    if (u.x < ps) {
        vec3 h = ggx_sample_visible_normal(wo, ggx_alphas(p), u.yz);
        wi = reflect(-wo, h);
        return wi.z > 0.0;
    }
    if (u.y < p.transmission) {
        vec2 v = vec2(min(u.y / p.transmission, 0.99999994), u.z);
        vec3 h = ggx_sample_visible_normal(wo, ggx_alphas(p), v);
        wi = reflect(-wo, h);
        wi.z = -wi.z;
        return wi.z < 0.0;
    }
    float t = p.transmission;
    float y = t > 0.0 ? min((u.y - t) / (1.0 - t), 0.99999994) : u.y;
    // Diffuse transmission: y below its share sends the cosine sample below the surface.
    float dt = p.diffuse_transmission;
    bool below = dt > 0.0 && y < dt;
    if (dt > 0.0) y = below ? min(y / dt, 0.99999994) : min((y - dt) / (1.0 - dt), 0.99999994);
    wi = square_to_cosine_hemisphere(vec2(y, u.z));
    if (below) {
        wi.z = -wi.z;
        return wi.z < 0.0;
    }
    return wi.z > 0.0;
}

// ---- the Lambertian lobe alone -------------------------------------------------------
// What the functions above compute for a Lambertian material (metallic 0, specular 0, no
// transmission, coat or sheen, not a solid's boundary: bsdf_specular_probability is then
// 0 and every other lobe has weight 0), without the other lobes' arithmetic. The kernels
// call these instead at Lambertian surfaces (specialization constant BSDF_KERNEL,
// inc/material.glsl). Each takes its values in the same order of
// operations as the general functions, so a Lambertian material gets the same bits
// either way (tests/bsdf.rs compares them).

BsdfWo bsdf_at_lambertian(vec3 wo) {
    BsdfWo c;
    c.wo = wo;
    c.lambda_wo = 0.0;  // only the specular lobes read it
    c.spec_prob = 0.0;
    c.coat_weight = 0.0;
    c.coat_prob = 0.0;
    c.coat_lambda_wo = 0.0;
    c.sheen_albedo_wo = 0.0;
    c.sheen_prob = 0.0;
    return c;
}

// f·|cosθi| = base_color/π·cosθi and the cosine density, above the surface only.
vec3 lambertian_eval_pdf(BsdfParams p, BsdfWo c, vec3 wi, out float pdf) {
    pdf = 0.0;
    if (c.wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    pdf = wi.z * INV_PI;
    return p.base_color * INV_PI * wi.z;
}

// bsdf_sample's diffuse branch: the cosine-weighted direction from u.yz (u.x chose the
// lobe there; it is not read).
bool lambertian_sample(BsdfWo c, vec3 u, out vec3 wi) {
    wi = vec3(0.0);
    if (c.wo.z <= 0.0) return false;
    wi = square_to_cosine_hemisphere(u.yz);
    return wi.z > 0.0;
}

#endif
