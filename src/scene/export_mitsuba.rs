//! Export a loaded scene to Mitsuba 3 (XML + binary PLY meshes + images), so that an
//! independent renderer can check lanterna's images. The export starts from what
//! lanterna itself loaded — the same world-space triangles, materials, light table,
//! camera and resolution — and maps every convention explicitly: the camera's −Z view
//! axis and vertical field of view, one-sided front-face emission (double-sided emitters
//! become two one-sided sheets a hair apart, since Mitsuba's `area` emitter is one-sided),
//! two-sided BSDFs, the box pixel filter, segment-counted `max_depth`, sRGB textures and
//! the glTF spot falloff (baked into the spot's projection texture). Anything that has
//! no exact Mitsuba counterpart (glossy glTF materials → `principled`, alpha, normal
//! maps, …) is approximated and listed in [`MitsubaExport::approximations`]: the peer
//! check is exact only when that list is empty. The directory is written under a
//! temporary name and renamed into place, so a failed export leaves nothing behind.

mod files;

use crate::gpu;
use crate::lights::{transform_uv, LightTable};
use crate::scene::{Camera, Instance, Projection, Scene, TextureData};
use crate::vk::{TextureFormat, WrapMode};
use files::PlyMesh;
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Name of the XML scene inside the export directory.
pub const SCENE_XML: &str = "scene.xml";
/// Name of the export's manifest (settings, approximations, warnings) as JSON.
pub const MANIFEST: &str = "lanterna_export.json";

/// What to put in the Mitsuba scene besides the geometry.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    pub width: u32,
    pub height: u32,
    /// Path segments, lanterna's `--max-depth` = Mitsuba's `max_depth`.
    pub max_depth: u32,
    /// Default sample count of the XML's sampler (`$spp`, overridable at load time).
    pub spp: u32,
    /// Default seed of the XML's sampler (`$seed`).
    pub seed: u32,
}

/// What an export wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MitsubaExport {
    pub dir: PathBuf,
    pub xml: PathBuf,
    /// Mitsuba shapes written (meshes, after grouping per material).
    pub shapes: usize,
    /// Mitsuba emitters: emissive shapes plus punctual lights.
    pub emitters: usize,
    pub triangles: u64,
    /// Where the Mitsuba scene differs from lanterna's on purpose; empty = exact match
    /// expected (up to Monte Carlo noise).
    pub approximations: Vec<String>,
    /// Everything else worth knowing (files, ignored attributes that do not matter).
    pub warnings: Vec<String>,
}

/// Errors while exporting. Every variant names the file or directory at fault.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {error}")]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error("{path} exists and is not a lanterna Mitsuba export (no {MANIFEST}); refusing to replace it")]
    NotAnExport { path: PathBuf },
    #[error("cannot export to Mitsuba: {0}")]
    Invalid(String),
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> ExportError + '_ {
    move |error| ExportError::Io {
        path: path.to_path_buf(),
        error,
    }
}

