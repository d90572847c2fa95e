"""KHR_materials_clearcoat and KHR_materials_sheen (and thin-walled rough
KHR_materials_transmission, the sample viewer's model, and
KHR_materials_diffuse_transmission, as `gltf_thin`) on top of the glTF BRDF of
mitsuba_gltf_bsdf.py, as a Mitsuba 3 plugin `gltf_layered`, written from the Khronos
extension texts (ratified versions, KhronosGroup/glTF commit 60ad0f83):

  sheen (KHR_materials_sheen, "Implementation Notes"):
    alpha_g = sheenRoughness^2 ; k = 1/alpha_g
    D_s = (2 + k) sin(theta_h)^k / (2 pi)
    l(x) = a/(1 + b x^c) + d x + e   (a..e mixed by (1-alpha_g)^2)
    Lambda(c) = exp(l(c)) if c < 0.5 else exp(2 l(0.5) - l(1 - c))
    V_s = 1 / ((1 + Lambda(NV) + Lambda(NL)) 4 NV NL)
    sheen_material = sheenColor D_s V_s + material * min(1 - max3(C) E(NV), 1 - max3(C) E(NL))
    E(mu) = directional albedo of the white lobe D_s V_s (own numerical integration)
  clearcoat (KHR_materials_clearcoat):
    Fc = 0.04 + 0.96 (1 - |V.Nc|)^5
    coated = mix(sheen_material, D_ggx(a_c) Vis_ggx(a_c), clearcoat * Fc),  a_c = ccRoughness^2
  Options not in the spec:
    sheen_vclamp=1  clamps V_s to 1 (the glTF sample viewer, and lanterna; plugin_dict sets
                    it unless GLTF_SHEEN_SPEC_V=1)
    scale_floor=1   (default 1) keeps the sheen's base scale >= 0 (E > 1 near grazing)
  Deliberate defects, to show a comparison can see them: GLTF_DEFECT=coat-alpha (the
  coat's alpha = roughness), coat-vdoth (its Fresnel at V.H), sheen-v-only (the
  albedo scaling at E(N.V) alone).
Checked on its own (2026-11-29): against the float64 transcription np_full (relative
error <= 3.8e-4 over 7 materials), sample weights = f cos / pdf (1.2e-7), mean sample
weight against a quadrature of f cos, E(mu) against Monte Carlo, and a white coat over
white Lambert conserving energy (albedo 0.991-1.000).
"""
import math
import os
import numpy as np
import drjit as dr
import mitsuba as mi
import mitsuba_gltf_bsdf as base_mod

# ---------------------------------------------------------------- float64 numpy spec ---

def l_coefficients(ag):
    """Estevez & Kulla's fitted curve l(x) = a/(1 + b x^c) + d x + e: its coefficients,
    mixed between their two fits by (1 - alpha_g)^2 (KHR_materials_sheen)."""
    t = (1.0 - ag) ** 2
    fits = ((21.5473, 25.3245), (3.82987, 3.32435), (0.19823, 0.16801),
            (-1.97760, -1.27393), (-4.32054, -4.85967))
    return tuple(lo + (hi - lo) * t for lo, hi in fits)


def np_l(x, ag):
    a, b, c, d, e = l_coefficients(ag)
    return a / (1.0 + b * np.power(x, c)) + d * x + e


def np_lambda(ct, ag):
    ct = np.abs(ct)
    return np.where(ct < 0.5, np.exp(np_l(ct, ag)),
                    np.exp(2.0 * np_l(0.5, ag) - np_l(1.0 - ct, ag)))


def np_sheen_D(nh, ag):
    k = 1.0 / ag
    s2 = np.maximum(1.0 - nh * nh, 0.0)
    return (2.0 + k) * np.power(s2, 0.5 * k) / (2.0 * math.pi)


def np_sheen_V(nv, nl, ag, vclamp=False):
    v = 1.0 / ((1.0 + np_lambda(nv, ag) + np_lambda(nl, ag)) * 4.0 * nv * nl)
    return np.minimum(v, 1.0) if vclamp else v


