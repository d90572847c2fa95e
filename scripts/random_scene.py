#!/usr/bin/env python3
"""Random Lambertian glTF scenes for checking lanterna against Mitsuba 3 on scenes that
nobody designed.

Each seed gives a room (floor, back wall, some of the ceiling and side walls), a group of
boxes under a rotated, non-uniformly scaled parent node (some mirrored by a negative
scale), emissive quads in the air and flush on the back wall (1 mm in front of it) and
small emissive boxes, of sizes from 2 cm to 1 m, one- or two-sided, with the glTF
default white base colour, a random one or a dark one, emissive strengths from 1 to
100, up to three point and spot lights, and a camera looking into the room. Every
material is Lambertian (metallic 0, KHR_materials_specular 0), so
`lanterna scene export-mitsuba` is exact and Mitsuba's `path` must agree with every
method up to noise:

    python3 scripts/random_scene.py 7 -o r7.gltf
    lanterna scene export-mitsuba r7.gltf -o r7_mitsuba --width 64 --height 48
    python3 scripts/mitsuba_compare.py r7_mitsuba --lanterna target/release/lanterna \\
        --method ris --batches 8 --spp 512 --runs 16 --json r7_ris.json

Give Mitsuba 64 runs (`--runs 64`, about 0.2 s each at 48×36) where the scene is dark or
has glass: with 16, its rare bright samples leave most of its runs low in the dark pixels
and the pixel test rejects methods that have fewer such samples (README, "Random scenes").
The skew can be lanterna's too: when most rejected pixels are darker in lanterna while
the image mean is not, eight batches miss lanterna's own rare paths (through glass),
and more samples per lanterna batch (`--spp`) cure it where more Mitsuba runs make it
worse.

`--materials` widens the material mix where the export stays exact: sRGB base colour
textures (nearest and bilinear, on the walls, the floor and some boxes), emissive
textures, vertex colours, solid glass boxes (KHR_materials_volume: smooth and rough,
indices 1.1-2.0, tinted, some absorbing, some mirrored), and thin panes without
Fresnel reflection (specularFactor 0) that pass part of the light straight through. A
scene with panes gets no point or spot lights: seen through smooth thin glass they
differ by design (lanterna's smooth glass is a GGX lobe of α = 10⁻⁴, Mitsuba's a
delta), and the export would say it is approximate.

`--normal-maps` puts random tangent-space normal maps (tilts up to 35°, scales 0.3-1) on
about half of the opaque Lambertian materials with texture coordinates (walls and the
box group then carry UVs; the scene is otherwise the seed's). The export writes them as
Mitsuba's `normalmap` and marks the scene approximate for one reason only: a texel seen
from below its mapped normal reflects in lanterna and not in Mitsuba (README, shading
normals).

`--anisotropy` makes about half of the opaque Lambertian materials with texture
coordinates (walls and the box group then carry UVs) glossy metals or plastics with
KHR_materials_anisotropy (factors only), which `mitsuba_compare.py --gltf-bsdf` renders
exactly through the glTF BSDF plugin (Mitsuba's own anisotropic GGX). Don't combine it
with `--materials` there: the plugin refuses textures.

`--diffuse-transmission` makes about half of the opaque Lambertian materials diffusely
transmitting (KHR_materials_diffuse_transmission, factors only), half of those with a
specular lobe too, which `mitsuba_compare.py --gltf-bsdf` renders exactly through the
glTF BSDF plugin. Don't combine it with `--materials` there either.

`--iridescence` gives about half of the opaque Lambertian materials a thin film
(KHR_materials_iridescence, factors only: weight 0.3-1, index 1.2-2, 100-800 nm) and a
specular lobe (roughness 0.1-0.7), a third of them metals, which `mitsuba_compare.py
--gltf-bsdf` renders exactly through the glTF BSDF plugin. Not with `--materials` there.

`--layers` makes about half of the opaque Lambertian materials glossy metals, plastics or
something between (metallic 0-1, roughness 0.02-0.8), the dielectric ones with
KHR_materials_specular and KHR_materials_ior, about half with KHR_materials_clearcoat and
a third with KHR_materials_sheen (factors only), which `mitsuba_compare.py --gltf-bsdf`
renders exactly through the glTF BSDF plugin and its layers. Not with `--materials`
there.

`--dispersion` (with `--materials`) gives about two thirds of the solid glass boxes
KHR_materials_dispersion (0.5-8: Abbe numbers 40 down to 2.5), which the export writes
exactly as three `roughdielectric`s, one per colour channel.

`--alpha` makes about half of the opaque non-emissive Lambertian materials BLEND (alpha
0.2-0.9) or MASK (a nearest RGBA texture where the mesh has UVs, else a constant alpha
either side of the cutoff), which the export writes exactly as Mitsuba's `mask` under
`volpath`.

`--unlit` makes about half of the untextured emitters KHR_materials_unlit (base colour
0.3-1) with random vertex colours (float RGB or normalised 16-bit RGBA with alpha 1),
which tint what they emit. The export writes them exactly, their radiance a
`mesh_attribute` that Mitsuba finds by BSDF sampling alone (its emitter sampling reads
no attribute): give Mitsuba more samples (`--mitsuba-spp`).

Emissive boxes are closed and one-sided unless `--two-sided-boxes`: Mitsuba 3 stops
shadow rays 8.9e-4 of their length short of the light, which lets light emitted inside
a small two-sided box out near its edges (a 2 cm box 2-3 m away: +9 %), so its
references of such scenes are too bright (README, "Shadow rays").

Exit status 0, or 2 on bad arguments.
"""