/// Export `scene` (with its light table, the chosen camera and the image size) as a
/// Mitsuba 3 scene in directory `out_dir` (`scene.xml`, `meshes/`, `textures/`,
/// `lanterna_export.json`). An existing earlier export in `out_dir` is replaced.
pub fn export(
    scene: &Scene,
    lights: &LightTable,
    camera: &Camera,
    options: &ExportOptions,
    out_dir: &Path,
) -> Result<MitsubaExport, ExportError> {
    if options.width == 0 || options.height == 0 {
        return Err(ExportError::Invalid(format!(
            "image size {}×{} is empty",
            options.width, options.height
        )));
    }
    if options.max_depth == 0 {
        return Err(ExportError::Invalid("max depth must be at least 1".into()));
    }
    if lights.instance_lights.len() != scene.instances.len() {
        return Err(ExportError::Invalid(
            "the light table was built for another scene".into(),
        ));
    }
    if out_dir.exists() && !out_dir.join(MANIFEST).is_file() {
        let empty = std::fs::read_dir(out_dir)
            .map(|mut d| d.next().is_none())
            .unwrap_or(false);
        if !empty {
            return Err(ExportError::NotAnExport {
                path: out_dir.to_path_buf(),
            });
        }
    }
    let parent = match out_dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(io_err(&parent))?;
    let name = out_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "export".into());
    let tmp = TempDir(parent.join(format!(".{name}.tmp-{}", std::process::id())));
    if tmp.0.exists() {
        std::fs::remove_dir_all(&tmp.0).map_err(io_err(&tmp.0))?;
    }
    for sub in ["", "meshes", "textures"] {
        let d = tmp.0.join(sub);
        std::fs::create_dir_all(&d).map_err(io_err(&d))?;
    }

    let mut w = Writer {
        scene,
        dir: tmp.0.clone(),
        textures: HashMap::new(),
        approximations: Vec::new(),
        warnings: Vec::new(),
        // Far above float resolution at the scene's coordinates (so Mitsuba always
        // orders the sheets), far below a pixel (so silhouettes do not move).
        epsilon: 4e-6
            * scene
                .bounds_min
                .abs()
                .max(scene.bounds_max.abs())
                .max_element()
                .max(scene.extent()),
    };
    let mut xml = String::new();
    let body = w.scene_body(lights, camera, options)?;
    xml.push_str("<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    let _ = writeln!(
        xml,
        "<!-- Exported by lanterna {} from {} (scene hash {}). -->",
        env!("CARGO_PKG_VERSION"),
        xml_escape(&scene.path.display().to_string()),
        scene.hash
    );
    xml.push_str("<scene version=\"3.0.0\">\n");
    let _ = writeln!(xml, "  <default name=\"spp\" value=\"{}\"/>", options.spp);
    let _ = writeln!(xml, "  <default name=\"seed\" value=\"{}\"/>", options.seed);
    let _ = writeln!(
        xml,
        "  <default name=\"max_depth\" value=\"{}\"/>",
        options.max_depth
    );
    xml.push_str(&body.xml);
    xml.push_str("</scene>\n");
    w.write(SCENE_XML, xml.as_bytes())?;

    w.approximations.sort();
    w.approximations.dedup();
    w.warnings.sort();
    w.warnings.dedup();
    let summary = MitsubaExport {
        dir: out_dir.to_path_buf(),
        xml: out_dir.join(SCENE_XML),
        shapes: body.shapes,
        emitters: body.emitters,
        triangles: body.triangles,
        approximations: w.approximations.clone(),
        warnings: w.warnings.clone(),
    };
    let manifest = serde_json::json!({
        "generator": format!("lanterna {}", env!("CARGO_PKG_VERSION")),
        "scene_path": scene.path.display().to_string(),
        "scene_hash": scene.hash,
        "camera": camera.name,
        "camera_index": scene.cameras.iter().position(|c| {
            c.name == camera.name && c.to_world == camera.to_world && c.projection == camera.projection
        }),
        "width": options.width,
        "height": options.height,
        "max_depth": options.max_depth,
        "spp": options.spp,
        "seed": options.seed,
        "shapes": body.shapes,
        "emitters": body.emitters,
        "triangles": body.triangles,
        "exact": summary.approximations.is_empty(),
        "approximations": summary.approximations,
        "warnings": summary.warnings,
    });
    let text = serde_json::to_string_pretty(&manifest).expect("JSON of plain values");
    w.write(MANIFEST, text.as_bytes())?;

    // Swap the finished directory into place; an earlier export is removed only after.
    let old = parent.join(format!(".{name}.old-{}", std::process::id()));
    if out_dir.exists() {
        std::fs::rename(out_dir, &old).map_err(io_err(out_dir))?;
    }
    std::fs::rename(&tmp.0, out_dir).map_err(io_err(out_dir))?;
    std::mem::forget(tmp);
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(io_err(&old))?;
    }
    Ok(summary)
}

/// Removes the temporary directory unless the export succeeded.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

struct Body {
    xml: String,
    shapes: usize,
    emitters: usize,
    triangles: u64,
}

/// How one material's texture coordinates reach Mitsuba.
#[derive(Clone, Copy)]
struct UvPlan {
    /// glTF UV set written to the PLY, `None` when no texture needs coordinates.
    set: Option<u32>,
    /// Transform baked into the written coordinates (the emissive texture's, because
    /// Mitsuba's emitter sampling needs its bitmap's own `to_uv` to be the identity).
    bake: Option<gpu::TextureRef>,
}

#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct GroupKey {
    material: u32,
    emitter: bool,
    smooth: bool,
}

struct Writer<'a> {
    scene: &'a Scene,
    dir: PathBuf,
    /// (texture slot, factor bits) → file name relative to the export directory.
    textures: HashMap<(i32, [u32; 3]), (String, bool)>,
    approximations: Vec<String>,
    warnings: Vec<String>,
    /// Gap between the two sheets of a double-sided emitter.
    epsilon: f32,
}