def sheen_albedo(mu, rough, n_t=600, n_p=400, vclamp=False):
    """E(mu) = int f_s(v, l) cos(l) dl of the white sheen lobe, float64, Gauss-Legendre
    in s (cos theta_l = s^2) and phi in [0, pi] (symmetry), for an array of mu."""
    ag = rough * rough
    xs, ws = np.polynomial.legendre.leggauss(n_t)
    s = 0.5 * (xs + 1.0); wsv = 0.5 * ws
    nl = s * s; w_nl = wsv * 2.0 * s           # d(nl) = 2 s ds
    xp, wp = np.polynomial.legendre.leggauss(n_p)
    phi = 0.5 * math.pi * (xp + 1.0); w_phi = 0.5 * math.pi * wp * 2.0  # x2 for [pi, 2pi]
    NL, PHI = np.meshgrid(nl, phi, indexing="ij")
    W = np.outer(w_nl, w_phi)
    sl = np.sqrt(np.maximum(1.0 - NL * NL, 0.0))
    lx, ly, lz = sl * np.cos(PHI), sl * np.sin(PHI), NL
    out = []
    for m in np.atleast_1d(mu):
        vx, vz = math.sqrt(max(1.0 - m * m, 0.0)), m
        hx, hy, hz = vx + lx, ly, vz + lz
        hn = np.sqrt(hx * hx + hy * hy + hz * hz)
        nh = hz / hn
        f = np_sheen_D(nh, ag) * np_sheen_V(m, NL, ag, vclamp)
        out.append(float(np.sum(W * f * NL)))
    return np.array(out)


def np_ggx_D(nh, a):
    a2 = a * a
    c2 = nh * nh
    den = (1.0 - c2) + a2 * c2
    return a2 / (math.pi * den * den)


def np_ggx_Vis(nl, nv, a):
    a2 = a * a
    gv = nl * np.sqrt(a2 + (1 - a2) * nv * nv)
    gl = nv * np.sqrt(a2 + (1 - a2) * nl * nl)
    return 0.5 / (gv + gl)


def np_base(p, v, l):
    """Appendix B (+ KHR_materials_specular), RGB, v and l (N,3) upper hemisphere."""
    a = max(p["roughness"] ** 2, 1e-4)
    h = v + l; h /= np.linalg.norm(h, axis=-1, keepdims=True)
    vh = np.abs(np.sum(v * h, -1))
    fw = (1.0 - vh) ** 5
    spec = np_ggx_D(h[:, 2], a) * np_ggx_Vis(l[:, 2], v[:, 2], a)
    f0i = ((1 - p["ior"]) / (1 + p["ior"])) ** 2
    f0 = np.array([min(f0i * c, 1.0) * p["specular"] for c in p["spec_color"]])
    F = f0[None] + (p["specular"] - f0[None]) * fw[:, None]
    base = np.array(p["base"])[None]
    diel = F * spec[:, None] + (1 - F.max(1, keepdims=True)) * base / math.pi
    metal = (base + (1 - base) * fw[:, None]) * spec[:, None]
    return (1 - p["metallic"]) * diel + p["metallic"] * metal


def np_full(p, v, l, E=None):
    """The coated, sheened BRDF (no cosine), RGB, float64."""
    f = np_base(p, v, l)
    C = np.array(p["sheen"])
    if C.max() > 0:
        ag = p["sheen_rough"] ** 2
        h = v + l; h /= np.linalg.norm(h, axis=-1, keepdims=True)
        fs = np_sheen_D(h[:, 2], ag) * np_sheen_V(v[:, 2], l[:, 2], ag, p.get("sheen_vclamp", 0))
        if E is None:
            Ev = sheen_albedo(v[:, 2], p["sheen_rough"], vclamp=p.get("sheen_vclamp", 0))
            El = sheen_albedo(l[:, 2], p["sheen_rough"], vclamp=p.get("sheen_vclamp", 0))
        else:
            Ev, El = E(v[:, 2]), E(l[:, 2])
        sc = np.minimum(1 - C.max() * Ev, 1 - C.max() * El)
        if p.get("scale_floor", 1):
            sc = np.maximum(sc, 0.0)
        f = C[None] * fs[:, None] + f * sc[:, None]
    if p["clearcoat"] > 0:
        ac = max(p["cc_rough"] ** 2, 1e-4)
        h = v + l; h /= np.linalg.norm(h, axis=-1, keepdims=True)
        fc = np_ggx_D(h[:, 2], ac) * np_ggx_Vis(l[:, 2], v[:, 2], ac)
        w = p["clearcoat"] * (0.04 + 0.96 * (1 - np.abs(v[:, 2])) ** 5)
        f = (1 - w)[:, None] * f + (w * fc)[:, None]
    return f


