#!/usr/bin/env python3
"""Writes the tiny single-file glTF scenes of the Mitsuba peer check (tests/data/mitsuba):
each covers conventions the exporter must map exactly, with Lambertian materials
(metallic 0, KHR_materials_specular specularFactor 0) so lanterna and Mitsuba 3 must
agree up to noise.

  tex.gltf        textured diffuse floor (sRGB PNG, 4 coloured quadrants, nearest and
                  bilinear), an emissive-textured panel (emissive strength 3, so its
                  texture goes out as linear PFM), a 4:3 camera (vertical fov)
  tex16.gltf      tex.gltf's layout with 16-bit sRGB PNGs (floor, wall, emitter) whose
                  samples lie between 8-bit codes, plus a point light
  normal_map.gltf  Lambertian floor and wall with tangent-space normal maps (tilts up
                  to 25°, bilinear and nearest, scale 0.5), the floor under a mirroring
                  node, the wall's right half with its u running backward; an area light
                  and two point lights; the camera sees every texel from well above its
                  mapped normal
  normal_map_glossy.gltf  the same with a rough gold metal floor and a glossy plastic
                  wall (checked through the glTF BSDF plugin)
  anisotropy.gltf  KHR_materials_anisotropy: a brushed gold floor under a mirroring
                  node, a stretched blue plastic wall with a mirror seam and a rotated
                  brushed steel box, lit by two point lights and a small lamp (checked
                  through the glTF BSDF plugin)
  diffuse_transmission.gltf  KHR_materials_diffuse_transmission: a paper shade (no
                  specular lobe) around a small lamp, a glossy green leaf panel lit from
                  behind by a point light, and a block of wax (KHR_materials_volume,
                  absorbing) that light enters diffusely, 5 cm above the floor (a face
                  in the floor's plane would leave to each renderer which of the two a
                  ray meets), under a ceiling lamp (checked through the glTF BSDF plugin)
  iridescence.gltf  KHR_materials_iridescence: a dark glossy floor under a soap-like
                  film (index 1.33, 380 nm), a metal wall under a film (index 1.8, 450 nm,
                  factor 0.8) that mirrors a white wall lit behind the camera, a coated box whose film (index 1.3, 300 nm) lies
                  under the coat's 1.5 (phase shift and total internal reflection in the
                  film), and a thin rough pane that transmits (film 1.4, 500 nm) in
                  front of a point light, under a ceiling lamp (checked through the glTF
                  BSDF plugin)
  alpha.gltf      alpha between a lamp and a floor: a fence cut out (MASK) by a
                  nearest RGBA texture, a BLEND panel whose alpha runs across a bilinear
                  texture (times 0.8), a constant BLEND of 0.4, a MASK under its cutoff
                  and a one-sided emitter under a constant BLEND of 0.5
  twosided.gltf   a double-sided emitter standing in a room seen edge-on, and a
                  one-sided emitter facing away from the camera
  punctual.gltf   point, spot (penumbra), hard spot and directional lights on a floor
                  and a back wall
  hierarchy.gltf  nested rotated and scaled nodes, a mirrored (negative determinant)
                  emissive one-sided quad and box, a perspective and an orthographic camera
  texxform.gltf   floor and emissive panel textured with black/white texels (exact in
                  any sRGB decoder) for texture-transform checks
  smooth.gltf     a coarse sphere with smooth vertex normals (approximate export)
  colors.gltf     COLOR_0 vertex colours (float RGB on the floor, normalised 16-bit RGBA
                  times a base colour factor on the wall, a box of the wall's material
                  without colours, colours on an emitter, which they must not tint)
  unlit_colors.gltf  KHR_materials_unlit with vertex colours, which tint what it emits:
                  a ceiling panel (float RGB corners) lighting a floor and a wall, and a
                  box on the floor (normalised 16-bit RGBA, a colour per corner of each
                  face) seen directly, beside a small ordinary lamp
  quantized.gltf  smooth.gltf with KHR_mesh_quantization (required): the sphere's
                  positions and normals as normalised shorts, the floor and wall as
                  unnormalised unsigned bytes scaled by their nodes, their texture
                  coordinates as normalised unsigned bytes; must load as smooth.gltf does
  ies.gltf        EXT_lights_ies: a round downlight (0–90°, its profile in a file
                  beside the scene, ies_downlight.ies), a wall washer whose profile
                  covers every horizontal angle (in a buffer view) under a mirroring
                  node, and an uplight on the floor (90–180°, bilateral, in a data URI)
                  lighting the wall, around a box (the export bakes each profile into
                  six spot lights' textures, its one approximation)
  glass.gltf      KHR_materials_transmission with specularFactor 0 and roughness 0 (exact
                  against Mitsuba's dielectric of index 1.00001): a ceiling lamp
                  whose light reaches the floor only through an amber pane below it, and
                  a half-transmitting blue partition (diffuse + thin glass) in front of
                  a wall lamp, casting a tinted shadow
  solid.gltf      KHR_materials_volume: a smooth clear glass box (index 1.5) and a rough
                  absorbing ball (index 1.33, attenuation) around a small lamp (exact
                  against Mitsuba's roughdielectric and an interior homogeneous medium)
  dispersion.gltf  KHR_materials_dispersion: a smooth box of index 1.6 at dispersion 4
                  and a rough amber ball at 1.5 and 2 under a ceiling lamp and beside a
                  wall lamp (exact against three roughdielectrics, one per channel)
  solid_pane.gltf  an absorbing glass box and a thin amber pane under a ceiling lamp: the
                  export needs `volpath` for the box, which would not count passes through
                  a `thindielectric` pane as bounces, so the pane must go out as a dielectric
  glossy.gltf     rough metal and rough dielectric panels (not Lambertian: the export
                  approximates them with `principled`; measures the gap, no exact check)
  lit_emitters.gltf  emitters with bright base colours seen by the camera and lit by
                  lights in front of them (a one-sided panel 1 cm before the wall with a
                  point light 25 cm away, a two-sided fin under a spot), so that the light
                  their surfaces reflect is a large part of the image where emission seen
                  directly is hidden
  uvsets.gltf     textures on the second UV set (TEXCOORD_1: a floor's base colour, a
                  panel's base colour and emission) of meshes whose first set maps every
                  vertex to one texel, and a wall on the first set whose second is constant
  closed_emitters.gltf  small closed emissive cubes (1, 2 and 3 cm, rotated) 1.5–2.5 m
                  above a floor, one-sided, seen from 3 m: tests/core_render.rs makes them
                  two-sided, which must not let out any of the light emitted inside

Run from anywhere: python3 make_scenes.py (writes next to itself).
"""

import base64
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def _png(w, h, bit_depth, colour_type, rows):
    """A minimal PNG from its filtered-out scanlines (`rows`: bytes per row)."""
    raw = b"".join(b"\x00" + row for row in rows)

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", w, h, bit_depth, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw))
            + chunk(b"IEND", b""))


def png_rgb(w, h, pixels):
    """A minimal RGB8 PNG (pixels: rows of (r, g, b) tuples, top row first)."""
    return _png(w, h, 8, 2, [bytes(c for px in row for c in px) for row in pixels])


def png_rgba(w, h, pixels):
    """A minimal RGBA8 PNG (pixels: rows of (r, g, b, a) tuples, top row first)."""
    return _png(w, h, 8, 6, [bytes(c for px in row for c in px) for row in pixels])


def png_rgb16(w, h, pixels):
    """A minimal 16-bit RGB PNG (pixels: rows of (r, g, b) tuples of 0-65535, top row first)."""
    return _png(w, h, 16, 2, [b"".join(struct.pack(">3H", *px) for px in row) for row in pixels])


