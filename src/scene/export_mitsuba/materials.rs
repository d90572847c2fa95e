//! Materials and textures: glTF materials as Mitsuba BSDFs (exact `diffuse` for
//! Lambertian ones, `principled` otherwise; KHR_materials_transmission as a blend with
//! `thindielectric`, exact for smooth glass without Fresnel reflection; with
//! KHR_materials_volume as `roughdielectric`, exact for glass through and through, its
//! absorption as an interior `homogeneous` medium), base colour and
//! emission as constants or bitmaps (8- or 16-bit sRGB PNG, or linear PFM
//! with the factor baked in).

use super::files::{self, PlyMesh};
use super::geometry::UvPlan;
use super::textures::{average_colour, linear_texels};
use super::uv_cover;
use super::writer::Writer;
use super::xml::{bitmap_xml, bsdf_id, is_identity, is_solid, rgb_xml, uv_matrix, xml_escape};
use super::ExportError;
use crate::gpu;
use crate::scene::TextureData;
use crate::vk::{Texels, TextureFormat};
use glam::Mat3;
use std::fmt::Write as _;

/// How many texels the cut of a bilinearly filtered MASK may have in the export.
const MASK_CUT_TEXELS: f64 = 4.0 * 1024.0 * 1024.0;

impl Writer<'_> {
    /// Which UV set the PLY of a material carries, which transform is baked in, and
    /// whether its normal map goes out (see [`Self::normal_map_exportable`]).
    pub(super) fn uv_plan(&mut self, m: u32) -> UvPlan {
        let mat = &self.scene.materials[m as usize];
        let emissive = mat.emissive_tex.index >= 0 && mat.emission.iter().any(|&c| c > 0.0);
        let base = mat.base_color_tex.index >= 0;
        let mut plan = if emissive {
            let bake = (!is_identity(&mat.emissive_tex)).then_some(mat.emissive_tex);
            UvPlan {
                set: Some(mat.emissive_tex.uv_set),
                bake,
                normal: false,
                frame: false,
            }
        } else if base {
            UvPlan {
                set: Some(mat.base_color_tex.uv_set),
                bake: None,
                normal: false,
                frame: false,
            }
        } else {
            UvPlan {
                set: None,
                bake: None,
                normal: false,
                frame: false,
            }
        };
        if mat.normal_tex.index >= 0 {
            match self.normal_map_exportable(m, plan) {
                Ok(()) => {
                    plan.set = Some(mat.normal_tex.uv_set);
                    plan.normal = true;
                    plan.frame = true;
                }
                Err(why) => self.approximations.push(format!(
                    "material `{}`: its normal texture is not exported ({why})",
                    self.material_name(m)
                )),
            }
        }
        if mat.anisotropy_strength > 0.0 && !crate::scene::is_lambertian(mat) {
            // Only the glTF BSDF plugin reads the anisotropy (from the glTF file), in the
            // frame of the PLY's UVs; `principled` stays isotropic.
            let set = if mat.anisotropy_tex.index >= 0 {
                mat.anisotropy_tex.uv_set
            } else if mat.normal_tex.index >= 0 {
                mat.normal_tex.uv_set
            } else {
                0
            };
            match self.frame_exportable(m, plan, set) {
                Ok(()) => {
                    plan.set = Some(set);
                    plan.frame = true;
                }
                Err(why) => self.approximations.push(format!(
                    "material `{}`: its anisotropy's frame is not exported ({why})",
                    self.material_name(m)
                )),
            }
        }
        plan
    }

    /// Whether a tangent frame of material `m` (its anisotropy's, its normal map's) can
    /// reach Mitsuba through the PLY's coordinates of UV set `set`, given the UVs `plan`
    /// already writes: Mitsuba takes the frame from them (∂P/∂u, its bitangent
    /// cross(n, ∂P/∂u)), so they must be that set, untransformed; the frame from a
    /// TANGENT attribute is lanterna's alone.
    fn frame_exportable(&self, m: u32, plan: UvPlan, set: u32) -> Result<(), &'static str> {
        if plan.set.is_some_and(|s| s != set) {
            return Err("another texture of the material uses another UV set");
        }
        if plan.bake.is_some() {
            return Err("the PLY's coordinates carry the emissive texture's transform");
        }
        if self.has_tangents(m) {
            return Err(
                "its meshes have TANGENT attributes; Mitsuba derives tangents from the UVs",
            );
        }
        Ok(())
    }

    /// Whether some mesh of material `m` has a TANGENT attribute.
    fn has_tangents(&self, m: u32) -> bool {
        self.scene.primitives.iter().any(|p| {
            p.material == m
                && self.scene.vertices[p.vertex_offset as usize..][..p.vertex_count as usize]
                    .iter()
                    .any(|v| v.tangent[..3] != [0.0; 3])
        })
    }

    /// Whether material `m`'s normal map can go out as Mitsuba's `normalmap` around the
    /// opaque BSDF, given the UVs `plan` already writes: its frame must reach Mitsuba
    /// ([`Self::frame_exportable`] for the normal texture's set), and the material must
    /// be opaque.
    fn normal_map_exportable(&self, m: u32, plan: UvPlan) -> Result<(), &'static str> {
        let mat = &self.scene.materials[m as usize];
        if (mat.transmission > 0.0 || mat.diffuse_transmission > 0.0) && mat.metallic < 1.0 {
            return Err("transmitting materials keep their geometric frame in the export");
        }
        self.frame_exportable(m, plan, mat.normal_tex.uv_set)
    }

    /// The BSDF of material `m`; with `vertex_colors`, its base colour is the meshes'
    /// `vertex_color` attribute (the factor baked in, see `append_instance`); with
    /// `mirrored_uvs`, for triangles whose UVs are mirrored (see `GroupKey`). A material
    /// with alpha goes out inside Mitsuba's `mask` (see [`Self::opacity_xml`]): a hit
    /// reflects with probability `opacity` and passes straight on otherwise, as
    /// lanterna's alpha test keeps or skips it, and shadow rays (through `volpath`) pass
    /// with 1 − opacity, as lanterna's do.
    pub(super) fn bsdf_xml(
        &mut self,
        m: u32,
        plan: UvPlan,
        vertex_colors: bool,
        mirrored_uvs: bool,
    ) -> Result<String, ExportError> {
        let mat =
            *self.scene.materials.get(m as usize).ok_or_else(|| {
                ExportError::Invalid(format!("material index {m} is out of range"))
            })?;
        let opacity = self.opacity_xml(m, &mat, plan, vertex_colors)?;
        let bsdf = self.opaque_bsdf_xml(m, &mat, plan, vertex_colors, mirrored_uvs)?;
        let Some(opacity) = opacity else {
            return Ok(bsdf);
        };
        // The material's comment line, then the BSDF inside the mask, without its id.
        let id = bsdf_id(m, vertex_colors, mirrored_uvs);
        let (comment, inner) = bsdf.split_once('\n').unwrap_or(("", &bsdf));
        let inner = inner.replacen(&format!(" id=\"{id}\""), "", 1);
        Ok(format!(
            "{comment}\n  <bsdf type=\"mask\" id=\"{id}\">\n{opacity}{inner}  </bsdf>\n"
        ))
    }

    /// [`Self::bsdf_xml`] without the material's alpha.
    fn opaque_bsdf_xml(
        &mut self,
        m: u32,
        mat: &gpu::Material,
        plan: UvPlan,
        vertex_colors: bool,
        mirrored_uvs: bool,
    ) -> Result<String, ExportError> {
        let id = bsdf_id(m, vertex_colors, mirrored_uvs);
        let mat = *mat;
        let name = self.material_name(m).to_string();
        // An unlit material's vertex colours tint its emission (see `radiance_xml`); its
        // base colour is black.
        let colour = if vertex_colors && mat.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION == 0 {
            "      <texture type=\"mesh_attribute\" name=\"reflectance\">\n        <string name=\"name\" value=\"vertex_color\"/>\n      </texture>\n".to_string()
        } else {
            self.base_colour_xml(m, &mat, plan, "reflectance")?
        };
        let mut s = String::new();
        let _ = writeln!(s, "  <!-- material `{}` -->", xml_escape(&name));
        if mat.diffuse_transmission > 0.0 && mat.metallic < 1.0 {
            self.approximations.push(format!(
                "material `{name}`: its diffuse transmission (factor {}) is left out: Mitsuba has no diffuse BTDF (the glTF BSDF plugin of scripts/mitsuba_gltf_layers.py renders it)",
                mat.diffuse_transmission
            ));
        }
        if mat.iridescence > 0.0 {
            self.approximations.push(format!(
                "material `{name}`: its iridescence (factor {}) is left out: Mitsuba has no thin-film Fresnel term (the glTF BSDF plugin of scripts/mitsuba_gltf_bsdf.py renders it)",
                mat.iridescence
            ));
        }
        let transmits = mat.transmission > 0.0 && mat.metallic < 1.0;
        let solid = transmits && is_solid(&mat);
        // A constant transmittance, which a dispersive interface splits by channel.
        let constant = (!vertex_colors && mat.base_color_tex.index < 0)
            .then(|| std::array::from_fn(|c| mat.base_color[c].clamp(0.0, 1.0)));
        let share = (1.0 - mat.metallic) * mat.transmission.min(1.0);
        if solid && share >= 1.0 {
            // Clear or tinted glass through and through: exactly `roughdielectric`.
            s.push_str(&self.solid_glass_xml(m, &mat, &colour, constant, Some(&id)));
            return Ok(s);
        }
        if transmits {
            // The reflecting part stays two-sided inside the blend (Mitsuba's `twosided`
            // refuses transmitting BSDFs; `thindielectric` is symmetric already).
            let _ = writeln!(s, "  <bsdf type=\"blendbsdf\" id=\"{id}\">");
            let _ = writeln!(
                s,
                "    <float name=\"weight\" value=\"{}\"/>",
                if solid {
                    share
                } else {
                    mat.transmission.min(1.0)
                }
            );
            s.push_str("  <bsdf type=\"twosided\">\n");
        } else if plan.normal {
            // Mitsuba's `normalmap` around the two-sided BSDF, so that a view from below
            // the mapped normal sees its other side, as in lanterna; without its flip of
            // such normals and its shadowing term, which lanterna does not have.
            let _ = writeln!(s, "  <bsdf type=\"normalmap\" id=\"{id}\">");
            s.push_str("  <boolean name=\"flip_invalid_normals\" value=\"false\"/>\n");
            s.push_str("  <boolean name=\"use_shadowing_function\" value=\"false\"/>\n");
            s.push_str(&self.normal_map_xml(&mat, mirrored_uvs)?);
            s.push_str("  <bsdf type=\"twosided\">\n");
        } else {
            let _ = writeln!(s, "  <bsdf type=\"twosided\" id=\"{id}\">");
        }
        // glTF with specularFactor 0 and metallic 0 is exactly Lambertian (albedo/π).
        let sheen = mat.sheen_color.iter().cloned().fold(0.0, f32::max);
        if mat.specular == 0.0
            && mat.metallic == 0.0
            && mat.clearcoat == 0.0
            && sheen == 0.0
            && mat.iridescence == 0.0
        {
            s.push_str("    <bsdf type=\"diffuse\">\n");
            s.push_str(&colour);
            s.push_str("    </bsdf>\n");
        } else {
            self.approximations.push(format!(
                "material `{name}`: glTF metallic-roughness (metallic {}, roughness {}, specular {}) approximated by Mitsuba's `principled`",
                mat.metallic, mat.roughness, mat.specular
            ));
            if mat.metallic_roughness_tex.index >= 0 {
                self.approximations.push(format!(
                    "material `{name}`: metallic-roughness texture not exported (factors used)"
                ));
            }
            let colour = colour.replace("\"reflectance\"", "\"base_color\"");
            let f0 = ((mat.ior - 1.0) / (mat.ior + 1.0)).powi(2)
                * mat.specular
                * mat.specular_color.iter().cloned().fold(0.0, f32::max);
            s.push_str("    <bsdf type=\"principled\">\n");
            s.push_str(&colour.replace("\n      ", "\n        "));
            let _ = writeln!(
                s,
                "      <float name=\"metallic\" value=\"{}\"/>",
                mat.metallic
            );
            let _ = writeln!(
                s,
                "      <float name=\"roughness\" value=\"{}\"/>",
                mat.roughness
            );
            // Mitsuba: F0 = 0.08 · specular for dielectrics.
            let _ = writeln!(
                s,
                "      <float name=\"specular\" value=\"{}\"/>",
                (f0 / 0.08).clamp(1e-4, 1.0)
            );
            if mat.clearcoat > 0.0 {
                // Mitsuba's coat is Disney's (GTR1 lobe, F at the half vector, the base
                // not darkened), not glTF's fresnel_coat: an approximation.
                self.approximations.push(format!(
                    "material `{name}`: its clearcoat (factor {}, roughness {}) approximated by `principled`'s clearcoat",
                    mat.clearcoat, mat.clearcoat_roughness
                ));
                let _ = writeln!(
                    s,
                    "      <float name=\"clearcoat\" value=\"{}\"/>\n      <float name=\"clearcoat_gloss\" value=\"{}\"/>",
                    mat.clearcoat,
                    1.0 - mat.clearcoat_roughness
                );
            }
            if mat.anisotropy_strength > 0.0 {
                self.approximations.push(format!(
                    "material `{name}`: its anisotropy (strength {}) is left out of `principled` (the glTF BSDF plugin of scripts/mitsuba_gltf_bsdf.py renders it)",
                    mat.anisotropy_strength
                ));
            }
            if sheen > 0.0 {
                // Mitsuba's sheen is Disney's (a Schlick-weighted lobe tinted toward the
                // base colour), not glTF's Charlie sheen: an approximation.
                self.approximations.push(format!(
                    "material `{name}`: its sheen (colour {:?}, roughness {}) approximated by `principled`'s sheen",
                    mat.sheen_color, mat.sheen_roughness
                ));
                let _ = writeln!(s, "      <float name=\"sheen\" value=\"{sheen}\"/>");
            }
            s.push_str("    </bsdf>\n");
        }
        s.push_str("  </bsdf>\n");
        if plan.normal && !transmits {
            s.push_str("  </bsdf>\n");
        }
        if transmits {
            if solid {
                self.approximations.push(format!(
                    "material `{name}`: a solid whose interface takes only part of the material (metallic {}, transmission {}) as a blend of `roughdielectric` with the opaque part",
                    mat.metallic, mat.transmission
                ));
                s.push_str(&self.solid_glass_xml(m, &mat, &colour, constant, None));
            } else {
                s.push_str(&self.thin_glass_xml(m, &mat, &colour));
            }
            s.push_str("  </bsdf>\n");
        }
        Ok(s)
    }

    /// The interface of a solid (KHR_materials_volume) as Mitsuba's `roughdielectric`:
    /// GGX at lanterna's α (roughness², at least MIN_GGX_ALPHA), visible normals, the
    /// material's index inside (the side behind the front face, which both renderers
    /// take from the winding), transmittance the base colour. The same model as
    /// lanterna's (exact Fresnel, separable Smith, 1/η² for radiance).
    /// `id`: the BSDF's own id when it stands alone (not inside a blend).
    ///
    /// A dispersive interface (KHR_materials_dispersion) is lanterna's three interfaces,
    /// one per channel, as an equal `blendbsdf` mixture of three `roughdielectric`s, each
    /// at its channel's index and passing only its channel, three times over (the
    /// mixture's weight of 1/3 brings it back): exact where the transmittance is
    /// `constant`; a textured or per-vertex one keeps one index (approximate).
    fn solid_glass_xml(
        &mut self,
        m: u32,
        mat: &gpu::Material,
        colour: &str,
        constant: Option<[f32; 3]>,
        id: Option<&str>,
    ) -> String {
        let name = self.material_name(m).to_string();
        if mat.transmission_tex.index >= 0 {
            self.approximations.push(format!(
                "material `{name}`: transmission texture not exported (factor used)"
            ));
        }
        if mat.metallic_roughness_tex.index >= 0 {
            self.approximations.push(format!(
                "material `{name}`: metallic-roughness texture not exported (factors used)"
            ));
        }
        let alpha = (mat.roughness * mat.roughness).max(gpu::MIN_GGX_ALPHA);
        let open = |id: Option<&str>, kind: &str| match id {
            Some(id) => format!("    <bsdf type=\"{kind}\" id=\"{id}\">\n"),
            None => format!("    <bsdf type=\"{kind}\">\n"),
        };
        // One interface of index `ior`, its reflectance and transmittance given as XML.
        let interface = |ior: f32, id: Option<&str>, weights: &str| {
            // Mitsuba refuses equal indices; 1.0001 bends light by nothing visible.
            let ior = ior.max(1.0001);
            let mut s = open(id, "roughdielectric");
            s.push_str("      <string name=\"distribution\" value=\"ggx\"/>\n");
            let _ = writeln!(s, "      <float name=\"alpha\" value=\"{alpha}\"/>");
            let _ = writeln!(s, "      <float name=\"int_ior\" value=\"{ior}\"/>");
            s.push_str("      <float name=\"ext_ior\" value=\"1\"/>\n");
            s.push_str("      <boolean name=\"sample_visible\" value=\"true\"/>\n");
            s.push_str(weights);
            s.push_str("    </bsdf>\n");
            s
        };
        let plain = colour.replace("\"reflectance\"", "\"specular_transmittance\"");
        if mat.dispersion <= 0.0 {
            return interface(mat.ior, id, &plain);
        }
        let Some(base) = constant else {
            self.approximations.push(format!(
                "material `{name}`: its dispersion ({}) is left out: the transmittance is textured or per vertex (one index for every channel)",
                mat.dispersion
            ));
            return interface(mat.ior, id, &plain);
        };
        // Mitsuba's reflectances are clamped to 1 unless `unbounded`.
        let unbounded = |param: &str, c: [f32; 3]| {
            format!(
                "      <texture type=\"srgb\" name=\"{param}\">\n        {}\n        <boolean name=\"unbounded\" value=\"true\"/>\n      </texture>\n",
                rgb_xml("color", c)
            )
        };
        let etas = crate::scene::dispersion_iors(mat.ior, mat.dispersion);
        let channel = |k: usize| {
            let only = |v: f32| std::array::from_fn(|c| if c == k { 3.0 * v } else { 0.0 });
            let weights = unbounded("specular_reflectance", only(1.0))
                + &unbounded("specular_transmittance", only(base[k]));
            interface(etas[k], None, &weights)
        };
        // blend(2/3: red | blend(1/2: green | blue)): each a third.
        let mut s = open(id, "blendbsdf");
        s.push_str("      <float name=\"weight\" value=\"0.6666667\"/>\n");
        s.push_str(&channel(0));
        s.push_str(&open(None, "blendbsdf"));
        s.push_str("      <float name=\"weight\" value=\"0.5\"/>\n");
        s.push_str(&channel(1));
        s.push_str(&channel(2));
        s.push_str("    </bsdf>\n    </bsdf>\n");
        s
    }

    /// The transmitting part of a KHR_materials_transmission material, its transmittance
    /// the base colour (`colour`, the reflectance XML). glTF's thin wall passes
    /// (1 − F)·base colour straight through (roughness 0) and reflects F by Schlick's
    /// approximation. Glass without Fresnel reflection (specularFactor 0: matched indices,
    /// nothing reflected) goes out as a `dielectric` of index 1.00001: straight through,
    /// reflecting ~10⁻¹¹, radiance scaled by 1/1.00001² — exact to 2·10⁻⁵. Not as
    /// `thindielectric`, which Mitsuba flags as a null event: `volpath` does not count a
    /// pass through it as a bounce, and `path` inside a `blendbsdf` with it gave half the
    /// direct light the diffuse part reflects on the lit side (3.9.1; a `dielectric` or a
    /// black `diffuse` in its place give the opaque equivalent, as lanterna does). Glass
    /// that reflects goes out as `thindielectric`, which also follows the light bouncing
    /// inside the wall: approximate.
    fn thin_glass_xml(&mut self, m: u32, mat: &gpu::Material, colour: &str) -> String {
        let name = self.material_name(m).to_string();
        let smooth = mat.roughness * mat.roughness <= gpu::MIN_GGX_ALPHA;
        let reflects = mat.specular > 0.0;
        if !smooth || reflects {
            self.approximations.push(format!(
                "material `{name}`: KHR_materials_transmission (roughness {}, specular {}) approximated by Mitsuba's smooth `thindielectric`",
                mat.roughness, mat.specular
            ));
        }
        if mat.transmission_tex.index >= 0 {
            self.approximations.push(format!(
                "material `{name}`: transmission texture not exported (factor used)"
            ));
        }
        self.smooth_thin_walls |= smooth;
        let mut s = if reflects {
            self.thin_walls = true;
            let mut s = String::from("    <bsdf type=\"thindielectric\">\n");
            let _ = writeln!(
                s,
                "      <float name=\"int_ior\" value=\"{}\"/>",
                mat.ior.max(1.0)
            );
            s
        } else {
            String::from(
                "    <bsdf type=\"dielectric\">\n      <float name=\"int_ior\" value=\"1.00001\"/>\n",
            )
        };
        s.push_str("      <float name=\"ext_ior\" value=\"1\"/>\n");
        s.push_str(&colour.replace("\"reflectance\"", "\"specular_transmittance\""));
        s.push_str("    </bsdf>\n");
        s
    }

    /// Mitsuba `mask`'s opacity for a material whose alpha mode is MASK or BLEND, as
    /// lanterna's alpha test takes it (`geometry_coverage`): BLEND the alpha (factor ×
    /// the base colour texture's alpha, filtered as lanterna filters it); MASK 1 where
    /// that reaches the cutoff, else 0 (exact for a constant alpha and for a nearest-
    /// filtered texture, whose texels can be cut out one by one; a bilinear texture's cut
    /// goes out sampled at up to 16× its resolution, an approximation). `None` for
    /// opaque materials, and where the export cannot match lanterna (the reason goes to
    /// the approximations; the material then goes out opaque): an emitter whose alpha
    /// comes from a texture or that is double-sided (Mitsuba's `area` emitter emits
    /// wherever a ray meets the shape, so a one-sided emitter under a constant alpha
    /// goes out with its radiance premultiplied by the coverage instead; a double-sided
    /// one's back sheet would need to be a pure null interface), a transmitting
    /// material, vertex colours with alpha, a texture on another UV set than the PLY's.
    /// Sets `self.masks` when it returns one (the integrator must be `volpath`, whose
    /// shadow rays pass through null interfaces).
    fn opacity_xml(
        &mut self,
        m: u32,
        mat: &gpu::Material,
        plan: UvPlan,
        vertex_colors: bool,
    ) -> Result<Option<String>, ExportError> {
        if mat.alpha_mode == gpu::ALPHA_MODE_OPAQUE {
            return Ok(None);
        }
        let mask = mat.alpha_mode == gpu::ALPHA_MODE_MASK;
        let name = self.material_name(m).to_string();
        let emits = mat.emission.iter().any(|&c| c > 0.0);
        let double_sided = mat.flags & gpu::MATERIAL_FLAG_DOUBLE_SIDED != 0;
        let why = if emits && (mat.base_color_tex.index >= 0 || double_sided) {
            Some("an emitter whose alpha varies or that is double-sided (Mitsuba's area emitter also emits in the holes)")
        } else if mat.transmission > 0.0 && mat.metallic < 1.0 {
            Some("a transmitting material")
        } else if vertex_colors && self.vertex_alpha_below_one(m) {
            Some("vertex colours with alpha")
        } else if mat.base_color_tex.index >= 0 && plan.set != Some(mat.base_color_tex.uv_set) {
            Some("its texture is on another UV set than the exported one")
        } else {
            None
        };
        if let Some(why) = why {
            self.approximations.push(format!(
                "material `{name}`: alpha mode {} not exported, {why}: Mitsuba sees it opaque",
                if mask { "MASK" } else { "BLEND" }
            ));
            return Ok(None);
        }
        self.masks = true;
        let factor = mat.base_color[3];
        let cut = |alpha: f32| -> f32 {
            if !mask {
                alpha.clamp(0.0, 1.0)
            } else if alpha >= mat.alpha_cutoff {
                1.0
            } else {
                0.0
            }
        };
        let tref = mat.base_color_tex;
        if tref.index < 0 {
            if emits {
                // Mitsuba's area emitter emits wherever a ray meets the shape, hole or
                // not: its radiance is premultiplied by the coverage (radiance_xml), so
                // that it emits what lanterna's hits find on average.
                self.emitter_coverage.insert(m, cut(factor));
            }
            return Ok(Some(format!(
                "  <float name=\"opacity\" value=\"{}\"/>\n",
                cut(factor)
            )));
        }
        let tex = &self.scene.textures[tref.index as usize];
        let key = format!(
            "opacity {} {:08x} {:08x} {mask}",
            tref.index,
            factor.to_bits(),
            mat.alpha_cutoff.to_bits()
        );
        let mut sampler = tex.sampler;
        let file = if mask && !sampler.nearest {
            // lanterna cuts the bilinearly filtered alpha, a curve inside each texel;
            // Mitsuba gets that cut sampled at k× the resolution, nearest-filtered.
            let k = (MASK_CUT_TEXELS / (tex.width as f64 * tex.height as f64))
                .sqrt()
                .clamp(1.0, 16.0) as u32;
            self.approximations.push(format!(
                "material `{name}`: its MASK is cut from a bilinear texture; exported as that cut at {k}× the texture's resolution"
            ));
            sampler.nearest = true;
            let size = (tex.width * k, tex.height * k);
            self.derived_texture(key, "opacity", tref.index, size, |uv| {
                [cut(factor * tex.bilinear(uv)[3]); 3]
            })?
        } else {
            let size = (tex.width, tex.height);
            self.derived_texture(key, "opacity", tref.index, size, |uv| {
                [cut(factor * tex.texel(uv)[3]); 3]
            })?
        };
        let to_uv = match plan.bake {
            Some(b) => uv_matrix(&tref) * uv_matrix(&b).inverse(),
            None => uv_matrix(&tref),
        };
        Ok(Some(bitmap_xml(
            "opacity", &file, true, sampler, &to_uv, "  ",
        )))
    }

    /// A linear PFM of `size` texels made from texture `slot` (`texel` gives the RGB
    /// written at each texel centre's uv), once per `key`: the file name.
    fn derived_texture(
        &mut self,
        key: String,
        stem: &str,
        slot: i32,
        (w, h): (u32, u32),
        texel: impl Fn([f32; 2]) -> [f32; 3],
    ) -> Result<String, ExportError> {
        if let Some(f) = self.derived_textures.get(&key) {
            return Ok(f.clone());
        }
        let rgb: Vec<[f32; 3]> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| texel([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]))
            .collect();
        let file = format!("textures/{stem}{slot}-{}.pfm", self.derived_textures.len());
        self.write(&file, &files::pfm_bytes(w, h, &rgb))?;
        self.derived_textures.insert(key, file.clone());
        Ok(file)
    }

    /// Whether some vertex colour of a mesh of material `m` has alpha below one.
    fn vertex_alpha_below_one(&self, m: u32) -> bool {
        self.scene.primitives.iter().any(|p| {
            p.material == m
                && p.color_offset != gpu::INVALID_INDEX
                && self.scene.colors[p.color_offset as usize..][..p.vertex_count as usize]
                    .iter()
                    .any(|c| c[3] < 1.0)
        })
    }

    /// `<rgb name=…>` or `<texture type="bitmap" name=…>` for the base colour.
    pub(super) fn base_colour_xml(
        &mut self,
        m: u32,
        mat: &gpu::Material,
        plan: UvPlan,
        param: &str,
    ) -> Result<String, ExportError> {
        let factor = [
            mat.base_color[0].clamp(0.0, 1.0),
            mat.base_color[1].clamp(0.0, 1.0),
            mat.base_color[2].clamp(0.0, 1.0),
        ];
        if mat.base_color[..3].iter().any(|&c| c > 1.0) {
            self.warnings.push(format!(
                "material `{}`: base colour above 1 clamped (as lanterna does)",
                self.material_name(m)
            ));
        }
        let tref = mat.base_color_tex;
        if tref.index < 0 {
            return Ok(format!("      {}\n", rgb_xml(param, factor)));
        }
        let tex = &self.scene.textures[tref.index as usize];
        if plan.set != Some(tref.uv_set) {
            let avg = average_colour(tex);
            self.approximations.push(format!(
                "material `{}`: base colour texture uses UV set {} but the emissive texture set {:?}: exported as its average colour",
                self.material_name(m),
                tref.uv_set,
                plan.set
            ));
            return Ok(format!(
                "      {}\n",
                rgb_xml(param, std::array::from_fn(|c| avg[c] * factor[c]))
            ));
        }
        // The written UVs carry the baked transform B; the texture wants T(uv) =
        // (T ∘ B⁻¹)(written).
        let to_uv = match plan.bake {
            Some(b) => uv_matrix(&tref) * uv_matrix(&b).inverse(),
            None => uv_matrix(&tref),
        };
        let (file, raw) = self.texture_file(tref.index, tex, factor)?;
        Ok(bitmap_xml(param, &file, raw, tex.sampler, &to_uv, "      "))
    }

    pub(super) fn radiance_xml(
        &mut self,
        m: u32,
        plan: UvPlan,
        mesh: &PlyMesh,
    ) -> Result<String, ExportError> {
        let mat = self.scene.materials[m as usize];
        // An emitter under a constant alpha emits its coverage's share (see opacity_xml).
        let coverage = self.emitter_coverage.get(&m).copied().unwrap_or(1.0);
        let radiance = mat.emission.map(|c| c * coverage);
        let tref = mat.emissive_tex;
        if tref.index < 0
            && mat.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION != 0
            && !mesh.colors.is_empty()
        {
            // An unlit material's emission tinted by its vertex colours: the PLY's
            // `vertex_color` holds emission × colour (`append_instance`). Mitsuba 3's area
            // emitter evaluates a `mesh_attribute` only where a ray hits the shape: its
            // light samples find no attribute and carry nothing (measured with Mitsuba
            // 3.9.1: with emitter sampling on, the floor such a panel lights came out
            // 1,000× too dark, what MIS left of BSDF sampling), so Mitsuba finds this
            // light by BSDF sampling alone (sampling weight 0), exact for any mesh.
            self.warnings.push(format!(
                "material `{}`: its emission is tinted by vertex colours, which Mitsuba's emitter sampling does not read: Mitsuba finds its light by BSDF sampling alone (sampling weight 0)",
                self.material_name(m)
            ));
            return Ok(format!(
                "      <float name=\"sampling_weight\" value=\"0\"/>\n      <texture type=\"mesh_attribute\" name=\"radiance\">\n        <string name=\"name\" value=\"vertex_color\"/>\n        <float name=\"scale\" value=\"{coverage}\"/>\n      </texture>\n"
            ));
        }
        if tref.index < 0 {
            self.sampled_emitters += 1;
            return Ok(format!("      {}\n", rgb_xml("radiance", radiance)));
        }
        let tex = &self.scene.textures[tref.index as usize];
        debug_assert_eq!(plan.set, Some(tref.uv_set));
        // Mitsuba's texture-driven emitter sampling is exact only for a one-to-one UV
        // map into the unit square (see `uv_cover`). Any other emitter (signs sharing a
        // cell of a texture atlas, a repeated texture) gets sampling weight 0: Mitsuba
        // then finds its light by BSDF sampling alone, exact for any UV map. (Measured
        // on a generated street whose signs overlap on their atlas: with texture-driven
        // sampling Mitsuba's direct light from the signs was 2.5–5.7× below lanterna's;
        // by BSDF sampling alone they agreed.)
        let mut xml = String::new();
        match uv_cover::one_to_one(&mesh.uvs, &mesh.faces) {
            Ok(_) => self.sampled_emitters += 1,
            Err(why) => {
                self.warnings.push(format!(
                    "material `{}`: its emissive texture coordinates are not one-to-one into the unit square ({why}): Mitsuba finds its light by BSDF sampling alone (sampling weight 0)",
                    self.material_name(m)
                ));
                xml.push_str("      <float name=\"sampling_weight\" value=\"0\"/>\n");
            }
        }
        let (file, raw) = self.texture_file(tref.index, tex, radiance)?;
        xml.push_str(&bitmap_xml(
            "radiance",
            &file,
            raw,
            tex.sampler,
            &Mat3::IDENTITY,
            "      ",
        ));
        Ok(xml)
    }

    /// The `normalmap` plugin's texture: the normal texture's texels as m = 2c − 1 with
    /// lanterna's arithmetic baked in (x and y times the scale, z at least 10⁻⁴, y
    /// negated for mirrored UVs) and stored back as (m + 1) / 2 in a linear PFM, which
    /// Mitsuba interpolates, maps to 2c − 1 and normalises as lanterna does.
    fn normal_map_xml(
        &mut self,
        mat: &gpu::Material,
        mirrored_uvs: bool,
    ) -> Result<String, ExportError> {
        let tref = mat.normal_tex;
        let tex = &self.scene.textures[tref.index as usize];
        let key = format!(
            "normal {} {:08x} {mirrored_uvs}",
            tref.index,
            mat.normal_scale.to_bits()
        );
        let y = if mirrored_uvs { -1.0 } else { 1.0 };
        let size = (tex.width, tex.height);
        let file = self.derived_texture(key, "normal", tref.index, size, |uv| {
            let m = tex.texel(uv).map(|v| 2.0 * v - 1.0);
            [
                m[0] * mat.normal_scale,
                m[1] * mat.normal_scale * y,
                m[2].max(1e-4),
            ]
            .map(|v| (v + 1.0) / 2.0)
        })?;
        Ok(bitmap_xml(
            "normalmap",
            &file,
            true,
            tex.sampler,
            &uv_matrix(&tref),
            "  ",
        ))
    }

    /// Write texture `slot` scaled by `factor`: sRGB texels as PNG (8 or 16 bits, as the
    /// image has them) when the factor is one (Mitsuba decodes sRGB as lanterna does),
    /// else linear float texels × factor as PFM. Returns the file and whether it is raw
    /// (linear).
    pub(super) fn texture_file(
        &mut self,
        slot: i32,
        tex: &TextureData,
        factor: [f32; 3],
    ) -> Result<(String, bool), ExportError> {
        let key = (slot, factor.map(f32::to_bits));
        if let Some(f) = self.textures.get(&key) {
            return Ok(f.clone());
        }
        let (w, h) = (tex.width, tex.height);
        let result = if factor == [1.0; 3] && tex.format == TextureFormat::Srgb {
            // The image's own sRGB codes at its own depth, for Mitsuba to decode.
            let (bytes, colour) = match &tex.texels {
                Texels::Rgba8(v) => (
                    v.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
                    image::ExtendedColorType::Rgb8,
                ),
                Texels::Rgba16(v) => (
                    v.chunks_exact(4)
                        .flat_map(|p| [p[0], p[1], p[2]])
                        .flat_map(u16::to_ne_bytes)
                        .collect::<Vec<u8>>(),
                    image::ExtendedColorType::Rgb16,
                ),
            };
            let mut png = Vec::new();
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(&mut png),
                &bytes,
                w,
                h,
                colour,
            )
            .map_err(|e| ExportError::Invalid(format!("texture `{}`: {e}", tex.name)))?;
            let file = format!("textures/t{slot}.png");
            self.write(&file, &png)?;
            (file, false)
        } else {
            let texels = linear_texels(tex);
            let rgb: Vec<[f32; 3]> = texels
                .iter()
                .map(|t| std::array::from_fn(|c| t[c] * factor[c]))
                .collect();
            let file = format!("textures/t{slot}-{}.pfm", self.textures.len());
            self.write(&file, &files::pfm_bytes(w, h, &rgb))?;
            (file, true)
        };
        if tex.sampler.wrap_u != tex.sampler.wrap_v {
            self.approximations.push(format!(
                "texture `{}`: different wrap modes along u and v; Mitsuba uses one ({:?})",
                tex.name, tex.sampler.wrap_u
            ));
        }
        self.textures.insert(key, result.clone());
        Ok(result)
    }
}