import argparse
import math
import os
import random
import sys

# The glTF writer of the Mitsuba peer scenes (tests/data/mitsuba/make_scenes.py).
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests",
                                "data", "mitsuba"))
from make_scenes import Builder, look_at_rotation, png_rgb, png_rgba  # noqa: E402

UNIT_QUAD = ((-0.5, -0.5, 0.0), (0.5, -0.5, 0.0), (0.5, 0.5, 0.0), (-0.5, 0.5, 0.0))  # faces +z


def quat(axis, angle):
    n = math.sqrt(sum(a * a for a in axis)) or 1.0
    s = math.sin(angle / 2) / n
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)]


def material(b, base, emission=None, strength=None, two_sided=False):
    """A Lambertian material; `base` None leaves out the base colour (glTF's default white)."""
    m = b.lambert(base or (1.0, 1.0, 1.0), emission, strength, two_sided)
    if base is None:
        del b.materials[m]["pbrMetallicRoughness"]["baseColorFactor"]
    return m


def random_texture(r, s):
    """A random sRGB texture of 2-8 texels a side, nearest or bilinear."""
    w, h = r.randint(2, 8), r.randint(2, 8)
    pixels = [[tuple(r.randrange(256) for _ in range(3)) for _ in range(w)] for _ in range(h)]
    return s.texture(png_rgb(w, h, pixels), nearest=r.random() < 0.5)


def textured(r, s, lo, hi):
    """A Lambertian material whose base colour is a random texture times a factor."""
    m = s.lambert(rgb_of(r, lo, hi), base_tex=random_texture(r, s))
    return m


def rgb_of(r, lo, hi):
    return [r.uniform(lo, hi) for _ in range(3)]


def solid_glass(r, s, absorbing):
    """A glass solid's boundary: smooth or rough, tinted, some absorbing if `absorbing`."""
    rough = r.choice([0.0, 0.0, r.uniform(0.1, 0.6)])
    att = ((rgb_of(r, 0.3, 1.0), r.uniform(0.3, 2.0)) if absorbing and r.random() < 0.5 else None)
    return s.solid_glass(rgb_of(r, 0.6, 1.0), rough, r.uniform(1.1, 2.0), attenuation=att)


def random_normal_map(r, s, max_tilt):
    """A random tangent-space normal map of 2-8 texels a side (8-bit, linear), its texels
    tilted by up to max_tilt radians in random directions, nearest or bilinear."""
    w, h = r.randint(2, 8), r.randint(2, 8)

    def texel():
        tilt, phi = r.uniform(0, max_tilt), r.uniform(0, 2 * math.pi)
        n = (math.sin(tilt) * math.cos(phi), math.sin(tilt) * math.sin(phi), math.cos(tilt))
        return tuple(round((c + 1) / 2 * 255) for c in n)

    return s.texture(png_rgb(w, h, [[texel() for _ in range(w)] for _ in range(h)]),
                     nearest=r.random() < 0.5)