impl Writer<'_> {
    fn write(&self, rel: &str, bytes: &[u8]) -> Result<(), ExportError> {
        let path = self.dir.join(rel);
        std::fs::write(&path, bytes).map_err(io_err(&path))
    }

    fn material_name(&self, m: u32) -> &str {
        self.scene
            .material_names
            .get(m as usize)
            .map(String::as_str)
            .unwrap_or("?")
    }

    fn scene_body(
        &mut self,
        lights: &LightTable,
        camera: &Camera,
        options: &ExportOptions,
    ) -> Result<Body, ExportError> {
        let scene = self.scene;
        let mut xml = String::new();
        xml.push_str(&integrator_xml(options));
        xml.push_str(&self.sensor_xml(camera, options));

        // Geometry, grouped per material and role.
        let mut plans: HashMap<u32, UvPlan> = HashMap::new();
        let mut shadings: HashMap<u32, Shading> = HashMap::new();
        let mut groups: BTreeMap<GroupKey, PlyMesh> = BTreeMap::new();
        let mut triangles = 0u64;
        for (i, inst) in scene.instances.iter().enumerate() {
            let prim = &scene.primitives[inst.primitive as usize];
            let emitter = lights.instance_lights[i].1 != gpu::INVALID_INDEX;
            let plan = match plans.get(&prim.material) {
                Some(p) => *p,
                None => {
                    let p = self.uv_plan(prim.material);
                    plans.insert(prim.material, p);
                    p
                }
            };
            let kind = *shadings
                .entry(inst.primitive)
                .or_insert_with(|| shading(scene, prim));
            if kind == Shading::Mixed {
                self.approximations.push(format!(
                    "mesh {}: only some vertices have normals; exported flat",
                    prim.name
                ));
            }
            let curved = kind == Shading::Curved;
            if emitter && curved {
                let m = &scene.materials[prim.material as usize];
                if m.base_color[..3].iter().any(|&c| c > 0.0) {
                    self.approximations.push(format!(
                        "material `{}`: emissive mesh `{}` has vertex normals; Mitsuba shades it with face normals (its area emitter must use the geometric normal, like lanterna's)",
                        self.material_name(prim.material),
                        prim.name
                    ));
                }
            }
            let key = GroupKey {
                material: prim.material,
                emitter,
                smooth: curved && !emitter,
            };
            let mesh = groups.entry(key).or_default();
            append_instance(mesh, scene, inst, key.smooth, plan);
            triangles += prim.triangle_count as u64;
        }
        if groups.keys().any(|k| k.smooth) {
            // Same interpolation, but lanterna also flips shading normals to the
            // geometric side and zeroes light below the geometric surface; Mitsuba
            // does neither.
            self.approximations.push(
                "curved vertex normals: lanterna and Mitsuba treat shading normals that disagree with the geometric normal differently (grazing angles only)".into(),
            );
        }

        // BSDFs, one per material used.
        let mut used: Vec<u32> = groups.keys().map(|k| k.material).collect();
        used.dedup();
        for &m in &used {
            let plan = plans[&m];
            xml.push_str(&self.bsdf_xml(m, plan)?);
        }

        let mut shapes = 0;
        let mut emitters = 0;
        for (key, mesh) in &groups {
            let plan = plans[&key.material];
            let material = &scene.materials[key.material as usize];
            let radiance = if key.emitter {
                Some(self.radiance_xml(key.material, plan, mesh)?)
            } else {
                None
            };
            let double_sided = material.flags & gpu::MATERIAL_FLAG_DOUBLE_SIDED != 0;
            let mut sheets = vec![(mesh, "")];
            let back;
            if key.emitter && double_sided {
                back = back_sheet(mesh, self.epsilon);
                sheets.push((&back, "-back"));
            }
            for (sheet, suffix) in sheets {
                let file = format!(
                    "meshes/m{}{}{}{}.ply",
                    key.material,
                    if key.emitter { "-emitter" } else { "" },
                    if key.smooth { "-smooth" } else { "" },
                    suffix
                );
                self.write(&file, &sheet.to_bytes())?;
                let _ = writeln!(
                    xml,
                    "  <!-- material `{}`{} -->",
                    xml_escape(self.material_name(key.material)),
                    if suffix.is_empty() {
                        ""
                    } else {
                        ", back sheet of a double-sided emitter"
                    }
                );
                let _ = writeln!(xml, "  <shape type=\"ply\">");
                let _ = writeln!(xml, "    <string name=\"filename\" value=\"{file}\"/>");
                if !key.smooth {
                    xml.push_str("    <boolean name=\"face_normals\" value=\"true\"/>\n");
                }
                let _ = writeln!(xml, "    <ref id=\"bsdf{}\"/>", key.material);
                if let Some(r) = &radiance {
                    let _ = writeln!(xml, "    <emitter type=\"area\">\n{r}    </emitter>");
                    emitters += 1;
                }
                xml.push_str("  </shape>\n");
                shapes += 1;
            }
        }

        for (i, l) in scene.punctual.iter().enumerate() {
            if l.intensity.iter().all(|&c| c <= 0.0) {
                continue;
            }
            xml.push_str(&self.punctual_xml(i, l)?);
            emitters += 1;
        }
        if emitters == 0 {
            return Err(ExportError::Invalid(format!(
                "{}: the scene has no lights",
                scene.path.display()
            )));
        }
        Ok(Body {
            xml,
            shapes,
            emitters,
            triangles,
        })
    }

    fn sensor_xml(&mut self, camera: &Camera, o: &ExportOptions) -> String {
        // glTF cameras look down −Z with +X to the right of the image; Mitsuba's look
        // down +Z with +X to the left: a half turn about the camera's Y axis maps one
        // frame onto the other (no mirror, determinant +1).
        let flip = Mat4::from_diagonal(glam::Vec4::new(-1.0, 1.0, -1.0, 1.0));
        let rigid = camera.rigid_to_world();
        let extent = self.scene.extent();
        let eye = rigid.transform_point3(Vec3::ZERO);
        let reach = (eye - self.scene.bounds_min)
            .abs()
            .max((eye - self.scene.bounds_max).abs())
            .length();
        let far = (10.0 * (reach + extent)).max(1e4);
        let near = 1e-5 * extent;
        let mut s = String::new();
        let aspect = o.width as f32 / o.height as f32;
        match camera.projection {
            Projection::Perspective {
                yfov,
                aspect: file_aspect,
            } => {
                if let Some(a) = file_aspect {
                    if (a - aspect).abs() > 1e-3 * a {
                        self.warnings.push(format!(
                            "camera `{}` has aspect ratio {a} but the image is {}×{}: both renderers use the image's",
                            camera.name, o.width, o.height
                        ));
                    }
                }
                s.push_str("  <sensor type=\"perspective\">\n");
                s.push_str("    <string name=\"fov_axis\" value=\"y\"/>\n");
                let _ = writeln!(
                    s,
                    "    <float name=\"fov\" value=\"{}\"/>",
                    yfov.to_degrees()
                );
                let _ = writeln!(s, "    {}", matrix_xml("to_world", &(rigid * flip)));
            }
            Projection::Orthographic { xmag, ymag } => {
                // Mitsuba's orthographic view spans x ∈ [−1, 1], y ∈ [−1/aspect, 1/aspect]
                // before to_world; lanterna's spans [−xmag, xmag] × [−ymag, ymag].
                let scale = Mat4::from_scale(Vec3::new(xmag, ymag * aspect, 1.0));
                s.push_str("  <sensor type=\"orthographic\">\n");
                let _ = writeln!(s, "    {}", matrix_xml("to_world", &(rigid * flip * scale)));
            }
        }
        let _ = writeln!(s, "    <float name=\"near_clip\" value=\"{near}\"/>");
        let _ = writeln!(s, "    <float name=\"far_clip\" value=\"{far}\"/>");
        s.push_str("    <sampler type=\"independent\">\n");
        s.push_str("      <integer name=\"sample_count\" value=\"$spp\"/>\n");
        s.push_str("      <integer name=\"seed\" value=\"$seed\"/>\n");
        s.push_str("    </sampler>\n");
        s.push_str("    <film type=\"hdrfilm\">\n");
        let _ = writeln!(s, "      <integer name=\"width\" value=\"{}\"/>", o.width);
        let _ = writeln!(s, "      <integer name=\"height\" value=\"{}\"/>", o.height);
        s.push_str("      <string name=\"pixel_format\" value=\"rgb\"/>\n");
        s.push_str("      <string name=\"component_format\" value=\"float32\"/>\n");
        // lanterna averages uniform samples over each pixel's square: a box of radius ½.
        s.push_str("      <rfilter type=\"box\"/>\n");
        s.push_str("    </film>\n");
        s.push_str("  </sensor>\n");
        s
    }

    /// Which UV set the PLY of a material carries, and which transform is baked in.
    fn uv_plan(&mut self, m: u32) -> UvPlan {
        let mat = &self.scene.materials[m as usize];
        let emissive = mat.emissive_tex.index >= 0 && mat.emission.iter().any(|&c| c > 0.0);
        let base = mat.base_color_tex.index >= 0;
        if emissive {
            let bake = (!is_identity(&mat.emissive_tex)).then_some(mat.emissive_tex);
            UvPlan {
                set: Some(mat.emissive_tex.uv_set),
                bake,
            }
        } else if base {
            UvPlan {
                set: Some(mat.base_color_tex.uv_set),
                bake: None,
            }
        } else {
            UvPlan {
                set: None,
                bake: None,
            }
        }
    }

    fn bsdf_xml(&mut self, m: u32, plan: UvPlan) -> Result<String, ExportError> {
        let mat =
            *self.scene.materials.get(m as usize).ok_or_else(|| {
                ExportError::Invalid(format!("material index {m} is out of range"))
            })?;
        let name = self.material_name(m).to_string();
        let colour = self.base_colour_xml(m, &mat, plan, "reflectance")?;
        if mat.alpha_mode != gpu::ALPHA_MODE_OPAQUE {
            self.approximations.push(format!(
                "material `{name}`: alpha mode {} is not exported (Mitsuba sees it opaque)",
                if mat.alpha_mode == gpu::ALPHA_MODE_MASK {
                    "MASK"
                } else {
                    "BLEND"
                }
            ));
        }
        if mat.normal_tex.index >= 0 {
            self.approximations.push(format!(
                "material `{name}`: its normal texture is not exported"
            ));
        }
        let mut s = String::new();
        let _ = writeln!(s, "  <!-- material `{}` -->", xml_escape(&name));
        let _ = writeln!(s, "  <bsdf type=\"twosided\" id=\"bsdf{m}\">");
        // glTF with specularFactor 0 and metallic 0 is exactly Lambertian (albedo/π).
        if mat.specular == 0.0 && mat.metallic == 0.0 {
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
            s.push_str("    </bsdf>\n");
        }
        s.push_str("  </bsdf>\n");
        Ok(s)
    }

    /// `<rgb name=…>` or `<texture type="bitmap" name=…>` for the base colour.
    fn base_colour_xml(
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
        Ok(bitmap_xml(param, &file, raw, tex, &to_uv, "      "))
    }

    fn radiance_xml(
        &mut self,
        m: u32,
        plan: UvPlan,
        mesh: &PlyMesh,
    ) -> Result<String, ExportError> {
        let mat = self.scene.materials[m as usize];
        let tref = mat.emissive_tex;
        if tref.index < 0 {
            return Ok(format!("      {}\n", rgb_xml("radiance", mat.emission)));
        }
        let tex = &self.scene.textures[tref.index as usize];
        debug_assert_eq!(plan.set, Some(tref.uv_set));
        // Mitsuba samples textured emitters through the inverse of the UV map: it must
        // be one-to-one onto a part of the unit square.
        let mut uv_area = 0.0f64;
        let mut outside = false;
        for f in &mesh.faces {
            let [a, b, c] = f.map(|i| Vec2::from(mesh.uvs[i as usize]));
            uv_area += 0.5 * ((b - a).perp_dot(c - a) as f64).abs();
            outside |= [a, b, c]
                .iter()
                .any(|p| p.min_element() < -1e-4 || p.max_element() > 1.0 + 1e-4);
        }
        if outside || uv_area > 1.0 + 1e-3 {
            self.approximations.push(format!(
                "material `{}`: emissive texture coordinates leave the unit square or overlap (UV area {uv_area:.3}); Mitsuba's emitter sampling assumes a one-to-one UV map",
                self.material_name(m)
            ));
        }
        let (file, raw) = self.texture_file(tref.index, tex, mat.emission)?;
        Ok(bitmap_xml(
            "radiance",
            &file,
            raw,
            tex,
            &Mat3::IDENTITY,
            "      ",
        ))
    }

    /// Write texture `slot` scaled by `factor`: the 8-bit sRGB texels as PNG when the
    /// factor is one (Mitsuba decodes sRGB as lanterna's sampler does), else linear
    /// float texels × factor as PFM. Returns the file and whether it is raw (linear).
    fn texture_file(
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
            let rgb: Vec<u8> = tex
                .rgba
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            let mut bytes = Vec::new();
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(&mut bytes),
                &rgb,
                w,
                h,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| ExportError::Invalid(format!("texture `{}`: {e}", tex.name)))?;
            let file = format!("textures/t{slot}.png");
            self.write(&file, &bytes)?;
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

    fn punctual_xml(&mut self, i: usize, l: &gpu::PunctualLight) -> Result<String, ExportError> {
        let mut s = String::new();
        if l.range > 0.0 {
            self.warnings.push(format!(
                "punctual light {i}: range {} ignored (by lanterna and Mitsuba alike)",
                l.range
            ));
        }
        let p = Vec3::from(l.position);
        let d = Vec3::from(l.direction).normalize_or(Vec3::NEG_Z);
        match l.kind {
            gpu::PUNCTUAL_POINT => {
                let _ = writeln!(s, "  <emitter type=\"point\">");
                let _ = writeln!(
                    s,
                    "    <point name=\"position\" x=\"{}\" y=\"{}\" z=\"{}\"/>",
                    p.x, p.y, p.z
                );
                let _ = writeln!(s, "    {}", rgb_xml("intensity", l.intensity));
            }
            gpu::PUNCTUAL_DIRECTIONAL => {
                let _ = writeln!(s, "  <emitter type=\"directional\">");
                let _ = writeln!(
                    s,
                    "    <vector name=\"direction\" x=\"{}\" y=\"{}\" z=\"{}\"/>",
                    d.x, d.y, d.z
                );
                let _ = writeln!(s, "    {}", rgb_xml("irradiance", l.intensity));
            }
            gpu::PUNCTUAL_SPOT => {
                // Mitsuba's spot looks down its +Z and ramps linearly in angle between
                // beam_width and cutoff_angle; glTF's (and lanterna's) falloff is the
                // square of a linear ramp in cosθ. It is baked into the spot's projected
                // texture (uv = ½ + ½·(x, y)/(z·tan cutoff)) with a flat Mitsuba ramp.
                let outer = l.cos_outer.clamp(-1.0, 1.0).acos();
                let up = if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
                let to_world = Mat4::look_at_rh(p, p + d, up).inverse()
                    * Mat4::from_diagonal(glam::Vec4::new(-1.0, 1.0, -1.0, 1.0));
                let _ = writeln!(s, "  <emitter type=\"spot\">");
                let _ = writeln!(s, "    {}", matrix_xml("to_world", &to_world));
                let _ = writeln!(s, "    {}", rgb_xml("intensity", l.intensity));
                let _ = writeln!(
                    s,
                    "    <float name=\"cutoff_angle\" value=\"{}\"/>",
                    outer.to_degrees()
                );
                let hard = l.cos_inner - l.cos_outer < 1e-3;
                if hard || outer > 85f32.to_radians() {
                    if !hard {
                        self.approximations.push(format!(
                            "spot light {i}: cone wider than 85°: Mitsuba's linear-in-angle falloff from the inner angle is used instead of glTF's"
                        ));
                        let inner = l.cos_inner.clamp(-1.0, 1.0).acos();
                        let _ = writeln!(
                            s,
                            "    <float name=\"beam_width\" value=\"{}\"/>",
                            inner.to_degrees()
                        );
                    } else {
                        let _ = writeln!(
                            s,
                            "    <float name=\"beam_width\" value=\"{}\"/>",
                            outer.to_degrees()
                        );
                    }
                } else {
                    let _ = writeln!(
                        s,
                        "    <float name=\"beam_width\" value=\"{}\"/>",
                        outer.to_degrees()
                    );
                    let file = format!("textures/spot{i}.pfm");
                    self.write(&file, &spot_falloff_pfm(l, outer, 256))?;
                    let _ = writeln!(s, "    <texture type=\"bitmap\" name=\"texture\">");
                    let _ = writeln!(s, "      <string name=\"filename\" value=\"{file}\"/>");
                    s.push_str("      <boolean name=\"raw\" value=\"true\"/>\n");
                    s.push_str("      <string name=\"wrap_mode\" value=\"clamp\"/>\n");
                    s.push_str("    </texture>\n");
                }
            }
            k => {
                return Err(ExportError::Invalid(format!(
                    "punctual light {i} has unknown kind {k}"
                )))
            }
        }
        s.push_str("  </emitter>\n");
        Ok(s)
    }
}

