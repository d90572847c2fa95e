//! The light table NEE samples from.
//!
//! Every emissive triangle is a light; a *light model* is one mesh instance whose
//! material emits, or one punctual light. The paper's source distribution picks a light
//! model uniformly, then a triangle of it uniformly, then a point on it uniformly; the
//! `power` source picks models and triangles proportionally to emitted power through
//! alias tables; the `tree` source picks models by what they can send toward the shading
//! point (`tree`), then triangles by power. Triangles with zero area or zero emission are dropped here, so they are
//! never sampled, and the triangle→light map lets a BSDF-sampled hit find the
//! probability with which NEE would have chosen the same point (for MIS).

pub mod alias;
pub mod reservoir;
pub mod tree;

use crate::gpu;
use crate::scene::{ies, Scene, SceneError};
use glam::Vec3;
use std::collections::HashMap;

/// GPU-ready light data.
#[derive(Debug)]
pub struct LightTable {
    pub triangles: Vec<gpu::LightTriangle>,
    /// The compact records light sampling reads, one per entry of `triangles`.
    pub candidates: Vec<gpu::LightCandidateTriangle>,
    pub models: Vec<gpu::LightModel>,
    /// Alias table over models by power.
    pub model_alias: Vec<gpu::AliasEntry>,
    /// Per model, an alias table over its triangles by power, stored at the model's
    /// `first_triangle` (same indices as `triangles`).
    pub triangle_alias: Vec<gpu::AliasEntry>,
    /// The light tree's nodes (`--source tree`; each model holds its path in it).
    pub tree: Vec<gpu::LightTreeNode>,
    /// For every triangle of every emissive instance: its light-triangle index or
    /// `INVALID_INDEX` (dropped). Instances point into it with `light_index_offset`.
    pub triangle_light_index: Vec<u32>,
    /// Per scene instance: (light_index_offset, light_model), INVALID_INDEX when none.
    pub instance_lights: Vec<(u32, u32)>,
    /// Triangles dropped for zero area or zero emission.
    pub dropped_triangles: u64,
    /// Sum of model powers (luminance flux, W if units are radiometric).
    pub total_power: f64,
}

/// A glTF spot's falloff toward a direction at cos θ from its axis, as the kernels
/// weigh it (`inc/lights.glsl`): t², t = clamp((cos θ − cos_outer) / R) with R =
/// max(cos_inner − cos_outer, 10⁻⁴).
pub fn spot_falloff(l: &gpu::PunctualLight, cos: f32) -> f32 {
    let t = ((cos - l.cos_outer) / (l.cos_inner - l.cos_outer).max(1e-4)).clamp(0.0, 1.0);
    t * t
}

/// ∫ falloff dω of a unit-intensity glTF spot: the kernels' falloff t², t = clamp((cos θ −
/// cos_outer) / R) with R = max(cos_inner − cos_outer, 10⁻⁴), is 1 above cos_outer + R
/// and (x / R)² over the ramp below it, so the integral over cos θ is 1 − cos_outer − R
/// + R / 3.
fn spot_flux(cos_inner: f32, cos_outer: f32) -> f64 {
    let outer = cos_outer.clamp(-1.0, 1.0) as f64;
    let ramp = ((cos_inner - cos_outer) as f64).max(1e-4).min(1.0 - outer);
    2.0 * std::f64::consts::PI * (1.0 - outer - 2.0 * ramp / 3.0).max(0.0)
}

fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// `KHR_texture_transform` applied to a UV — mirrors `texture_uv` in the kernels.
pub fn transform_uv(t: &gpu::TextureRef, uv: [f32; 2]) -> [f32; 2] {
    let (s, c) = t.rotation.sin_cos();
    let (u, v) = (uv[0] * t.scale[0], uv[1] * t.scale[1]);
    [c * u + s * v + t.offset[0], -s * u + c * v + t.offset[1]]
}

