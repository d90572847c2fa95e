//! Adversarial scenes for the light-transport conformance suite (`tests/conformance.rs`):
//! small rooms where a renderer's geometric shortcuts show as lost or leaked light.
//! Every surface is Lambertian (or an emitter with a black base), so Mitsuba 3's `path`
//! integrator on the exported scene is an exact, independent reference.
//!
//! - `sconces`: a closed room whose lamps sit on, near or inside other geometry —
//!   closed emissive cubes 1–5 cm in front of a wall, a wall-washer panel facing the wall
//!   2 cm away, a two-sided emissive fin touching the wall, lamps standing on and sunk
//!   into a ledge, a 1 cm lamp, a lamp 1 cm under a 2 mm slab (thin-slab leaks), a strip
//!   lying 1 mm above the floor (seen and lighting at grazing angles) and a large dim
//!   ceiling panel.
//! - `punctual-near`: point and spot lights 1–5 cm from walls, floor, a box top and the
//!   ceiling corner.
//! - `alpha-lights`: a lantern — a lamp inside a cage of alpha-masked lattice walls (MASK,
//!   nearest-filtered binary alpha) — lighting the floor and walls through the holes only;
//!   Mitsuba has no exact counterpart, so the suite compares lanterna's strategies with
//!   each other there.
//!
//! All kinds take `--offset X,Y,Z` (handled by the writer: the whole scene, camera
//! included, moves), which the suite uses to check precision far from the origin.

use super::mesh::MeshData;
use super::textures;
use super::writer::{num, Filter, Gltf, Material, Node};
use super::{check_range, Built, GenerateError, Options};
use glam::{Quat, Vec2, Vec3};
use serde_json::{json, Map};

const WARM: [f32; 3] = [1.0, 0.8, 0.6];
const COOL: [f32; 3] = [0.6, 0.8, 1.0];

fn scaled(c: [f32; 3], s: f32) -> [f32; 3] {
    [c[0] * s, c[1] * s, c[2] * s]
}

/// Adds a mesh of one material as its own node (one light model when it emits).
fn place(g: &mut Gltf, name: &str, geo: &MeshData, material: usize) {
    let mesh = g.mesh(name, &[(geo, material)]);
    g.node(Node::mesh(mesh, Vec3::ZERO).named(name));
}

/// A closed cube lamp (six outward emitting faces) from `min` to `min + size`.
fn cube_lamp(g: &mut Gltf, name: &str, min: Vec3, size: f32, radiance: [f32; 3]) {
    let mut geo = MeshData::new();
    geo.cuboid(min, min + Vec3::splat(size));
    let m = g.material(Material::emitter(name, radiance));
    place(g, name, &geo, m);
}

fn finish(g: Gltf, o: &Options, analytic: serde_json::Value) -> Built {
    let mut options = Map::new();
    if let Some(a) = o.aspect {
        options.insert("aspect".into(), num(a));
    }
    Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    }
}