class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors, self.meshes = [], [], []
        self.materials, self.nodes, self.cameras = [], [], []
        self.images, self.textures, self.samplers = [], [], []
        self.lights = []
        self.roots = []
        self.required = []
        self.used = []
        self.root_extensions = {}

    def _view(self, data, stride=None):
        while len(self.bin) % 4:
            self.bin += b"\x00"
        off = len(self.bin)
        self.bin += data
        view = {"buffer": 0, "byteOffset": off, "byteLength": len(data)}
        if stride:
            view["byteStride"] = stride
        self.views.append(view)
        return len(self.views) - 1

    def _acc(self, data, comp, count, typ, stride=None, **kw):
        self.accessors.append(dict(bufferView=self._view(data, stride), componentType=comp,
                                   count=count, type=typ, **kw))
        return len(self.accessors) - 1

    def mesh(self, positions, indices, material, normals=None, uvs=None, colors=None,
             color_format="float", uvs1=None):
        attrs = {}
        mn = [min(p[i] for p in positions) for i in range(3)]
        mx = [max(p[i] for p in positions) for i in range(3)]
        attrs["POSITION"] = self._acc(b"".join(struct.pack("<3f", *p) for p in positions),
                                      5126, len(positions), "VEC3", min=mn, max=mx)
        if normals:
            attrs["NORMAL"] = self._acc(b"".join(struct.pack("<3f", *n) for n in normals),
                                        5126, len(normals), "VEC3")
        if uvs:
            attrs["TEXCOORD_0"] = self._acc(b"".join(struct.pack("<2f", *t) for t in uvs),
                                            5126, len(uvs), "VEC2")
        if uvs1:
            attrs["TEXCOORD_1"] = self._acc(b"".join(struct.pack("<2f", *t) for t in uvs1),
                                            5126, len(uvs1), "VEC2")
        if colors:
            n = len(colors[0])
            typ = "VEC%d" % n
            if color_format == "float":
                data = b"".join(struct.pack("<%df" % n, *c) for c in colors)
                attrs["COLOR_0"] = self._acc(data, 5126, len(colors), typ)
            else:  # normalised unsigned short
                data = b"".join(struct.pack("<%dH" % n, *(round(65535 * v) for v in c))
                                for c in colors)
                attrs["COLOR_0"] = self._acc(data, 5123, len(colors), typ, normalized=True)
        ind = self._acc(b"".join(struct.pack("<I", i) for i in indices), 5125, len(indices),
                        "SCALAR")
        self.meshes.append({"primitives": [{"attributes": attrs, "indices": ind,
                                            "material": material}]})
        return len(self.meshes) - 1

    def quad(self, p0, p1, p2, p3, material, uv=True, normal=True):
        """Quad p0 p1 p2 p3 (counter-clockwise seen from its front), uv (0,0) at p0."""
        n = None
        if normal:
            a = [p1[i] - p0[i] for i in range(3)]
            b = [p2[i] - p0[i] for i in range(3)]
            c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            l = math.sqrt(sum(v * v for v in c))
            n = [[v / l for v in c]] * 4
        uvs = [(0, 0), (1, 0), (1, 1), (0, 1)] if uv else None
        return self.mesh([p0, p1, p2, p3], [0, 1, 2, 0, 2, 3], material, n, uvs)

    def box(self, material, uv=False):
        """Unit cube [-0.5, 0.5]^3, outward faces, flat normals; with `uv`, each face
        carries uv (0,0)-(1,1) in the order of its corners."""
        prims_p, prims_n, idx = [], [], []
        for axis in range(3):
            for s in (-1, 1):
                u, v = (axis + 1) % 3, (axis + 2) % 3
                corners = []
                for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                    p = [0, 0, 0]
                    p[axis] = 0.5 * s
                    p[u] = 0.5 * a
                    p[v] = 0.5 * b
                    corners.append(p)
                if s < 0:
                    corners = corners[::-1]
                n = [0, 0, 0]
                n[axis] = s
                base = len(prims_p)
                prims_p += corners
                prims_n += [n] * 4
                idx += [base, base + 1, base + 2, base, base + 2, base + 3]
        mesh = self.mesh(prims_p, idx, material, prims_n)
        if uv:
            uvs = [(0, 0), (1, 0), (1, 1), (0, 1)] * 6
            self.meshes[mesh]["primitives"][0]["attributes"]["TEXCOORD_0"] = self._acc(
                b"".join(struct.pack("<2f", *t) for t in uvs), 5126, len(uvs), "VEC2")
        return mesh

    def lambert(self, rgb, emission=None, strength=None, double_sided=False, base_tex=None,
                emissive_tex=None):
        m = {"pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1], "metallicFactor": 0,
                                      "roughnessFactor": 1},
             "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}
        if base_tex is not None:
            m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": base_tex}
        if emission:
            m["emissiveFactor"] = list(emission)
        if strength is not None:
            m["extensions"]["KHR_materials_emissive_strength"] = {"emissiveStrength": strength}
        if emissive_tex is not None:
            m["emissiveTexture"] = {"index": emissive_tex}
        if double_sided:
            m["doubleSided"] = True
        self.materials.append(m)
        return len(self.materials) - 1

    def glass(self, rgb, transmission):
        """Thin smooth glass without Fresnel reflection (specularFactor 0): a share
        `transmission` passes straight through tinted by `rgb`, the rest is diffuse."""
        self.materials.append({
            "pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1], "metallicFactor": 0,
                                     "roughnessFactor": 0},
            "extensions": {"KHR_materials_specular": {"specularFactor": 0},
                           "KHR_materials_transmission": {"transmissionFactor": transmission}}})
        self.uses("KHR_materials_transmission")
        return len(self.materials) - 1

    def solid_glass(self, rgb, roughness, ior, attenuation=None, dispersion=None):
        """The boundary of a glass solid (KHR_materials_volume, thickness > 0):
        `attenuation` = (colour, distance) makes it absorb, `dispersion` (20 / Abbe
        number) spreads its index over the colour channels."""
        volume = {"thicknessFactor": 0.1}
        if attenuation:
            volume.update(attenuationColor=list(attenuation[0]),
                          attenuationDistance=attenuation[1])
        extensions = {"KHR_materials_transmission": {"transmissionFactor": 1},
                      "KHR_materials_ior": {"ior": ior},
                      "KHR_materials_volume": volume}
        self.uses("KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume")
        if dispersion is not None:
            extensions["KHR_materials_dispersion"] = {"dispersion": dispersion}
            self.uses("KHR_materials_dispersion")
        self.materials.append({
            "pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1], "metallicFactor": 0,
                                     "roughnessFactor": roughness},
            "extensions": extensions})
        return len(self.materials) - 1

    # The extensions write() lists in every file.
    ALWAYS_USED = ["KHR_materials_specular", "KHR_materials_emissive_strength"]

    def uses(self, *names):
        """Lists extensions in the file's extensionsUsed, each once."""
        for e in names:
            if e not in self.used and e not in self.ALWAYS_USED:
                self.used.append(e)

    def extend(self, m, extensions):
        """Material `m` gains `extensions` (name: JSON), listed as used; returns m."""
        self.materials[m].setdefault("extensions", {}).update(extensions)
        self.uses(*extensions)
        return m

    def pbr(self, rgb, metallic, roughness):
        self.materials.append({"pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1],
                                                        "metallicFactor": metallic,
                                                        "roughnessFactor": roughness}})
        return len(self.materials) - 1

    def texture(self, png, nearest=False):
        self.images.append({"uri": "data:image/png;base64," + base64.b64encode(png).decode()})
        s = {"wrapS": 10497, "wrapT": 10497}
        if nearest:
            s.update(magFilter=9728, minFilter=9728)
        self.samplers.append(s)
        self.textures.append({"source": len(self.images) - 1, "sampler": len(self.samplers) - 1})
        return len(self.textures) - 1

    def node(self, root=True, **kw):
        self.nodes.append(kw)
        if root:
            self.roots.append(len(self.nodes) - 1)
        return len(self.nodes) - 1

    def camera(self, yfov=None, aspect=None, ortho=None):
        if ortho:
            self.cameras.append({"type": "orthographic", "orthographic": {
                "xmag": ortho[0], "ymag": ortho[1], "znear": 0.01, "zfar": 100}})
        else:
            p = {"yfov": yfov, "znear": 0.05}
            if aspect:
                p["aspectRatio"] = aspect
            self.cameras.append({"type": "perspective", "perspective": p})
        return len(self.cameras) - 1

    def light(self, **kw):
        self.lights.append(kw)
        return len(self.lights) - 1

    def point_light(self, color, intensity, translation):
        """A KHR_lights_punctual point light at `translation` (a root node)."""
        return self.node(extensions={"KHR_lights_punctual": {"light": self.light(
            type="point", color=color, intensity=intensity)}}, translation=translation)

    def write(self, name):
        used = list(self.ALWAYS_USED)
        g = {"asset": {"version": "2.0", "generator": "lanterna tests/data/mitsuba/make_scenes.py"},
             "extensionsUsed": used + (["KHR_lights_punctual"] if self.lights else [])
             + self.used + self.required,
             "buffers": [{"byteLength": len(self.bin), "uri": "data:application/octet-stream;base64,"
                          + base64.b64encode(bytes(self.bin)).decode()}],
             "bufferViews": self.views, "accessors": self.accessors, "meshes": self.meshes,
             "materials": self.materials, "nodes": self.nodes,
             "scenes": [{"nodes": self.roots}], "scene": 0, "cameras": self.cameras}
        if self.images:
            g.update(images=self.images, textures=self.textures, samplers=self.samplers)
        if self.lights:
            g["extensions"] = {"KHR_lights_punctual": {"lights": self.lights}}
        if self.root_extensions:
            g.setdefault("extensions", {}).update(self.root_extensions)
        if self.required:
            g["extensionsRequired"] = self.required
        with open(os.path.join(HERE, name), "w") as f:
            json.dump(g, f, separators=(",", ":"))


def look_at_rotation(eye, target):
    """Quaternion (x, y, z, w) turning glTF's −Z view axis toward target (up +Y)."""
    f = [target[i] - eye[i] for i in range(3)]
    l = math.sqrt(sum(v * v for v in f))
    f = [v / l for v in f]
    z = [-v for v in f]
    up = [0, 1, 0]
    x = [up[1] * z[2] - up[2] * z[1], up[2] * z[0] - up[0] * z[2], up[0] * z[1] - up[1] * z[0]]
    lx = math.sqrt(sum(v * v for v in x))
    x = [v / lx for v in x]
    y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]]
    m = [[x[0], y[0], z[0]], [x[1], y[1], z[1]], [x[2], y[2], z[2]]]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = 0.5 / math.sqrt(tr + 1)
        return [(m[2][1] - m[1][2]) * s, (m[0][2] - m[2][0]) * s, (m[1][0] - m[0][1]) * s, 0.25 / s]
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2 * math.sqrt(1 + m[i][i] - m[j][j] - m[k][k])
    q = [0, 0, 0, 0]
    q[i] = 0.25 * s
    q[j] = (m[j][i] + m[i][j]) / s
    q[k] = (m[k][i] + m[i][k]) / s
    q[3] = (m[k][j] - m[j][k]) / s
    return q