def opaque_lambertian_materials(s):
    """The non-emissive, non-transmitting Lambertian materials the meshes use, each with
    whether every primitive of it has texture coordinates."""
    uvs = {}
    for mesh in s.meshes:
        for prim in mesh["primitives"]:
            m = s.materials[prim["material"]]
            lambertian = (m.get("extensions", {}).get("KHR_materials_specular", {})
                          .get("specularFactor") == 0 and "emissiveFactor" not in m
                          and "KHR_materials_transmission" not in m.get("extensions", {}))
            if lambertian:
                has_uv = "TEXCOORD_0" in prim["attributes"]
                uvs[prim["material"]] = uvs.get(prim["material"], True) and has_uv
    return uvs


def about_half_of_the_matte(s, seed):
    """(generator, material) for about half of the opaque Lambertian materials, drawn
    with a generator seeded by `seed` that the caller goes on drawing from."""
    r = random.Random(seed)
    for index in sorted(opaque_lambertian_materials(s)):
        if r.random() < 0.5:
            yield r, s.materials[index]


def listed_if_used(s, extension, count):
    """Lists `extension` in the file's extensionsUsed (once) when `count` materials use it;
    returns `count`."""
    if count and extension not in s.used:
        s.used.append(extension)
    return count


def add_normal_maps(s, seed):
    """Normal maps (tilts up to 35°, scales 0.3-1) on about half of the opaque Lambertian
    materials of meshes with texture coordinates, drawn from a generator of their own so
    that the scene is otherwise the one the seed gives without them."""
    r = random.Random(seed + 1_000_003)
    count = 0
    for index, has_uv in sorted(opaque_lambertian_materials(s).items()):
        if has_uv and r.random() < 0.5:
            s.materials[index]["normalTexture"] = {"index": random_normal_map(r, s, math.radians(35)),
                                                   "scale": r.uniform(0.3, 1.0)}
            count += 1
    return count


def add_alpha(s, seed):
    """Alpha on about half of the opaque non-emissive Lambertian materials: BLEND with an
    alpha factor of 0.2-0.9, or MASK cut by a nearest RGBA texture of 2-6 texels a side
    (alphas 0-255, cutoff 0.2-0.8; the texture replaces the base colour's) where the mesh
    has UVs, else a constant MASK above or below its cutoff. Drawn from a generator of
    their own, so that the scene is otherwise the one the seed gives without them."""
    r = random.Random(seed + 2_000_003)
    uv_of = opaque_lambertian_materials(s)
    kinds = []
    for index in sorted(uv_of):
        if r.random() >= 0.5:
            continue
        m = s.materials[index]
        pbr = m.setdefault("pbrMetallicRoughness", {})
        factor = pbr.setdefault("baseColorFactor", [1.0, 1.0, 1.0, 1.0])
        kind = r.choice(["BLEND", "MASK"])
        m["alphaMode"] = kind
        if kind == "BLEND":
            factor[3] = r.uniform(0.2, 0.9)
        elif uv_of[index]:
            m["alphaCutoff"] = r.uniform(0.2, 0.8)
            w, h = r.randint(2, 6), r.randint(2, 6)
            px = [[tuple(r.randrange(256) for _ in range(4)) for _ in range(w)] for _ in range(h)]
            pbr["baseColorTexture"] = {"index": s.texture(png_rgba(w, h, px), nearest=True)}
        else:
            m["alphaCutoff"] = r.uniform(0.2, 0.8)
            factor[3] = r.choice([0.1, 0.95])
        kinds.append(kind)
    return kinds


def add_anisotropy(s, seed):
    """KHR_materials_anisotropy on about half of the opaque Lambertian materials of meshes
    with texture coordinates (factors only): each becomes a glossy metal or plastic
    (roughness 0.05-0.5) stretched by a strength of 0.3-1 at a rotation of 0-2π. Drawn
    from a generator of their own, so that the scene is otherwise the one the seed gives
    without them."""
    r = random.Random(seed + 3_000_003)
    count = 0
    for index, has_uv in sorted(opaque_lambertian_materials(s).items()):
        if not has_uv or r.random() >= 0.5:
            continue
        m = s.materials[index]
        pbr = m.setdefault("pbrMetallicRoughness", {})
        metal = r.random() < 0.5
        pbr["metallicFactor"] = 1.0 if metal else 0.0
        pbr["roughnessFactor"] = r.uniform(0.05, 0.5)
        if metal:
            pbr["baseColorFactor"] = rgb_of(r, 0.5, 1.0) + [1.0]
        m["extensions"].pop("KHR_materials_specular", None)
        m["extensions"]["KHR_materials_anisotropy"] = {
            "anisotropyStrength": r.uniform(0.3, 1.0),
            "anisotropyRotation": r.uniform(0.0, 2 * math.pi)}
        count += 1
    return listed_if_used(s, "KHR_materials_anisotropy", count)