fn integrator_xml(o: &ExportOptions) -> String {
    // Russian roulette only adds noise here (lanterna's is off by default): start it
    // beyond the last segment.
    format!(
        "  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"$max_depth\"/>\n    <integer name=\"rr_depth\" value=\"{}\"/>\n    <boolean name=\"hide_emitters\" value=\"false\"/>\n  </integrator>\n",
        o.max_depth.max(1) + 1000
    )
}

/// How a primitive's vertex normals shade it.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Shading {
    /// No vertex normals, or all equal to their faces' normals (up to sign): flat.
    Flat,
    /// Every vertex has a normal and some differ from their faces' normals.
    Curved,
    /// Some vertices have normals and some do not: exported flat (approximation).
    Mixed,
}

fn shading(scene: &Scene, p: &crate::scene::MeshPrimitive) -> Shading {
    let verts =
        &scene.vertices[p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize];
    let (mut curved, mut missing, mut present) = (false, false, false);
    for t in 0..p.triangle_count as usize {
        let idx =
            &scene.indices[p.index_offset as usize + 3 * t..p.index_offset as usize + 3 * t + 3];
        let [a, b, c] = [0, 1, 2].map(|k| Vec3::from(verts[idx[k] as usize].position));
        let ng = (b - a).cross(c - a).normalize_or_zero();
        for &i in idx {
            let n = Vec3::from(verts[i as usize].normal);
            if n == Vec3::ZERO {
                missing = true;
                continue;
            }
            present = true;
            // lanterna turns a shading normal to the side of the geometric one, so an
            // authored normal opposite to the face is flat shading too.
            curved |= ng != Vec3::ZERO && n.dot(ng).abs() < 1.0 - 1e-5;
        }
    }
    match (curved, missing && present) {
        (true, true) => Shading::Mixed,
        (true, false) => Shading::Curved,
        _ => Shading::Flat,
    }
}

