//! The sensor (camera frame, field of view axis, box-filtered film) and the punctual
//! lights (point, spot with the glTF falloff, directional).

use super::textures::spot_falloff_pfm;
use super::writer::Writer;
use super::xml::{matrix_xml, rgb_xml, spot_texture_xml};
use super::{ExportError, ExportOptions};
use crate::gpu;
use crate::scene::{Camera, Projection};
use glam::{Mat4, Vec3};
use std::fmt::Write as _;

impl Writer<'_> {
    pub(super) fn sensor_xml(&mut self, camera: &Camera, o: &ExportOptions) -> String {
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
        // The camera's clip planes where it has them (Mitsuba's sensors clip along the
        // view axis, as lanterna's camera rays do), else planes enclosing the scene.
        let clip = camera.clip;
        let far = if clip.far.is_finite() {
            clip.far
        } else {
            (10.0 * (reach + extent)).max(1e4)
        };
        let near = clip.near.max(1e-5 * extent);
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

    /// An `EXT_lights_ies` light as six Mitsuba spot lights at its position, one per
    /// cube face around it (world ±X, ±Y, ±Z), each projecting the profile's candela over
    /// its face through a texture looked up without filtering. The face's square fills
    /// the texels [m, res − m) exactly (the cutoff's tangent is res / (res − 2m), just
    /// wide enough for the face's corners), so that every direction lies in exactly one
    /// spot's texels; within a texel the profile is the texel centre's, the one
    /// approximation, which the manifest lists.
    fn ies_xml(
        &mut self,
        i: usize,
        l: &gpu::PunctualLight,
        offset: usize,
    ) -> Result<String, ExportError> {
        const RES: u32 = 512;
        const MARGIN: u32 = 75; // ≥ RES·(1 − 1/√2)/2: the cone holds the face's corners
        let profile = crate::scene::ies::unpack(&self.scene.light_profiles, offset);
        let p = Vec3::from(l.position);
        let d = Vec3::from(l.direction);
        let x = Vec3::from(l.tangent);
        let mut y = (-d).cross(x);
        if l.profile & crate::scene::ies::PROFILE_MIRRORED != 0 {
            y = -y;
        }
        let tan_c = RES as f32 / (RES - 2 * MARGIN) as f32;
        let cutoff = tan_c.atan().to_degrees();
        self.approximations.push(format!(
            "IES light {i}: its profile is projected by six spot lights, {}² texels per cube face, each texel the profile at its centre",
            RES - 2 * MARGIN
        ));
        let mut s = String::new();
        for (face, n) in [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ]
        .into_iter()
        .enumerate()
        {
            // A right-handed frame (u, v, n): Mitsuba's spot shines along its local +Z.
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            let to_world =
                Mat4::from_cols(u.extend(0.0), v.extend(0.0), n.extend(0.0), p.extend(1.0));
            let mut texels = Vec::with_capacity((RES * RES) as usize);
            for row in 0..RES {
                for col in 0..RES {
                    let inside = (MARGIN..RES - MARGIN).contains(&row)
                        && (MARGIN..RES - MARGIN).contains(&col);
                    let mut c = 0.0;
                    if inside {
                        // Mitsuba's uv = ½ + ½·(x, y)/(z·tan cutoff); row 0 is v = 0.
                        let a = (2.0 * (col as f32 + 0.5) / RES as f32 - 1.0) * tan_c;
                        let b = (2.0 * (row as f32 + 0.5) / RES as f32 - 1.0) * tan_c;
                        let w = (a * u + b * v + n).normalize();
                        let theta = w.dot(d).clamp(-1.0, 1.0).acos();
                        let mut phi = w.dot(y).atan2(w.dot(x));
                        if phi < 0.0 {
                            phi += std::f32::consts::TAU;
                        }
                        c = profile.eval(theta, phi);
                    }
                    texels.push([c; 3]);
                }
            }
            let file = format!("textures/ies{i}_{face}.pfm");
            self.write(&file, &super::files::pfm_bytes(RES, RES, &texels))?;
            let _ = writeln!(s, "  <emitter type=\"spot\">");
            let _ = writeln!(s, "    {}", matrix_xml("to_world", &to_world));
            let _ = writeln!(s, "    {}", rgb_xml("intensity", l.intensity));
            let _ = writeln!(s, "    <float name=\"cutoff_angle\" value=\"{cutoff}\"/>");
            let _ = writeln!(s, "    <float name=\"beam_width\" value=\"{cutoff}\"/>");
            s.push_str(&spot_texture_xml(&file, true));
            s.push_str("  </emitter>\n");
        }
        Ok(s)
    }

    pub(super) fn punctual_xml(
        &mut self,
        i: usize,
        l: &gpu::PunctualLight,
    ) -> Result<String, ExportError> {
        if let Some(offset) = crate::scene::ies::profile_offset(l) {
            return self.ies_xml(i, l, offset);
        }
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
                    s.push_str(&spot_texture_xml(&file, false));
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
