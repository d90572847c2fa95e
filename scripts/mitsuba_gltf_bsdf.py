"""The glTF 2.0 metallic-roughness BRDF (the specification's appendix B, with
KHR_materials_specular) as a Mitsuba 3 BSDF plugin, `gltf`, so that Mitsuba can render
lanterna's glossy materials exactly instead of approximating them by `principled`.

Written from the specification's formulas, not from lanterna's kernels:

    fresnel_w       = (1 - |V.H|)^5
    D               = a^2 / (pi ((N.H)^2 (a^2 - 1) + 1)^2),  a = roughness^2 (at least 1e-4)
    Vis             = 1 / (2 (|N.V| sqrt(a^2 + (1-a^2)(N.L)^2) + |N.L| sqrt(a^2 + (1-a^2)(N.V)^2)))
                      (the specification's visibility formula: height-correlated Smith)
    dielectric_f0   = min(((1 - ior)/(1 + ior))^2 * specularColor, 1) * specular
    dielectric_f90  = specular
    dielectric_F    = f0 + (f90 - f0) * fresnel_w
    dielectric_brdf = dielectric_F * D * Vis + (1 - max(dielectric_F)) * baseColor / pi
    metal_brdf      = (baseColor + (1 - baseColor) * fresnel_w) * D * Vis
    material        = mix(dielectric_brdf, metal_brdf, metallic)

KHR_materials_anisotropy (factors only: `anisotropy` the strength, `anisotropy_rotation` in
radians from the local frame's x, which is Mitsuba's ∂P/∂u, toward its y): the specular
lobes take Mitsuba's own anisotropic GGX (`mi.MicrofacetDistribution`, α_u = mix(a, 1,
strength^2) along the rotated x and α_v = a across it) for D, its Smith G1 for the
height-correlated visibility 1 / ((1 + Λ(V) + Λ(L)) 4 |N.V| |N.L|) with Λ = 1/G1 − 1, and
its visible-normal sampling, so that lanterna's anisotropic GGX meets an implementation
it does not share.

KHR_materials_iridescence (factors only: `iridescence`, `irid_ior`, `irid_thickness` in
nm): both Fresnel terms above become mix(F, F_iridescence, iridescence), the thin film's
term of the extension's implementation notes (`thin_film` below), the film's outside
index 1 (1.5 under a coat, mitsuba_gltf_layers).

Two-sided (a view from the back sees the same BRDF, both directions mirrored), reflection
only. Sampling is a one-sample mixture of GGX visible normals (Heitz 2018) and the cosine
hemisphere; `pdf` is the mixture's density. Only constant factors (no textures):
`rewrite_export` refuses materials it cannot write exactly.

`GLTF_DEFECT` makes the plugin differ from the specification on purpose, to show that a
peer test notices such a BRDF (tests/mitsuba_peer.rs,
`glossy_materials_agree_with_mitsuba_through_the_gltf_bsdf`): `separable` swaps the
visibility term for the separable product of G1s, `alpha-roughness` takes a = roughness
instead of roughness^2.
"""

import math
import drjit as dr
import mitsuba as mi
import json
import os
import re

_DEFECT = os.environ.get("GLTF_DEFECT", "")


def _params(props):
    g = lambda k, d: float(props[k]) if props.has_property(k) else d
    p = dict(base=(g("base_r", 0.8), g("base_g", 0.8), g("base_b", 0.8)),
             metallic=g("metallic", 1.0), roughness=g("roughness", 1.0),
             specular=g("specular", 1.0), spec_color=(g("spec_r", 1.0), g("spec_g", 1.0), g("spec_b", 1.0)),
             ior=g("ior", 1.5))
    default_ps = 0.0 if (p["metallic"] == 0.0 and p["specular"] == 0.0) else 0.5 + 0.5 * p["metallic"]
    p["spec_prob"] = g("spec_prob", default_ps)
    p["anisotropy"] = g("anisotropy", 0.0)
    p["anisotropy_rotation"] = g("anisotropy_rotation", 0.0)
    p["iridescence"] = g("iridescence", 0.0)
    p["irid_ior"] = g("irid_ior", 1.3)
    p["irid_thickness"] = g("irid_thickness", 400.0)
    return p