/// Append an instance's triangles in world space. Negative-determinant transforms flip
/// the winding, so the triangle's vertex order is reversed to keep Mitsuba's geometric
/// normal on lanterna's front side.
fn append_instance(mesh: &mut PlyMesh, scene: &Scene, inst: &Instance, smooth: bool, plan: UvPlan) {
    let p = &scene.primitives[inst.primitive as usize];
    let base = mesh.positions.len() as u32;
    let normal_matrix = Mat3::from_mat4(inst.transform).inverse().transpose();
    let flipped = inst.transform.determinant() < 0.0;
    for v in &scene.vertices[p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize]
    {
        mesh.positions.push(
            inst.transform
                .transform_point3(Vec3::from(v.position))
                .into(),
        );
        if smooth {
            mesh.normals.push(
                (normal_matrix * Vec3::from(v.normal))
                    .normalize_or_zero()
                    .into(),
            );
        }
        if let Some(set) = plan.set {
            let uv = if set == 1 { v.uv1 } else { v.uv0 };
            let uv = match &plan.bake {
                Some(t) => transform_uv(t, uv),
                None => uv,
            };
            mesh.uvs.push(uv);
        }
    }
    for t in 0..p.triangle_count as usize {
        let i = p.index_offset as usize + 3 * t;
        let [a, b, c] = [0, 1, 2].map(|k| base + scene.indices[i + k]);
        mesh.faces.push(if flipped { [a, c, b] } else { [a, b, c] });
    }
}

