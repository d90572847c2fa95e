//! glTF materials → the kernels' `Material`: metallic-roughness with
//! KHR_materials_specular / emissive_strength / ior / texture_transform / transmission /
//! volume / clearcoat / sheen / anisotropy, and KHR_materials_pbrSpecularGlossiness converted to
//! metallic-roughness.

use super::texture::{to_texels, TextureData, TextureKey};
use crate::gpu;
use crate::vk::{SamplerDesc, TextureFormat, WrapMode};
use std::collections::HashMap;

/// Collects the textures materials reference and assigns bindless slots.
pub struct TextureRegistry<'a> {
    pub images: &'a [Option<gltf::image::Data>],
    pub slots: HashMap<TextureKey, u32>,
    pub textures: Vec<TextureData>,
    pub warnings: Vec<String>,
}

fn sampler_desc(s: gltf::texture::Sampler<'_>) -> SamplerDesc {
    use gltf::texture::{MagFilter, WrappingMode as W};
    let wrap = |w: W| match w {
        W::Repeat => WrapMode::Repeat,
        W::MirroredRepeat => WrapMode::MirroredRepeat,
        W::ClampToEdge => WrapMode::ClampToEdge,
    };
    SamplerDesc {
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
        nearest: s.mag_filter() == Some(MagFilter::Nearest),
    }
}

impl TextureRegistry<'_> {
    /// A texture reference for `texture` read from UV set `tex_coord` with an optional
    /// KHR_texture_transform (raw JSON, so that every texture slot type is handled alike).
    fn reference(
        &mut self,
        texture: gltf::Texture<'_>,
        tex_coord: u32,
        transform: Option<&serde_json::Value>,
        format: TextureFormat,
    ) -> gpu::TextureRef {
        let image = texture.source().index();
        let key = TextureKey {
            image,
            format,
            sampler: sampler_desc(texture.sampler()),
        };
        let slot = match self.slots.get(&key) {
            Some(&s) => Some(s),
            None => match self
                .images
                .get(image)
                .and_then(|d| d.as_ref())
                .and_then(|d| to_texels(d).map(|p| (d, p)))
            {
                Some((data, texels)) => {
                    let slot = self.textures.len() as u32;
                    self.textures.push(TextureData {
                        name: texture
                            .source()
                            .name()
                            .map(str::to_string)
                            .unwrap_or_else(|| format!("image {image}")),
                        width: data.width,
                        height: data.height,
                        texels,
                        format,
                        sampler: key.sampler,
                    });
                    self.slots.insert(key, slot);
                    Some(slot)
                }
                None => None,
            },
        };
        let mut r = gpu::TextureRef {
            index: slot.map_or(-1, |s| s as i32),
            uv_set: tex_coord,
            offset: [0.0, 0.0],
            scale: [1.0, 1.0],
            rotation: 0.0,
        };
        if let Some(t) = transform {
            let pair = |v: Option<&serde_json::Value>, d: [f32; 2]| {
                v.and_then(|v| v.as_array())
                    .filter(|a| a.len() == 2)
                    .map(|a| {
                        [
                            a[0].as_f64().unwrap_or(d[0] as f64) as f32,
                            a[1].as_f64().unwrap_or(d[1] as f64) as f32,
                        ]
                    })
                    .unwrap_or(d)
            };
            r.offset = pair(t.get("offset"), [0.0, 0.0]);
            r.scale = pair(t.get("scale"), [1.0, 1.0]);
            r.rotation = t.get("rotation").and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
            if let Some(tc) = t.get("texCoord").and_then(|v| v.as_u64()) {
                r.uv_set = tc as u32;
            }
        }
        if r.uv_set > 1 {
            self.warnings.push(format!(
                "texture uses TEXCOORD_{}; only sets 0 and 1 are supported, using 0",
                r.uv_set
            ));
            r.uv_set = 0;
        }
        r
    }

    fn info(
        &mut self,
        info: Option<gltf::texture::Info<'_>>,
        format: TextureFormat,
    ) -> gpu::TextureRef {
        match info {
            Some(i) => {
                // The gltf crate parses KHR_texture_transform of texture infos into a typed
                // field (extension_value() then finds nothing); rebuild the JSON form the
                // rest of this file reads, as normal textures still provide it.
                let transform = i.texture_transform().map(|t| {
                    let mut v = serde_json::json!({
                        "offset": t.offset(),
                        "rotation": t.rotation(),
                        "scale": t.scale(),
                    });
                    if let Some(tc) = t.tex_coord() {
                        v["texCoord"] = tc.into();
                    }
                    v
                });
                self.reference(i.texture(), i.tex_coord(), transform.as_ref(), format)
            }
            None => no_texture(),
        }
    }
}

