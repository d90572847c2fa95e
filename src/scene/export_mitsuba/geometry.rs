//! Geometry going out: world-space triangles of each instance appended to per-material
//! PLY meshes (winding fixed under mirroring, normals only where they shade curved
//! surfaces, the texture coordinates a material needs), and the back sheet that makes a
//! double-sided emitter out of two one-sided ones.

use super::files::PlyMesh;
use crate::gpu;
use crate::lights::transform_uv;
use crate::scene::{Instance, MeshPrimitive, Scene};
use glam::{Mat3, Vec3};

/// How a primitive's vertex normals shade it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Shading {
    /// No vertex normals, or all equal to their faces' normals (up to sign): flat.
    Flat,
    /// Every vertex has a normal and some differ from their faces' normals.
    Curved,
    /// Some vertices have normals and some do not: exported flat (approximation).
    Mixed,
}

pub(super) fn shading(scene: &Scene, p: &MeshPrimitive) -> Shading {
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

/// How one material's texture coordinates reach Mitsuba.
#[derive(Clone, Copy)]
pub(super) struct UvPlan {
    /// glTF UV set written to the PLY, `None` when no texture needs coordinates.
    pub(super) set: Option<u32>,
    /// Transform baked into the written coordinates (the emissive texture's, because
    /// Mitsuba's emitter sampling needs its bitmap's own `to_uv` to be the identity).
    pub(super) bake: Option<gpu::TextureRef>,
    /// The material's normal map goes out (`set` is its UV set, nothing baked).
    pub(super) normal: bool,
    /// The PLY's coordinates give Mitsuba the material's tangent frame, for its normal
    /// map or its anisotropy (`set` is the frame's UV set, nothing baked), and its
    /// triangles go out in two groups by the orientation of their UVs.
    pub(super) frame: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub(super) struct GroupKey {
    pub(super) material: u32,
    pub(super) emitter: bool,
    pub(super) smooth: bool,
    /// The base colour is the material's factor × the vertex colours, written into the
    /// PLY (Mitsuba's `vertex_color` attribute); for an unlit material, whose vertex
    /// colours tint its emission, the emission factor × them.
    pub(super) colored: bool,
    /// Triangles with a tangent frame (normal-mapped or anisotropic) on whose front the texture's image appears mirrored
    /// (det(Δuv) > 0 in the PLY's winding, glTF's v pointing down the image): there
    /// lanterna's bitangent is −cross(n, ∂P/∂u), while Mitsuba's is always
    /// +cross(n, ∂P/∂u), so they use the map with its green channel negated (and the
    /// anisotropy's direction mirrored: `scripts/mitsuba_gltf_bsdf.py`).
    pub(super) mirrored_uvs: bool,
}

/// Whether the image mapped by a triangle's UVs (a, b, c, in the PLY's winding) appears
/// mirrored on its front: det(b − a, c − a) > 0, glTF's v pointing down the image (an
/// upright image has det < 0); `None` when the UVs are degenerate.
pub(super) fn uvs_mirrored(uv: [[f32; 2]; 3]) -> Option<bool> {
    let d1 = [uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]];
    let d2 = [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]];
    let det = d1[0] * d2[1] - d1[1] * d2[0];
    (det.abs() > 1e-20).then_some(det > 0.0)
}

/// Whether some triangle of `p` has no UV parameterisation in the set `plan` writes.
pub(super) fn degenerate_uvs(scene: &Scene, p: &MeshPrimitive, plan: UvPlan) -> bool {
    let verts = &scene.vertices[p.vertex_offset as usize..][..p.vertex_count as usize];
    let indices = &scene.indices[p.index_offset as usize..][..3 * p.triangle_count as usize];
    indices.chunks_exact(3).any(|t| {
        let uv = [0, 1, 2].map(|k| {
            let v = &verts[t[k] as usize];
            if plan.set == Some(1) {
                v.uv1
            } else {
                v.uv0
            }
        });
        uvs_mirrored(uv).is_none()
    })
}

/// Append an instance's triangles in world space. Negative-determinant transforms flip
/// the winding, so the triangle's vertex order is reversed to keep Mitsuba's geometric
/// normal on lanterna's front side.
pub(super) fn append_instance(
    mesh: &mut PlyMesh,
    scene: &Scene,
    inst: &Instance,
    key: GroupKey,
    plan: UvPlan,
) {
    let smooth = key.smooth;
    let p = &scene.primitives[inst.primitive as usize];
    if key.colored {
        let material = &scene.materials[p.material as usize];
        let colours = &scene.colors[p.color_offset as usize..][..p.vertex_count as usize];
        if material.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION != 0 {
            // An unlit material: the colours tint its emission (radiance, unbounded),
            // and its BSDF is black.
            let factor = Vec3::from(material.emission);
            mesh.colors.extend(colours.iter().map(|c| {
                (factor * Vec3::from_slice(&c[..3]))
                    .max(Vec3::ZERO)
                    .to_array()
            }));
        } else {
            let factor = Vec3::from_slice(&material.base_color[..3]);
            mesh.colors.extend(colours.iter().map(|c| {
                (factor * Vec3::from_slice(&c[..3]))
                    .clamp(Vec3::ZERO, Vec3::ONE)
                    .to_array()
            }));
        }
    }
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
        let face = if flipped { [a, c, b] } else { [a, b, c] };
        if plan.frame {
            let uv = face.map(|v| mesh.uvs[v as usize]);
            if uvs_mirrored(uv).unwrap_or(false) != key.mirrored_uvs {
                continue;
            }
        }
        mesh.faces.push(face);
    }
}

/// The back sheet of a double-sided emitter: every face reversed (so it emits to the
/// other side) and moved `epsilon` behind the front sheet, which therefore is the first
/// hit from the front and the back sheet the first hit from behind.
pub(super) fn back_sheet(mesh: &PlyMesh, epsilon: f32) -> PlyMesh {
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
            if !mesh.colors.is_empty() {
                out.colors.push(mesh.colors[i as usize]);
            }
        }
        out.faces.push([base, base + 1, base + 2]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

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