/// The back sheet of a double-sided emitter: every face reversed (so it emits to the
/// other side) and moved `epsilon` behind the front sheet, which therefore is the first
/// hit from the front and the back sheet the first hit from behind.
fn back_sheet(mesh: &PlyMesh, epsilon: f32) -> PlyMesh {
    let mut out = PlyMesh::default();
    for f in &mesh.faces {
        let [a, b, c] = f.map(|i| Vec3::from(mesh.positions[i as usize]));
        let n = (b - a).cross(c - a).normalize_or_zero();
        let base = out.positions.len() as u32;
        for &i in &[f[0], f[2], f[1]] {
            out.positions
                .push((Vec3::from(mesh.positions[i as usize]) - epsilon * n).into());
            if !mesh.uvs.is_empty() {
                out.uvs.push(mesh.uvs[i as usize]);
            }
        }
        out.faces.push([base, base + 1, base + 2]);
    }
    out
}

fn is_identity(t: &gpu::TextureRef) -> bool {
    t.offset == [0.0, 0.0] && t.scale == [1.0, 1.0] && t.rotation == 0.0
}

/// KHR_texture_transform as an affine 3×3 matrix, the same map as [`transform_uv`].
fn uv_matrix(t: &gpu::TextureRef) -> Mat3 {
    let (s, c) = t.rotation.sin_cos();
    Mat3::from_cols(
        Vec3::new(c * t.scale[0], -s * t.scale[0], 0.0),
        Vec3::new(s * t.scale[1], c * t.scale[1], 0.0),
        Vec3::new(t.offset[0], t.offset[1], 1.0),
    )
}

