//! The export's state and the scene body: instances grouped per material and role into
//! PLY shapes, each with its BSDF and, for lights, its `area` emitter (two sheets when
//! double-sided), then the punctual lights.

use super::files::PlyMesh;
use super::geometry::{
    append_instance, back_sheet, degenerate_uvs, shading, GroupKey, Shading, UvPlan,
};
use super::xml::{bsdf_id, integrator_xml, interior_medium_xml, medium_id, xml_escape};
use super::{io_err, ExportError, ExportOptions};
use crate::gpu;
use crate::lights::LightTable;
use crate::scene::{Camera, Scene};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::PathBuf;

pub(super) struct Body {
    pub(super) xml: String,
    pub(super) shapes: usize,
    pub(super) emitters: usize,
    pub(super) triangles: u64,
}

pub(super) struct Writer<'a> {
    pub(super) scene: &'a Scene,
    pub(super) dir: PathBuf,
    /// (texture slot, factor bits) → file name relative to the export directory.
    pub(super) textures: HashMap<(i32, [u32; 3]), (String, bool)>,
    /// Textures made for Mitsuba from lanterna's (normal maps with lanterna's arithmetic
    /// baked in, `mask` opacities), by what they were made of → file name.
    pub(super) derived_textures: HashMap<String, String>,
    /// Whether some BSDF went out inside a `mask` (the integrator must be `volpath`).
    pub(super) masks: bool,
    /// Emissive materials under a constant alpha → their coverage, which premultiplies
    /// their radiance (see `opacity_xml`).
    pub(super) emitter_coverage: HashMap<u32, f32>,
    pub(super) approximations: Vec<String>,
    pub(super) warnings: Vec<String>,
    /// Emitters Mitsuba may sample (area emitters of nonzero sampling weight; punctual
    /// lights): it refuses a scene without one.
    pub(super) sampled_emitters: usize,
    /// Gap between the two sheets of a double-sided emitter.
    pub(super) epsilon: f32,
    /// Whether some BSDF went out as `thindielectric` (thin glass that reflects).
    pub(super) thin_walls: bool,
    /// Whether some thin glass is smooth (lanterna: GGX at MIN_GGX_ALPHA; Mitsuba: delta).
    pub(super) smooth_thin_walls: bool,
}