fn no_texture() -> gpu::TextureRef {
    gpu::TextureRef {
        index: -1,
        uv_set: 0,
        offset: [0.0, 0.0],
        scale: [1.0, 1.0],
        rotation: 0.0,
    }
}

/// glTF's default material (used by primitives without one).
pub fn default_material() -> gpu::Material {
    gpu::Material {
        base_color: [1.0; 4],
        emission: [0.0; 3],
        metallic: 1.0,
        roughness: 1.0,
        specular: 1.0,
        specular_color: [1.0; 3],
        normal_scale: 1.0,
        alpha_cutoff: 0.5,
        alpha_mode: gpu::ALPHA_MODE_OPAQUE,
        flags: 0,
        ior: 1.5,
        base_color_tex: no_texture(),
        metallic_roughness_tex: no_texture(),
        normal_tex: no_texture(),
        emissive_tex: no_texture(),
        transmission: 0.0,
        transmission_tex: no_texture(),
        attenuation: [0.0; 3],
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
        clearcoat_normal_scale: 1.0,
        clearcoat_tex: no_texture(),
        clearcoat_roughness_tex: no_texture(),
        clearcoat_normal_tex: no_texture(),
        sheen_color: [0.0; 3],
        sheen_roughness: 0.0,
        sheen_color_tex: no_texture(),
        sheen_roughness_tex: no_texture(),
        anisotropy_strength: 0.0,
        anisotropy_rotation: [1.0, 0.0],
        anisotropy_tex: no_texture(),
        diffuse_transmission: 0.0,
        diffuse_transmission_color: [1.0; 3],
        diffuse_transmission_tex: no_texture(),
        diffuse_transmission_color_tex: no_texture(),
        iridescence: 0.0,
        iridescence_ior: 1.3,
        iridescence_thickness_min: 100.0,
        iridescence_thickness_max: 400.0,
        iridescence_tex: no_texture(),
        iridescence_thickness_tex: no_texture(),
        dispersion: 0.0,
    }
}

/// The most radiance a material may emit (per channel, vertex colours included), eleven
/// orders of magnitude above the sun's disk (about 2·10⁹ cd/m²). A finite emission near
/// f32's limit (3.4·10³⁸) overflowed in the kernels to NaN samples; a file that asks for
/// more than this is broken, and is refused with its material named. Punctual lights'
/// intensity × colour has the same bound.
pub const MAX_EMISSION: f32 = 1e20;

/// The extension that asks for a surface shown in its base colour whatever the lighting.
pub const UNLIT: &str = "KHR_materials_unlit";

/// A `KHR_materials_unlit` material from the base colour (factor × texture × vertex
/// colour) and alpha that `read` holds; everything else of the PBR model is dropped, as
/// the extension says. A physically based renderer has no unlit shading, so the surface
/// emits its base colour as radiance and reflects nothing (black, no specular layer):
/// seen directly it is exactly that colour, it casts shadows, and, like any emitter, it
/// lights what it faces. The vertex colour (COLOR_0), which multiplies the base colour,
/// multiplies the emission here (`MATERIAL_FLAG_VERTEX_COLOR_EMISSION`; the kernels
/// interpolate it, the light table weighs each triangle by its corners' mean). Alpha
/// coverage and double-sidedness stay (the caller sets them); an emitter is one-sided
/// unless double-sided, as every emitter here.
fn unlit(read: &gpu::Material) -> gpu::Material {
    let [r, g, b, a] = read.base_color;
    gpu::Material {
        base_color: [0.0, 0.0, 0.0, a],
        base_color_tex: read.base_color_tex,
        emission: [r, g, b],
        emissive_tex: read.base_color_tex,
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        flags: gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION,
        ..default_material()
    }
}

