//! One glTF mesh primitive → vertices and indices appended to the scene's arrays and a
//! [`MeshPrimitive`]: attributes read and checked (`gltf_check`), triangles only, within
//! the loader's allocation budget.

use super::gltf_check::{self, Role};
use super::sources;
use super::MeshPrimitive;
use crate::gpu;
use glam::{Mat3, Mat4, Vec3};

/// Where primitives' vertices and indices go, and what they may still take.
pub(super) struct Geometry<'a> {
    /// The document's JSON, for the checks of `gltf_check`.
    pub root: &'a gltf::json::Root,
    pub vertices: &'a mut Vec<gpu::Vertex>,
    pub colors: &'a mut Vec<[f32; 4]>,
    pub indices: &'a mut Vec<u32>,
    pub budget: &'a mut sources::Budget,
}

// The mesh, the primitive and its pose are what it is; the rest is the output and context.
#[allow(clippy::too_many_arguments)]
pub(super) fn load_primitive(
    mesh: &gltf::Mesh<'_>,
    prim: &gltf::Primitive<'_>,
    morph_weights: &[f32],
    joints: Option<&[Mat4]>,
    buffers: &[gltf::buffer::Data],
    material: u32,
    materials: &[gpu::Material],
    out: &mut Geometry<'_>,
    warnings: &mut Vec<String>,
) -> Result<Option<MeshPrimitive>, String> {
    use gltf::mesh::Mode;
    let name = format!(
        "mesh {} primitive {}",
        mesh.name()
            .map(|n| format!("`{n}`"))
            .unwrap_or_else(|| format!("#{}", mesh.index())),
        prim.index()
    );
    match prim.mode() {
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => {}
        other => {
            warnings.push(format!("{name}: mode {other:?} is not triangles; skipped"));
            return Ok(None);
        }
    }
    // Types and ranges first: the crate's readers reinterpret any type as the one asked
    // for, stop silently at a view's end, and panic on some component types.
    let root = out.root;
    let max_bytes = out.budget.left();
    for (semantic, accessor) in prim.attributes() {
        use gltf::Semantic as S;
        let role = match semantic {
            S::Positions => Role::Position,
            S::Normals => Role::Normal,
            S::Tangents => Role::Tangent,
            S::TexCoords(_) => Role::TexCoord,
            S::Colors(_) => Role::Color,
            _ => continue,
        };
        gltf_check::check_accessor(root, accessor.index(), role, max_bytes)
            .map_err(|e| format!("{name}: {e}"))?;
    }
    if let Some(accessor) = prim.indices() {
        gltf_check::check_accessor(root, accessor.index(), Role::Indices, max_bytes)
            .map_err(|e| format!("{name}: {e}"))?;
    }
    // Reading holds every attribute and the index list as temporary arrays, about
    // twice the final vertices and indices: refuse before, not after, allocating them.
    let vertex_count = prim
        .get(&gltf::Semantic::Positions)
        .map_or(0, |a| a.count() as u64);
    let index_count = prim.indices().map_or(vertex_count, |a| a.count() as u64);
    let colour_bytes = if prim.get(&gltf::Semantic::Colors(0)).is_some() {
        16
    } else {
        0
    };
    let per_vertex = std::mem::size_of::<gpu::Vertex>() as u64 + colour_bytes;
    let reading = 2 * (vertex_count * per_vertex + index_count * 4);
    if reading > out.budget.left() {
        return Err(format!(
            "{name}: {vertex_count} vertices and {index_count} indices would take the scene past the input limit"
        ));
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let get = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
    let attribute = |semantic: gltf::Semantic| prim.get(&semantic);
    let mut positions: Vec<[f32; 3]> = attribute(gltf::Semantic::Positions)
        .and_then(|a| read_floats(a, get, false))
        .ok_or_else(|| format!("{name} has no POSITION data"))?;
    if positions.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{name} has non-finite vertex positions"));
    }
    let n = positions.len();
    let has_normals = attribute(gltf::Semantic::Normals).is_some();
    let mut normals: Vec<[f32; 3]> = attribute(gltf::Semantic::Normals)
        .and_then(|a| read_floats(a, get, false))
        .unwrap_or_else(|| vec![[0.0; 3]; n]);
    morph(
        prim,
        morph_weights,
        &mut positions,
        has_normals.then_some(&mut normals[..]),
        (root, max_bytes, &name),
        get,
        warnings,
    )?;
    let mut tangents: Vec<[f32; 4]> = attribute(gltf::Semantic::Tangents)
        .and_then(|a| read_floats(a, get, false))
        .unwrap_or_else(|| vec![[0.0; 4]; n]);
    if let Some(joints) = joints {
        let geometry = Skinned {
            positions: &mut positions,
            normals: &mut normals,
            tangents: &mut tangents,
        };
        skin(prim, joints, geometry, (root, max_bytes, &name), buffers)?;
    }
    // Core glTF allows only normalised integer texture coordinates; files that forget
    // the flag read as normalised, as they always have. With KHR_mesh_quantization the
    // flag decides (unnormalised ones come with a texture transform that scales them).
    let lenient = !gltf_check::uses_quantization(root);
    let uv = |set: u32| -> Vec<[f32; 2]> {
        attribute(gltf::Semantic::TexCoords(set))
            .and_then(|a| read_floats(a, get, lenient))
            .unwrap_or_else(|| vec![[0.0; 2]; n])
    };
    let (uv0, uv1) = (uv(0), uv(1));
    if [normals.len(), tangents.len(), uv0.len(), uv1.len()]
        .iter()
        .any(|&l| l != n)
    {
        return Err(format!("{name} has attributes of different lengths"));
    }
    // COLOR_0 multiplies the base colour (RGB, or RGBA whose alpha multiplies the base
    // alpha), which an unlit material emits; normalised integers are read as [0, 1].
    // Further colour sets have no role.
    let colors: Option<Vec<[f32; 4]>> = reader.read_colors(0).map(|r| r.into_rgba_f32().collect());
    if let Some(c) = &colors {
        if c.len() != n {
            return Err(format!("{name} has attributes of different lengths"));
        }
        if c.iter().flatten().any(|v| !v.is_finite()) {
            return Err(format!("{name} has non-finite vertex colours (COLOR_0)"));
        }
        // They tint an unlit material's emission, which stays within MAX_EMISSION.
        let m = &materials[material as usize];
        if m.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION != 0 {
            let peak = c
                .iter()
                .flat_map(|c| (0..3).map(move |k| m.emission[k] * c[k]))
                .fold(0.0f32, f32::max);
            if peak > super::material::MAX_EMISSION {
                return Err(format!(
                    "{name}: its vertex colours (COLOR_0) make its unlit material emit {peak:e}, \
                     above {:e}: far beyond any physical radiance, where the renderer's \
                     32-bit arithmetic overflows",
                    super::material::MAX_EMISSION
                ));
            }
        }
    }
    if prim.get(&gltf::Semantic::Colors(1)).is_some() {
        warnings.push(format!("{name}: COLOR_1 and later colour sets are ignored"));
    }
    let raw_indices: Vec<u32> = match reader.read_indices() {
        Some(r) => r.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    let tri: Vec<u32> = match prim.mode() {
        Mode::Triangles => raw_indices,
        Mode::TriangleStrip => (2..raw_indices.len())
            .flat_map(|i| {
                let (a, b, c) = (raw_indices[i - 2], raw_indices[i - 1], raw_indices[i]);
                if i % 2 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        _ => (2..raw_indices.len())
            .flat_map(|i| [raw_indices[0], raw_indices[i - 1], raw_indices[i]])
            .collect(),
    };
    let tri_count = tri.len() / 3;
    if tri_count == 0 {
        warnings.push(format!("{name} has no triangles; skipped"));
        return Ok(None);
    }
    if let Some(bad) = tri.iter().find(|&&i| i as usize >= n) {
        return Err(format!("{name} has index {bad} but only {n} vertices"));
    }
    let opaque = materials[material as usize].alpha_mode == gpu::ALPHA_MODE_OPAQUE;

    let color_bytes = colors.as_ref().map_or(0, |c| c.len() * 16);
    let bytes = n * std::mem::size_of::<gpu::Vertex>() + color_bytes + tri_count * 3 * 4;
    out.budget.take(bytes as u64, &name)?;
    if out.vertices.len() + n > u32::MAX as usize
        || out.indices.len() + 3 * tri_count > u32::MAX as usize
    {
        return Err(format!(
            "{name}: the scene has more than 2^32 vertices or indices"
        ));
    }
    if out.colors.len() + colors.as_ref().map_or(0, Vec::len) >= u32::MAX as usize {
        return Err(format!("{name}: the scene has 2^32 vertex colours or more"));
    }
    let color_offset = match colors {
        Some(c) => {
            let offset = out.colors.len() as u32;
            out.colors.extend(c);
            offset
        }
        None => gpu::INVALID_INDEX,
    };
    let (vertices, indices) = (&mut *out.vertices, &mut *out.indices);
    let vertex_offset = vertices.len() as u32;
    let index_offset = indices.len() as u32;
    vertices.extend((0..n).map(|i| {
        // Zero normals mean "use the geometric normal" (glTF: flat shading when absent).
        let nrm = normals[i];
        let len = (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]).sqrt();
        let normal = if len.is_finite() && len > 1e-12 {
            nrm.map(|c| c / len)
        } else {
            [0.0; 3]
        };
        gpu::Vertex {
            position: positions[i],
            normal,
            tangent: if tangents[i].iter().all(|c| c.is_finite()) {
                tangents[i]
            } else {
                [0.0; 4]
            },
            uv0: uv0[i],
            uv1: uv1[i],
        }
    }));
    indices.extend_from_slice(&tri[..tri_count * 3]);
    Ok(Some(MeshPrimitive {
        vertex_offset,
        vertex_count: n as u32,
        index_offset,
        triangle_count: tri_count as u32,
        material,
        opaque,
        color_offset,
        name,
    }))
}

/// Displaces positions and normals (None: the primitive has none) by the morph targets
/// at `weights` (the node's, else the mesh's default weights): a static scene shows
/// base + Σ wᵢ·targetᵢ. Tangent displacements are left out: the shader makes the
/// tangent orthogonal to the normal.
/// Missing weights count as 0 (with a warning when the file gives a different number).
fn morph<'a, 's>(
    prim: &gltf::Primitive<'a>,
    weights: &[f32],
    positions: &mut [[f32; 3]],
    normals: Option<&mut [[f32; 3]]>,
    (root, max_bytes, name): (&gltf::json::Root, u64, &str),
    get: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
    warnings: &mut Vec<String>,
) -> Result<(), String> {
    let targets: Vec<_> = prim.morph_targets().collect();
    if targets.is_empty() {
        return Ok(());
    }
    let mut normals = normals;
    if !weights.is_empty() && weights.len() != targets.len() {
        warnings.push(format!(
            "{name}: {} morph targets but {} weights; missing weights count as 0",
            targets.len(),
            weights.len()
        ));
    }
    if let Some(w) = weights.iter().find(|w| !w.is_finite()) {
        return Err(format!("{name}: morph weight {w} is not finite"));
    }
    let n = positions.len();
    let add = |k: usize,
               accessor: gltf::Accessor<'a>,
               role: Role,
               w: f32,
               to: &mut [[f32; 3]]|
     -> Result<(), String> {
        gltf_check::check_accessor(root, accessor.index(), role, max_bytes)
            .map_err(|e| format!("{name} morph target {k}: {e}"))?;
        let d: Vec<[f32; 3]> = read_floats(accessor, get.clone(), false)
            .ok_or_else(|| format!("{name} morph target {k}: unreadable data"))?;
        if d.len() != n {
            return Err(format!(
                "{name} morph target {k} has {} elements for {n} vertices",
                d.len()
            ));
        }
        for (v, d) in to.iter_mut().zip(&d) {
            for c in 0..3 {
                v[c] += w * d[c];
            }
        }
        Ok(())
    };
    for (k, target) in targets.into_iter().enumerate() {
        let w = weights.get(k).copied().unwrap_or(0.0);
        if w == 0.0 {
            continue;
        }
        if let Some(a) = target.positions() {
            add(k, a, Role::Position, w, positions)?;
        }
        if let (Some(a), Some(normals)) = (target.normals(), normals.as_deref_mut()) {
            add(k, a, Role::Normal, w, normals)?;
        }
    }
    if positions.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{name} has non-finite morphed vertex positions"));
    }
    Ok(())
}

/// The elements of a float or integer vertex attribute as floats: integer components
/// (`KHR_mesh_quantization`, or the core spec's normalised texture coordinates) are
/// mapped to [0, 1] or [−1, 1] when the accessor is normalized (the glTF spec's
/// formulas) or `assume_normalized`, and taken as they are otherwise (the node
/// transform or a texture transform then scales them). `None` when the data cannot be
/// read.
pub(super) fn read_floats<'a, 's, const N: usize>(
    accessor: gltf::Accessor<'a>,
    get: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
    assume_normalized: bool,
) -> Option<Vec<[f32; N]>>
where
    [f32; N]: gltf::accessor::Item,
    [i8; N]: gltf::accessor::Item,
    [u8; N]: gltf::accessor::Item,
    [i16; N]: gltf::accessor::Item,
    [u16; N]: gltf::accessor::Item,
{
    use gltf::accessor::{DataType, Iter};
    let normalized = accessor.normalized() || assume_normalized;
    // The spec's formulas: c / largest, clamped at −1 for signed types (unsigned ones
    // never reach it).
    fn convert<T: Copy + Into<f32>, const N: usize>(
        iter: Iter<'_, [T; N]>,
        largest: f32,
        normalized: bool,
    ) -> Vec<[f32; N]>
    where
        [T; N]: gltf::accessor::Item,
    {
        let f = |c: T| {
            let c: f32 = c.into();
            if normalized {
                (c / largest).max(-1.0)
            } else {
                c
            }
        };
        iter.map(|e| e.map(f)).collect()
    }
    Some(match accessor.data_type() {
        DataType::F32 => Iter::<[f32; N]>::new(accessor, get)?.collect(),
        DataType::I8 => convert(Iter::<[i8; N]>::new(accessor, get)?, 127.0, normalized),
        DataType::U8 => convert(Iter::<[u8; N]>::new(accessor, get)?, 255.0, normalized),
        DataType::I16 => convert(Iter::<[i16; N]>::new(accessor, get)?, 32767.0, normalized),
        DataType::U16 => convert(Iter::<[u16; N]>::new(accessor, get)?, 65535.0, normalized),
        // Refused by `gltf_check::check_accessor` for every vertex attribute.
        DataType::U32 => return None,
    })
}

/// What skinning moves: positions, normals and tangents (morphed already).
struct Skinned<'v> {
    positions: &'v mut [[f32; 3]],
    normals: &'v mut [[f32; 3]],
    tangents: &'v mut [[f32; 4]],
}