pub fn build_sconces(o: &Options) -> Result<Built, GenerateError> {
    let aspect = o.aspect.unwrap_or(4.0 / 3.0);
    let mut g = Gltf::new();
    let wall = g.material(Material::diffuse("wall", [0.6, 0.6, 0.6]));
    let ledge_m = g.material(Material::diffuse("ledge", [0.7, 0.65, 0.6]));

    // The room: x ∈ [−2, 2], y ∈ [0, 2.4], z ∈ [−2, 2], faces looking inward.
    let mut room = MeshData::new();
    room.aabb(
        Vec3::new(-2.0, 0.0, -2.0),
        Vec3::new(2.0, 2.4, 2.0),
        false,
        0,
    );
    place(&mut g, "room", &room, wall);

    // A ledge on the back wall (z = −2), sharing the wall's plane.
    let mut ledge = MeshData::new();
    ledge.cuboid(Vec3::new(-1.8, 0.8, -2.0), Vec3::new(1.8, 0.84, -1.7));
    // A 2 mm slab with a lamp 1 cm under it: its top must stay dark.
    ledge.cuboid(Vec3::new(0.9, 0.5, -2.0), Vec3::new(1.7, 0.502, -1.5));
    place(&mut g, "ledge", &ledge, ledge_m);

    // Closed emissive cubes in front of the wall: 10 cm at 5 cm, 6 cm at 1 cm.
    cube_lamp(
        &mut g,
        "cube-gap-5cm",
        Vec3::new(-1.55, 1.5, -1.95),
        0.1,
        scaled(WARM, 40.0),
    );
    cube_lamp(
        &mut g,
        "cube-gap-1cm",
        Vec3::new(-0.93, 1.6, -1.99),
        0.06,
        scaled(COOL, 60.0),
    );
    // A wall washer: a one-sided panel 2 cm from the wall, emitting toward it.
    let mut washer = MeshData::new();
    washer.rect(Vec3::new(-0.3, 1.5, -1.98), Vec3::Y * 0.15, Vec3::X * 0.3); // faces −z
    let m = g.material(Material::emitter("washer", scaled(WARM, 30.0)));
    place(&mut g, "washer", &washer, m);
    // A two-sided emissive fin touching the wall.
    let mut fin = MeshData::new();
    fin.rect(Vec3::new(0.6, 1.4, -2.0), Vec3::Z * 0.2, Vec3::Y * 0.3);
    let m = g.material(Material {
        double_sided: true,
        ..Material::emitter("fin", scaled(COOL, 15.0))
    });
    place(&mut g, "fin", &fin, m);
    // On the ledge (top at y = 0.84): standing on it, sunk halfway into it, and a 1 cm cube.
    cube_lamp(
        &mut g,
        "on-ledge",
        Vec3::new(-1.2, 0.84, -1.9),
        0.08,
        scaled(WARM, 30.0),
    );
    cube_lamp(
        &mut g,
        "in-ledge",
        Vec3::new(-0.2, 0.80, -1.9),
        0.08,
        scaled(COOL, 30.0),
    );
    cube_lamp(
        &mut g,
        "tiny",
        Vec3::new(0.5, 0.84, -1.8),
        0.01,
        scaled(WARM, 2000.0),
    );
    // Under the slab (bottom at y = 0.5), 1 cm below it.
    cube_lamp(
        &mut g,
        "under-slab",
        Vec3::new(1.28, 0.45, -1.8),
        0.04,
        scaled(WARM, 80.0),
    );
    // A strip lying 1 mm above the floor, facing up.
    let mut strip = MeshData::new();
    strip.rect(
        Vec3::new(-1.5, 0.001, -0.45),
        Vec3::X * 3.0,
        Vec3::Z * -0.05,
    );
    let m = g.material(Material::emitter("strip", scaled(COOL, 5.0)));
    place(&mut g, "strip", &strip, m);
    // A large dim panel under the ceiling, facing down.
    let mut panel = MeshData::new();
    panel.rect(Vec3::new(-0.6, 2.39, -0.6), Vec3::X * 1.2, Vec3::Z * 1.2);
    let m = g.material(Material::emitter("ceiling-panel", [1.5, 1.5, 1.5]));
    place(&mut g, "ceiling-panel", &panel, m);

    let cam = g.camera("room", 60.0, aspect);
    g.camera_node(cam, Vec3::new(0.0, 1.3, 1.9), Vec3::new(0.0, 1.0, -2.0));
    Ok(finish(
        g,
        o,
        json!({"lambertian": true, "mitsuba_exact": true}),
    ))
}

pub fn build_punctual_near(o: &Options) -> Result<Built, GenerateError> {
    let aspect = o.aspect.unwrap_or(4.0 / 3.0);
    let intensity = check_range(
        "intensity",
        o.intensity.unwrap_or(0.5),
        0.0,
        1e6,
        "in [0, 1e6]",
    )?;
    let mut g = Gltf::new();
    let wall = g.material(Material::diffuse("wall", [0.6, 0.6, 0.6]));
    let block_m = g.material(Material::diffuse("block", [0.5, 0.6, 0.7]));
    // The room: x ∈ [−1.5, 1.5], y ∈ [0, 2.2], z ∈ [−1.5, 1.5].
    let mut room = MeshData::new();
    room.aabb(
        Vec3::new(-1.5, 0.0, -1.5),
        Vec3::new(1.5, 2.2, 1.5),
        false,
        0,
    );
    place(&mut g, "room", &room, wall);
    let mut block = MeshData::new();
    block.cuboid(Vec3::new(0.3, 0.0, -1.0), Vec3::new(0.8, 0.4, -0.5));
    place(&mut g, "block", &block, block_m);

    let light = |g: &mut Gltf,
                 name: &str,
                 color: [f32; 3],
                 i: f32,
                 at: Vec3,
                 spot: Option<(f32, f32, Quat)>| {
        let l = g.punctual_light(name, color, i, spot.map(|(a, b, _)| (a, b)));
        g.node(Node {
            name: Some(name.into()),
            light: Some(l),
            translation: at,
            rotation: spot.map_or(Quat::IDENTITY, |(_, _, q)| q),
            scale: Vec3::ONE,
            ..Default::default()
        });
    };
    // glTF spots shine along the node's −Z.
    let down = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let along_wall = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2); // −Z → −X
    light(
        &mut g,
        "point-2cm-wall",
        WARM,
        intensity,
        Vec3::new(-0.7, 1.2, -1.48),
        None,
    );
    light(
        &mut g,
        "point-1cm-block",
        COOL,
        intensity,
        Vec3::new(0.55, 0.41, -0.75),
        None,
    );
    light(
        &mut g,
        "point-ceiling-corner",
        WARM,
        intensity,
        Vec3::new(1.47, 2.18, -1.47),
        None,
    );
    light(
        &mut g,
        "spot-5cm-floor",
        COOL,
        4.0 * intensity,
        Vec3::new(-0.6, 0.05, 0.0),
        Some((0.3, 0.6, down)),
    );
    light(
        &mut g,
        "spot-along-wall",
        WARM,
        4.0 * intensity,
        Vec3::new(1.2, 1.0, -1.45),
        Some((0.2, 0.5, along_wall)),
    );

    let cam = g.camera("room", 60.0, aspect);
    g.camera_node(cam, Vec3::new(0.0, 1.2, 1.4), Vec3::new(0.0, 0.8, -1.5));
    let mut built = finish(g, o, json!({"lambertian": true, "mitsuba_exact": true}));
    built.options.insert("intensity".into(), num(intensity));
    Ok(built)
}

