//! `plane-quad` and `plane-point`: a large Lambertian plane (y = 0, facing up) lit by one
//! light straight above the origin, with the camera aimed at the origin. The radiance
//! there has a closed form, recorded in `asset.extras.lanterna.analytic`:
//! - square emitter of side 2a, radiance L, at height h, facing down: irradiance
//!   E = 4·L·(A/√(1+A²))·atan(A/√(1+A²)) with A = a/h (four corner-aligned rectangles of
//!   the standard point-to-parallel-rectangle form factor);
//! - point light of intensity I at height h: E = I/h² (also for a spot light, whose axis
//!   points at the origin and whose inner cone contains it).
//!
//! The emitter reflects nothing and the plane is flat, so there is no interreflection:
//! the expected radiance ρ/π·E holds for every max depth ≥ 2.

use super::mesh::MeshData;
use super::writer::{num, Gltf, Material, Node};
use super::{check_range, Built, GenerateError, Options};
use glam::{Quat, Vec3};
use serde_json::{json, Map};

const PLANE_HALF: f32 = 100.0;

fn plane(g: &mut Gltf, albedo: f32) {
    let mut geo = MeshData::new();
    geo.rect(
        Vec3::new(-PLANE_HALF, 0.0, PLANE_HALF),
        Vec3::X * 2.0 * PLANE_HALF,
        -Vec3::Z * 2.0 * PLANE_HALF,
    );
    let mat = g.material(Material::diffuse("plane", [albedo; 3]));
    let mesh = g.mesh("plane", &[(&geo, mat)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("plane"));
}

/// A steep view of the origin (so the centre pixel's footprint on the plane is small)
/// whose line of sight passes beside an emitter of half-side `half` at `height`.
fn camera(g: &mut Gltf, aspect: f32, height: f32, half: f32) {
    let cam = g.camera("camera", 20.0, aspect);
    let elevation = (height / (half + 0.25 * height)).atan();
    let distance = 3.0 * height.max(half);
    let eye = Vec3::new(0.0, elevation.sin(), elevation.cos()) * distance;
    g.camera_node(cam, eye, Vec3::ZERO);
}

/// Irradiance at the point under the centre of a parallel square of half-side `a` at
/// distance `h`, emitting radiance `l` (Lambertian).
pub fn square_irradiance(l: f64, a: f64, h: f64) -> f64 {
    let x = a / h;
    let s = x / (1.0 + x * x).sqrt();
    4.0 * l * s * s.atan()
}

pub fn build_plane_quad(o: &Options) -> Result<Built, GenerateError> {
    let albedo = check_range("albedo", o.albedo.unwrap_or(0.5), 0.0, 1.0, "in [0, 1]")?;
    let radiance = check_range(
        "emission",
        o.emission.unwrap_or(10.0),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let h = check_range(
        "height",
        o.height.unwrap_or(1.0),
        0.01,
        50.0,
        "in [0.01, 50] m",
    )?;
    let side = check_range(
        "size",
        o.size.unwrap_or(0.5),
        0.001,
        50.0,
        "in [0.001, 50] m",
    )?;
    let aspect = o.aspect.unwrap_or(1.0);

    let mut g = Gltf::new();
    plane(&mut g, albedo);
    let a = side / 2.0;
    let mut quad = MeshData::new();
    // Facing down: u × v = X × Z = −Y.
    quad.rect(Vec3::new(-a, h, -a), Vec3::X * side, Vec3::Z * side);
    let mat = g.material(Material::emitter("quad", [radiance; 3]));
    let mesh = g.mesh("emitter", &[(&quad, mat)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("emitter"));
    camera(&mut g, aspect, h, a);

    let e = square_irradiance(radiance as f64, a as f64, h as f64);
    let mut options = Map::new();
    options.insert("albedo".into(), num(albedo));
    options.insert("emission".into(), num(radiance));
    options.insert("height".into(), num(h));
    options.insert("size".into(), num(side));
    options.insert("aspect".into(), num(aspect));
    let analytic = json!({
        "albedo": num(albedo),
        "emitter_radiance": num(radiance),
        "emitter_side": num(side),
        "emitter_height": num(h),
        "look_at": [0.0, 0.0, 0.0],
        "irradiance_at_look_at": e,
        "expected_radiance_at_look_at": albedo as f64 / std::f64::consts::PI * e,
        "formula": "E = 4 L s atan(s), s = A/sqrt(1+A^2), A = (side/2)/height; radiance = albedo/pi * E",
        "valid_for_max_depth_at_least": 2,
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}

pub fn build_plane_point(o: &Options) -> Result<Built, GenerateError> {
    let albedo = check_range("albedo", o.albedo.unwrap_or(0.5), 0.0, 1.0, "in [0, 1]")?;
    let intensity = check_range(
        "intensity",
        o.intensity.unwrap_or(10.0),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let h = check_range(
        "height",
        o.height.unwrap_or(1.0),
        0.01,
        50.0,
        "in [0.01, 50] m",
    )?;
    let aspect = o.aspect.unwrap_or(1.0);

    let mut g = Gltf::new();
    plane(&mut g, albedo);
    let cone = (30f32.to_radians(), 45f32.to_radians());
    let light = g.punctual_light("light", [1.0; 3], intensity, o.spot.then_some(cone));
    // A spot light shines down its local −Z; turning −Z onto −Y is −90° about X.
    let rotation = if o.spot {
        Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)
    } else {
        Quat::IDENTITY
    };
    g.node(Node {
        name: Some("light".into()),
        light: Some(light),
        translation: Vec3::new(0.0, h, 0.0),
        rotation,
        scale: Vec3::ONE,
        ..Default::default()
    });
    camera(&mut g, aspect, h, 0.0);

    let e = intensity as f64 / (h as f64 * h as f64);
    let mut options = Map::new();
    options.insert("albedo".into(), num(albedo));
    options.insert("intensity".into(), num(intensity));
    options.insert("height".into(), num(h));
    options.insert("spot".into(), json!(o.spot));
    options.insert("aspect".into(), num(aspect));
    let mut analytic = json!({
        "albedo": num(albedo),
        "light_intensity": num(intensity),
        "light_height": num(h),
        "light_type": if o.spot { "spot" } else { "point" },
        "look_at": [0.0, 0.0, 0.0],
        "irradiance_at_look_at": e,
        "expected_radiance_at_look_at": albedo as f64 / std::f64::consts::PI * e,
        "formula": "E = intensity / height^2; radiance = albedo/pi * E",
        "valid_for_max_depth_at_least": 2,
    });
    if o.spot {
        analytic["spot_inner_cone_angle"] = num(cone.0);
        analytic["spot_outer_cone_angle"] = num(cone.1);
    }
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}

#[cfg(test)]
mod tests {
    use super::square_irradiance;

    #[test]
    fn square_irradiance_limits() {
        // A huge square is an infinite plane: E = π L.
        assert!((square_irradiance(1.0, 1e6, 1.0) - std::f64::consts::PI).abs() < 1e-5);
        // A tiny square is a point source of intensity L·area: E = L·(2a)²/h².
        let (a, h) = (1e-3, 2.0);
        let e = square_irradiance(3.0, a, h);
        assert!((e / (3.0 * 4.0 * a * a / (h * h)) - 1.0).abs() < 1e-5);
    }
}