/// Convert one glTF material of `doc`.
pub fn convert(
    m: &gltf::Material<'_>,
    doc: &gltf::Document,
    reg: &mut TextureRegistry<'_>,
) -> Result<gpu::Material, String> {
    let name = m
        .name()
        .map(str::to_string)
        .unwrap_or_else(|| format!("#{}", m.index().unwrap_or(0)));
    let mut out = default_material();
    let pbr = m.pbr_metallic_roughness();
    out.base_color = pbr.base_color_factor();
    out.metallic = pbr.metallic_factor();
    out.roughness = pbr.roughness_factor();
    out.base_color_tex = reg.info(pbr.base_color_texture(), TextureFormat::Srgb);
    // An unlit material ignores the rest of the PBR model: its textures are not loaded.
    let is_unlit = m.extension_value(UNLIT).is_some();
    if !is_unlit {
        out.metallic_roughness_tex =
            reg.info(pbr.metallic_roughness_texture(), TextureFormat::Linear);
    }

    if let Some(sg) = m.pbr_specular_glossiness() {
        let (base, metallic) =
            specular_glossiness_to_metallic(sg.diffuse_factor(), sg.specular_factor());
        out.base_color = base;
        out.metallic = metallic;
        out.roughness = 1.0 - sg.glossiness_factor();
        out.base_color_tex = reg.info(sg.diffuse_texture(), TextureFormat::Srgb);
        out.metallic_roughness_tex = no_texture();
        let mut note = format!(
            "material `{name}` uses KHR_materials_pbrSpecularGlossiness: converted to metallic-roughness"
        );
        if sg.specular_glossiness_texture().is_some() {
            note.push_str(" (its specular-glossiness texture is ignored; factors only)");
        }
        reg.warnings.push(note);
    }

    if is_unlit {
        out = unlit(&out);
    } else {
        read_shading(m, doc, reg, &name, &mut out)?;
    }

    out.alpha_cutoff = m.alpha_cutoff().unwrap_or(0.5);
    out.alpha_mode = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => gpu::ALPHA_MODE_OPAQUE,
        gltf::material::AlphaMode::Mask => gpu::ALPHA_MODE_MASK,
        gltf::material::AlphaMode::Blend => gpu::ALPHA_MODE_BLEND,
    };
    if m.double_sided() {
        out.flags |= gpu::MATERIAL_FLAG_DOUBLE_SIDED;
    }

    // Reject values that would poison the image.
    let scalars = [
        out.metallic,
        out.roughness,
        out.specular,
        out.normal_scale,
        out.alpha_cutoff,
        out.ior,
        out.transmission,
        out.clearcoat,
        out.clearcoat_roughness,
        out.clearcoat_normal_scale,
        out.sheen_roughness,
        out.anisotropy_strength,
        out.anisotropy_rotation[0],
        out.anisotropy_rotation[1],
        out.diffuse_transmission,
        out.iridescence,
    ];
    let finite = out
        .base_color
        .iter()
        .chain(&out.emission)
        .chain(&out.specular_color)
        .chain(&out.sheen_color)
        .chain(&out.diffuse_transmission_color)
        .chain(&scalars)
        .all(|v| v.is_finite());
    if !finite {
        return Err(format!(
            "material `{name}` has a non-finite (NaN or infinite) factor"
        ));
    }
    if let Some(e) = out.emission.iter().find(|&&c| c > MAX_EMISSION) {
        return Err(format!(
            "material `{name}` emits {e:e} (emissive factor × strength, or an unlit base \
             colour), above {MAX_EMISSION:e}: far beyond any physical radiance, where the \
             renderer's 32-bit arithmetic overflows"
        ));
    }
    if out.emission.iter().any(|&c| c < 0.0) || out.base_color.iter().any(|&c| c < 0.0) {
        return Err(format!(
            "material `{name}` has a negative colour or emission factor"
        ));
    }
    out.metallic = out.metallic.clamp(0.0, 1.0);
    out.roughness = out.roughness.clamp(0.0, 1.0);
    out.specular = out.specular.max(0.0);
    out.transmission = out.transmission.clamp(0.0, 1.0);
    out.clearcoat = out.clearcoat.clamp(0.0, 1.0);
    out.clearcoat_roughness = out.clearcoat_roughness.clamp(0.0, 1.0);
    out.sheen_color = out.sheen_color.map(|c| c.clamp(0.0, 1.0));
    out.sheen_roughness = out.sheen_roughness.clamp(0.0, 1.0);
    out.anisotropy_strength = out.anisotropy_strength.clamp(0.0, 1.0);
    out.diffuse_transmission = out.diffuse_transmission.clamp(0.0, 1.0);
    out.diffuse_transmission_color = out.diffuse_transmission_color.map(|c| c.clamp(0.0, 1.0));
    out.iridescence = out.iridescence.clamp(0.0, 1.0);
    Ok(out)
}