/// Texels decoded to linear RGB (top row first), exactly as lanterna's sampler sees them.
fn linear_texels(tex: &TextureData) -> Vec<[f32; 3]> {
    let (w, h) = (tex.width, tex.height);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let t = tex.texel([(x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32]);
            out.push([t[0], t[1], t[2]]);
        }
    }
    out
}

fn average_colour(tex: &TextureData) -> [f32; 3] {
    let texels = linear_texels(tex);
    let n = texels.len().max(1) as f64;
    let mut sum = [0.0f64; 3];
    for t in &texels {
        for c in 0..3 {
            sum[c] += t[c] as f64;
        }
    }
    sum.map(|s| (s / n) as f32)
}

/// The glTF spot falloff, (clamp((cosθ − cos_outer)/(cos_inner − cos_outer)))², on
/// Mitsuba's spot texture parameterisation.
fn spot_falloff_pfm(l: &gpu::PunctualLight, outer: f32, res: u32) -> Vec<u8> {
    let tan_c = outer.tan();
    let ramp = (l.cos_inner - l.cos_outer).max(1e-4);
    let mut rgb = Vec::with_capacity((res * res) as usize);
    for y in 0..res {
        for x in 0..res {
            let a = (2.0 * (x as f32 + 0.5) / res as f32 - 1.0) * tan_c;
            let b = (2.0 * (y as f32 + 0.5) / res as f32 - 1.0) * tan_c;
            let cos = 1.0 / (1.0 + a * a + b * b).sqrt();
            let t = ((cos - l.cos_outer) / ramp).clamp(0.0, 1.0);
            rgb.push([t * t; 3]);
        }
    }
    files::pfm_bytes(res, res, &rgb)
}

