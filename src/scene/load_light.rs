//! KHR_lights_punctual and EXT_lights_ies → the kernel's punctual lights, placed in
//! world space.

use crate::gpu;
use glam::{Mat4, Vec3};

pub(super) fn convert_light(
    light: &gltf::khr_lights_punctual::Light<'_>,
    world: &Mat4,
    node: &str,
) -> Result<gpu::PunctualLight, String> {
    use gltf::khr_lights_punctual::Kind;
    let color = light.color();
    let intensity = light.intensity();
    if !intensity.is_finite() || intensity < 0.0 || color.iter().any(|c| !c.is_finite() || *c < 0.0)
    {
        return Err(format!(
            "light on node {node} has a non-finite or negative intensity/colour"
        ));
    }
    // The bound emission has (material::MAX_EMISSION), for the same reason.
    let peak = color.iter().fold(0.0f32, |m, &c| m.max(c * intensity));
    if peak > super::material::MAX_EMISSION {
        return Err(format!(
            "light on node {node} has intensity × colour {peak:e}, above {:e}: far beyond \
             any physical light, where the renderer's 32-bit arithmetic overflows",
            super::material::MAX_EMISSION
        ));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .normalize_or(Vec3::NEG_Z);
    let (kind, cos_inner, cos_outer) = match light.kind() {
        Kind::Point => (gpu::PUNCTUAL_POINT, 1.0, 1.0),
        Kind::Directional => (gpu::PUNCTUAL_DIRECTIONAL, 1.0, 1.0),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let outer = outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2);
            let inner = inner_cone_angle.clamp(0.0, outer);
            (gpu::PUNCTUAL_SPOT, inner.cos(), outer.cos())
        }
    };
    Ok(gpu::PunctualLight {
        position: position.into(),
        kind,
        direction: direction.into(),
        range: light.range().unwrap_or(0.0),
        intensity: color.map(|c| c * intensity),
        cos_inner,
        cos_outer,
        profile: gpu::INVALID_INDEX,
        tangent: [0.0; 3],
    })
}

/// A node's `EXT_lights_ies` light: a point light at the node whose intensity toward
/// each direction is its profile's candela (packed at `offset` in the scene's light
/// profile array) times `multiplier × color`. The profile's vertical angle 0 is the
/// node's −Z and its horizontal angle 0 the node's +X (`ies.rs` says the frame); a
/// mirroring transform mirrors the profile. The node's scale does not change the
/// intensity, as the extension says.
pub(super) fn convert_ies_light(
    value: &serde_json::Value,
    offsets: &[u32],
    world: &Mat4,
    node: &str,
) -> Result<gpu::PunctualLight, String> {
    let ext = super::ies::EXTENSION;
    let index = value
        .get("light")
        .and_then(|l| l.as_u64())
        .ok_or_else(|| format!("node {node}: {ext} has no `light` index"))?;
    let &offset = offsets.get(index as usize).ok_or_else(|| {
        format!(
            "node {node}: {ext} light {index} does not exist (the file has {})",
            offsets.len()
        )
    })?;
    let multiplier = match value.get("multiplier") {
        None => 1.0,
        Some(m) => m
            .as_f64()
            .filter(|m| m.is_finite() && *m >= 0.0)
            .ok_or_else(|| format!("node {node}: {ext} `multiplier` is not a number ≥ 0"))?
            as f32,
    };
    let color = match value.get("color") {
        None => [1.0f32; 3],
        Some(c) => {
            let c: Vec<f64> = c
                .as_array()
                .filter(|a| a.len() == 3)
                .map(|a| a.iter().filter_map(|x| x.as_f64()).collect())
                .filter(|v: &Vec<f64>| v.len() == 3 && v.iter().all(|x| x.is_finite()))
                .ok_or_else(|| format!("node {node}: {ext} `color` is not three numbers"))?;
            // Linear RGB clamped to [0, 1], as the extension says.
            [0, 1, 2].map(|i| c[i].clamp(0.0, 1.0) as f32)
        }
    };
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .normalize_or(Vec3::NEG_Z);
    let x = world.transform_vector3(Vec3::X);
    let tangent = (x - x.dot(direction) * direction)
        .try_normalize()
        .unwrap_or_else(|| direction.any_orthonormal_vector());
    let mirrored = glam::Mat3::from_mat4(*world).determinant() < 0.0;
    Ok(gpu::PunctualLight {
        position: position.into(),
        kind: gpu::PUNCTUAL_POINT,
        direction: direction.into(),
        range: 0.0,
        intensity: color.map(|c| c * multiplier),
        cos_inner: 1.0,
        cos_outer: 1.0,
        profile: offset
            | if mirrored {
                super::ies::PROFILE_MIRRORED
            } else {
                0
            },
        tangent: tangent.into(),
    })
}