impl Writer<'_> {
    pub(super) fn write(&self, rel: &str, bytes: &[u8]) -> Result<(), ExportError> {
        let path = self.dir.join(rel);
        std::fs::write(&path, bytes).map_err(io_err(&path))
    }

    pub(super) fn material_name(&self, m: u32) -> &str {
        self.scene
            .material_names
            .get(m as usize)
            .map(String::as_str)
            .unwrap_or("?")
    }

    pub(super) fn scene_body(
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
            let colored = prim.color_offset != gpu::INVALID_INDEX;
            let m = &scene.materials[prim.material as usize];
            if colored && m.base_color_tex.index >= 0 {
                self.approximations.push(format!(
                    "mesh {}: its vertex colours are not exported with material `{}`'s base colour texture (Mitsuba has no product of textures)",
                    prim.name,
                    self.material_name(prim.material)
                ));
            } else if colored {
                // Exact while factor × colour stays in [0, 1] at every vertex (for an
                // unlit material's emission, at or above 0): lanterna clamps the
                // interpolated product, Mitsuba interpolates the clamped one.
                let colours =
                    &scene.colors[prim.color_offset as usize..][..prim.vertex_count as usize];
                let tints = m.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION != 0;
                let outside = colours.iter().any(|c| {
                    (0..3).any(|k| {
                        if tints {
                            c[k] < 0.0
                        } else {
                            !(0.0..=1.0).contains(&(m.base_color[k] * c[k]))
                        }
                    })
                });
                if outside {
                    self.approximations.push(format!(
                        "mesh {}: {} leaves [0, {}]; clamped per vertex",
                        prim.name,
                        if tints {
                            "the vertex colour tinting its emission"
                        } else {
                            "base colour × vertex colour"
                        },
                        if tints { "∞)" } else { "1]" }
                    ));
                }
            }
            if plan.frame && degenerate_uvs(scene, prim, plan) {
                self.approximations.push(format!(
                    "mesh {}: triangles without a UV parameterisation under material `{}`'s normal map or anisotropy (lanterna leaves them unmapped or isotropic, Mitsuba takes an arbitrary frame)",
                    prim.name,
                    self.material_name(prim.material)
                ));
            }
            // Normal-mapped and anisotropic meshes go out in two groups by the
            // orientation of their UVs.
            for mirrored_uvs in [false, true] {
                if mirrored_uvs && !plan.frame {
                    continue;
                }
                let key = GroupKey {
                    material: prim.material,
                    emitter,
                    smooth: curved && !emitter,
                    colored: colored && m.base_color_tex.index < 0,
                    mirrored_uvs,
                };
                let mesh = groups.entry(key).or_default();
                append_instance(mesh, scene, inst, key, plan);
            }
            triangles += prim.triangle_count as u64;
        }
        groups.retain(|_, mesh| !mesh.faces.is_empty());
        if plans.values().any(|p| p.normal) {
            // lanterna turns a shading frame seen from below over (its other side
            // reflects), Mitsuba's `normalmap` without its flip reflects nothing there.
            self.approximations.push(
                "normal maps: a texel seen from below its mapped normal (grazing views of tilted texels, from the camera or along a path) reflects in lanterna, not in Mitsuba".into(),
            );
        }
        if groups.keys().any(|k| k.smooth) {
            // Same interpolation, but lanterna also flips shading normals to the
            // geometric side and zeroes light below the geometric surface; Mitsuba
            // does neither.
            self.approximations.push(
                "curved vertex normals: lanterna and Mitsuba treat shading normals that disagree with the geometric normal differently (grazing angles only)".into(),
            );
        }

        // BSDFs, one per material used (with and without vertex colours).
        let mut used: Vec<(u32, bool, bool)> = groups
            .keys()
            .map(|k| (k.material, k.colored, k.mirrored_uvs))
            .collect();
        used.sort_unstable();
        used.dedup();
        for &(m, colored, mirrored_uvs) in &used {
            let plan = plans[&m];
            xml.push_str(&self.bsdf_xml(m, plan, colored, mirrored_uvs)?);
        }

        // The absorbing interiors of solids (KHR_materials_volume).
        let mut media = Vec::new();
        for &(m, _, _) in &used {
            if let Some(medium) = interior_medium_xml(m, &scene.materials[m as usize]) {
                if !media.contains(&m) {
                    xml.push_str(&medium);
                    media.push(m);
                }
            }
        }
        if !media.is_empty() || self.masks {
            // Mitsuba's `path` ignores media and stops shadow rays at `mask`s; `volpath`
            // is `path` plus them (a shadow ray passes a null interface with its null
            // transmission, as lanterna's pass alpha), except that it takes a straight
            // pass through `thindielectric` (a null event) without counting a bounce,
            // where `path` and lanterna count one (thin glass that does not reflect goes
            // out as a `dielectric`, which it counts). A pass through a mask's hole is no
            // bounce in either.
            xml = xml.replacen(
                "<integrator type=\"path\">",
                "<integrator type=\"volpath\">",
                1,
            );
            if self.thin_walls {
                self.approximations.push(
                    "absorbing solids and alpha need Mitsuba's `volpath`, which does not count a pass through thin transmitting glass (`thindielectric`) as a bounce, as lanterna does: paths through thin glass reach one bounce further there".into(),
                );
            }
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
                    "meshes/m{}{}{}{}{}{}.ply",
                    key.material,
                    if key.emitter { "-emitter" } else { "" },
                    if key.smooth { "-smooth" } else { "" },
                    if key.colored { "-colors" } else { "" },
                    if key.mirrored_uvs {
                        "-mirrored-uvs"
                    } else {
                        ""
                    },
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
                let _ = writeln!(
                    xml,
                    "    <ref id=\"{}\"/>",
                    bsdf_id(key.material, key.colored, key.mirrored_uvs)
                );
                if media.contains(&key.material) {
                    let _ = writeln!(
                        xml,
                        "    <ref name=\"interior\" id=\"{}\"/>",
                        medium_id(key.material)
                    );
                }
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
            self.sampled_emitters += 1;
        }
        if self.smooth_thin_walls
            && scene
                .punctual
                .iter()
                .any(|l| l.intensity.iter().any(|&c| c > 0.0))
        {
            self.approximations.push(
                "point and spot lights with smooth thin glass: lanterna's smooth glass is a GGX lobe of α = MIN_GGX_ALPHA, through which a point light shows as a small highlight; Mitsuba's is a delta, through which it shows nothing".into(),
            );
        }
        if emitters > 0 && self.sampled_emitters == 0 {
            xml.push_str(
                "  <!-- Every emitter has sampling weight 0 and Mitsuba needs one it may sample: this one emits nothing. -->\n  <emitter type=\"point\">\n    <point name=\"position\" x=\"0\" y=\"0\" z=\"0\"/>\n    <rgb name=\"intensity\" value=\"0\"/>\n  </emitter>\n",
            );
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
}