def floor_and_wall(b, mat, size=2.0):
    b.node(mesh=b.quad((-size, 0, size), (size, 0, size), (size, 0, -size), (-size, 0, -size), mat))
    b.node(mesh=b.quad((-size, 0, -size), (size, 0, -size), (size, 2 * size, -size),
                       (-size, 2 * size, -size), mat))


def tex_scene():
    b = Builder()
    quads = [[(230, 40, 40)] * 2 + [(40, 200, 40)] * 2] * 2 + [[(40, 40, 230)] * 2 + [(240, 240, 60)] * 2] * 2
    t_near = b.texture(png_rgb(4, 4, quads), nearest=True)
    ramp = [[(int(255 * x / 7), 128, int(255 * (7 - y) / 7)) for x in range(8)] for y in range(8)]
    t_lin = b.texture(png_rgb(8, 8, ramp))
    floor = b.lambert((1, 1, 1), base_tex=t_near)
    wall = b.lambert((1, 1, 1), base_tex=t_lin)
    b.node(mesh=b.quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1), floor))
    b.node(mesh=b.quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1), wall))
    glow = b.texture(png_rgb(2, 2, [[(255, 255, 255), (255, 60, 0)], [(0, 90, 255), (40, 40, 40)]]),
                     nearest=True)
    panel = b.lambert((0.5, 0.5, 0.5), emission=(1, 1, 1), strength=3, emissive_tex=glow)
    # Panel above the floor, facing down and toward the camera.
    b.node(mesh=b.quad((-0.6, 1.3, 0.2), (0.6, 1.3, 0.2), (0.6, 1.6, 0.9), (-0.6, 1.6, 0.9),
                       panel))
    eye = (0.3, 1.2, 2.6)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.6, 0)))
    b.write("tex.gltf")


def tex16_scene():
    """16-bit sRGB textures whose samples lie 0.45-0.49 of an 8-bit code above a code, so
    that rounding them to 8 bits darkens every texel (dark ones by up to 20 %)."""
    b = Builder()

    def between_codes(code):
        return round((code + 0.45 + 0.04 * ((code * 7) % 5) / 4) * 257)

    dark = [[tuple(between_codes(2 + (3 * x + 5 * y + k) % 14) for k in range(3)) for x in range(4)]
            for y in range(4)]
    mid = [[tuple(between_codes(40 + 23 * ((x + 2 * y + k) % 8)) for k in range(3)) for x in range(8)]
           for y in range(8)]
    floor = b.lambert((1, 1, 1), base_tex=b.texture(png_rgb16(4, 4, dark), nearest=True))
    wall = b.lambert((1, 1, 1), base_tex=b.texture(png_rgb16(8, 8, mid)))
    b.node(mesh=b.quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1), floor))
    b.node(mesh=b.quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1), wall))
    # An emitter whose radiance is its 16-bit texture (factor and strength 1).
    glow = b.texture(png_rgb16(2, 2, [[(65535, 30000, 2000), (between_codes(20), 65535, 9000)],
                                      [(between_codes(9), 20000, 65535), (50000, 50000, 50000)]]),
                     nearest=True)
    panel = b.lambert((0.5, 0.5, 0.5), emission=(1, 1, 1), emissive_tex=glow)
    b.node(mesh=b.quad((-0.6, 1.3, 0.2), (0.6, 1.3, 0.2), (0.6, 1.6, 0.9), (-0.6, 1.6, 0.9),
                       panel))
    b.point_light([1, 0.95, 0.9], 4.0, [0.5, 1.0, 0.6])
    eye = (0.3, 1.2, 2.6)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.6, 0)))
    b.write("tex16.gltf")


def normal_map_png(w, h, max_tilt_deg, seed):
    """A tangent-space normal map of w × h texels tilted by up to max_tilt_deg in turning
    directions (8-bit, linear: (n + 1) / 2)."""
    rows = []
    for y in range(h):
        row = []
        for x in range(w):
            tilt = math.radians(max_tilt_deg) * ((3 * x + 5 * y + seed) % 7) / 6
            phi = 2 * math.pi * ((5 * x + 3 * y + 2 * seed) % 8) / 8
            n = (math.sin(tilt) * math.cos(phi), math.sin(tilt) * math.sin(phi), math.cos(tilt))
            row.append(tuple(round((c + 1) / 2 * 255) for c in n))
        rows.append(row)
    return png_rgb(w, h, rows)


def mirrored_floor_and_seamed_wall(b, floor, wall):
    """A 2 m floor under a node mirrored in x, and a 2 m wall behind it in two halves,
    the right half's u running backward (a mirror seam), both with UVs."""
    up, front = [0, 1, 0], [0, 0, 1]
    b.node(mesh=b.mesh([(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)], [0, 1, 2, 0, 2, 3], floor,
                       [up] * 4, [(0, 0), (1, 0), (1, 1), (0, 1)]), scale=[-1, 1, 1])
    b.node(mesh=b.mesh([(-1, 0, -1), (0, 0, -1), (0, 2, -1), (-1, 2, -1),
                        (0, 0, -1), (1, 0, -1), (1, 2, -1), (0, 2, -1)],
                       [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7], wall, [front] * 8,
                       [(0, 1), (1, 1), (1, 0), (0, 0), (1, 1), (0, 1), (0, 0), (1, 0)]))


def normal_map_scene(glossy=False):
    """normal_map.gltf, or with `glossy` normal_map_glossy.gltf: the same layout with a
    rough gold metal floor and a glossy plastic wall, for the glTF BSDF plugin."""
    b = Builder()
    floor_map = b.texture(normal_map_png(8, 8, 25, 0))
    wall_map = b.texture(normal_map_png(4, 4, 25, 3), nearest=True)
    floor = b.pbr((1.0, 0.78, 0.34), 1.0, 0.35) if glossy else b.lambert((0.7, 0.7, 0.7))
    b.materials[floor]["normalTexture"] = {"index": floor_map, "scale": 0.5}
    wall = b.pbr((0.2, 0.4, 0.8), 0.0, 0.3) if glossy else b.lambert((0.8, 0.6, 0.4))
    b.materials[wall]["normalTexture"] = {"index": wall_map}
    mirrored_floor_and_seamed_wall(b, floor, wall)
    lamp = b.lambert((0, 0, 0), emission=(1, 0.9, 0.8), strength=4)
    b.node(mesh=b.quad((-0.4, 2.2, 0.1), (-0.4, 2.0, 0.7), (0.4, 2.0, 0.7), (0.4, 2.2, 0.1), lamp))
    b.point_light([1, 0.9, 0.7], 1.5, [0.6, 1.4, -0.65])
    b.point_light([0.7, 0.8, 1], 0.8, [-0.5, 0.35, 0.3])
    eye = (0.0, 2.6, 2.2)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.4, -0.4)))
    b.write("normal_map_glossy.gltf" if glossy else "normal_map.gltf")


def anisotropic(b, rgb, metallic, roughness, strength, rotation):
    """A glossy material with KHR_materials_anisotropy (factors only)."""
    return b.extend(b.pbr(rgb, metallic, roughness), {"KHR_materials_anisotropy": {
        "anisotropyStrength": strength, "anisotropyRotation": rotation}})


def translucent(b, rgb, roughness, factor, colour, specular=None, ior=None, volume=None):
    """A material with KHR_materials_diffuse_transmission (factors only); `volume` =
    (attenuation colour, distance) makes it the boundary of an absorbing solid."""
    ext = {"KHR_materials_diffuse_transmission": {
        "diffuseTransmissionFactor": factor, "diffuseTransmissionColorFactor": list(colour)}}
    if specular is not None:
        ext["KHR_materials_specular"] = {"specularFactor": specular}
    if ior is not None:
        ext["KHR_materials_ior"] = {"ior": ior}
    if volume is not None:
        ext["KHR_materials_volume"] = {"thicknessFactor": 0.1, "attenuationColor": list(volume[0]),
                                       "attenuationDistance": volume[1]}
    return b.extend(b.pbr(rgb, 0.0, roughness), ext)


def diffuse_transmission_scene():
    """diffuse_transmission.gltf: light that reaches the room through diffusely
    transmitting surfaces: a paper shade (an open box, no specular lobe) around a small
    lamp, a glossy leaf-green panel whose point light stands behind it, and a block of
    wax (index 1.45, absorbing inside) under a ceiling lamp."""
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    ceiling_lamp(b)
    paper = translucent(b, (0.9, 0.88, 0.8), 1.0, 0.6, (1.0, 0.85, 0.6), specular=0.0)
    x0, x1, z0, z1, y0, y1 = -1.05, -0.55, -0.55, -0.05, 0.6, 1.2
    for a, c in (((x0, z0), (x1, z0)), ((x1, z0), (x1, z1)), ((x1, z1), (x0, z1)), ((x0, z1), (x0, z0))):
        b.node(mesh=b.quad((a[0], y0, a[1]), (c[0], y0, c[1]), (c[0], y1, c[1]), (a[0], y1, a[1]),
                           paper, uv=False))
    bulb = b.lambert((0, 0, 0), emission=(1, 0.9, 0.7), strength=15)
    b.node(mesh=b.box(bulb), translation=[-0.8, 0.9, -0.3], scale=[0.12, 0.12, 0.12])
    leaf = translucent(b, (0.25, 0.5, 0.15), 0.5, 0.5, (0.6, 0.9, 0.2))
    b.node(mesh=b.quad((0.2, 0.3, 0.3), (0.9, 0.3, 0.3), (0.9, 1.2, 0.3), (0.2, 1.2, 0.3), leaf,
                       uv=False))
    b.point_light([1, 0.95, 0.8], 2.0, [0.55, 0.75, -0.1])
    wax = translucent(b, (0.95, 0.9, 0.8), 0.6, 0.9, (1.0, 0.8, 0.5), ior=1.45,
                      volume=((0.9, 0.6, 0.4), 0.3))
    b.node(mesh=b.box(wax), translation=[-0.2, 0.25, 0.9], scale=[0.4, 0.4, 0.4],
           rotation=[0, 0.258819, 0, 0.9659258])
    eye = (0.3, 1.4, 3.6)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (-0.1, 0.7, -0.2)))
    b.write("diffuse_transmission.gltf")