impl LightTable {
    pub fn build(scene: &Scene) -> Result<LightTable, SceneError> {
        let mut triangles = Vec::new();
        let mut candidates = Vec::new();
        let mut models = Vec::new();
        let mut triangle_light_index = Vec::new();
        let mut instance_lights = Vec::with_capacity(scene.instances.len());
        let mut dropped = 0u64;
        // Each emissive texture's largest luminance, found once: a scan of every texel,
        // which per instance or per triangle took minutes on a 2K emissive map.
        let mut max_luminance: Vec<Option<f32>> = vec![None; scene.textures.len()];

        for (instance_index, inst) in scene.instances.iter().enumerate() {
            let prim = &scene.primitives[inst.primitive as usize];
            let material = &scene.materials[prim.material as usize];
            let factor = material.emission;
            let texture = (material.emissive_tex.index >= 0)
                .then(|| &scene.textures[material.emissive_tex.index as usize]);
            let texture_max = texture.map(|t| {
                *max_luminance[material.emissive_tex.index as usize]
                    .get_or_insert_with(|| t.max_luminance())
            });
            let texture_black = texture_max.is_some_and(|m| m <= 0.0);
            let coverage = uniform_coverage(material, prim.color_offset);
            if factor.iter().all(|&c| c <= 0.0) || texture_black || coverage == Some(0.0) {
                if factor.iter().any(|&c| c > 0.0) {
                    dropped += prim.triangle_count as u64;
                }
                instance_lights.push((gpu::INVALID_INDEX, gpu::INVALID_INDEX));
                continue;
            }
            let two_sided = material.flags & gpu::MATERIAL_FLAG_DOUBLE_SIDED != 0;
            // Not opaque: the kernels scale the emission by the coverage at the point.
            let masked = material.alpha_mode != gpu::ALPHA_MODE_OPAQUE;
            // An unlit material's vertex colours tint its emission at the point.
            let tinted = material.flags & gpu::MATERIAL_FLAG_VERTEX_COLOR_EMISSION != 0
                && prim.color_offset != gpu::INVALID_INDEX;
            let flipped = inst.transform.determinant() < 0.0;
            let model_index = models.len() as u32;
            let first = triangles.len() as u32;
            let map_offset = triangle_light_index.len() as u32;
            let mut model_power = 0.0f64;
            for t in 0..prim.triangle_count {
                let [p0, p1, p2] = scene.world_triangle(inst, t);
                let cross = (p1 - p0).cross(p2 - p0);
                let area = 0.5 * cross.length();
                let base = (prim.index_offset + 3 * t) as usize;
                let uv_of = |k: usize| {
                    let v =
                        &scene.vertices[(prim.vertex_offset + scene.indices[base + k]) as usize];
                    if material.emissive_tex.uv_set == 1 {
                        v.uv1
                    } else {
                        v.uv0
                    }
                };
                let uvs = [uv_of(0), uv_of(1), uv_of(2)];
                // The tint's mean over the triangle, the mean of its corners' colours
                // (clamped at 0, as the kernels clamp the interpolated colour): 0 in a
                // channel only where the tint is 0 all over the triangle.
                let tint: [f32; 3] = if tinted {
                    let colour = |k: usize| {
                        scene.colors[(prim.color_offset + scene.indices[base + k]) as usize]
                    };
                    std::array::from_fn(|c| {
                        (0..3).map(|k| colour(k)[c].max(0.0)).sum::<f32>() / 3.0
                    })
                } else {
                    [1.0; 3]
                };
                let emission: [f32; 3] = std::array::from_fn(|c| factor[c] * tint[c]);
                let mean_texture = texture.zip(texture_max).map_or(1.0, |(tex, max)| {
                    let avg = mean_texture_luminance(tex, &material.emissive_tex, uvs);
                    // Never let an estimate make a triangle unsamplable: the power
                    // source must stay positive wherever emission may be.
                    avg.max(1e-3 * max)
                });
                // Where the coverage varies over the emitter, its mean over the triangle
                // (at least 1/64, so that no estimate makes a lit part unsamplable).
                let coverage = coverage.unwrap_or_else(|| {
                    let local = |k: usize| scene.indices[base + k];
                    mean_coverage(scene, material, prim, [local(0), local(1), local(2)])
                        .max(1.0 / 64.0)
                });
                let power = area as f64
                    * coverage as f64
                    * std::f64::consts::PI
                    * luminance(emission) as f64
                    * mean_texture as f64
                    * if two_sided { 2.0 } else { 1.0 };
                let samplable =
                    area.is_finite() && area > 1e-14 && power.is_finite() && power > 0.0;
                if !samplable {
                    dropped += 1;
                    triangle_light_index.push(gpu::INVALID_INDEX);
                    continue;
                }
                let mut normal = cross / (2.0 * area);
                if flipped {
                    normal = -normal;
                }
                triangle_light_index.push(triangles.len() as u32);
                let flags = if two_sided {
                    gpu::LIGHT_CANDIDATE_TWO_SIDED
                } else {
                    0
                } | if texture.is_some() || tinted {
                    gpu::LIGHT_CANDIDATE_TEXTURED
                } else {
                    0
                } | if flipped {
                    gpu::LIGHT_CANDIDATE_FLIPPED
                } else {
                    0
                } | if masked {
                    gpu::LIGHT_CANDIDATE_ALPHA
                } else {
                    0
                };
                candidates.push(gpu::LightCandidateTriangle {
                    p0: p0.into(),
                    inv_area: 1.0 / area,
                    e1: (p1 - p0).into(),
                    flags,
                    e2: (p2 - p0).into(),
                    emission: emission.map(|c| c * mean_texture * coverage),
                });
                triangles.push(gpu::LightTriangle {
                    p0: p0.into(),
                    p1: p1.into(),
                    p2: p2.into(),
                    normal: normal.into(),
                    area,
                    material: prim.material,
                    model: model_index,
                    two_sided: two_sided as u32,
                    uv0: uvs[0],
                    uv1: uvs[1],
                    uv2: uvs[2],
                    power: power as f32,
                    // The scene's instance here; `GpuScene` renumbers it in kernel order.
                    instance: if masked || tinted {
                        instance_index as u32
                    } else {
                        gpu::INVALID_INDEX
                    },
                    primitive: t,
                });
                model_power += power;
            }
            let count = triangles.len() as u32 - first;
            if count == 0 {
                triangle_light_index.truncate(map_offset as usize);
                instance_lights.push((gpu::INVALID_INDEX, gpu::INVALID_INDEX));
                continue;
            }
            models.push(gpu::LightModel {
                first_triangle: first,
                triangle_count: count,
                punctual: gpu::INVALID_INDEX,
                power: model_power as f32,
                tree_path: 0,
                tree_depth: 0,
            });
            instance_lights.push((map_offset, model_index));
        }

        let radius = 0.5 * scene.extent();
        // Each IES profile's flux (∫ candela dω), once per profile.
        let mut profile_flux: HashMap<usize, f64> = HashMap::new();
        for (i, l) in scene.punctual.iter().enumerate() {
            let lum = luminance(l.intensity) as f64;
            let power = match (l.kind, ies::profile_offset(l)) {
                (gpu::PUNCTUAL_POINT, Some(offset)) => {
                    let flux = *profile_flux
                        .entry(offset)
                        .or_insert_with(|| ies::unpack(&scene.light_profiles, offset).flux());
                    flux * lum
                }
                (gpu::PUNCTUAL_POINT, None) => 4.0 * std::f64::consts::PI * lum,
                (gpu::PUNCTUAL_SPOT, _) => spot_flux(l.cos_inner, l.cos_outer) * lum,
                _ => std::f64::consts::PI * (radius * radius) as f64 * lum,
            };
            if power <= 0.0 {
                log::warn!("punctual light {i} emits nothing; ignored");
                continue;
            }
            models.push(gpu::LightModel {
                first_triangle: 0,
                triangle_count: 0,
                punctual: i as u32,
                power: power as f32,
                tree_path: 0,
                tree_depth: 0,
            });
        }

        if models.is_empty() {
            return Err(SceneError::NoLights {
                path: scene.path.clone(),
            });
        }
        if dropped > 0 {
            log::info!(
                "dropped {dropped} emissive triangles with zero area, emission or alpha coverage"
            );
        }

        let model_weights: Vec<f64> = models.iter().map(|m| m.power as f64).collect();
        let model_alias = alias::build(&model_weights).ok_or_else(|| SceneError::Invalid {
            path: scene.path.clone(),
            message: "light powers are not finite".into(),
        })?;
        let mut triangle_alias = vec![gpu::AliasEntry::default(); triangles.len()];
        for m in models.iter().filter(|m| m.triangle_count > 0) {
            let range = m.first_triangle as usize..(m.first_triangle + m.triangle_count) as usize;
            let w: Vec<f64> = triangles[range.clone()]
                .iter()
                .map(|t| t.power as f64)
                .collect();
            let table = alias::build(&w).ok_or_else(|| SceneError::Invalid {
                path: scene.path.clone(),
                message: "emissive triangle powers are not finite".into(),
            })?;
            triangle_alias[range].copy_from_slice(&table);
        }
        let total_power = model_weights.iter().sum();
        let light_tree = tree::build(&models, &triangles, &scene.punctual, &scene.light_profiles);
        for (m, &(path, depth)) in models.iter_mut().zip(&light_tree.paths) {
            m.tree_path = path;
            m.tree_depth = depth;
        }
        Ok(LightTable {
            tree: light_tree.nodes,
            triangles,
            candidates,
            models,
            model_alias,
            triangle_alias,
            triangle_light_index,
            instance_lights,
            dropped_triangles: dropped,
            total_power,
        })
    }

