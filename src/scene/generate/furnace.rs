//! `furnace`: a closed box or sphere whose every face looks inward and carries one
//! material, a Lambertian albedo ρ that also emits Le. Inside, every path of any length
//! sees the same radiance field, so a renderer with max depth D must converge to
//! Le·Σ_{k<D} ρ^k at every pixel: the white-furnace test of energy conservation.

use super::mesh::MeshData;
use super::writer::{num, Gltf, Material, Node};
use super::{check_range, Built, GenerateError, Options, Shape};
use glam::{Vec2, Vec3};
use serde_json::{json, Map};

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let albedo = check_range(
        "albedo",
        o.albedo.unwrap_or(0.5),
        0.0,
        0.999,
        "in [0, 0.999]",
    )?;
    let emission = check_range(
        "emission",
        o.emission.unwrap_or(1.0),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let shape = o.shape.unwrap_or(Shape::Box);
    let aspect = o.aspect.unwrap_or(1.0);

    let mut geo = MeshData::new();
    match shape {
        Shape::Box => geo.aabb(Vec3::splat(-1.0), Vec3::splat(1.0), false, 0),
        Shape::Sphere => inward_sphere(&mut geo, 1.0, 48, 24),
    }
    let mut g = Gltf::new();
    let mat = g.material(Material {
        emission: [emission; 3],
        ..Material::diffuse("furnace", [albedo; 3])
    });
    let mesh = g.mesh("enclosure", &[(&geo, mat)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("enclosure"));
    let cam = g.camera("inside", 60.0, aspect);
    g.camera_node(cam, Vec3::new(0.0, 0.0, 0.3), Vec3::new(0.2, 0.1, -1.0));

    let mut options = Map::new();
    options.insert("albedo".into(), num(albedo));
    options.insert("emission".into(), num(emission));
    options.insert(
        "shape".into(),
        json!(if shape == Shape::Box { "box" } else { "sphere" }),
    );
    options.insert("aspect".into(), num(aspect));
    let expected: Vec<f64> = (1..=8)
        .map(|d| {
            (0..d)
                .map(|k| emission as f64 * (albedo as f64).powi(k))
                .sum::<f64>()
        })
        .collect();
    let analytic = json!({
        "albedo": num(albedo),
        "emission": num(emission),
        "formula": "pixel value = emission * sum_{k=0}^{D-1} albedo^k for max depth D",
        "expected_by_max_depth": expected,
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}

/// A UV sphere with its faces wound to look inward (triangles at the poles).
fn inward_sphere(geo: &mut MeshData, r: f32, slices: u32, stacks: u32) {
    let p = |i: u32, j: u32| {
        let (phi, theta) = (
            i as f32 / slices as f32 * std::f32::consts::TAU,
            j as f32 / stacks as f32 * std::f32::consts::PI,
        );
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        ) * r
    };
    for j in 0..stacks {
        for i in 0..slices {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            // Along φ then θ the winding faces outward, so each face is listed reversed.
            if j == 0 {
                geo.triangle(a, d, c);
            } else if j == stacks - 1 {
                geo.triangle(a, d, b);
            } else {
                geo.quad([a, d, c, b], [Vec2::ZERO, Vec2::Y, Vec2::ONE, Vec2::X]);
            }
        }
    }
}