def iridescent(b, rgb, metallic, roughness, factor, ior, thickness, coat=None, transmission=None):
    """A material with KHR_materials_iridescence (factors only: no thickness texture, so
    the film is `thickness` nm, its maximum)."""
    ext = {"KHR_materials_iridescence": {"iridescenceFactor": factor, "iridescenceIor": ior,
                                         "iridescenceThicknessMaximum": thickness}}
    if coat is not None:
        ext["KHR_materials_clearcoat"] = {"clearcoatFactor": coat[0],
                                          "clearcoatRoughnessFactor": coat[1]}
    if transmission is not None:
        ext["KHR_materials_transmission"] = {"transmissionFactor": transmission}
    return b.extend(b.pbr(rgb, metallic, roughness), ext)


def iridescence_scene():
    """iridescence.gltf: thin films on four materials under a ceiling lamp and a point
    light (see the module's docstring)."""
    b = Builder()
    floor = iridescent(b, (0.05, 0.05, 0.08), 0.0, 0.35, 1.0, 1.33, 380.0)
    wall = iridescent(b, (0.9, 0.85, 0.8), 1.0, 0.3, 0.8, 1.8, 450.0)
    b.node(mesh=b.quad((-2, 0, 2), (2, 0, 2), (2, 0, -1.2), (-2, 0, -1.2), floor))
    b.node(mesh=b.quad((-2, 0, -1.2), (2, 0, -1.2), (2, 2.5, -1.2), (-2, 2.5, -1.2), wall,
                       uv=False))
    # A white wall behind the camera, lit by the lamp, for the metal to mirror.
    white = b.lambert((0.8, 0.8, 0.8))
    b.node(mesh=b.quad((2, 0, 3.8), (-2, 0, 3.8), (-2, 2.5, 3.8), (2, 2.5, 3.8), white, uv=False))
    ceiling_lamp(b)
    coated = iridescent(b, (0.5, 0.3, 0.2), 0.0, 0.5, 1.0, 1.3, 300.0, coat=(1.0, 0.1))
    b.node(mesh=b.box(coated), translation=[-0.6, 0.3, 0.2], scale=[0.6, 0.6, 0.6],
           rotation=[0, 0.3826834, 0, 0.9238795])
    pane = iridescent(b, (0.8, 0.9, 0.95), 0.0, 0.25, 1.0, 1.4, 500.0, transmission=0.7)
    b.node(mesh=b.quad((0.3, 0.1, 0.6), (1.1, 0.1, 0.4), (1.1, 1.1, 0.4), (0.3, 1.1, 0.6), pane,
                       uv=False))
    b.point_light([1, 0.95, 0.85], 3.0, [0.8, 0.6, -0.3])
    b.point_light([1, 1, 1], 6.0, [0.0, 2.2, 3.3])
    eye = (0.2, 1.5, 3.4)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.5, -0.3)))
    b.write("iridescence.gltf")


def anisotropy_scene():
    """anisotropy.gltf: brushed metal and anisotropic plastic under point lights and a
    small lamp, where the highlights stretch across the surfaces: a floor of brushed
    gold (rotation 0.6 rad) under a node mirrored in x, a wall of blue plastic stretched
    along its tangent whose right half runs its u backward (a mirror seam, where the
    bitangent turns), and a rotated box of brushed steel stretched at 1.2 rad."""
    b = Builder()
    floor = anisotropic(b, (1.0, 0.78, 0.34), 1.0, 0.2, 0.9, 0.6)
    wall = anisotropic(b, (0.2, 0.4, 0.8), 0.0, 0.15, 1.0, 0.4)
    steel = anisotropic(b, (0.85, 0.85, 0.88), 1.0, 0.1, 0.8, 1.2)
    mirrored_floor_and_seamed_wall(b, floor, wall)
    b.node(mesh=b.box(steel, uv=True), translation=[0.45, 0.25, -0.3], scale=[0.5, 0.5, 0.5],
           rotation=[0, 0.3826834, 0, 0.9238795])
    lamp = b.lambert((0, 0, 0), emission=(1, 0.9, 0.8), strength=4)
    b.node(mesh=b.quad((-0.3, 2.2, 0.1), (-0.3, 2.0, 0.5), (0.3, 2.0, 0.5), (0.3, 2.2, 0.1), lamp))
    b.point_light([1, 0.9, 0.7], 1.5, [0.5, 1.3, -0.6])
    b.point_light([0.7, 0.8, 1], 0.8, [-0.5, 0.4, 0.2])
    eye = (0.0, 2.4, 2.3)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.4, -0.4)))
    b.write("anisotropy.gltf")


def alpha_scene():
    """Alpha MASK and BLEND between a lamp and a floor, seen by the camera."""
    b = Builder()
    floor = b.lambert((0.8, 0.8, 0.8))
    floor_and_wall(b, floor, size=1.5)
    # A fence cut out by a nearest-filtered texture (alpha 0, 255, and values either
    # side of the cutoff 0.4), its colour from the same texture.
    fence_px = [[((60 + 40 * x) % 256, 180, (200 - 30 * y) % 256,
                  [0, 255, 90, 120, 255, 0][(x + 2 * y) % 6]) for x in range(6)] for y in range(4)]
    fence = b.lambert((1, 0.9, 0.8), base_tex=b.texture(png_rgba(6, 4, fence_px), nearest=True))
    b.materials[fence].update(alphaMode="MASK", alphaCutoff=0.4, doubleSided=True)
    b.node(mesh=b.quad((-1.0, 0.2, 0.3), (0.1, 0.2, 0.3), (0.1, 1.0, -0.1), (-1.0, 1.0, -0.1),
                       fence))
    # A BLEND panel whose alpha runs across a bilinear texture, times a factor 0.8.
    blend_px = [[(200, 90 + 20 * x, 60, round(255 * (x + y) / 6)) for x in range(4)]
                for y in range(4)]
    glassy = b.lambert((0.9, 0.9, 1.0), base_tex=b.texture(png_rgba(4, 4, blend_px)))
    b.materials[glassy]["pbrMetallicRoughness"]["baseColorFactor"][3] = 0.8
    b.materials[glassy]["alphaMode"] = "BLEND"
    b.node(mesh=b.quad((0.2, 0.1, 0.2), (1.1, 0.1, 0.2), (1.1, 1.1, -0.3), (0.2, 1.1, -0.3), glassy))
    # A constant BLEND of 0.4 and a MASK whose constant alpha is under its cutoff (not
    # there at all).
    veil = b.lambert((0.3, 0.7, 0.4))
    b.materials[veil]["pbrMetallicRoughness"]["baseColorFactor"][3] = 0.4
    b.materials[veil]["alphaMode"] = "BLEND"
    b.node(mesh=b.quad((-0.6, 1.2, 0.6), (0.6, 1.2, 0.6), (0.6, 1.5, 0.0), (-0.6, 1.5, 0.0), veil))
    ghost = b.lambert((0.9, 0.1, 0.1))
    b.materials[ghost]["pbrMetallicRoughness"]["baseColorFactor"][3] = 0.3
    b.materials[ghost].update(alphaMode="MASK", alphaCutoff=0.5)
    b.node(mesh=b.quad((-0.5, 0.05, 0.9), (0.5, 0.05, 0.9), (0.5, 0.7, 0.9), (-0.5, 0.7, 0.9), ghost))
    lamp = b.lambert((0, 0, 0), emission=(1, 0.95, 0.9), strength=6)
    b.node(mesh=b.quad((-0.5, 2.3, -0.2), (-0.5, 2.2, 0.5), (0.5, 2.2, 0.5), (0.5, 2.3, -0.2), lamp))
    # A one-sided emitter under a constant BLEND of 0.5, before the wall and over the
    # floor, facing the camera: it emits as much as rays find of it.
    glow = b.lambert((0.6, 0.6, 0.6), emission=(1, 0.5, 0.2), strength=3)
    b.materials[glow]["pbrMetallicRoughness"]["baseColorFactor"][3] = 0.5
    b.materials[glow]["alphaMode"] = "BLEND"
    b.node(mesh=b.quad((0.5, 1.3, -1.2), (1.2, 1.3, -1.2), (1.2, 1.8, -1.2), (0.5, 1.8, -1.2), glow))
    b.point_light([1, 0.8, 0.6], 2.0, [-0.3, 1.4, 0.6])
    eye = (0.2, 1.6, 2.8)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.5, -0.2)))
    b.write("alpha.gltf")