/// The shading a lit material adds to its base colour and metallic-roughness: the
/// KHR_materials_* layers, the normal map and the emission.
fn read_shading(
    m: &gltf::Material<'_>,
    doc: &gltf::Document,
    reg: &mut TextureRegistry<'_>,
    name: &str,
    out: &mut gpu::Material,
) -> Result<(), String> {
    if let Some(spec) = m.specular() {
        out.specular = spec.specular_factor();
        out.specular_color = spec.specular_color_factor();
        if spec.specular_texture().is_some() || spec.specular_color_texture().is_some() {
            reg.warnings.push(format!(
                "material `{name}`: KHR_materials_specular textures are ignored (factors used)"
            ));
        }
    }
    // Transmission: a thin wall, or with KHR_materials_volume and a thickness the boundary
    // of a refracting solid.
    if let Some(t) = m.transmission() {
        out.transmission = t.transmission_factor();
        out.transmission_tex = reg.info(t.transmission_texture(), TextureFormat::Linear);
    }
    if let Some(v) = m.extension_value("KHR_materials_volume") {
        read_volume(v, name, out)?;
    }
    if let Some(coat) = Clearcoat::read(m, doc)? {
        out.clearcoat = coat.factor;
        out.clearcoat_roughness = coat.roughness;
        let mut slot = |t: &Option<RawTexture<'_>>| match t {
            Some(t) => t.reference(reg, TextureFormat::Linear),
            None => no_texture(),
        };
        out.clearcoat_tex = slot(&coat.texture);
        out.clearcoat_roughness_tex = slot(&coat.roughness_texture);
        out.clearcoat_normal_tex = slot(&coat.normal_texture);
        if let Some(n) = &coat.normal_texture {
            out.clearcoat_normal_scale = n.scale;
        }
    }
    if let Some(sheen) = Sheen::read(m, doc)? {
        out.sheen_color = sheen.colour;
        out.sheen_roughness = sheen.roughness;
        if let Some(t) = &sheen.colour_texture {
            out.sheen_color_tex = t.reference(reg, TextureFormat::Srgb);
        }
        if let Some(t) = &sheen.roughness_texture {
            out.sheen_roughness_tex = t.reference(reg, TextureFormat::Linear);
        }
    }
    if let Some(a) = Anisotropy::read(m, doc)? {
        out.anisotropy_strength = a.strength;
        out.anisotropy_rotation = [a.rotation.cos(), a.rotation.sin()];
        if let Some(t) = &a.texture {
            out.anisotropy_tex = t.reference(reg, TextureFormat::Linear);
        }
    }
    if let Some(dt) = DiffuseTransmission::read(m, doc)? {
        out.diffuse_transmission = dt.factor;
        out.diffuse_transmission_color = dt.colour;
        if let Some(t) = &dt.texture {
            out.diffuse_transmission_tex = t.reference(reg, TextureFormat::Linear);
        }
        if let Some(t) = &dt.colour_texture {
            out.diffuse_transmission_color_tex = t.reference(reg, TextureFormat::Srgb);
        }
    }
    if let Some(i) = Iridescence::read(m, doc)? {
        out.iridescence = i.factor;
        out.iridescence_ior = i.ior;
        out.iridescence_thickness_min = i.thickness_min;
        out.iridescence_thickness_max = i.thickness_max;
        if let Some(t) = &i.texture {
            out.iridescence_tex = t.reference(reg, TextureFormat::Linear);
        }
        if let Some(t) = &i.thickness_texture {
            out.iridescence_thickness_tex = t.reference(reg, TextureFormat::Linear);
        }
    }
    out.dispersion = read_dispersion(m, doc)?;
    if out.dispersion > 0.0 && !bounds_solid(out) {
        reg.warnings.push(format!(
            "material `{name}`: KHR_materials_dispersion has no effect, the material bounds no \
             solid (KHR_materials_volume with a thickness, and transmission)"
        ));
    }
    if let Some(ior) = m
        .extension_value("KHR_materials_ior")
        .and_then(|v| v.get("ior"))
        .and_then(|v| v.as_f64())
    {
        out.ior = ior as f32;
    }

    if let Some(n) = m.normal_texture() {
        let transform = n.extension_value("KHR_texture_transform").cloned();
        out.normal_tex = reg.reference(
            n.texture(),
            n.tex_coord(),
            transform.as_ref(),
            TextureFormat::Linear,
        );
        out.normal_scale = n.scale();
    }

    let strength = m.emissive_strength();
    let factor = m.emissive_factor();
    if strength.is_none() && factor.iter().any(|&c| c > 1.0) {
        reg.warnings.push(format!(
            "material `{name}`: emissiveFactor {factor:?} exceeds 1 without KHR_materials_emissive_strength \
             (not glTF-conformant); accepted as given"
        ));
    }
    let strength = strength.unwrap_or(1.0);
    out.emission = factor.map(|c| c * strength);
    out.emissive_tex = reg.info(m.emissive_texture(), TextureFormat::Srgb);
    if out.clearcoat > 0.0 && out.emission.iter().any(|&e| e > 0.0) {
        reg.warnings.push(format!(
            "material `{name}`: its emission is not darkened by its clearcoat's Fresnel term \
             (the glTF spec's 1 − clearcoat·F: 4 % at normal incidence, more at grazing angles)"
        ));
    }

    Ok(())
}