def add_diffuse_transmission(s, seed):
    """KHR_materials_diffuse_transmission on about half of the opaque Lambertian
    materials (factors only: a share of 0.2-1 in a colour of 0.3-1), half of them given
    a specular lobe too (roughness 0.2-1). Drawn from a generator of their own, so that
    the scene is otherwise the one the seed gives without them."""
    count = 0
    for r, m in about_half_of_the_matte(s, seed + 4_000_003):
        if r.random() < 0.5:
            m["extensions"].pop("KHR_materials_specular", None)
            m.setdefault("pbrMetallicRoughness", {})["roughnessFactor"] = r.uniform(0.2, 1.0)
        m["extensions"]["KHR_materials_diffuse_transmission"] = {
            "diffuseTransmissionFactor": r.uniform(0.2, 1.0),
            "diffuseTransmissionColorFactor": rgb_of(r, 0.3, 1.0)}
        count += 1
    return listed_if_used(s, "KHR_materials_diffuse_transmission", count)


def add_iridescence(s, seed):
    """KHR_materials_iridescence on about half of the opaque Lambertian materials
    (factors only: weight 0.3-1, film index 1.2-2, thickness 100-800 nm), each given a
    specular lobe (roughness 0.1-0.7) and a third of them made metals (base colour
    0.5-1). Drawn from a generator of their own, so that the scene is otherwise the one
    the seed gives without them."""
    count = 0
    for r, m in about_half_of_the_matte(s, seed + 5_000_003):
        pbr = m.setdefault("pbrMetallicRoughness", {})
        m["extensions"].pop("KHR_materials_specular", None)
        pbr["roughnessFactor"] = r.uniform(0.1, 0.7)
        if r.random() < 1 / 3:
            pbr["metallicFactor"] = 1.0
            pbr["baseColorFactor"] = rgb_of(r, 0.5, 1.0) + [1.0]
        m["extensions"]["KHR_materials_iridescence"] = {
            "iridescenceFactor": r.uniform(0.3, 1.0),
            "iridescenceIor": r.uniform(1.2, 2.0),
            "iridescenceThicknessMaximum": r.uniform(100.0, 800.0)}
        count += 1
    return listed_if_used(s, "KHR_materials_iridescence", count)


def add_layers(s, seed):
    """Glossy metallic-roughness materials with their layers on about half of the opaque
    Lambertian materials (factors only): metallic 0, 1 or between, roughness 0.02-0.8
    (a quarter of them below 0.1), KHR_materials_specular (factor 0.3-1, a colour of
    0.5-1) and KHR_materials_ior (1.2-2.4) on dielectric ones, KHR_materials_clearcoat
    (factor 0.3-1, roughness 0-0.5) on about half and KHR_materials_sheen (a colour of
    0.2-1, roughness 0.1-1) on about a third, which `mitsuba_compare.py --gltf-bsdf`
    renders exactly through the glTF BSDF plugin and its layers. Drawn from a generator
    of their own, so that the scene is otherwise the one the seed gives without them."""
    count = 0
    for r, m in about_half_of_the_matte(s, seed + 6_000_003):
        pbr = m.setdefault("pbrMetallicRoughness", {})
        ext = m["extensions"]
        ext.pop("KHR_materials_specular", None)
        metallic = r.choice([0.0, 0.0, 1.0, r.uniform(0.0, 1.0)])
        pbr["metallicFactor"] = metallic
        pbr["roughnessFactor"] = (r.uniform(0.02, 0.1) if r.random() < 0.25
                                  else r.uniform(0.1, 0.8))
        if metallic > 0.0:
            pbr["baseColorFactor"] = rgb_of(r, 0.4, 1.0) + [1.0]
        if metallic < 1.0:
            if r.random() < 0.5:
                ext["KHR_materials_specular"] = {"specularFactor": r.uniform(0.3, 1.0),
                                                 "specularColorFactor": rgb_of(r, 0.5, 1.0)}
            if r.random() < 0.5:
                ext["KHR_materials_ior"] = {"ior": r.uniform(1.2, 2.4)}
        if r.random() < 0.5:
            ext["KHR_materials_clearcoat"] = {"clearcoatFactor": r.uniform(0.3, 1.0),
                                              "clearcoatRoughnessFactor": r.uniform(0.0, 0.5)}
        if r.random() < 1 / 3:
            ext["KHR_materials_sheen"] = {"sheenColorFactor": rgb_of(r, 0.2, 1.0),
                                          "sheenRoughnessFactor": r.uniform(0.1, 1.0)}
        count += 1
    s.uses(*(e for e in ("KHR_materials_ior", "KHR_materials_clearcoat", "KHR_materials_sheen")
             if any(e in m.get("extensions", {}) for m in s.materials)))
    return count


