//! KHR_lights_punctual → the kernel's punctual lights, placed in world space.

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
    })
}