/// Linear blend skinning in the scene's static pose (the nodes' own transforms; glTF:
/// the skinned node's transform is ignored): each vertex moves by Σ wᵢ·Jᵢ over its
/// JOINTS_n / WEIGHTS_n sets, Jᵢ = (joint's world transform)·(its inverse bind matrix),
/// given as `joints`. Normals move by the blended matrix's inverse transpose, tangents by
/// the matrix. Weights are normalised by their sum; a vertex without weight stays as
/// stored. `context`: the document, the reading budget and the primitive's name.
fn skin(
    prim: &gltf::Primitive<'_>,
    joints: &[Mat4],
    geometry: Skinned<'_>,
    context: (&gltf::json::Root, u64, &str),
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let (root, max_bytes, name) = context;
    let n = geometry.positions.len();
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let mut blend = vec![Mat4::ZERO; n];
    let mut total = vec![0.0f32; n];
    for set in 0.. {
        let (Some(j), Some(w)) = (
            prim.get(&gltf::Semantic::Joints(set)),
            prim.get(&gltf::Semantic::Weights(set)),
        ) else {
            if set == 0 {
                return Err(format!(
                    "{name} belongs to a skinned node but has no JOINTS_0 and WEIGHTS_0"
                ));
            }
            break;
        };
        for (accessor, role) in [(j, Role::Joints), (w, Role::Weights)] {
            gltf_check::check_accessor(root, accessor.index(), role, max_bytes)
                .map_err(|e| format!("{name}: {e}"))?;
        }
        let indices: Vec<[u16; 4]> = reader
            .read_joints(set)
            .map(|r| r.into_u16().collect())
            .unwrap_or_default();
        let weights: Vec<[f32; 4]> = reader
            .read_weights(set)
            .map(|r| r.into_f32().collect())
            .unwrap_or_default();
        if indices.len() != n || weights.len() != n {
            return Err(format!("{name} has attributes of different lengths"));
        }
        for (v, (js, ws)) in indices.iter().zip(&weights).enumerate() {
            for (&joint, &weight) in js.iter().zip(ws) {
                if !(weight.is_finite() && weight >= 0.0) {
                    return Err(format!("{name}: vertex {v} has joint weight {weight}"));
                }
                if weight == 0.0 {
                    continue;
                }
                let m = joints.get(joint as usize).ok_or_else(|| {
                    format!(
                        "{name}: vertex {v} uses joint {joint}, but the skin has {}",
                        joints.len()
                    )
                })?;
                blend[v] += *m * weight;
                total[v] += weight;
            }
        }
    }
    for v in 0..n {
        if total[v] <= 0.0 {
            continue;
        }
        let m = blend[v] * (1.0 / total[v]);
        let p = m.transform_point3(Vec3::from(geometry.positions[v]));
        if !p.is_finite() {
            return Err(format!(
                "{name}: vertex {v} is skinned to a non-finite position"
            ));
        }
        geometry.positions[v] = p.into();
        let linear = Mat3::from_mat4(m);
        let normal_matrix = linear.inverse().transpose();
        let nrm = normal_matrix * Vec3::from(geometry.normals[v]);
        geometry.normals[v] = if nrm.is_finite() {
            nrm.into()
        } else {
            [0.0; 3]
        };
        let t = geometry.tangents[v];
        let tt = linear * Vec3::new(t[0], t[1], t[2]);
        geometry.tangents[v] = [tt.x, tt.y, tt.z, t[3]];
    }
    Ok(())
}