def add_dispersion(s, seed):
    """KHR_materials_dispersion (0.5-8) on about two thirds of the solid glass materials,
    drawn from a generator of their own, so that the scene is otherwise the seed's."""
    r = random.Random(seed + 7_000_003)
    used = sorted({prim["material"] for mesh in s.meshes for prim in mesh["primitives"]})
    count = 0
    for m in (s.materials[i] for i in used):
        ext = m.get("extensions", {})
        if "KHR_materials_volume" in ext and r.random() < 2 / 3:
            ext["KHR_materials_dispersion"] = {"dispersion": r.uniform(0.5, 8.0)}
            count += 1
    return listed_if_used(s, "KHR_materials_dispersion", count)


def add_unlit(s, seed):
    """KHR_materials_unlit with random vertex colours on about half of the untextured
    emitters' primitives, drawn from a generator of their own, so that the scene is
    otherwise the seed's. Each takes a material of its own (base colour 0.3-1, the
    emitter's sidedness kept) and COLOR_0 per vertex: float RGB or normalised 16-bit
    RGBA with alpha 1."""
    import struct
    r = random.Random(seed + 8_000_003)
    count = 0
    for mesh in s.meshes:
        for prim in mesh["primitives"]:
            m = s.materials[prim["material"]]
            if "emissiveFactor" not in m or "emissiveTexture" in m or r.random() >= 0.5:
                continue
            unlit = {"pbrMetallicRoughness": {"baseColorFactor": [r.uniform(0.3, 1.0) for _ in range(3)] + [1]},
                     "extensions": {"KHR_materials_unlit": {}}}
            if m.get("doubleSided"):
                unlit["doubleSided"] = True
            s.materials.append(unlit)
            prim["material"] = len(s.materials) - 1
            n = s.accessors[prim["attributes"]["POSITION"]]["count"]
            if r.random() < 0.5:
                colours = [[r.random() for _ in range(3)] for _ in range(n)]
                data = b"".join(struct.pack("<3f", *c) for c in colours)
                prim["attributes"]["COLOR_0"] = s._acc(data, 5126, n, "VEC3")
            else:
                colours = [[r.random() for _ in range(3)] + [1.0] for _ in range(n)]
                data = b"".join(struct.pack("<4H", *(round(65535 * v) for v in c)) for c in colours)
                prim["attributes"]["COLOR_0"] = s._acc(data, 5123, n, "VEC4", normalized=True)
            count += 1
    return listed_if_used(s, "KHR_materials_unlit", count)