# ------------------------------------------------------------------- Mitsuba plugin ---

_E_CACHE = {}
E_N = 513  # table points, uniform in sqrt(mu)


def e_table(rough, vclamp=False):
    key = (round(rough, 9), bool(vclamp))
    if key not in _E_CACHE:
        s = np.linspace(0.0, 1.0, E_N)
        mu = np.maximum(s * s, 1e-7)
        _E_CACHE[key] = sheen_albedo(mu, rough, vclamp=vclamp)
    return _E_CACHE[key]


def params(props):
    g = lambda k, d: float(props[k]) if props.has_property(k) else d
    p = base_mod._params(props)
    p.update(clearcoat=g("clearcoat", 0.0), cc_rough=g("cc_rough", 0.0),
             sheen=(g("sheen_r", 0.0), g("sheen_g", 0.0), g("sheen_b", 0.0)),
             sheen_rough=g("sheen_rough", 0.0), sheen_vclamp=g("sheen_vclamp", 0.0),
             scale_floor=g("scale_floor", 1.0),
             p_coat=g("p_coat", -1.0), p_sheen=g("p_sheen", -1.0))
    return p


class GltfLayered(base_mod.GltfBSDF):
    def __init__(self, props):
        base_mod.GltfBSDF.__init__(self, props)
        p = params(props)
        self.p = p
        self.cc = p["clearcoat"]
        # KHR_materials_iridescence: under a coat the film's outside is the coat (1.5).
        self.irid_outside = 1.5 if self.cc > 0 else 1.0
        self.alpha_c = max(p["cc_rough"] ** (1 if base_mod._DEFECT == "coat-alpha" else 2), 1e-4)
        self.C = mi.Color3f(*p["sheen"])
        self.Cmax = max(p["sheen"])
        self.has_sheen = self.Cmax > 0
        self.ag = max(p["sheen_rough"] ** 2, 1e-7)
        self.vclamp = bool(p["sheen_vclamp"])
        self.floor = bool(p["scale_floor"])
        if self.has_sheen:
            self.E = mi.Float(e_table(p["sheen_rough"], self.vclamp).astype(np.float32))
        self.pc = (p["p_coat"] if p["p_coat"] >= 0 else (0.35 if self.cc > 0 else 0.0))
        self.psh = (p["p_sheen"] if p["p_sheen"] >= 0 else (0.25 if self.has_sheen else 0.0))

    # generic GGX pieces for any alpha
    @staticmethod
    def Dg(cos_h, a):
        a2 = a * a
        c2 = cos_h * cos_h
        den = (1.0 - c2) + a2 * c2
        return a2 / (dr.pi * den * den)

    @staticmethod
    def Visg(nl, nv, a):
        a2 = a * a
        gv = nl * dr.sqrt(a2 + (1.0 - a2) * nv * nv)
        gl = nv * dr.sqrt(a2 + (1.0 - a2) * nl * nl)
        return dr.select(gv + gl > 0, 0.5 / (gv + gl), 0.0)

    @staticmethod
    def G1g(c, a):
        a2 = a * a
        t2 = dr.maximum(1.0 - c * c, 0.0) / dr.maximum(c * c, 1e-12)
        return 2.0 / (1.0 + dr.sqrt(1.0 + a2 * t2))

    # sheen pieces (spec)
    def _l(self, x):
        a, b, c, d, e = l_coefficients(self.ag)
        return a / (1.0 + b * dr.power(x, c)) + d * x + e

    def _lambda(self, ct):
        ct = dr.abs(ct)
        return dr.select(ct < 0.5, dr.exp(self._l(ct)),
                         dr.exp(2.0 * self._l(mi.Float(0.5)) - self._l(1.0 - ct)))

    def sheenD(self, nh):
        k = 1.0 / self.ag
        s2 = dr.maximum(1.0 - nh * nh, 0.0)
        return (2.0 + k) * dr.power(s2, 0.5 * k) / (2.0 * dr.pi)

    def sheenV(self, nv, nl):
        v = 1.0 / ((1.0 + self._lambda(nv) + self._lambda(nl)) * 4.0 * nv * nl)
        return dr.minimum(v, 1.0) if self.vclamp else v

    def Eval(self, mu):
        x = dr.sqrt(dr.clip(mu, 0.0, 1.0)) * (E_N - 1)
        i0 = dr.minimum(mi.UInt32(dr.floor(x)), E_N - 2)
        t = x - mi.Float(i0)
        e0 = dr.gather(mi.Float, self.E, i0)
        e1 = dr.gather(mi.Float, self.E, i0 + 1)
        return e0 + (e1 - e0) * t

    def brdf(self, wi, wo):
        f = base_mod.GltfBSDF.brdf(self, wi, wo)
        h = dr.normalize(wi + wo)
        if self.has_sheen:
            fs = self.sheenD(h.z) * self.sheenV(wi.z, wo.z)
            sc = dr.minimum(1.0 - self.Cmax * self.Eval(wi.z), 1.0 - self.Cmax * self.Eval(wo.z))
            if base_mod._DEFECT == "sheen-v-only":  # the spec's simplified scaling
                sc = 1.0 - self.Cmax * self.Eval(wi.z)
            if self.floor:
                sc = dr.maximum(sc, 0.0)
            f = self.C * fs + f * sc
        if self.cc > 0:
            fc = self.Dg(h.z, self.alpha_c) * self.Visg(wo.z, wi.z, self.alpha_c)
            cw = dr.abs(dr.dot(wi, h)) if base_mod._DEFECT == "coat-vdoth" else dr.abs(wi.z)
            w = self.cc * (0.04 + 0.96 * dr.power(1.0 - cw, 5.0))
            f = (1.0 - w) * f + w * fc
        return f

    def vndf_pdf(self, wi, h, a):
        return self.G1g(wi.z, a) * self.Dg(h.z, a) / (4.0 * wi.z)

    def charlie_pdf(self, wi, h):
        vh = dr.dot(wi, h)
        return dr.select(vh > 0, self.sheenD(h.z) * h.z / (4.0 * vh), 0.0)

    def pdf_local(self, wi, wo):
        h = dr.normalize(wi + wo)
        p_base = base_mod.GltfBSDF.pdf_local(self, wi, wo)
        p = (1.0 - self.pc - self.psh) * p_base
        if self.pc > 0:
            p += self.pc * self.vndf_pdf(wi, h, self.alpha_c)
        if self.psh > 0:
            p += self.psh * self.charlie_pdf(wi, h)
        return p

    def sample_vndf_a(self, wi, u, a):
        saved = self.alpha
        self.alpha = a
        h = base_mod.GltfBSDF.sample_vndf(self, wi, u)
        self.alpha = saved
        return h

    def sample_charlie(self, u):
        k = 1.0 / self.ag
        st = dr.power(dr.maximum(u.x, 1e-30), 1.0 / (k + 2.0))
        ct = dr.sqrt(dr.maximum(1.0 - st * st, 0.0))
        phi = 2.0 * dr.pi * u.y
        return mi.Vector3f(st * dr.cos(phi), st * dr.sin(phi), ct)

    def sample(self, ctx, si, sample1, sample2, active=True):
        sgn = self._side(si)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sgn)
        # lobe choice: [0, pc) coat, [pc, pc+psh) sheen, rest base (spec/diffuse mixture)
        pb = 1.0 - self.pc - self.psh
        use_coat = sample1 < self.pc
        use_sheen = (~use_coat) & (sample1 < self.pc + self.psh)
        ub = dr.clip((sample1 - self.pc - self.psh) / max(pb, 1e-9), 0.0, 0.99999994)
        use_spec = (~use_coat) & (~use_sheen) & (ub < self.ps)
        h_b = self.sample_vndf_a(wi, sample2, self.alpha)
        h = h_b
        if self.pc > 0:
            h = dr.select(use_coat, self.sample_vndf_a(wi, sample2, self.alpha_c), h)
        if self.psh > 0:
            h = dr.select(use_sheen, self.sample_charlie(sample2), h)
        wo_refl = 2.0 * dr.dot(wi, h) * h - wi
        wo_diff = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(use_coat | use_sheen | use_spec, wo_refl, wo_diff)
        pdf = self.pdf_local(wi, wo)
        f = self.brdf(wi, wo) * wo.z
        valid = (active & (wi.z > 1e-6) & (wo.z > 1e-6) & dr.isfinite(pdf)
                 & dr.isfinite(f.x) & dr.isfinite(f.y) & dr.isfinite(f.z))
        kind = dr.select(use_coat | use_sheen | use_spec,
                         mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                         mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        return base_mod.sample_result(wo, sgn, pdf, f, valid, kind)

    # robustness (one NaN pixel seen in one of 32 Mitsuba runs of sheen.gltf): directions
    # within 1e-6 of the horizon are left out and non-finite values are dropped
    def _local(self, si, wo):
        wi, wl, valid = base_mod.GltfBSDF._local(self, si, wo)
        return wi, wl, valid & (wi.z > 1e-6) & (wl.z > 1e-6)

    def eval(self, ctx, si, wo, active=True):
        f = base_mod.GltfBSDF.eval(self, ctx, si, wo, active)
        return dr.select(dr.isfinite(f), f, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        p = base_mod.GltfBSDF.pdf(self, ctx, si, wo, active)
        return dr.select(dr.isfinite(p), p, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        f, p = base_mod.GltfBSDF.eval_pdf(self, ctx, si, wo, active)
        ok = dr.isfinite(p) & dr.isfinite(f.x) & dr.isfinite(f.y) & dr.isfinite(f.z)
        return dr.select(ok, f, 0.0), dr.select(ok, p, 0.0)

    def to_string(self):
        return "GltfLayered[%s]" % self.p


def layered_dict(mat):
    """The plugin dictionary of glTF material `mat` with its coat and sheen factors."""
    d = base_mod.plugin_dict(mat)
    ext = mat.get("extensions", {})
    cc = ext.get("KHR_materials_clearcoat")
    sh = ext.get("KHR_materials_sheen")
    if cc or sh:
        d["type"] = "gltf_layered"
    if cc:
        d["clearcoat"] = cc.get("clearcoatFactor", 0.0)
        d["cc_rough"] = cc.get("clearcoatRoughnessFactor", 0.0)
    if sh:
        c = sh.get("sheenColorFactor", [0, 0, 0])
        d.update(sheen_r=c[0], sheen_g=c[1], sheen_b=c[2],
                 sheen_rough=sh.get("sheenRoughnessFactor", 0.0))
        # The sheen's visibility clamped to 1, as the glTF sample viewer and lanterna
        # (README, Conventions, "Sheen") have it; GLTF_SHEEN_SPEC_V=1 evaluates the
        # extension's text as written, which is up to 9 % brighter at grazing angles.
        if not os.environ.get("GLTF_SHEEN_SPEC_V"):
            d["sheen_vclamp"] = 1.0
    return d


# ------------------------------------------- thin-walled rough transmission (optional) ---
# KHR_materials_transmission (thin-walled, no KHR_materials_volume), as the glTF sample
# viewer evaluates it: the dielectric's diffuse lobe becomes
#   mix(diffuse, specular_btdf, transmission)
#   specular_btdf(v, l) = (1 - F(v.h')) baseColor D(h') Vis(l'.z, v.z),
#   l' = l mirrored through the surface plane, h' = normalize(v + l'),
# with alpha = roughness^2 (applyIorToRoughness: factor clamp(2 ior - 2, 0, 1) = 1 at 1.5).
# KHR_materials_diffuse_transmission (its README, "Material Structure Updates") makes the
# diffuse BSDF in there
#   mix(diffuse_brdf(baseColor), diffuse_btdf(diffuseTransmissionColor), diffuseTransmission)
#   diffuse_btdf(v, l) = color / pi for v and l on opposite sides,
# under the same Fresnel weight 1 - max(F(v.h')) as the diffuse BRDF (l mirrored, as the
# sample viewer does). With KHR_materials_volume (thickness > 0, no transmission) the
# light it passes enters the solid: the export's interior medium absorbs it (volpath).


class GltfThin(base_mod.GltfBSDF):
    def __init__(self, props):
        base_mod.GltfBSDF.__init__(self, props)
        g = lambda k, d: float(props[k]) if props.has_property(k) else d
        self.t = g("transmission", 0.0)
        self.p["transmission"] = self.t
        self.dt = g("diffuse_transmission", 0.0)
        self.dtc = mi.Color3f(g("dt_r", 1.0), g("dt_g", 1.0), g("dt_b", 1.0))
        self.p["diffuse_transmission"] = self.dt
        self.p["dt_color"] = (g("dt_r", 1.0), g("dt_g", 1.0), g("dt_b", 1.0))
        w_spec = 0.5 + 0.5 * self.metallic
        self.pt = (1.0 - self.metallic) * self.t * 0.6
        self.pr = (1.0 - self.pt) * w_spec       # reflection VNDF
        cosine = 1.0 - self.pt - self.pr
        self.pdb = cosine * self.dt              # cosine, below the surface
        self.pd = cosine - self.pdb              # cosine, above
        flags = (mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.DiffuseReflection
                 | mi.BSDFFlags.GlossyTransmission | mi.BSDFFlags.DiffuseTransmission
                 | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide)
        self.m_components = [flags]
        self.m_flags = flags

    def bsdf(self, wi, wo):
        """wi upper; wo either side. No cosine."""
        up = wo.z > 0
        lm = mi.Vector3f(wo.x, wo.y, dr.abs(wo.z))
        h = dr.normalize(wi + lm)
        vh = dr.abs(dr.dot(wi, h))
        fw = dr.power(1.0 - vh, 5.0)
        spec = self.D(h.z) * self.Vis(lm.z, wi.z)
        Fd, Fm = self.fresnel(vh, fw)
        Fd_max = dr.maximum(dr.maximum(Fd.x, Fd.y), Fd.z)
        refl_d = Fd * spec + (1.0 - Fd_max) * (1.0 - self.t) * (1.0 - self.dt) * self.base * dr.inv_pi
        refl_m = Fm * spec
        refl = (1.0 - self.metallic) * refl_d + self.metallic * refl_m
        # The transmission lobe is part of fresnel_mix's base: 1 - max(F) (KHR_materials_
        # specular), as the diffuse lobe.
        trans = (1.0 - self.metallic) * (self.t * (1.0 - Fd_max) * self.base * spec
                                         + (1.0 - Fd_max) * (1.0 - self.t) * self.dt * self.dtc * dr.inv_pi)
        return dr.select(up, refl, trans)

    def pdf_l(self, wi, wo):
        lm = mi.Vector3f(wo.x, wo.y, dr.abs(wo.z))
        h = dr.normalize(wi + lm)
        pv = self.G1(wi.z) * self.D(h.z) / (4.0 * wi.z)
        return dr.select(wo.z > 0, self.pr * pv + self.pd * wo.z * dr.inv_pi,
                         self.pt * pv + self.pdb * dr.abs(wo.z) * dr.inv_pi)

    def _loc(self, si, wo):
        sgn = self._side(si)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sgn)
        wl = mi.Vector3f(wo.x, wo.y, wo.z * sgn)
        return wi, wl, (wi.z > 1e-6) & (dr.abs(wl.z) > 1e-6)

    def eval(self, ctx, si, wo, active=True):
        wi, wl, ok = self._loc(si, wo)
        f = self.bsdf(wi, wl) * dr.abs(wl.z)
        ok &= active & dr.isfinite(f.x) & dr.isfinite(f.y) & dr.isfinite(f.z)
        return dr.select(ok, f, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        wi, wl, ok = self._loc(si, wo)
        p = self.pdf_l(wi, wl)
        return dr.select(active & ok & dr.isfinite(p), p, 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        sgn = self._side(si)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sgn)
        use_t = sample1 < self.pt
        use_r = (~use_t) & (sample1 < self.pt + self.pr)
        # The last share of sample1, pdb, takes the cosine below the surface.
        use_db = (~use_t) & (~use_r) & (sample1 >= 1.0 - self.pdb)
        h = self.sample_vndf(wi, sample2)
        wr = 2.0 * dr.dot(wi, h) * h - wi
        wt = mi.Vector3f(wr.x, wr.y, -wr.z)
        wd = mi.warp.square_to_cosine_hemisphere(sample2)
        wd = dr.select(use_db, mi.Vector3f(wd.x, wd.y, -wd.z), wd)
        wo = dr.select(use_t, wt, dr.select(use_r, wr, wd))
        ok_dir = dr.select(use_t, wr.z > 1e-6, dr.select(use_db, wo.z < -1e-6, wo.z > 1e-6))
        pdf = self.pdf_l(wi, wo)
        f = self.bsdf(wi, wo) * dr.abs(wo.z)
        valid = (active & (wi.z > 1e-6) & ok_dir & dr.isfinite(pdf) & (pdf > 0)
                 & dr.isfinite(f.x) & dr.isfinite(f.y) & dr.isfinite(f.z))
        kind = dr.select(use_t, mi.UInt32(+mi.BSDFFlags.GlossyTransmission),
                         dr.select(use_r, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                                   dr.select(use_db, mi.UInt32(+mi.BSDFFlags.DiffuseTransmission),
                                             mi.UInt32(+mi.BSDFFlags.DiffuseReflection))))
        # valid already requires pdf > 0 here.
        return base_mod.sample_result(wo, sgn, pdf, f, valid, kind)

    def to_string(self):
        return "GltfThin[%s]" % self.p


def register():
    base_mod.register()
    mi.register_bsdf("gltf_layered", lambda props: GltfLayered(props))
    mi.register_bsdf("gltf_thin", lambda props: GltfThin(props))


def plugin_dict(mat):
    """The plugin dictionary of glTF material `mat`: `gltf`, `gltf_layered` (coat, sheen)
    or `gltf_thin` (thin-walled transmission, diffuse transmission)."""
    d = layered_dict(mat)
    ext = mat.get("extensions", {})
    tr = ext.get("KHR_materials_transmission")
    if tr and tr.get("transmissionFactor", 0.0) > 0:
        if d["type"] != "gltf" or "KHR_materials_volume" in ext:
            raise ValueError("thin transmission with coat/sheen/volume not supported here")
        d["type"] = "gltf_thin"
        d["transmission"] = tr["transmissionFactor"]
    dt = ext.get("KHR_materials_diffuse_transmission")
    if dt and dt.get("diffuseTransmissionFactor", 0.0) > 0 and d.get("metallic", 1.0) < 1.0:
        if d["type"] not in ("gltf", "gltf_thin"):
            raise ValueError("diffuse transmission with coat/sheen not supported here")
        d["type"] = "gltf_thin"
        d["diffuse_transmission"] = min(float(dt["diffuseTransmissionFactor"]), 1.0)
        c = dt.get("diffuseTransmissionColorFactor", [1.0, 1.0, 1.0])
        d.update(dt_r=min(max(c[0], 0.0), 1.0), dt_g=min(max(c[1], 0.0), 1.0),
                 dt_b=min(max(c[2], 0.0), 1.0))
    if d["type"] == "gltf_thin" and "anisotropy" in d:
        raise ValueError("transmission with anisotropy not supported here")
    return d
