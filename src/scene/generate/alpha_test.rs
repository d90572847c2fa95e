//! `alpha-test`: a black, alpha-masked checkerboard quad (8×8 cells, half of them holes)
//! filling the camera's view exactly, in front of a larger emitter of radiance Le. A
//! renderer that honours `alphaMode: MASK` sees Le through the holes and 0 elsewhere, so
//! the image mean is Le/2 and each cell is either Le or 0; one that ignores the mask sees
//! black. The texture uses nearest filtering so the cutoff is unambiguous.

use super::mesh::MeshData;
use super::textures;
use super::writer::{num, Filter, Gltf, Material, Node};
use super::{check_range, Built, GenerateError, Options};
use glam::{Vec2, Vec3};
use serde_json::{json, Map};

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let radiance = check_range(
        "emission",
        o.emission.unwrap_or(1.0),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let aspect = o.aspect.unwrap_or(1.0);
    let mut g = Gltf::new();
    let cells = 8;
    let tex = g.texture(
        "checker",
        textures::alpha_checker(cells, 8).png()?,
        Filter::Nearest,
    );
    let mask = g.material(Material {
        base_color: [0.0, 0.0, 0.0, 1.0],
        base_color_texture: Some(tex),
        alpha_cutoff: Some(0.5),
        double_sided: true,
        ..Material::diffuse("mask", [0.0; 3])
    });
    let mut quad = MeshData::new();
    quad.rect_mapped(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::X * 2.0,
        Vec3::Y * 2.0,
        Vec2::ZERO,
        Vec2::ONE,
    );
    let mesh = g.mesh("mask", &[(&quad, mask)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("mask"));

    let mut back = MeshData::new();
    back.rect(Vec3::new(-3.0, -3.0, -1.0), Vec3::X * 6.0, Vec3::Y * 6.0); // faces +z
    let emitter = g.material(Material::emitter("emitter", [radiance; 3]));
    let mesh = g.mesh("emitter", &[(&back, emitter)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("emitter"));

    // yfov = 2·atan(1/3): the 2 m quad at 3 m fills the frame's height exactly.
    let cam = g.camera("front", 2.0 * (1.0f32 / 3.0).atan().to_degrees(), aspect);
    g.camera_node(cam, Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO);

    let mut options = Map::new();
    options.insert("emission".into(), num(radiance));
    options.insert("aspect".into(), num(aspect));
    let analytic = json!({
        "emitter_radiance": num(radiance),
        "checker_cells": cells,
        "hole_fraction": 0.5,
        "expected_mean_for_aspect_1": num(radiance * 0.5),
        "mask_albedo": 0.0,
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}