def generate(seed, two_sided_boxes, materials=False, normal_maps=False, alpha=False,
             anisotropy=False, diffuse_transmission=False, iridescence=False,
             layers=False, dispersion=False, unlit=False):
    r = random.Random(seed)
    s = Builder()
    rgb = lambda lo, hi: [r.uniform(lo, hi) for _ in range(3)]  # noqa: E731
    room = r.uniform(3.0, 6.0)
    absorbing = materials and r.random() < 0.5
    wall_material = (lambda: textured(r, s, 0.4, 1.0) if materials and r.random() < 0.5
                     else material(s, rgb(0.2, 0.9)))
    with_uvs = materials or normal_maps or anisotropy
    walls = [s.quad(*UNIT_QUAD, wall_material(), uv=with_uvs) for _ in range(3)]
    for k, (t, q) in enumerate([
            ([0, 0, 0], quat([1, 0, 0], -math.pi / 2)),  # floor, facing +y
            ([0, room, 0], quat([1, 0, 0], math.pi / 2)),  # ceiling, facing −y
            ([0, room / 2, -room / 2], [0, 0, 0, 1]),  # back wall, facing +z
            ([-room / 2, room / 2, 0], quat([0, 1, 0], math.pi / 2)),
            ([room / 2, room / 2, 0], quat([0, 1, 0], -math.pi / 2))]):
        if k in (0, 2) or r.random() >= 0.25:
            s.node(mesh=walls[k % 3], translation=t, rotation=q, scale=[room, room, 1])
    boxes = []
    for _ in range(r.randint(2, 5)):
        scale = [r.uniform(0.2, 1.0) for _ in range(3)]
        if r.random() < 0.3:
            scale[r.randrange(3)] *= -1  # mirrored: the winding flips
        m = material(s, rgb(0.1, 0.9))
        if materials:
            m = r.choice([m, solid_glass(r, s, absorbing), solid_glass(r, s, absorbing),
                          textured(r, s, 0.3, 1.0)])
        boxes.append(s.node(root=False, mesh=box(s, m, textured=with_uvs),
                            translation=[r.uniform(-1.5, 1.5), r.uniform(0.2, 1.2), r.uniform(-1.5, 1.0)],
                            rotation=quat(rgb(-1, 1), r.uniform(0, 2 * math.pi)), scale=scale))
    s.node(children=boxes, rotation=quat([0, 1, 0], r.uniform(0, 2 * math.pi)),
           scale=[r.uniform(0.7, 1.3) for _ in range(3)])
    kinds = []
    panes = 0
    if materials:
        for _ in range(r.randint(0, 3)):
            # A thin pane (no Fresnel reflection): part passes straight through, tinted.
            pane = s.glass(rgb(0.3, 1.0), r.uniform(0.3, 1.0))
            s.node(mesh=s.quad(*UNIT_QUAD, pane, uv=False),
                   translation=[r.uniform(-1.5, 1.5), r.uniform(0.3, room - 0.3), r.uniform(-1.5, 1.0)],
                   rotation=quat(rgb(-1, 1), r.uniform(0, 2 * math.pi)),
                   scale=[r.uniform(0.3, 1.5), r.uniform(0.3, 1.5), 1])
            kinds.append("pane")
        panes = kinds.count("pane")
        # A quad with vertex colours (base colour factor × COLOR_0).
        cols = [rgb(0.0, 1.0) for _ in range(4)]
        q = s.mesh([list(p) for p in UNIT_QUAD], [0, 1, 2, 0, 2, 3], material(s, rgb(0.5, 1.0)),
                   [[0, 0, 1]] * 4, None, cols)
        s.node(mesh=q, translation=[r.uniform(-1.5, 1.5), r.uniform(0.3, 1.5), r.uniform(-1.5, 1.0)],
               rotation=quat(rgb(-1, 1), r.uniform(0, 2 * math.pi)), scale=[1.0, 1.0, 1])
        kinds.append("vertex colours")
    for _ in range(r.randint(3, 9)):
        kind = r.choice(["quad", "quad", "wall", "box"])
        two = r.random() < 0.4 and (kind != "box" or two_sided_boxes)
        base = r.choice([None, None, rgb(0.0, 1.0), [0.1, 0.1, 0.1]])
        m = material(s, base, rgb(0.2, 1.0), 10 ** r.uniform(0, 2), two)
        glow = materials and kind != "box" and r.random() < 0.4
        if glow:
            # An emissive texture (emissive factor × texture), the base colour a texture too.
            m = s.lambert(rgb(0.0, 1.0), rgb(0.2, 1.0), 10 ** r.uniform(0, 2), two,
                          base_tex=random_texture(r, s), emissive_tex=random_texture(r, s))
        size = 10 ** r.uniform(-1.7, 0)
        at = [r.uniform(-1.5, 1.5), r.uniform(0.3, room - 0.3), r.uniform(-1.5, 1.5)]
        if kind == "box":
            s.node(mesh=s.box(m), translation=at,
                   rotation=quat(rgb(-1, 1), r.uniform(0, 2 * math.pi)),
                   scale=[size, size * r.uniform(0.3, 1), size])
        elif kind == "wall":
            at[2] = -room / 2 + 0.001
            s.node(mesh=s.quad(*UNIT_QUAD, m, uv=glow), translation=at,
                   scale=[size, size * r.uniform(0.2, 1), 1])
        else:
            s.node(mesh=s.quad(*UNIT_QUAD, m, uv=glow), translation=at,
                   rotation=quat(rgb(-1, 1), r.uniform(0, 2 * math.pi)),
                   scale=[size, size * r.uniform(0.2, 1), 1])
        kinds.append(kind + (" two-sided" if two else "") + (" textured" if glow else ""))
    # No point or spot lights with thin panes: seen through smooth thin glass they differ
    # by design (lanterna's smooth glass is a GGX lobe of α = 1e-4; the export says so).
    for _ in range(0 if panes else r.randint(0, 3)):
        light = {"type": r.choice(["point", "spot"]), "color": rgb(0.3, 1.0),
                 "intensity": 10 ** r.uniform(-0.5, 1)}
        if light["type"] == "spot":
            outer = r.uniform(0.3, 1.2)
            light["spot"] = {"innerConeAngle": outer * r.uniform(0, 0.9), "outerConeAngle": outer}
        kinds.append(light["type"])
        s.node(extensions={"KHR_lights_punctual": {"light": s.light(**light)}},
               translation=[r.uniform(-1.5, 1.5), r.uniform(0.3, room - 0.3), r.uniform(-1.5, 1.5)],
               rotation=quat([1, 0, 0], -r.uniform(0.3, 1.5)))
    eye = [r.uniform(-1, 1), r.uniform(0.8, 2.0), room / 2 - 0.2]
    target = [r.uniform(-0.5, 0.5), r.uniform(0.3, 1.0), -0.5]
    s.node(camera=s.camera(yfov=r.uniform(0.6, 1.3), aspect=4 / 3), translation=eye,
           rotation=look_at_rotation(eye, target))
    if normal_maps:
        kinds.append(f"{add_normal_maps(s, seed)} normal-mapped materials")
    if alpha:
        alphas = add_alpha(s, seed)
        kinds.append(f"alpha: {', '.join(alphas) or 'none'}")
    if anisotropy:
        kinds.append(f"{add_anisotropy(s, seed)} anisotropic materials")
    if diffuse_transmission:
        kinds.append(f"{add_diffuse_transmission(s, seed)} diffusely transmitting materials")
    if iridescence:
        kinds.append(f"{add_iridescence(s, seed)} iridescent materials")
    if layers:
        kinds.append(f"{add_layers(s, seed)} glossy layered materials")
    if dispersion:
        kinds.append(f"{add_dispersion(s, seed)} dispersive glass materials")
    if unlit:
        kinds.append(f"{add_unlit(s, seed)} unlit vertex-coloured emitters")
    return s, kinds