def twosided_scene():
    b = Builder()
    grey = b.lambert((0.7, 0.7, 0.7))
    red = b.lambert((0.7, 0.2, 0.2))
    floor_and_wall(b, grey)
    # Double-sided emitter: a vertical panel in the x = 0 plane, seen edge-on-ish.
    ds = b.lambert((0.3, 0.3, 0.3), emission=(1, 0.9, 0.7), strength=4, double_sided=True)
    b.node(mesh=b.quad((0, 0.3, -0.4), (0, 0.3, 0.4), (0, 1.1, 0.4), (0, 1.1, -0.4), ds))
    # One-sided emitter facing away from the camera (toward the back wall).
    os_ = b.lambert((0.5, 0.5, 0.5), emission=(0.4, 0.6, 1), strength=5)
    b.node(mesh=b.quad((0.8, 1.4, -0.6), (0.8, 1.8, -0.6), (1.4, 1.8, -0.6), (1.4, 1.4, -0.6),
                       os_, uv=False, normal=False))
    b.node(mesh=b.box(red), translation=[-1.0, 0.25, 0.3], scale=[0.5, 0.5, 0.5])
    eye = (1.6, 1.4, 2.8)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.6, -0.3)))
    b.write("twosided.gltf")


def punctual_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    b.node(mesh=b.box(b.lambert((0.2, 0.5, 0.8))), translation=[0.6, 0.3, -0.4],
           scale=[0.6, 0.6, 0.6])
    down = [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)]  # −Z → −Y
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(type="point", color=[1, 0.8, 0.6],
                                                               intensity=2.0)}},
           translation=[-1.0, 1.5, 0.5])
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(
        type="spot", color=[0.6, 0.8, 1], intensity=6.0,
        spot={"innerConeAngle": 0.2, "outerConeAngle": 0.5})}},
        translation=[0.5, 2.0, 0.3], rotation=down)
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(
        type="spot", color=[1, 1, 1], intensity=4.0,
        spot={"innerConeAngle": 0.3, "outerConeAngle": 0.3})}},
        translation=[-0.9, 1.8, -1.2], rotation=down)
    tilt = [-0.3, 0.2, 0.1, 0.93]
    n = math.sqrt(sum(v * v for v in tilt))
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(
        type="directional", color=[1, 1, 0.9], intensity=0.5)}},
        rotation=[v / n for v in tilt])
    eye = (0.4, 1.8, 3.4)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.5, -0.5)))
    b.write("punctual.gltf")


def hierarchy_scene():
    b = Builder()
    grey = b.lambert((0.65, 0.65, 0.65))
    floor_and_wall(b, grey)
    green = b.lambert((0.2, 0.7, 0.3))
    light = b.lambert((0.8, 0.8, 0.8), emission=(1, 1, 1), strength=6)
    quad = b.quad((-0.3, 0, -0.3), (0.3, 0, -0.3), (0.3, 0, 0.3), (-0.3, 0, 0.3), light,
                  uv=False)  # faces −Y (down) before any transform
    box = b.box(green)
    # Children: a lamp facing down, and a mirrored copy under a negative-scale node
    # (x → −x keeps it facing down only if the renderer flips the winding's normal).
    lamp = b.node(root=False, mesh=quad, translation=[0.6, 0, 0])
    mirrored = b.node(root=False, mesh=quad, translation=[0.6, 0, 0])
    mirror = b.node(root=False, children=[mirrored], scale=[-1, 1, 1])
    cube = b.node(root=False, mesh=box, translation=[0, -1.2, 0.4],
                  rotation=[0, 0.3826834, 0, 0.9238795], scale=[0.5, 0.8, 0.5])
    flipped_cube = b.node(root=False, mesh=box, translation=[0.7, -1.35, -0.2],
                          scale=[0.3, -0.3, 0.3])
    b.node(children=[lamp, mirror, cube, flipped_cube], translation=[0, 1.9, -0.2],
           rotation=[0, 0.1305262, 0, 0.9914449], scale=[1.2, 1.0, 1.2])
    eye = (0.5, 1.3, 3.0)
    b.node(camera=b.camera(yfov=0.85), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.7, -0.5)))
    eye2 = (2.5, 2.0, 2.5)
    b.node(camera=b.camera(ortho=(1.6, 1.2)), translation=list(eye2),
           rotation=look_at_rotation(eye2, (0, 0.6, -0.5)))
    b.write("hierarchy.gltf")


def sun_and_camera_over_the_panel(b):
    """The directional light and the camera of texxform.gltf (and uvsets.gltf), which look
    at a floor and at a panel 0.6 m behind its middle."""
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(
        type="directional", color=[1, 1, 1], intensity=2.0)}}, rotation=[-0.38, 0, 0, 0.925])
    eye = (0, 1.6, 2.2)
    b.node(camera=b.camera(yfov=0.9), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.5, -0.2)))


def texxform_scene():
    """Textures of exact-decode texels only (0 and 255), for KHR_texture_transform
    checks: the peer test sets the transforms on the loaded scene."""
    b = Builder()
    W, K = (255, 255, 255), (0, 0, 0)
    t = b.texture(png_rgb(4, 4, [[W, K, K, W], [K, K, W, W], [W, W, K, K], [K, W, K, W]]),
                  nearest=True)
    floor = b.lambert((1, 1, 1), base_tex=t)
    b.node(mesh=b.quad((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1), floor))
    panel = b.lambert((0.8, 0.8, 0.8), emission=(1, 1, 1), strength=2, base_tex=t,
                      emissive_tex=t)
    b.node(mesh=b.quad((-0.5, 0.6, -0.6), (0.5, 0.6, -0.6), (0.5, 1.4, -0.6), (-0.5, 1.4, -0.6),
                       panel))
    sun_and_camera_over_the_panel(b)
    b.write("texxform.gltf")


def sphere_room_light_and_camera(b):
    """The ceiling light and camera of smooth.gltf, its quantised copy and glossy.gltf."""
    light = b.lambert((0, 0, 0), emission=(1, 1, 1), strength=8)
    b.node(mesh=b.quad((-0.5, 2.2, -0.5), (0.5, 2.2, -0.5), (0.5, 2.2, 0.5), (-0.5, 2.2, 0.5),
                       light, uv=False))
    eye = (0.3, 1.4, 3.2)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.6, -0.3)))


def smooth_scene():
    """A coarse UV sphere with smooth vertex normals (the export notes an approximation:
    the renderers treat shading normals that disagree with the geometry differently)."""
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    pos, nrm, idx = [], [], []
    rings, segs = 6, 12
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs + 1):
            ph = 2 * math.pi * j / segs
            n = [math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)]
            pos.append(n)
            nrm.append(n)
    for i in range(rings):
        for j in range(segs):
            a, c = i * (segs + 1) + j, (i + 1) * (segs + 1) + j
            idx += [a, a + 1, c, a + 1, c + 1, c]
    sphere = b.mesh(pos, idx, b.lambert((0.8, 0.5, 0.3)), nrm)
    b.node(mesh=sphere, translation=[0, 0.7, -0.3], scale=[0.7, 0.7, 0.7])
    sphere_room_light_and_camera(b)
    b.write("smooth.gltf")


def colors_scene():
    b = Builder()
    floor = b.lambert((1, 1, 1))
    wall = b.lambert((0.9, 0.6, 1.0))
    b.node(mesh=b.mesh([(-1.5, 0, 1.5), (1.5, 0, 1.5), (1.5, 0, -1.5), (-1.5, 0, -1.5)],
                       [0, 1, 2, 0, 2, 3], floor,
                       colors=[(0.9, 0.1, 0.1), (0.1, 0.8, 0.1), (0.1, 0.2, 0.9), (0.95, 0.95, 0.95)]))
    b.node(mesh=b.mesh([(-1.5, 0, -1.5), (1.5, 0, -1.5), (1.5, 2.5, -1.5), (-1.5, 2.5, -1.5)],
                       [0, 1, 2, 0, 2, 3], wall,
                       colors=[(1, 1, 0.2, 1), (0.2, 1, 1, 1), (1, 0.3, 1, 1), (0.5, 0.5, 0.5, 1)],
                       color_format="unorm16"))
    b.node(mesh=b.box(wall), translation=[0.5, 0.35, -0.4], scale=[0.7, 0.7, 0.7])
    light = b.lambert((0.3, 0.3, 0.3), emission=(1, 1, 1), strength=8)
    b.node(mesh=b.mesh([(-0.5, 2.2, -0.5), (0.5, 2.2, -0.5), (0.5, 2.2, 0.5), (-0.5, 2.2, 0.5)],
                       [0, 1, 2, 0, 2, 3], light,
                       colors=[(0.1, 0.1, 0.1)] * 4))
    eye = (0.3, 1.4, 3.2)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.6, -0.3)))
    b.write("colors.gltf")


