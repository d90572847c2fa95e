//! `gap`: two closed rooms joined by a narrow doorway in a 0.2 m thick wall. The only
//! emitter hangs from the ceiling of the far room, out of sight of the camera in the near
//! room, so every pixel of the near room is lit indirectly through the gap: the case where
//! next-event estimation finds almost nothing and path guiding has to learn the way.
//!
//! Near room: x ∈ [0, 4]; wall: x ∈ [−0.2, 0]; far room: x ∈ [−3.2, −0.2]; all rooms
//! y ∈ [0, 2.6], z ∈ [0, 4]. Doorway: z ∈ [2.9, 3.4], y ∈ [0, 2].

use super::mesh::MeshData;
use super::writer::{num, Gltf, Material, Node};
use super::{check_range, Built, GenerateError, Options};
use glam::Vec3;
use serde_json::{json, Map};

const H: f32 = 2.6;
const D: f32 = 4.0;
const T: f32 = 0.2;
const DOOR: (f32, f32, f32) = (2.9, 3.4, 2.0);

/// The inward faces of a room spanning [x0, x1] × [0, H] × [0, D], except its wall at
/// `open_x`, which the dividing wall provides.
fn room(geo: &mut MeshData, x0: f32, x1: f32, open_x: f32) {
    let skip = if open_x == x0 { 1 } else { 2 };
    geo.aabb(Vec3::new(x0, 0.0, 0.0), Vec3::new(x1, H, D), false, skip);
}

/// One face of the dividing wall at `x`, with the doorway cut out; `sign` is the
/// direction it faces (+1 toward +x).
fn wall_face(geo: &mut MeshData, x: f32, sign: f32) {
    let (z0, z1, top) = DOOR;
    let mut rect = |za: f32, zb: f32, ya: f32, yb: f32| {
        let (o, u, v) = (
            Vec3::new(x, ya, za),
            Vec3::Z * (zb - za),
            Vec3::Y * (yb - ya),
        );
        // Z × Y = −X: swap the edges for a face looking toward +x.
        if sign > 0.0 {
            geo.rect(o, v, u)
        } else {
            geo.rect(o, u, v)
        }
    };
    rect(0.0, z0, 0.0, H);
    rect(z1, D, 0.0, H);
    rect(z0, z1, top, H);
}

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let albedo = check_range("albedo", o.albedo.unwrap_or(0.7), 0.0, 1.0, "in [0, 1]")?;
    let radiance = check_range(
        "emission",
        o.emission.unwrap_or(1000.0),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let aspect = o.aspect.unwrap_or(4.0 / 3.0);
    let mut g = Gltf::new();
    let wall = g.material(Material::diffuse("wall", [albedo; 3]));
    let mut geo = MeshData::new();
    room(&mut geo, 0.0, D, 0.0);
    room(&mut geo, -3.0 - T, -T, -T);
    wall_face(&mut geo, 0.0, 1.0);
    wall_face(&mut geo, -T, -1.0);
    // Doorway reveals, facing into the passage.
    let (z0, z1, top) = DOOR;
    geo.rect(Vec3::new(-T, 0.0, z0), Vec3::X * T, Vec3::Y * top); // side at z0, faces +z
    geo.rect(Vec3::new(-T, 0.0, z1), Vec3::Y * top, Vec3::X * T); // side at z1, faces −z
    geo.rect(Vec3::new(-T, top, z0), Vec3::X * T, Vec3::Z * (z1 - z0)); // lintel, faces down
    let rooms = g.mesh("rooms", &[(&geo, wall)]);
    g.node(Node::mesh(rooms, Vec3::ZERO).named("rooms"));

    // The emitter: a 0.6 m square just under the far room's ceiling, far from the door.
    let side = 0.6;
    let mut quad = MeshData::new();
    quad.rect(
        Vec3::new(-2.6, H - 0.01, 0.5),
        Vec3::X * side,
        Vec3::Z * side,
    );
    let lamp = g.material(Material::emitter(
        "lamp",
        [radiance, radiance * 0.85, radiance * 0.7],
    ));
    let mesh = g.mesh("lamp", &[(&quad, lamp)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named("lamp"));

    let cam = g.camera("near-room", 60.0, aspect);
    g.camera_node(cam, Vec3::new(3.7, 1.5, 0.3), Vec3::new(0.0, 1.0, 3.0));

    let mut options = Map::new();
    options.insert("albedo".into(), num(albedo));
    options.insert("emission".into(), num(radiance));
    options.insert("aspect".into(), num(aspect));
    let analytic = json!({
        "emitter_visible_from_camera": false,
        "doorway": {"x": [-T, 0.0], "y": [0.0, top], "z": [z0, z1]},
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}