    /// Number of light models (emissive instances + punctual lights).
    pub fn model_count(&self) -> usize {
        self.models.len()
    }
}

/// Mean linear luminance of an emissive texture over a triangle, from a fixed stratified
/// set of barycentric points (deterministic, so power tables do not change run to run).
fn mean_texture_luminance(
    tex: &crate::scene::TextureData,
    tref: &gpu::TextureRef,
    uvs: [[f32; 2]; 3],
) -> f32 {
    mean_over_triangle(|b| {
        let c = tex.texel(transform_uv(tref, interpolate(uvs, b)));
        luminance([c[0], c[1], c[2]])
    })
}

/// The mean of `f` over a triangle, from the centres of its 36 cells of an 8 × 8
/// subdivision (barycentric coordinates of the corners 0, 1, 2).
fn mean_over_triangle(f: impl Fn([f32; 3]) -> f32) -> f32 {
    const N: usize = 8;
    let mut sum = 0.0;
    let mut count = 0;
    for i in 0..N {
        for j in 0..N - i {
            // Centre of a sub-triangle cell in barycentric coordinates.
            let b1 = (i as f32 + 1.0 / 3.0) / N as f32;
            let b2 = (j as f32 + 1.0 / 3.0) / N as f32;
            sum += f([1.0 - b1 - b2, b1, b2]);
            count += 1;
        }
    }
    sum / count as f32
}