def unlit_colors_scene():
    b = Builder()
    b.uses("KHR_materials_unlit")
    floor = b.lambert((0.8, 0.8, 0.8))
    wall = b.lambert((0.7, 0.75, 0.8))
    b.node(mesh=b.quad((-1.5, 0, 1.5), (1.5, 0, 1.5), (1.5, 0, -1.5), (-1.5, 0, -1.5), floor))
    b.node(mesh=b.quad((-1.5, 0, -1.5), (1.5, 0, -1.5), (1.5, 2.5, -1.5), (-1.5, 2.5, -1.5), wall))

    def unlit(rgb):
        b.materials.append({"pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1]},
                            "extensions": {"KHR_materials_unlit": {}}})
        return len(b.materials) - 1

    # The panel faces down: its corners counter-clockwise seen from below.
    b.node(mesh=b.mesh([(-0.6, 2.2, -0.9), (0.6, 2.2, -0.9), (0.6, 2.2, 0.3), (-0.6, 2.2, 0.3)],
                       [0, 1, 2, 0, 2, 3], unlit((1.0, 0.9, 0.8)),
                       colors=[(1.0, 0.15, 0.1), (0.1, 0.9, 0.2), (0.2, 0.3, 1.0), (1.0, 1.0, 1.0)]))
    box = b.box(unlit((0.9, 0.9, 0.9)))
    # A colour per corner of each face (24 corners), alpha 1: normalised 16-bit RGBA.
    colours = [((0.37 * k) % 1.0, (0.61 * k + 0.2) % 1.0, (0.83 * k + 0.5) % 1.0, 1.0)
               for k in range(24)]
    attrs = b.meshes[box]["primitives"][0]["attributes"]
    attrs["COLOR_0"] = b._acc(b"".join(struct.pack("<4H", *(round(65535 * v) for v in c))
                                       for c in colours), 5123, 24, "VEC4", normalized=True)
    b.node(mesh=box, translation=[0.5, 0.3, -0.6], scale=[0.6, 0.6, 0.6],
           rotation=[0, math.sin(0.3), 0, math.cos(0.3)])
    lamp = b.lambert((0.3, 0.3, 0.3), emission=(1, 0.9, 0.7), strength=6)
    b.node(mesh=b.quad((-1.2, 1.6, -1.3), (-0.9, 1.6, -1.3), (-0.9, 1.6, -1.0), (-1.2, 1.6, -1.0),
                       lamp))
    eye = (0.3, 1.4, 3.2)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.8, -0.5)))
    b.write("unlit_colors.gltf")


def sphere_geometry(rings=6, segs=12):
    pos, idx = [], []
    for i in range(rings + 1):
        th = math.pi * i / rings
        for j in range(segs + 1):
            ph = 2 * math.pi * j / segs
            pos.append([math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)])
    for i in range(rings):
        for j in range(segs):
            a, c = i * (segs + 1) + j, (i + 1) * (segs + 1) + j
            idx += [a, a + 1, c, a + 1, c + 1, c]
    return pos, idx


def quantized_scene():
    """smooth.gltf's geometry in KHR_mesh_quantization's integer types."""
    b = Builder()
    b.required = ["KHR_mesh_quantization"]

    def ind(indices):
        return b._acc(b"".join(struct.pack("<I", i) for i in indices), 5125, len(indices),
                      "SCALAR")

    def short3(vs):
        # Normalised shorts, padded to 8-byte elements (vertex data is 4-byte aligned).
        data = b"".join(struct.pack("<3hxx", *(round(32767 * c) for c in v)) for v in vs)
        return b._acc(data, 5122, len(vs), "VEC3", stride=8, normalized=True)

    grey = b.lambert((0.6, 0.6, 0.6))
    # Floor and wall: corners 0/1 as unsigned bytes, placed and sized by their nodes.
    corners = [(0, 0, 1), (1, 0, 1), (1, 0, 0), (0, 0, 0)]
    pos = b._acc(b"".join(struct.pack("<3Bx", *c) for c in corners), 5121, 4, "VEC3",
                 stride=4, min=[0, 0, 0], max=[1, 0, 1])
    uv = b._acc(b"".join(struct.pack("<2Bxx", *t) for t in [(0, 0), (255, 0), (255, 255), (0, 255)]),
                5121, 4, "VEC2", stride=4, normalized=True)
    quad = {"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                            "indices": ind([0, 1, 2, 0, 2, 3]), "material": grey}]}
    b.meshes.append(quad)
    floor = len(b.meshes) - 1
    size = 2.0
    b.node(mesh=floor, translation=[-size, 0, -size], scale=[2 * size, 1, 2 * size])
    # The wall: the same quad turned up about x (its z becomes y), mirrored in z so that
    # it faces the camera (a negative-determinant node flips the winding).
    b.node(mesh=floor, translation=[-size, 0, -size], scale=[2 * size, 1, -2 * size],
           rotation=[0.7071068, 0, 0, 0.7071068])
    pos, idx = sphere_geometry()
    sphere = {"primitives": [{"attributes": {
        "POSITION": short3(pos), "NORMAL": short3(pos)}, "indices": ind(idx),
        "material": b.lambert((0.8, 0.5, 0.3))}]}
    b.accessors[sphere["primitives"][0]["attributes"]["POSITION"]].update(
        min=[-1, -1, -1], max=[1, 1, 1])
    b.meshes.append(sphere)
    b.node(mesh=len(b.meshes) - 1, translation=[0, 0.7, -0.3], scale=[0.7, 0.7, 0.7])
    sphere_room_light_and_camera(b)
    b.write("quantized.gltf")


def ceiling_lamp(b):
    """A 0.8 m square lamp 2 m above the floor, facing down (strength 6)."""
    lamp = b.lambert((0, 0, 0), emission=(1, 1, 1), strength=6)
    b.node(mesh=b.quad((-0.4, 2.0, -0.4), (0.4, 2.0, -0.4), (0.4, 2.0, 0.4), (-0.4, 2.0, 0.4),
                       lamp, uv=False))


def glass_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    b.node(mesh=b.box(b.lambert((0.7, 0.2, 0.2))), translation=[0.9, 0.25, 0.2],
           scale=[0.5, 0.5, 0.5])
    # Ceiling lamp facing down, an amber pane below it: the floor under the pane sees the
    # lamp only through the glass.
    ceiling_lamp(b)
    amber = b.glass((0.9, 0.6, 0.3), 1.0)
    b.node(mesh=b.quad((-0.7, 1.7, -0.7), (0.7, 1.7, -0.7), (0.7, 1.7, 0.7), (-0.7, 1.7, 0.7),
                       amber, uv=False))
    # Wall lamp on the left facing +x, a half-transmitting blue partition in front of it.
    wall_lamp = b.lambert((0, 0, 0), emission=(1, 0.9, 0.8), strength=5)
    b.node(mesh=b.quad((-1.9, 0.5, 0.3), (-1.9, 0.5, -0.3), (-1.9, 1.1, -0.3), (-1.9, 1.1, 0.3),
                       wall_lamp, uv=False))
    blue = b.glass((0.3, 0.5, 0.9), 0.5)
    b.node(mesh=b.quad((-1.3, 0.0, -0.8), (-1.3, 0.0, 0.8), (-1.3, 1.4, 0.8), (-1.3, 1.4, -0.8),
                       blue, uv=False))
    eye = (0.6, 1.3, 3.4)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (-0.3, 0.8, -0.4)))
    b.write("glass.gltf")


def solid_scene():
    """Glass solids under a ceiling lamp: a clear, slightly green smooth box standing on
    the floor (light reaches the floor under it only through two interfaces), and a
    rough, blue-absorbing faceted ball of index 1.33 holding a small lamp, whose light
    leaves only through the absorbing solid."""
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    ceiling_lamp(b)
    clear = b.solid_glass((0.92, 1.0, 0.92), 0.0, 1.5)
    b.node(mesh=b.box(clear), translation=[-0.6, 0.36, -0.2], scale=[0.7, 0.7, 0.7],
           rotation=[0, 0.258819, 0, 0.9659258])
    pos, idx = sphere_geometry(rings=8, segs=16)
    murky = b.solid_glass((1, 1, 1), 0.3, 1.33, attenuation=((0.9, 0.6, 0.3), 0.5))
    b.node(mesh=b.mesh(pos, idx, murky), translation=[0.7, 0.5, 0.1], scale=[0.45, 0.45, 0.45])
    inner = b.lambert((0, 0, 0), emission=(1, 0.9, 0.7), strength=12)
    b.node(mesh=b.box(inner), translation=[0.7, 0.5, 0.1], scale=[0.15, 0.15, 0.15])
    eye = (0.3, 1.3, 3.4)
    b.node(camera=b.camera(yfov=0.8, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.5, -0.2)))
    b.write("solid.gltf")


def prism_geometry(apex, base_dir, side_dir, side, y0, y1):
    """An upright triangular prism from y0 to y1: its cross-section an equilateral
    triangle of side `side` with its apex at `apex` (x, z) and its base toward the unit
    vector `base_dir` (x, z), `side_dir` along the base; outward faces, flat normals."""
    h = side * math.sqrt(3) / 2
    mid = (apex[0] + h * base_dir[0], apex[1] + h * base_dir[1])
    corners = [apex,
               (mid[0] + side / 2 * side_dir[0], mid[1] + side / 2 * side_dir[1]),
               (mid[0] - side / 2 * side_dir[0], mid[1] - side / 2 * side_dir[1])]
    centre = [sum(c[i] for c in corners) / 3 for i in range(2)]
    centre = (centre[0], (y0 + y1) / 2, centre[1])
    faces = [[(x, y0, z) for x, z in corners], [(x, y1, z) for x, z in corners]]
    for i in range(3):
        (ax, az), (bx, bz) = corners[i], corners[(i + 1) % 3]
        faces.append([(ax, y0, az), (bx, y0, bz), (bx, y1, bz), (ax, y1, az)])
    pos, nrm, idx = [], [], []
    for f in faces:
        e1 = [f[1][k] - f[0][k] for k in range(3)]
        e2 = [f[2][k] - f[0][k] for k in range(3)]
        n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
             e1[0] * e2[1] - e1[1] * e2[0]]
        if sum(n[k] * (f[0][k] - centre[k]) for k in range(3)) < 0:
            f, n = f[::-1], [-v for v in n]
        ln = math.sqrt(sum(v * v for v in n))
        base = len(pos)
        pos += f
        nrm += [[v / ln for v in n]] * len(f)
        idx += [base + k for k in ([0, 1, 2] if len(f) == 3 else [0, 1, 2, 0, 2, 3])]
    return pos, nrm, idx