/// A texture slot of an extension the gltf crate has no typed access to
/// (KHR_materials_clearcoat, KHR_materials_sheen), read from the extension's JSON.
pub struct RawTexture<'a> {
    pub texture: gltf::Texture<'a>,
    tex_coord: u32,
    transform: Option<serde_json::Value>,
    scale: f32,
}

impl RawTexture<'_> {
    fn reference(&self, reg: &mut TextureRegistry<'_>, format: TextureFormat) -> gpu::TextureRef {
        reg.reference(
            self.texture.clone(),
            self.tex_coord,
            self.transform.as_ref(),
            format,
        )
    }
}

/// Reads an extension's JSON `v` for one material: its numbers and texture slots, with
/// errors naming the material and the extension.
struct ExtensionReader<'a, 'v> {
    v: &'v serde_json::Value,
    doc: &'a gltf::Document,
    what: String,
}

impl<'a> ExtensionReader<'a, '_> {
    /// The reader of material `m`'s `extension`, or None where it has none.
    fn of<'v>(
        m: &'v gltf::Material<'_>,
        doc: &'a gltf::Document,
        extension: &str,
    ) -> Option<ExtensionReader<'a, 'v>> {
        let v = m.extension_value(extension)?;
        let name = m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("#{}", m.index().unwrap_or(0)));
        Some(ExtensionReader {
            v,
            doc,
            what: format!("material `{name}`: {extension}"),
        })
    }

    fn bad(&self, what: String) -> String {
        format!("{} {what}", self.what)
    }

    fn number(&self, key: &str, default: f32) -> Result<f32, String> {
        match self.v.get(key) {
            None => Ok(default),
            Some(x) => x
                .as_f64()
                .filter(|x| x.is_finite())
                .map(|x| x as f32)
                .ok_or_else(|| self.bad(format!("{key} is not a finite number"))),
        }
    }

    fn colour(&self, key: &str, default: [f32; 3]) -> Result<[f32; 3], String> {
        match self.v.get(key) {
            None => Ok(default),
            Some(c) => c
                .as_array()
                .filter(|a| a.len() == 3)
                .and_then(|a| {
                    a.iter()
                        .map(|x| x.as_f64().filter(|x| x.is_finite()).map(|x| x as f32))
                        .collect::<Option<Vec<f32>>>()
                })
                .map(|p| [p[0], p[1], p[2]])
                .ok_or_else(|| self.bad(format!("{key} must be three finite numbers"))),
        }
    }

    fn texture(&self, key: &str) -> Result<Option<RawTexture<'a>>, String> {
        let Some(info) = self.v.get(key) else {
            return Ok(None);
        };
        let index = info
            .get("index")
            .and_then(|i| i.as_u64())
            .ok_or_else(|| self.bad(format!("{key} has no texture index")))?;
        let texture = usize::try_from(index)
            .ok()
            .and_then(|i| self.doc.textures().nth(i))
            .ok_or_else(|| {
                self.bad(format!(
                    "{key} refers to texture {index}, which does not exist"
                ))
            })?;
        let tex_coord = match info.get("texCoord") {
            None => 0,
            Some(t) => t
                .as_u64()
                .and_then(|t| u32::try_from(t).ok())
                .ok_or_else(|| self.bad(format!("{key} texCoord is not a small integer")))?,
        };
        let scale = match info.get("scale") {
            None => 1.0,
            Some(x) => x
                .as_f64()
                .filter(|x| x.is_finite())
                .map(|x| x as f32)
                .ok_or_else(|| self.bad(format!("{key} scale is not a finite number")))?,
        };
        Ok(Some(RawTexture {
            texture,
            tex_coord,
            transform: info
                .get("extensions")
                .and_then(|e| e.get("KHR_texture_transform"))
                .cloned(),
            scale,
        }))
    }
}