fn interpolate<const K: usize>(v: [[f32; K]; 3], b: [f32; 3]) -> [f32; K] {
    std::array::from_fn(|k| b[0] * v[0][k] + b[1] * v[1][k] + b[2] * v[2][k])
}

/// The mean coverage (`geometry_coverage`) over a triangle of an emitter whose alpha
/// varies: the material's alpha factor times its base colour texture's alpha and its
/// vertex colours' (`local`: the triangle's vertex indices within the primitive).
fn mean_coverage(
    scene: &Scene,
    material: &gpu::Material,
    prim: &crate::scene::MeshPrimitive,
    local: [u32; 3],
) -> f32 {
    let vertex = |k: usize| &scene.vertices[(prim.vertex_offset + local[k]) as usize];
    let tref = &material.base_color_tex;
    let texture = (tref.index >= 0).then(|| &scene.textures[tref.index as usize]);
    let uvs: [[f32; 2]; 3] = std::array::from_fn(|k| {
        if tref.uv_set == 1 {
            vertex(k).uv1
        } else {
            vertex(k).uv0
        }
    });
    let colour_alpha: [[f32; 1]; 3] = std::array::from_fn(|k| {
        if prim.color_offset == gpu::INVALID_INDEX {
            [1.0]
        } else {
            [scene.colors[(prim.color_offset + local[k]) as usize][3]]
        }
    });
    mean_over_triangle(|b| {
        let mut alpha = material.base_color[3] * interpolate(colour_alpha, b)[0];
        if let Some(tex) = texture {
            alpha *= tex.texel(transform_uv(tref, interpolate(uvs, b)))[3];
        }
        coverage_at(material, alpha)
    })
}

/// The coverage where a non-opaque material's alpha is `alpha`: for MASK 1 or 0 as it
/// passes the cutoff, for BLEND the alpha itself.
fn coverage_at(material: &gpu::Material, alpha: f32) -> f32 {
    if material.alpha_mode == gpu::ALPHA_MODE_MASK {
        if alpha >= material.alpha_cutoff {
            1.0
        } else {
            0.0
        }
    } else {
        alpha.clamp(0.0, 1.0)
    }
}

/// Area of the triangle (p0, p1, p2).
pub fn triangle_area(p: [Vec3; 3]) -> f32 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}

/// The coverage of an emitter's surface where it is the same everywhere on it (no base
/// colour texture and no vertex colours): 1 when opaque, for alpha MASK 1 or 0 as its
/// alpha passes the cutoff, for BLEND its alpha (what `geometry_coverage` in
/// inc/geometry.glsl finds at every point). `None` where it varies: the kernels then find
/// it per light sample, and the power and RIS's stand-in emission take its mean over each
/// triangle (`mean_coverage`).
fn uniform_coverage(material: &gpu::Material, color_offset: u32) -> Option<f32> {
    if material.alpha_mode == gpu::ALPHA_MODE_OPAQUE {
        return Some(1.0);
    }
    if material.base_color_tex.index >= 0 || color_offset != gpu::INVALID_INDEX {
        return None;
    }
    Some(coverage_at(material, material.base_color[3]))
}

#[cfg(test)]
mod tests {
    use super::spot_flux;

    /// A spot's flux is the integral of the kernels' falloff (a hard cone, glTF's default
    /// 0°–45°, a soft 20°–60° and a wide 60°–120°), by the midpoint rule over cos θ.
    #[test]
    fn spot_flux_integrates_the_falloff() {
        for (inner, outer) in [(30.0f32, 30.0f32), (0.0, 45.0), (20.0, 60.0), (60.0, 120.0)] {
            let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
            let n = 200_000;
            let sum: f64 = (0..n)
                .map(|i| {
                    let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                    let t = ((c - co as f64) / ((ci - co) as f64).max(1e-4)).clamp(0.0, 1.0);
                    t * t
                })
                .sum::<f64>()
                * 2.0
                / n as f64;
            let expected = 2.0 * std::f64::consts::PI * sum;
            let got = spot_flux(ci, co);
            assert!(
                (got - expected).abs() < 1e-4 * expected,
                "spot {inner}°–{outer}°: {got} against {expected}"
            );
        }
    }
}