# KHR_materials_iridescence (its README, "Implementation Notes"): Belcour & Barla's thin-film
# Fresnel term with Schlick reflectances at both interfaces, 0/pi phase shifts, and the
# Airy series' first two interference terms integrated against Gaussian fits of the CIE
# matching functions (evalSensitivity), in linear Rec. 709. A film of no thickness takes
# the outside's index (the glTF sample viewer's smoothstep over 0-0.03 nm); the optical
# path difference is 2 n_film d cos(theta_2), the angle inside the film (Belcour & Barla,
# eq. 2); the result is clamped to [0, 1].
_XYZ_TO_REC709 = ((3.2404542, -1.5371385, -0.4985314),
                  (-0.9692660, 1.8760108, 0.0415560),
                  (0.0556434, -0.2040259, 1.0572252))


def _sensitivity(opd, shift):
    """evalSensitivity: the spectral integral of an interference term, Rec. 709."""
    phase = 2.0 * dr.pi * opd * 1e-9
    val = (5.4856e-13, 4.4201e-13, 5.2481e-13)
    pos = (1.6810e+06, 1.7953e+06, 2.2084e+06)
    var = (4.3278e+09, 9.3046e+09, 6.6121e+09)
    xyz = [val[k] * math.sqrt(2.0 * math.pi * var[k]) * dr.cos(pos[k] * phase + shift[k])
           * dr.exp(-var[k] * phase * phase) for k in range(3)]
    xyz[0] = xyz[0] + (9.7470e-14 * math.sqrt(2.0 * math.pi * 4.5282e+09)
                       * dr.cos(2.2399e+06 * phase + shift[0]) * dr.exp(-4.5282e+09 * phase * phase))
    xyz = [x / 1.0685e-7 for x in xyz]
    return [sum(_XYZ_TO_REC709[r][c] * xyz[c] for c in range(3)) for r in range(3)]


def thin_film(outside, film, thickness, cos1, base_f0):
    """F_iridescence (a Color3f) at cosine cos1 for a base of normal-incidence
    reflectance base_f0 (a 3-tuple of floats)."""
    t = min(max(thickness / 0.03, 0.0), 1.0)
    n2 = outside + (film - outside) * t * t * (3.0 - 2.0 * t)
    sin2_sq = (outside / n2) ** 2 * (1.0 - cos1 * cos1)
    tir = sin2_sq >= 1.0
    cos2 = dr.sqrt(dr.maximum(1.0 - sin2_sq, 0.0))
    schlick = lambda f0, c: f0 + (1.0 - f0) * (1.0 - c) ** 5
    r12 = schlick(((n2 - outside) / (n2 + outside)) ** 2, cos1)
    t121 = 1.0 - r12
    phi21 = math.pi - (math.pi if n2 < outside else 0.0)
    opd = 2.0 * n2 * thickness * cos2
    out = []
    phis, r23s = [], []
    for k in range(3):
        sq = math.sqrt(min(base_f0[k] + 1e-4, 0.9999))
        n3 = (1.0 + sq) / (1.0 - sq)
        r23s.append(schlick(((n3 - n2) / (n3 + n2)) ** 2, cos2))
        phis.append(phi21 + (math.pi if n3 < n2 else 0.0))
    terms = [_sensitivity(m * opd, [m * ph for ph in phis]) for m in (1, 2)]
    for k in range(3):
        r123 = dr.clip(r12 * r23s[k], 1e-5, 0.9999)
        rs = t121 * t121 * r23s[k] / (1.0 - r123)
        i = r12 + rs
        cm = rs - t121
        for m in (1, 2):
            cm = cm * dr.sqrt(r123)
            i = i + cm * 2.0 * terms[m - 1][k]
        out.append(dr.select(tir, 1.0, dr.clip(i, 0.0, 1.0)))
    return mi.Color3f(*out)


