//! Small XML builders of the Mitsuba scene: colours, bitmaps, matrices, the integrator,
//! and KHR_texture_transform as a matrix.

use super::ExportOptions;
use crate::gpu;
use crate::vk::{SamplerDesc, WrapMode};
use glam::{Mat3, Mat4, Vec3};
use std::fmt::Write as _;

pub(super) fn integrator_xml(o: &ExportOptions) -> String {
    // Russian roulette only adds noise here (lanterna's is off by default): start it
    // beyond the last segment. Mitsuba's `hide_emitters` is never set: it makes emitters
    // invisible to camera rays (they see what is behind them), while lanterna's
    // --hide-emitters drops only their emission and keeps the light their surfaces
    // reflect. That quantity is max_depth D minus max_depth 1 with the same seed (the
    // manifest's `hide_emitters`; scripts/mitsuba_compare.py renders it).
    let note = if o.hide_emitters {
        "  <!-- lanterna --hide-emitters: render max_depth D minus max_depth 1 with the same seed \
         (Mitsuba's hide_emitters would make emitters invisible to camera rays) -->\n"
    } else {
        ""
    };
    format!(
        "{note}  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"$max_depth\"/>\n    <integer name=\"rr_depth\" value=\"{}\"/>\n    <boolean name=\"hide_emitters\" value=\"false\"/>\n  </integrator>\n",
        o.max_depth.max(1) + 1000,
    )
}

pub(super) fn is_identity(t: &gpu::TextureRef) -> bool {
    t.offset == [0.0, 0.0] && t.scale == [1.0, 1.0] && t.rotation == 0.0
}

/// KHR_texture_transform as an affine 3×3 matrix, the same map as
/// [`crate::lights::transform_uv`].
pub(super) fn uv_matrix(t: &gpu::TextureRef) -> Mat3 {
    let (s, c) = t.rotation.sin_cos();
    Mat3::from_cols(
        Vec3::new(c * t.scale[0], -s * t.scale[0], 0.0),
        Vec3::new(s * t.scale[1], c * t.scale[1], 0.0),
        Vec3::new(t.offset[0], t.offset[1], 1.0),
    )
}

/// A spot light's projected texture (`file`, linear values, clamped at its edges),
/// indented for an emitter's body; `nearest` looks texels up without filtering.
pub(super) fn spot_texture_xml(file: &str, nearest: bool) -> String {
    let mut s = String::from("    <texture type=\"bitmap\" name=\"texture\">\n");
    s += &format!("      <string name=\"filename\" value=\"{file}\"/>\n");
    s.push_str("      <boolean name=\"raw\" value=\"true\"/>\n");
    if nearest {
        s.push_str("      <string name=\"filter_type\" value=\"nearest\"/>\n");
    }
    s.push_str("      <string name=\"wrap_mode\" value=\"clamp\"/>\n");
    s.push_str("    </texture>\n");
    s
}

pub(super) fn rgb_xml(name: &str, c: [f32; 3]) -> String {
    format!(
        "<rgb name=\"{name}\" value=\"{}, {}, {}\"/>",
        c[0], c[1], c[2]
    )
}

pub(super) fn bitmap_xml(
    name: &str,
    file: &str,
    raw: bool,
    sampler: SamplerDesc,
    to_uv: &Mat3,
    indent: &str,
) -> String {
    let wrap = match sampler.wrap_u {
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
        if sampler.nearest {
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
pub(super) fn matrix_xml(name: &str, m: &Mat4) -> String {
    let rows = m.transpose().to_cols_array();
    format!(
        "<transform name=\"{name}\"><matrix value=\"{}\"/></transform>",
        rows.map(|v| v.to_string()).join(" ")
    )
}

pub(super) fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace("--", "- -")
}

/// The XML id of material `m`'s BSDF, with or without vertex colours, and with its
/// normal map's green channel negated for triangles whose UVs are mirrored.
pub(super) fn bsdf_id(m: u32, vertex_colors: bool, mirrored_uvs: bool) -> String {
    format!(
        "bsdf{m}{}{}",
        if vertex_colors { "-colors" } else { "" },
        if mirrored_uvs { "-mirrored-uvs" } else { "" }
    )
}

/// Whether the export writes a material as a solid: it bounds one and is not wholly
/// metallic (the export, like the kernel's factors, lets metals transmit nothing).
pub(super) fn is_solid(mat: &gpu::Material) -> bool {
    mat.metallic < 1.0 && crate::scene::bounds_solid(mat)
}

/// A solid's absorption as Mitsuba's `homogeneous` medium (σt = σa, albedo 0: every
/// interaction absorbs), or None for a clear one.
pub(super) fn interior_medium_xml(m: u32, mat: &gpu::Material) -> Option<String> {
    if !is_solid(mat) || mat.attenuation.iter().all(|&a| a <= 0.0) {
        return None;
    }
    // Mitsuba reads an RGB σt as a reflectance (in [0, 1]) times `scale`.
    let scale = mat.attenuation.iter().cloned().fold(0.0, f32::max);
    Some(format!(
        "  <medium type=\"homogeneous\" id=\"{}\">\n    {}\n    <float name=\"scale\" value=\"{scale}\"/>\n    <rgb name=\"albedo\" value=\"0\"/>\n  </medium>\n",
        medium_id(m),
        rgb_xml("sigma_t", mat.attenuation.map(|a| (a / scale).clamp(0.0, 1.0)))
    ))
}

pub(super) fn medium_id(m: u32) -> String {
    format!("interior{m}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::transform_uv;
    use glam::Vec2;

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
}