def box(s, m, textured):
    """The unit cube; with `textured`, each face carries uv (0,0)-(1,1) for its texture."""
    return s.box(m, uv=textured)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("seed", type=int)
    ap.add_argument("-o", "--output", required=True, help="the .gltf to write")
    ap.add_argument("--materials", action="store_true",
                    help="textures, vertex colours, solid glass boxes and thin panes too")
    ap.add_argument("--normal-maps", action="store_true",
                    help="normal maps on about half of the opaque Lambertian materials with UVs")
    ap.add_argument("--alpha", action="store_true",
                    help="alpha BLEND or MASK on about half of the opaque Lambertian materials")
    ap.add_argument("--anisotropy", action="store_true",
                    help="anisotropic glossy metals and plastics on about half of the opaque "
                    "Lambertian materials with UVs")
    ap.add_argument("--diffuse-transmission", action="store_true",
                    help="diffuse transmission on about half of the opaque Lambertian "
                    "materials, half of them glossy too")
    ap.add_argument("--iridescence", action="store_true",
                    help="thin films on about half of the opaque Lambertian materials, "
                    "made glossy (a third of them metals)")
    ap.add_argument("--layers", action="store_true",
                    help="glossy metals and plastics with specular, ior, clearcoat and sheen "
                    "on about half of the opaque Lambertian materials")
    ap.add_argument("--dispersion", action="store_true",
                    help="dispersion on about two thirds of the solid glass boxes "
                    "(with --materials)")
    ap.add_argument("--unlit", action="store_true",
                    help="unlit vertex-coloured materials on about half of the untextured emitters")
    ap.add_argument("--two-sided-boxes", action="store_true",
                    help="let emissive boxes be two-sided too (Mitsuba's references leak there)")
    a = ap.parse_args()
    scene, kinds = generate(a.seed, a.two_sided_boxes, a.materials, a.normal_maps, a.alpha,
                            a.anisotropy, a.diffuse_transmission, a.iridescence, a.layers,
                            a.dispersion, a.unlit)
    scene.write(os.path.abspath(a.output))  # an absolute name: not next to make_scenes.py
    print(f"{a.output}: {', '.join(kinds)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