pub fn build_alpha_lights(o: &Options) -> Result<Built, GenerateError> {
    let aspect = o.aspect.unwrap_or(4.0 / 3.0);
    let mut g = Gltf::new();
    let wall = g.material(Material::diffuse("wall", [0.6, 0.6, 0.6]));
    let cells = 6;
    let tex = g.texture(
        "lattice",
        textures::alpha_checker(cells, 8).png()?,
        Filter::Nearest,
    );
    let screen_m = g.material(Material {
        base_color: [0.8, 0.8, 0.8, 1.0],
        base_color_texture: Some(tex),
        alpha_cutoff: Some(0.5),
        double_sided: true,
        ..Material::diffuse("screen", [0.8; 3])
    });
    // An open box (floor, back and side walls): x ∈ [−1.5, 1.5], y ∈ [0, 2], z ∈ [−1.5, 1.5].
    let mut room = MeshData::new();
    room.aabb(
        Vec3::new(-1.5, 0.0, -1.5),
        Vec3::new(1.5, 2.0, 1.5),
        false,
        8 | 32,
    );
    place(&mut g, "room", &room, wall);
    // A lantern: a lamp inside a cage of lattice walls (four sides and a top, each face
    // an alpha-masked checkerboard), so that all of its light leaves through the holes.
    let (lo, hi) = (Vec3::new(-0.25, 0.3, -0.75), Vec3::new(0.25, 0.8, -0.25));
    let mut cage = MeshData::new();
    let d = hi - lo;
    let faces = [
        (lo, Vec3::X * d.x, Vec3::Y * d.y),
        (Vec3::new(lo.x, lo.y, hi.z), Vec3::X * d.x, Vec3::Y * d.y),
        (lo, Vec3::Z * d.z, Vec3::Y * d.y),
        (Vec3::new(hi.x, lo.y, lo.z), Vec3::Z * d.z, Vec3::Y * d.y),
        (Vec3::new(lo.x, hi.y, lo.z), Vec3::X * d.x, Vec3::Z * d.z),
    ];
    for (o, u, v) in faces {
        cage.rect_mapped(o, u, v, Vec2::ZERO, Vec2::ONE);
    }
    place(&mut g, "cage", &cage, screen_m);
    // The lamp, and the cage's solid base plate under it.
    cube_lamp(
        &mut g,
        "lamp",
        Vec3::new(-0.075, 0.45, -0.575),
        0.15,
        scaled(WARM, 25.0),
    );
    let mut base = MeshData::new();
    base.cuboid(Vec3::new(lo.x, 0.0, lo.z), Vec3::new(hi.x, lo.y, hi.z));
    place(&mut g, "base", &base, wall);

    let cam = g.camera("room", 55.0, aspect);
    g.camera_node(cam, Vec3::new(0.0, 1.6, 1.4), Vec3::new(0.0, 0.5, -0.8));
    Ok(finish(
        g,
        o,
        json!({"lambertian": true, "mitsuba_exact": false}),
    ))
}