fn rgb_xml(name: &str, c: [f32; 3]) -> String {
    format!(
        "<rgb name=\"{name}\" value=\"{}, {}, {}\"/>",
        c[0], c[1], c[2]
    )
}

fn bitmap_xml(
    name: &str,
    file: &str,
    raw: bool,
    tex: &TextureData,
    to_uv: &Mat3,
    indent: &str,
) -> String {
    let wrap = match tex.sampler.wrap_u {
        WrapMode::Repeat => "repeat",
        WrapMode::MirroredRepeat => "mirror",
        WrapMode::ClampToEdge => "clamp",
    };
    let mut s = String::new();
    let _ = writeln!(s, "{indent}<texture type=\"bitmap\" name=\"{name}\">");
    let _ = writeln!(s, "{indent}  <string name=\"filename\" value=\"{file}\"/>");
    let _ = writeln!(s, "{indent}  <boolean name=\"raw\" value=\"{raw}\"/>");
    let _ = writeln!(s, "{indent}  <string name=\"wrap_mode\" value=\"{wrap}\"/>");
    let _ = writeln!(
        s,
        "{indent}  <string name=\"filter_type\" value=\"{}\"/>",
        if tex.sampler.nearest {
            "nearest"
        } else {
            "bilinear"
        }
    );
    if *to_uv != Mat3::IDENTITY {
        // Mitsuba reads a 9-value <matrix> as a linear 3×3 and drops its translation;
        // a 4×4 with the affine 2D map in rows/columns 0, 1 and 3 survives intact.
        let m = to_uv.to_cols_array_2d();
        let m4 = Mat4::from_cols_array_2d(&[
            [m[0][0], m[0][1], 0.0, 0.0],
            [m[1][0], m[1][1], 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [m[2][0], m[2][1], 0.0, 1.0],
        ]);
        let _ = writeln!(s, "{indent}  {}", matrix_xml("to_uv", &m4));
    }
    let _ = writeln!(s, "{indent}</texture>");
    s
}

/// `<transform name=…><matrix value="row-major 4×4"/></transform>`.
fn matrix_xml(name: &str, m: &Mat4) -> String {
    let rows = m.transpose().to_cols_array();
    format!(
        "<transform name=\"{name}\"><matrix value=\"{}\"/></transform>",
        rows.map(|v| v.to_string()).join(" ")
    )
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace("--", "- -")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uv_matrix_matches_transform_uv() {
        let t = gpu::TextureRef {
            index: 0,
            uv_set: 0,
            offset: [0.25, -0.5],
            scale: [2.0, 0.5],
            rotation: 0.7,
        };
        let m = uv_matrix(&t);
        for uv in [[0.0, 0.0], [1.0, 0.0], [0.3, 0.8]] {
            let a = transform_uv(&t, uv);
            let b = m.transform_point2(Vec2::from(uv));
            assert!((Vec2::from(a) - b).length() < 1e-6, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn back_sheet_faces_away() {
        let mesh = PlyMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            faces: vec![[0, 1, 2]],
            ..Default::default()
        };
        let back = back_sheet(&mesh, 0.01);
        let [a, b, c] = back.faces[0].map(|i| Vec3::from(back.positions[i as usize]));
        let n = (b - a).cross(c - a).normalize();
        assert!((n - Vec3::NEG_Z).length() < 1e-6);
        assert!((a.z + 0.01).abs() < 1e-7);
    }
}