/// KHR_materials_clearcoat of one material.
pub struct Clearcoat<'a> {
    factor: f32,
    roughness: f32,
    pub texture: Option<RawTexture<'a>>,
    pub roughness_texture: Option<RawTexture<'a>>,
    pub normal_texture: Option<RawTexture<'a>>,
}

impl<'a> Clearcoat<'a> {
    /// The material's coat, if it has the extension; malformed values and texture
    /// references are errors naming the material.
    pub fn read(m: &gltf::Material<'_>, doc: &'a gltf::Document) -> Result<Option<Self>, String> {
        const NAME: &str = "KHR_materials_clearcoat";
        let Some(r) = ExtensionReader::of(m, doc, NAME) else {
            return Ok(None);
        };
        Ok(Some(Clearcoat {
            factor: r.number("clearcoatFactor", 0.0)?,
            roughness: r.number("clearcoatRoughnessFactor", 0.0)?,
            texture: r.texture("clearcoatTexture")?,
            roughness_texture: r.texture("clearcoatRoughnessTexture")?,
            normal_texture: r.texture("clearcoatNormalTexture")?,
        }))
    }
}

/// KHR_materials_sheen of one material.
pub struct Sheen<'a> {
    colour: [f32; 3],
    roughness: f32,
    pub colour_texture: Option<RawTexture<'a>>,
    pub roughness_texture: Option<RawTexture<'a>>,
}

impl<'a> Sheen<'a> {
    /// The material's sheen, if it has the extension; malformed values and texture
    /// references are errors naming the material.
    pub fn read(m: &gltf::Material<'_>, doc: &'a gltf::Document) -> Result<Option<Self>, String> {
        const NAME: &str = "KHR_materials_sheen";
        let Some(r) = ExtensionReader::of(m, doc, NAME) else {
            return Ok(None);
        };
        Ok(Some(Sheen {
            colour: r.colour("sheenColorFactor", [0.0; 3])?,
            roughness: r.number("sheenRoughnessFactor", 0.0)?,
            colour_texture: r.texture("sheenColorTexture")?,
            roughness_texture: r.texture("sheenRoughnessTexture")?,
        }))
    }
}

/// KHR_materials_anisotropy of one material.
pub struct Anisotropy<'a> {
    strength: f32,
    /// Radians, counter-clockwise from the tangent toward the bitangent.
    rotation: f32,
    pub texture: Option<RawTexture<'a>>,
}

impl<'a> Anisotropy<'a> {
    /// The material's anisotropy, if it has the extension; malformed values and texture
    /// references are errors naming the material.
    pub fn read(m: &gltf::Material<'_>, doc: &'a gltf::Document) -> Result<Option<Self>, String> {
        const NAME: &str = "KHR_materials_anisotropy";
        let Some(r) = ExtensionReader::of(m, doc, NAME) else {
            return Ok(None);
        };
        Ok(Some(Anisotropy {
            strength: r.number("anisotropyStrength", 0.0)?,
            rotation: r.number("anisotropyRotation", 0.0)?,
            texture: r.texture("anisotropyTexture")?,
        }))
    }
}

/// KHR_materials_diffuse_transmission of one material.
pub struct DiffuseTransmission<'a> {
    factor: f32,
    colour: [f32; 3],
    pub texture: Option<RawTexture<'a>>,
    pub colour_texture: Option<RawTexture<'a>>,
}

impl<'a> DiffuseTransmission<'a> {
    /// The material's diffuse transmission, if it has the extension; malformed values and
    /// texture references are errors naming the material.
    pub fn read(m: &gltf::Material<'_>, doc: &'a gltf::Document) -> Result<Option<Self>, String> {
        const NAME: &str = "KHR_materials_diffuse_transmission";
        let Some(r) = ExtensionReader::of(m, doc, NAME) else {
            return Ok(None);
        };
        Ok(Some(DiffuseTransmission {
            factor: r.number("diffuseTransmissionFactor", 0.0)?,
            colour: r.colour("diffuseTransmissionColorFactor", [1.0; 3])?,
            texture: r.texture("diffuseTransmissionTexture")?,
            colour_texture: r.texture("diffuseTransmissionColorTexture")?,
        }))
    }
}

/// KHR_materials_iridescence of one material.
pub struct Iridescence<'a> {
    factor: f32,
    ior: f32,
    thickness_min: f32,
    thickness_max: f32,
    pub texture: Option<RawTexture<'a>>,
    pub thickness_texture: Option<RawTexture<'a>>,
}