def dispersion_scene():
    """Dispersive glass solids (KHR_materials_dispersion): a smooth 60° prism of index
    1.6 at dispersion 8 (Abbe number 2.5, red 1.48 to blue 1.72: far stronger than any
    glass), through which the camera sees a narrow upright lamp, out of view on the left,
    spread into its colours (red and blue some 20° apart), and which throws the lamp's
    spectrum on the floor; and a rough, slightly amber ball of index 1.5 at dispersion 2
    under a ceiling lamp."""
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    ceiling_lamp(b)
    strip = b.lambert((0, 0, 0), emission=(1, 1, 1), strength=40)
    b.node(mesh=b.quad((-1.8, 0.2, 2.02), (-1.8, 0.2, 1.98), (-1.8, 1.4, 1.98),
                       (-1.8, 1.4, 2.02), strip, uv=False))
    flint = b.solid_glass((1, 1, 1), 0.0, 1.6, dispersion=8.0)
    # The rays through it run at a heading of about 33° left of −z: the base lies
    # across them, toward the left (the way they bend).
    h = math.radians(33.5)
    along, base_dir = (-math.sin(h), -math.cos(h)), (-math.cos(h), math.sin(h))
    apex = (0.02 - 0.29 * base_dir[0], 1.8 - 0.29 * base_dir[1])
    pos, nrm, idx = prism_geometry(apex, base_dir, along, 0.5, 0.0, 1.1)
    b.node(mesh=b.mesh(pos, idx, flint, nrm))
    pos, idx = sphere_geometry(rings=8, segs=16)
    frosted = b.solid_glass((1, 0.9, 0.75), 0.35, 1.5, dispersion=2.0)
    b.node(mesh=b.mesh(pos, idx, frosted), translation=[0.7, 0.45, -0.3],
           scale=[0.45, 0.45, 0.45])
    eye = (0.3, 1.3, 3.4)
    b.node(camera=b.camera(yfov=0.8, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.5, -0.2)))
    b.write("dispersion.gltf")


def solid_pane_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    ceiling_lamp(b)
    amber = b.glass((0.9, 0.6, 0.3), 1.0)
    b.node(mesh=b.quad((-0.7, 1.7, -0.7), (0.7, 1.7, -0.7), (0.7, 1.7, 0.7), (-0.7, 1.7, 0.7),
                       amber, uv=False))
    murky = b.solid_glass((1, 1, 1), 0.0, 1.5, attenuation=((0.7, 0.7, 0.95), 0.9))
    b.node(mesh=b.box(murky), translation=[0.0, 0.8, 0.0], scale=[0.6, 0.6, 0.6])
    eye = (0.3, 1.3, 3.4)
    b.node(camera=b.camera(yfov=0.8, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.8, -0.2)))
    b.write("solid_pane.gltf")


def glossy_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    metal = b.pbr((0.9, 0.6, 0.3), 1.0, 0.4)
    plastic = b.pbr((0.2, 0.3, 0.8), 0.0, 0.3)
    b.node(mesh=b.box(metal), translation=[-0.6, 0.4, -0.3], scale=[0.8, 0.8, 0.8],
           rotation=[0, 0.3826834, 0, 0.9238795])
    b.node(mesh=b.box(plastic), translation=[0.7, 0.35, 0.2], scale=[0.7, 0.7, 0.7])
    sphere_room_light_and_camera(b)
    b.write("glossy.gltf")


def lit_emitters_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    # The glTF default base colour is white: emitters usually reflect.
    panel = b.lambert((0.9, 0.9, 0.9), emission=(1.0, 0.7, 0.4), strength=0.5)
    b.node(mesh=b.quad((-0.9, 0.6, -1.99), (-0.1, 0.6, -1.99), (-0.1, 1.2, -1.99),
                       (-0.9, 1.2, -1.99), panel))  # faces +Z, 1 cm before the wall
    b.point_light([0.7, 0.9, 1.0], 0.4, [-0.5, 0.9, -1.74])
    fin = b.lambert((0.3, 0.8, 0.5), emission=(0.4, 0.4, 1.0), strength=0.3, double_sided=True)
    b.node(mesh=b.quad((0.3, 0.0, -1.2), (0.9, 0.0, -0.9), (0.9, 0.7, -0.9), (0.3, 0.7, -1.2),
                       fin))
    down = [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)]  # −Z → −Y
    b.node(extensions={"KHR_lights_punctual": {"light": b.light(
        type="spot", color=[1, 0.9, 0.8], intensity=3.0,
        spot={"innerConeAngle": 0.3, "outerConeAngle": 0.6})}},
        translation=[0.6, 1.6, -0.8], rotation=down)
    eye = (0.0, 1.2, 2.2)
    b.node(camera=b.camera(yfov=0.7), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.6, -1.5)))
    b.write("lit_emitters.gltf")


def closed_emitters_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey, size=3.0)
    for i, (size, pos, axis, angle, rgb) in enumerate([
            (0.01, (-0.8, 1.5, -1.0), (1, 1, 0), 0.7, (1.0, 0.6, 0.3)),
            (0.02, (0.0, 2.5, -0.5), (0, 1, 1), 1.1, (0.4, 0.8, 1.0)),
            (0.03, (0.9, 2.0, -1.5), (1, 0, 1), 2.0, (0.9, 0.9, 0.6))]):
        n = math.sqrt(sum(a * a for a in axis))
        q = [a / n * math.sin(angle / 2) for a in axis] + [math.cos(angle / 2)]
        lamp = b.lambert((0.8, 0.8, 0.8), emission=rgb, strength=400.0 / (i + 1) ** 2)
        b.node(mesh=b.box(lamp), translation=list(pos), rotation=q, scale=[size] * 3)
    eye = (0.0, 1.6, 3.0)
    b.node(camera=b.camera(yfov=0.9), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 1.0, -1.0)))
    b.write("closed_emitters.gltf")


def uvsets_scene():
    b = Builder()
    W, K, R = (255, 255, 255), (0, 0, 0), (230, 40, 40)
    checker = b.texture(png_rgb(4, 4, [[W, K, R, W], [K, W, W, K], [R, K, W, R], [W, R, K, W]]),
                        nearest=True)

    def textured(set_):
        info = {"index": checker}
        if set_:
            info["texCoord"] = set_
        return info

    def quad(p, material, uv0, uv1):
        a = [p[1][i] - p[0][i] for i in range(3)]
        c = [p[2][i] - p[0][i] for i in range(3)]
        n = [a[1] * c[2] - a[2] * c[1], a[2] * c[0] - a[0] * c[2], a[0] * c[1] - a[1] * c[0]]
        ln = math.sqrt(sum(v * v for v in n))
        return b.mesh(list(p), [0, 1, 2, 0, 2, 3], material, [[v / ln for v in n]] * 4, uv0,
                      uvs1=uv1)

    one_texel = [(0.1, 0.1)] * 4
    floor = b.lambert((1, 1, 1))
    b.materials[floor]["pbrMetallicRoughness"]["baseColorTexture"] = textured(1)
    b.node(mesh=quad(((-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)), floor, one_texel,
                     [(0, 0), (2, 0), (2, 1.5), (0, 1.5)]))
    wall = b.lambert((0.9, 0.9, 0.9))
    b.materials[wall]["pbrMetallicRoughness"]["baseColorTexture"] = textured(0)
    b.node(mesh=quad(((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)), wall,
                     [(0, 0), (1, 0), (1, 1), (0, 1)], one_texel))
    panel = b.lambert((0.8, 0.8, 0.8), emission=(1, 1, 1), strength=2)
    b.materials[panel]["pbrMetallicRoughness"]["baseColorTexture"] = textured(1)
    b.materials[panel]["emissiveTexture"] = textured(1)
    b.node(mesh=quad(((-0.5, 0.6, -0.6), (0.5, 0.6, -0.6), (0.5, 1.4, -0.6), (-0.5, 1.4, -0.6)),
                     panel, one_texel, [(0, 0), (1, 0), (1, 1), (0, 1)]))
    sun_and_camera_over_the_panel(b)
    b.write("uvsets.gltf")


def layered(b, rgb, roughness, coat=None, sheen=None, specular=None):
    """A dielectric with KHR_materials_clearcoat (factor, roughness) and/or
    KHR_materials_sheen (colour, roughness) factors, and KHR_materials_specular."""
    m = {"pbrMetallicRoughness": {"baseColorFactor": list(rgb) + [1], "metallicFactor": 0.0,
                                  "roughnessFactor": roughness}, "extensions": {}}
    for ext, value in (("KHR_materials_specular", None if specular is None else
                        {"specularFactor": specular}),
                       ("KHR_materials_clearcoat", coat and
                        {"clearcoatFactor": coat[0], "clearcoatRoughnessFactor": coat[1]}),
                       ("KHR_materials_sheen", sheen and
                        {"sheenColorFactor": list(sheen[0]), "sheenRoughnessFactor": sheen[1]})):
        if value is not None:
            m["extensions"][ext] = value
    b.materials.append(m)
    b.uses(*m["extensions"])
    return len(b.materials) - 1