def sample_result(wo, sgn, pdf, f, valid, sampled_type):
    """A `sample` method's return: the BSDFSample of local direction `wo` (turned back to
    the side `sgn` the query came from) with density `pdf`, and its weight f / pdf, both
    zero where not `valid`."""
    bs = dr.zeros(mi.BSDFSample3f)
    bs.wo = mi.Vector3f(wo.x, wo.y, wo.z * sgn)
    bs.pdf = dr.select(valid, pdf, 0.0)
    bs.eta = 1.0
    bs.sampled_component = mi.UInt32(0)
    bs.sampled_type = sampled_type
    return (bs, mi.Color3f(dr.select(valid & (pdf > 0), f / pdf, 0.0)))


class GltfBSDF(mi.BSDF):
    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        p = _params(props)
        self.p = p
        self.base = mi.Color3f(*p["base"])
        self.metallic = p["metallic"]
        self.alpha = max(p["roughness"] ** (1 if _DEFECT == "alpha-roughness" else 2), 1e-4)
        self.specular = p["specular"]
        f0_ior = ((1.0 - p["ior"]) / (1.0 + p["ior"])) ** 2
        self.f0d = mi.Color3f(*[min(f0_ior * c, 1.0) * p["specular"] for c in p["spec_color"]])
        self.f90d = p["specular"]
        self.f0d_tuple = tuple(min(f0_ior * c, 1.0) * p["specular"] for c in p["spec_color"])
        self.ps = p["spec_prob"]
        self.irid = p["iridescence"]
        self.irid_outside = 1.0  # the film's outside index (a coat's 1.5 under a coat)
        # KHR_materials_anisotropy: Mitsuba's anisotropic GGX in the frame turned by the
        # rotation (None: isotropic, the formulas below).
        self.distr = None
        if p["anisotropy"] > 0.0:
            a = p["roughness"] ** 2
            at = max(a + (1.0 - a) * p["anisotropy"] ** 2, 1e-4)
            self.distr = mi.MicrofacetDistribution(mi.MicrofacetType.GGX, at, max(a, 1e-4), True)
            self.rot = (math.cos(p["anisotropy_rotation"]), math.sin(p["anisotropy_rotation"]))
        flags = (mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.DiffuseReflection
                 | mi.BSDFFlags.FrontSide | mi.BSDFFlags.BackSide)
        self.m_components = [flags]
        self.m_flags = flags

    # ---- microfacet pieces -------------------------------------------------------
    def D(self, cos_h):
        a2 = self.alpha * self.alpha
        c2 = cos_h * cos_h
        # denominator c2 (a2 - 1) + 1 written as s2 + a2 c2 (no cancellation)
        den = (1.0 - c2) + a2 * c2
        return a2 / (dr.pi * den * den)

    def Vis(self, nl, nv):
        a2 = self.alpha * self.alpha
        if _DEFECT == "separable":  # a defect on purpose: the product of G1s
            return 1.0 / ((nl + dr.sqrt(a2 + (1.0 - a2) * nl * nl)) * (nv + dr.sqrt(a2 + (1.0 - a2) * nv * nv)))
        gv = nl * dr.sqrt(a2 + (1.0 - a2) * nv * nv)
        gl = nv * dr.sqrt(a2 + (1.0 - a2) * nl * nl)
        return dr.select(gv + gl > 0, 0.5 / (gv + gl), 0.0)

    def G1(self, c):
        a2 = self.alpha * self.alpha
        t2 = dr.maximum(1.0 - c * c, 0.0) / dr.maximum(c * c, 1e-12)
        return 2.0 / (1.0 + dr.sqrt(1.0 + a2 * t2))

    def to_anisotropy_frame(self, v):
        """A local vector in the frame whose x is the anisotropy's direction."""
        c, s = self.rot
        return mi.Vector3f(c * v.x + s * v.y, c * v.y - s * v.x, v.z)

    def from_anisotropy_frame(self, v):
        c, s = self.rot
        return mi.Vector3f(c * v.x - s * v.y, s * v.x + c * v.y, v.z)

    def anisotropic_spec(self, wi, wo, h):
        """D·Vis of Mitsuba's anisotropic GGX (wi = V, wo = L, h their half vector)."""
        wi, wo, h = (self.to_anisotropy_frame(v) for v in (wi, wo, h))
        g1i, g1o = self.distr.smith_g1(wi, h), self.distr.smith_g1(wo, h)
        ok = (g1i > 0) & (g1o > 0)
        lam = lambda g: 1.0 / dr.select(ok, g, 1.0) - 1.0
        vis = 1.0 / ((1.0 + lam(g1i) + lam(g1o)) * 4.0 * wi.z * wo.z)
        return dr.select(ok, self.distr.eval(h) * vis, 0.0)

    def fresnel(self, vh, fw):
        """The dielectric's and the metal's Fresnel terms at |V.H| = vh (fw = (1 - vh)^5):
        Schlick's, mixed with the thin film's by the iridescence factor."""
        Fd = self.f0d + (self.f90d - self.f0d) * fw
        Fm = self.base + (1.0 - self.base) * fw
        if self.irid > 0.0:
            p = self.p
            film = lambda f0: thin_film(self.irid_outside, p["irid_ior"], p["irid_thickness"], vh, f0)
            Fd = Fd + (film(self.f0d_tuple) - Fd) * self.irid
            Fm = Fm + (film(tuple(p["base"])) - Fm) * self.irid
        return Fd, Fm

    def brdf(self, wi, wo):
        """f(wi, wo) for wi, wo in the upper local hemisphere (wi = view V, wo = light L)."""
        h = dr.normalize(wi + wo)
        vh = dr.abs(dr.dot(wi, h))
        fw = dr.power(1.0 - vh, 5.0) if hasattr(dr, "power") else (1.0 - vh) ** 5
        if self.distr is not None:
            spec = self.anisotropic_spec(wi, wo, h)
        else:
            spec = self.D(h.z) * self.Vis(wo.z, wi.z)
        Fd, Fm = self.fresnel(vh, fw)
        Fd_max = dr.maximum(dr.maximum(Fd.x, Fd.y), Fd.z)
        dielectric = Fd * spec + (1.0 - Fd_max) * self.base * dr.inv_pi
        metal = Fm * spec
        return (1.0 - self.metallic) * dielectric + self.metallic * metal

    def pdf_local(self, wi, wo):
        h = dr.normalize(wi + wo)
        if self.distr is not None:
            # Mitsuba's visible-normal density of h, reflected.
            hi = dr.dot(wi, h)
            p_spec = dr.select(hi > 0, self.distr.pdf(self.to_anisotropy_frame(wi),
                                                      self.to_anisotropy_frame(h)) / (4.0 * hi), 0.0)
        else:
            p_spec = self.G1(wi.z) * self.D(h.z) / (4.0 * wi.z)  # visible normals, reflected
        p_diff = wo.z * dr.inv_pi
        return self.ps * p_spec + (1.0 - self.ps) * p_diff

    def sample_vndf(self, wi, u):
        if self.distr is not None:
            m, _ = self.distr.sample(self.to_anisotropy_frame(wi), mi.Point2f(u.x, u.y))
            return self.from_anisotropy_frame(m)
        a = self.alpha
        vh = dr.normalize(mi.Vector3f(a * wi.x, a * wi.y, wi.z))
        lensq = vh.x * vh.x + vh.y * vh.y
        inv = dr.rsqrt(dr.maximum(lensq, 1e-30))
        t1 = dr.select(lensq > 0, mi.Vector3f(-vh.y * inv, vh.x * inv, 0.0), mi.Vector3f(1.0, 0.0, 0.0))
        t2 = dr.cross(vh, t1)
        r = dr.sqrt(u.x)
        phi = 2.0 * dr.pi * u.y
        p1 = r * dr.cos(phi)
        p2 = r * dr.sin(phi)
        s = 0.5 * (1.0 + vh.z)
        p2 = (1.0 - s) * dr.sqrt(dr.maximum(1.0 - p1 * p1, 0.0)) + s * p2
        nh = p1 * t1 + p2 * t2 + dr.sqrt(dr.maximum(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh
        return dr.normalize(mi.Vector3f(a * nh.x, a * nh.y, dr.maximum(nh.z, 0.0)))

    # ---- Mitsuba interface --------------------------------------------------------
    def _side(self, si):
        return dr.select(mi.Frame3f.cos_theta(si.wi) < 0, -1.0, 1.0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        sgn = self._side(si)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sgn)
        use_spec = sample1 < self.ps
        h = self.sample_vndf(wi, sample2)
        wo_spec = 2.0 * dr.dot(wi, h) * h - wi
        wo_diff = mi.warp.square_to_cosine_hemisphere(sample2)
        wo = dr.select(use_spec, wo_spec, wo_diff)
        valid = active & (wi.z > 0) & (wo.z > 0)
        pdf = self.pdf_local(wi, wo)
        f = self.brdf(wi, wo) * wo.z
        kind = dr.select(use_spec, mi.UInt32(+mi.BSDFFlags.GlossyReflection),
                         mi.UInt32(+mi.BSDFFlags.DiffuseReflection))
        return sample_result(wo, sgn, pdf, f, valid, kind)

    def _local(self, si, wo):
        sgn = self._side(si)
        wi = mi.Vector3f(si.wi.x, si.wi.y, si.wi.z * sgn)
        wl = mi.Vector3f(wo.x, wo.y, wo.z * sgn)
        return wi, wl, (wi.z > 0) & (wl.z > 0)

    def eval(self, ctx, si, wo, active=True):
        wi, wl, valid = self._local(si, wo)
        return dr.select(active & valid, self.brdf(wi, wl) * wl.z, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        wi, wl, valid = self._local(si, wo)
        return dr.select(active & valid, self.pdf_local(wi, wl), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        wi, wl, valid = self._local(si, wo)
        ok = active & valid
        return (dr.select(ok, self.brdf(wi, wl) * wl.z, 0.0), dr.select(ok, self.pdf_local(wi, wl), 0.0))

    def traverse(self, callback):
        pass

    def parameters_changed(self, keys):
        pass

    def to_string(self):
        return "GltfBSDF[%s]" % self.p


def register():
    mi.register_bsdf("gltf", lambda props: GltfBSDF(props))


def plugin_dict(mat):
    """Mitsuba dict for a glTF material (json dict)."""
    pbr = mat.get("pbrMetallicRoughness", {})
    bc = pbr.get("baseColorFactor", [1, 1, 1, 1])
    ext = mat.get("extensions", {}).get("KHR_materials_specular", {})
    sc = ext.get("specularColorFactor", [1, 1, 1])
    d = {"type": "gltf", "base_r": bc[0], "base_g": bc[1], "base_b": bc[2],
         "metallic": pbr.get("metallicFactor", 1.0), "roughness": pbr.get("roughnessFactor", 1.0),
         "specular": ext.get("specularFactor", 1.0), "spec_r": sc[0], "spec_g": sc[1], "spec_b": sc[2]}
    ior = mat.get("extensions", {}).get("KHR_materials_ior", {}).get("ior")
    if ior is not None:
        d["ior"] = ior
    ir = mat.get("extensions", {}).get("KHR_materials_iridescence", {})
    if ir.get("iridescenceFactor", 0.0) > 0.0:
        d["iridescence"] = min(float(ir["iridescenceFactor"]), 1.0)
        d["irid_ior"] = float(ir.get("iridescenceIor", 1.3))
        # No thickness texture: the maximum.
        d["irid_thickness"] = float(ir.get("iridescenceThicknessMaximum", 400.0))
    an = mat.get("extensions", {}).get("KHR_materials_anisotropy", {})
    if an.get("anisotropyStrength", 0.0) > 0.0:
        d["anisotropy"] = min(float(an["anisotropyStrength"]), 1.0)
        d["anisotropy_rotation"] = float(an.get("anisotropyRotation", 0.0))
    return d


# What a material may hold for `rewrite_export` to write it exactly with the plugin.
_TEXTURES = ("baseColorTexture", "metallicRoughnessTexture")
_UNSUPPORTED_EXTENSIONS = ("KHR_materials_volume",)
# Coats and sheens are written by mitsuba_gltf_layers (factors only), as is thin-walled
# transmission.
_LAYER_TEXTURES = ("clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture",
                   "sheenColorTexture", "sheenRoughnessTexture")


def _gltf_json(path):
    """The JSON of a .gltf or .glb file."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        length = int.from_bytes(data[12:16], "little")
        return json.loads(data[20:20 + length])
    return json.loads(data)


def _refusal(index, mat, wrappers=()):
    """Why material `index` cannot be written exactly by the plugin, or None. `wrappers`:
    the export's BSDFs around the material's own (`normalmap`, `mask`), which carry its
    normal map and alpha."""
    pbr = mat.get("pbrMetallicRoughness", {})
    for t in _TEXTURES:
        if t in pbr:
            return f"material {index} has a {t}"
    if "normalTexture" in mat and "normalmap" not in wrappers:
        return f"material {index} has a normalTexture the export left out"
    ext = mat.get("extensions", {})
    # A solid entered by diffuse transmission alone: the export's interior medium absorbs
    # what the plugin passes through (no refraction to write).
    translucent_solid = (ext.get("KHR_materials_diffuse_transmission", {}).get("diffuseTransmissionFactor", 0.0) > 0
                         and ext.get("KHR_materials_transmission", {}).get("transmissionFactor", 0.0) == 0)
    for e in _UNSUPPORTED_EXTENSIONS:
        if e in ext and not (e == "KHR_materials_volume" and translucent_solid):
            return f"material {index} uses {e}"
    for t in ("diffuseTransmissionTexture", "diffuseTransmissionColorTexture"):
        if t in ext.get("KHR_materials_diffuse_transmission", {}):
            return f"material {index} has a {t}"
    spec = mat.get("extensions", {}).get("KHR_materials_specular", {})
    if "specularTexture" in spec or "specularColorTexture" in spec:
        return f"material {index} has a specular texture"
    if "anisotropyTexture" in mat.get("extensions", {}).get("KHR_materials_anisotropy", {}):
        return f"material {index} has an anisotropyTexture"
    for t in ("iridescenceTexture", "iridescenceThicknessTexture"):
        if t in ext.get("KHR_materials_iridescence", {}):
            return f"material {index} has an {t}"
    for e in ("KHR_materials_clearcoat", "KHR_materials_sheen"):
        for t in _LAYER_TEXTURES:
            if t in mat.get("extensions", {}).get(e, {}):
                return f"material {index} has a {t}"
    if mat.get("alphaMode", "OPAQUE") != "OPAQUE" and "mask" not in wrappers:
        return f"material {index} is not opaque and the export left its alpha out"
    return None


def rewrite_export(export_dir):
    """Writes EXPORT_DIR/scene_gltf.xml: the export's scene.xml with every material's
    BSDF replaced by the plugin, from the glTF file the export was made of (its manifest's
    `scene_path`). Returns the path. Raises ValueError for a material the plugin cannot
    write exactly (textures, vertex colours, solid glass, a normal map or alpha the
    export left out). A BSDF the export wrapped in `normalmap` or `mask` keeps its
    wrappers around the plugin. Coats, sheens, thin-walled transmission and diffuse
    transmission are written by mitsuba_gltf_layers (a solid entered by diffuse
    transmission alone keeps the export's interior medium)."""
    import mitsuba_gltf_layers
    with open(os.path.join(export_dir, "lanterna_export.json")) as f:
        manifest = json.load(f)
    materials = _gltf_json(manifest["scene_path"]).get("materials", [])
    with open(os.path.join(export_dir, "scene.xml")) as f:
        xml = f.read()
    if 'id="bsdf' in xml and "-colors\"" in xml:
        raise ValueError("the export has vertex colours, which the plugin does not read")
    # A top-level BSDF block ends at the first "  </bsdf>" followed by a top-level
    # element (a blendbsdf, thin glass, nests a child at the same indentation). Its id is
    # bsdfK, with a suffix for the mirrored-UV half of a normal-mapped material.
    block = re.compile(r'  <bsdf type="([^"]*)" id="bsdf(\d+)((?:-[a-z]+)*)">.*?\n  </bsdf>\n'
                       r'(?=\s*(?:<!--|<shape|<bsdf type="[^"]*" id=|<emitter|</scene>|<sensor'
                       r'|<integrator|<texture|<medium))', re.S)

    def replace(m):
        kind, k, suffix = m.group(1), int(m.group(2)), m.group(3)
        # One past the file's materials is lanterna's default material (the glTF one).
        mat = materials[k] if k < len(materials) else {}
        lines = m.group(0).splitlines(keepends=True)
        # The export's wrappers (mask, then normalmap) come first, each closed by one
        # "  </bsdf>" line at the block's end; inside them the material's own two-sided
        # BSDF, which the plugin replaces.
        wrappers = [re.match(r'  <bsdf type="([a-z]+)"', line).group(1) for line in lines
                    if re.match(r'  <bsdf type="(mask|normalmap)"', line)]
        if wrappers and wrappers[0] != kind:
            raise ValueError(f"material {k}: unexpected BSDF nesting in the export")
        why = _refusal(k, mat, wrappers)
        if why:
            raise ValueError(why)
        params = mitsuba_gltf_layers.plugin_dict(mat)
        if "anisotropy_rotation" in params and "mirrored" in suffix:
            # Where the UVs appear mirrored lanterna's bitangent is −cross(n, ∂P/∂u) and
            # Mitsuba's +cross(n, ∂P/∂u): the direction (cos r, sin r) is (cos r, −sin r).
            params["anisotropy_rotation"] = -params["anisotropy_rotation"]
        body = "".join(f'    <float name="{name}" value="{value!r}"/>\n'
                       for name, value in params.items() if name != "type")
        if not wrappers:
            return f'  <bsdf type="{params["type"]}" id="bsdf{k}{suffix}">\n{body}  </bsdf>\n'
        start = next(i for i, line in enumerate(lines)
                     if line.startswith('  <bsdf type="twosided">'))
        inner = f'  <bsdf type="{params["type"]}">\n{body}  </bsdf>\n'
        return "".join(lines[:start]) + inner + "".join(lines[len(lines) - len(wrappers):])

    out, n = block.subn(replace, xml)
    if n == 0:
        raise ValueError(f"{export_dir}: no material BSDFs found in scene.xml")
    # Every material's BSDF must have been rewritten (wrappers keep their type, with the
    # plugin inside): one the pattern missed would stay the export's approximation while
    # the comparison calls it exact.
    missed = [i for kind, i in re.findall(r'^  <bsdf type="([^"]*)" id="(bsdf\d+(?:-[a-z]+)*)">', out, re.M)
              if not kind.startswith("gltf") and kind not in ("mask", "normalmap")]
    if missed:
        raise ValueError(f"{export_dir}: scene.xml's BSDFs {', '.join(missed)} were not rewritten")
    path = os.path.join(export_dir, "scene_gltf.xml")
    with open(path, "w") as f:
        f.write(out)
    return path