impl<'a> Iridescence<'a> {
    /// The material's thin film, if it has the extension; malformed values (non-finite
    /// numbers, an index below 1, a negative thickness: the extension's schema) and
    /// texture references are errors naming the material.
    pub fn read(m: &gltf::Material<'_>, doc: &'a gltf::Document) -> Result<Option<Self>, String> {
        const NAME: &str = "KHR_materials_iridescence";
        let Some(r) = ExtensionReader::of(m, doc, NAME) else {
            return Ok(None);
        };
        let ior = r.number("iridescenceIor", 1.3)?;
        if ior < 1.0 {
            return Err(r.bad(format!("iridescenceIor {ior} is below 1")));
        }
        let thickness = |key: &str, default: f32| -> Result<f32, String> {
            let t = r.number(key, default)?;
            if t < 0.0 {
                return Err(r.bad(format!("{key} {t} is negative")));
            }
            Ok(t)
        };
        Ok(Some(Iridescence {
            factor: r.number("iridescenceFactor", 0.0)?,
            ior,
            thickness_min: thickness("iridescenceThicknessMinimum", 100.0)?,
            thickness_max: thickness("iridescenceThicknessMaximum", 400.0)?,
            texture: r.texture("iridescenceTexture")?,
            thickness_texture: r.texture("iridescenceThicknessTexture")?,
        }))
    }
}

/// KHR_materials_dispersion's `dispersion` (20 / the Abbe number; 0 where the material
/// has none). The schema allows any number from 0: a negative or non-finite one (in
/// single precision too) is an error naming the material. It matters only on a solid's
/// boundary (KHR_materials_volume), where the kernels refract each colour channel with
/// its own index.
pub fn read_dispersion(m: &gltf::Material<'_>, doc: &gltf::Document) -> Result<f32, String> {
    let Some(r) = ExtensionReader::of(m, doc, "KHR_materials_dispersion") else {
        return Ok(0.0);
    };
    let dispersion = r.number("dispersion", 0.0)?;
    if !dispersion.is_finite() || dispersion < 0.0 {
        return Err(r.bad(format!(
            "dispersion {dispersion} is not a finite number of at least 0"
        )));
    }
    Ok(dispersion)
}

/// The red, green and blue indices of a solid of index `ior` and KHR_materials_dispersion
/// `dispersion`, by the extension's recipe for RGB renderers: the index n spreads to
/// n ∓ (n − 1)·0.025·dispersion (half its spread between the Fraunhofer C and F lines,
/// (n − 1)/V, for Abbe number V = 20 / dispersion), none below 1. The kernels take the
/// same (`interface_etas`, inc/bsdf.glsl); the Mitsuba export writes them out.
pub fn dispersion_iors(ior: f32, dispersion: f32) -> [f32; 3] {
    let half_spread = (ior - 1.0) * 0.025 * dispersion;
    [ior - half_spread, ior, ior + half_spread].map(|n| n.max(1.0))
}

/// Whether a material bounds a solid (KHR_materials_volume with a thickness, and a
/// transmission or diffuse transmission factor: light goes into it, refracted or
/// diffusely): what the kernels' SOLIDS constant, `lanterna info` and the Mitsuba export
/// ask. (A metallic texture may still make parts of it opaque.)
pub fn bounds_solid(m: &gpu::Material) -> bool {
    (m.transmission > 0.0 || m.diffuse_transmission > 0.0)
        && m.flags & gpu::MATERIAL_FLAG_VOLUME != 0
}

/// Whether a material's dispersion acts: KHR_materials_dispersion above 0 on a material
/// that bounds a solid (the kernels' DISPERSION constant, `lanterna info`).
pub fn disperses(m: &gpu::Material) -> bool {
    m.dispersion > 0.0 && bounds_solid(m)
}

/// Whether a material's BSDF is the Lambertian lobe alone, whatever its textures: no
/// metal (the factor, which its texture only scales, at 0), no specular lobe
/// (KHR_materials_specular's factor 0, which takes the dielectric's F0 and F90 to 0), no
/// transmission (specular or diffuse), coat, sheen or thin film (KHR_materials_iridescence,
/// whose film reflects whatever the specular factor). The kernels compare these factors
/// with 0 the same way (inc/material.glsl), and `Scene::only_lambertian` asks this of
/// every material in use.
pub fn is_lambertian(m: &gpu::Material) -> bool {
    m.metallic <= 0.0
        && m.specular == 0.0
        && m.transmission <= 0.0
        && m.diffuse_transmission <= 0.0
        && m.iridescence <= 0.0
        && m.clearcoat <= 0.0
        && m.sheen_color.iter().all(|&c| c <= 0.0)
}