def coat_sheen_scene():
    """Clearcoats and sheens in a closed room under an area light and a point light: a
    white matte floor under a thin coat (no specular layer of its own), a blue wall under
    a white sheen and a full coat, an amber wall and box under a green sheen and a sharp
    coat."""
    b = Builder()
    white_coat = layered(b, (1, 1, 1), 1.0, coat=(0.5, 0.1), specular=0.0)
    blue = layered(b, (0.2, 0.4, 0.8), 0.7, coat=(1.0, 0.2), sheen=((0.9, 0.9, 0.9), 0.5))
    amber = layered(b, (0.7, 0.5, 0.2), 0.4, coat=(0.8, 0.05), sheen=((0.2, 0.8, 0.3), 0.3))
    grey = b.lambert((0.6, 0.6, 0.6))
    s = 1.5
    for corners, m in (([(-s, 0, s), (s, 0, s), (s, 0, -s), (-s, 0, -s)], white_coat),
                       ([(-s, 0, -s), (s, 0, -s), (s, 2 * s, -s), (-s, 2 * s, -s)], blue),
                       ([(-s, 0, s), (-s, 0, -s), (-s, 2 * s, -s), (-s, 2 * s, s)], grey),
                       ([(s, 0, -s), (s, 0, s), (s, 2 * s, s), (s, 2 * s, -s)], amber),
                       ([(-s, 2 * s, -s), (s, 2 * s, -s), (s, 2 * s, s), (-s, 2 * s, s)], grey)):
        b.node(mesh=b.quad(*corners, m))
    lamp = b.lambert((0.5, 0.5, 0.5), emission=(1, 0.95, 0.85), strength=6.0)
    y = 2 * s - 0.01
    b.node(mesh=b.quad((-0.4, y, 0.4), (0.4, y, 0.4), (0.4, y, -0.4), (-0.4, y, -0.4), lamp))
    b.point_light([1, 0.9, 0.8], 3.0, [0.8, 1.2, 0.9])
    b.node(mesh=b.box(amber), translation=[-0.4, 0.35, -0.2], scale=[0.7, 0.7, 0.7],
           rotation=[0, 0.3826834, 0, 0.9238795])
    eye = (0.3, 1.1, 3.2)
    b.node(camera=b.camera(yfov=0.9, aspect=4 / 3), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.6, -0.5)))
    b.write("coat_sheen.gltf")


def instanced_scene():
    """EXT_mesh_gpu_instancing: twelve lamps along a wave under a turned node (every
    fourth mirrored, which flips its winding) and five turned, stretched boxes. Also the
    source of tests/data/meshopt/instanced-cc-mi.glb."""
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey, size=3.0)
    lamp = b.lambert((0.8, 0.8, 0.8), emission=(1.0, 0.8, 0.5), strength=8.0)
    quad = b.quad((-0.05, 0, -0.05), (0.05, 0, -0.05), (0.05, 0, 0.05), (-0.05, 0, 0.05),
                  lamp, uv=False)  # faces -Y
    box = b.box(b.lambert((0.2, 0.7, 0.3)))

    def floats(values, typ, count):
        return b._acc(struct.pack("<%df" % len(values), *values), 5126, count, typ)

    n = 12
    t, r, s = [], [], []
    for i in range(n):
        x = -1.4 + 2.8 * i / (n - 1)
        t += [x, 0.15 * math.sin(3 * x), 0.0]
        a = 0.3 * math.sin(2 * i)
        r += [math.sin(a / 2), 0, 0, math.cos(a / 2)]
        s += [1.0 + 0.5 * (i % 3), 1.0, -1.0 if i % 4 == 1 else 1.0]
    b.node(mesh=quad, translation=[0, 1.7, -1.2], rotation=[0, 0.0871557, 0, 0.9961947],
           extensions={"EXT_mesh_gpu_instancing": {"attributes": {
               "TRANSLATION": floats(t, "VEC3", n), "ROTATION": floats(r, "VEC4", n),
               "SCALE": floats(s, "VEC3", n)}}})
    t, r, s = [], [], []
    for i in range(5):
        t += [-1.2 + 0.6 * i, 0.0, 0.3 * (i % 2)]
        r += [0, math.sin(0.2 * i), 0, math.cos(0.2 * i)]
        k = 0.15 + 0.05 * i
        s += [k, k * (1 + 0.3 * i), k]
    b.node(mesh=box, translation=[0, 0.001, -1.0],
           extensions={"EXT_mesh_gpu_instancing": {"attributes": {
               "TRANSLATION": floats(t, "VEC3", 5), "ROTATION": floats(r, "VEC4", 5),
               "SCALE": floats(s, "VEC3", 5)}}})
    b.required.append("EXT_mesh_gpu_instancing")
    eye = (0.0, 1.4, 2.6)
    b.node(camera=b.camera(yfov=0.9), translation=list(eye),
           rotation=look_at_rotation(eye, (0.0, 0.8, -1.0)))
    b.write("instanced.gltf")


def ies_text(vertical, horizontal, candela, multiplier=1.0):
    """An IES LM-63-2002 profile: candela[h][v] over the angles (degrees)."""
    lines = ["IESNA:LM-63-2002", "[TEST] lanterna tests/data/mitsuba/make_scenes.py",
             "[LUMINAIRE] test luminaire", "TILT=NONE",
             f"1 -1 {multiplier} {len(vertical)} {len(horizontal)} 1 2 0.1 0.1 0.05",
             "1.0 1.0 15"]
    lines.append(" ".join(f"{a:g}" for a in vertical))
    lines.append(" ".join(f"{a:g}" for a in horizontal))
    lines += [" ".join(f"{c:.4f}" for c in column) for column in candela]
    return "\n".join(lines) + "\n"


def ies_scene():
    b = Builder()
    grey = b.lambert((0.6, 0.6, 0.6))
    floor_and_wall(b, grey)
    b.node(mesh=b.box(b.lambert((0.8, 0.4, 0.2))), translation=[-0.5, 0.25, -0.3],
           scale=[0.5, 0.5, 0.5])
    # A round downlight with a narrow beam (0–90°, one horizontal angle), in a file.
    v = [5.0 * i for i in range(19)]
    down = ies_text(v, [0], [[0.5 + 2.5 * math.exp(-(a / 30.0) ** 2) for a in v]], 2.0)
    with open(os.path.join(HERE, "ies_downlight.ies"), "w") as f:
        f.write(down)
    # A wall washer: every horizontal angle, thrown toward 50° (from its +X toward its +Y:
    # the mirror turns it), in a buffer view.
    hv = [10.0 * i for i in range(10)]
    hh = [30.0 * i for i in range(13)]
    washer = ies_text(hv, hh, [[0.3 + 1.5 * (1 + math.cos(math.radians(h - 50))) * math.sin(math.radians(a)) ** 2
                                + 0.2 * math.cos(math.radians(a)) for a in hv] for h in hh])
    washer_view = b._view(washer.encode())
    # An uplight (90–180°, mirrored across its 0–180° plane), in a data URI.
    uv = [90.0 + 15.0 * i for i in range(7)]
    uh = [0.0, 45.0, 90.0, 135.0, 180.0]
    up = ies_text(uv, uh, [[0.2 + 0.8 * (1 + 0.5 * math.cos(math.radians(h))) * (a - 90.0) / 90.0
                            for a in uv] for h in uh])
    b.root_extensions["EXT_lights_ies"] = {"lights": [
        {"uri": "ies_downlight.ies", "name": "downlight"},
        {"bufferView": washer_view, "mimeType": "application/x-ies-lm-63", "name": "washer"},
        {"uri": "data:application/octet-stream;base64," + base64.b64encode(up.encode()).decode(),
         "name": "uplight"}]}
    b.uses("EXT_lights_ies")
    aim_down = [-math.sqrt(0.5), 0, 0, math.sqrt(0.5)]  # −Z → −Y
    b.node(translation=[-0.5, 1.9, -0.3], rotation=aim_down,
           extensions={"EXT_lights_ies": {"light": 0, "multiplier": 1.5}})
    # The washer near the wall, tilted toward it; its node mirrors y.
    tilt = [-0.56, 0.43, 0.43, 0.56]
    n = math.sqrt(sum(t * t for t in tilt))
    b.node(translation=[0.9, 1.6, -1.2], rotation=[t / n for t in tilt], scale=[1, -1, 1],
           extensions={"EXT_lights_ies": {"light": 1, "color": [1.0, 0.85, 0.6]}})
    b.node(translation=[0.6, 0.05, -1.7], rotation=aim_down,
           extensions={"EXT_lights_ies": {"light": 2, "multiplier": 3.0, "color": [0.6, 0.8, 1.0]}})
    eye = (0.4, 1.6, 3.2)
    b.node(camera=b.camera(yfov=0.8), translation=list(eye),
           rotation=look_at_rotation(eye, (0, 0.7, -0.8)))
    b.write("ies.gltf")


if __name__ == "__main__":
    tex_scene()
    tex16_scene()
    twosided_scene()
    punctual_scene()
    hierarchy_scene()
    texxform_scene()
    uvsets_scene()
    smooth_scene()
    glossy_scene()
    lit_emitters_scene()
    closed_emitters_scene()
    colors_scene()
    unlit_colors_scene()
    quantized_scene()
    glass_scene()
    solid_scene()
    dispersion_scene()
    solid_pane_scene()
    coat_sheen_scene()
    normal_map_scene()
    normal_map_scene(glossy=True)
    alpha_scene()
    anisotropy_scene()
    diffuse_transmission_scene()
    iridescence_scene()
    instanced_scene()
    ies_scene()