/// KHR_materials_volume: a thickness above 0 makes a transmitting surface the boundary of
/// a solid (the spec's thin-walled case is thickness 0, its default); the solid absorbs
/// with σ = −ln(attenuationColor) / attenuationDistance per world unit (none when the
/// distance is absent, i.e. infinite). The thickness itself (and its texture) only serves
/// rasterisers that do not trace the solid, so a path tracer ignores its value.
fn read_volume(v: &serde_json::Value, name: &str, out: &mut gpu::Material) -> Result<(), String> {
    let number = |key: &str| -> Result<Option<f64>, String> {
        match v.get(key) {
            None => Ok(None),
            Some(x) => x
                .as_f64()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| {
                    format!("material `{name}`: KHR_materials_volume {key} is not a finite number")
                }),
        }
    };
    let thickness = number("thicknessFactor")?.unwrap_or(0.0);
    if thickness < 0.0 {
        return Err(format!(
            "material `{name}`: KHR_materials_volume thicknessFactor {thickness} is negative"
        ));
    }
    let distance = number("attenuationDistance")?;
    if let Some(d) = distance {
        if d <= 0.0 {
            return Err(format!(
                "material `{name}`: KHR_materials_volume attenuationDistance {d} must be positive"
            ));
        }
    }
    let colour = match v.get("attenuationColor") {
        None => [1.0f32; 3],
        Some(c) => {
            let parts: Option<Vec<f32>> = c.as_array().filter(|a| a.len() == 3).and_then(|a| {
                a.iter()
                    .map(|x| x.as_f64().filter(|x| x.is_finite()).map(|x| x as f32))
                    .collect()
            });
            match parts {
                Some(p) if p.iter().all(|&x| (0.0..=1.0).contains(&x)) => [p[0], p[1], p[2]],
                _ => {
                    return Err(format!(
                        "material `{name}`: KHR_materials_volume attenuationColor must be three numbers in [0, 1]"
                    ))
                }
            }
        }
    };
    if thickness <= 0.0 {
        return Ok(());
    }
    out.flags |= gpu::MATERIAL_FLAG_VOLUME;
    if let Some(d) = distance {
        // A channel of colour 0 absorbs everything: a large finite σ keeps exp(−σ·t)
        // a clean 0 beyond a few thousandths of the distance, without infinities.
        out.attenuation = colour.map(|c| (-(c.max(1e-30)).ln() / d as f32).min(1e30));
    }
    Ok(())
}

/// The usual specular-glossiness → metallic-roughness conversion: solve for the metallic
/// value that reproduces the specular reflectance given a dielectric F0 of 0.04, then
/// blend the base colour between the diffuse- and specular-derived estimates.
fn specular_glossiness_to_metallic(diffuse: [f32; 4], specular: [f32; 3]) -> ([f32; 4], f32) {
    const DIELECTRIC: f32 = 0.04;
    let brightness =
        |c: [f32; 3]| (0.299 * c[0] * c[0] + 0.587 * c[1] * c[1] + 0.114 * c[2] * c[2]).sqrt();
    let d = [diffuse[0], diffuse[1], diffuse[2]];
    let max_spec = specular[0].max(specular[1]).max(specular[2]);
    let pd = brightness(d);
    let ps = brightness(specular);
    let metallic = if ps < DIELECTRIC {
        0.0
    } else {
        let a = DIELECTRIC;
        let b = pd * (1.0 - max_spec) / (1.0 - DIELECTRIC) + ps - 2.0 * DIELECTRIC;
        let c = DIELECTRIC - ps;
        let disc = (b * b - 4.0 * a * c).max(0.0);
        ((-b + disc.sqrt()) / (2.0 * a)).clamp(0.0, 1.0)
    };
    let from_diffuse =
        d.map(|c| c * (1.0 - max_spec) / (1.0 - DIELECTRIC) / (1.0 - metallic).max(1e-4));
    let from_specular = specular.map(|c| (c - DIELECTRIC * (1.0 - metallic)) / metallic.max(1e-4));
    let t = metallic * metallic;
    let base = std::array::from_fn::<f32, 3, _>(|i| {
        (from_diffuse[i] + (from_specular[i] - from_diffuse[i]) * t).clamp(0.0, 1.0)
    });
    ([base[0], base[1], base[2], diffuse[3]], metallic)
}
