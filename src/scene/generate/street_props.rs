//! Street furniture for the `street` scene, built once in its own local frame and
//! placed many times as instances: lamp post, wall lantern, bistro table and chair,
//! candle holder and planter with alpha-masked foliage. Only geometry lives here; the
//! bulbs that make these objects light sources are separate light-model nodes placed by
//! `street`, at the offsets given by the `*_BULB` constants.

use super::mesh::MeshData;
use glam::{Mat4, Quat, Vec2, Vec3};

/// Where a lamp post's bulb sits above its base.
pub const POST_BULB: Vec3 = Vec3::new(0.0, 3.83, 0.0);
/// Where a wall lantern's bulb sits relative to its wall anchor (+z away from the wall).
pub const WALL_BULB: Vec3 = Vec3::new(0.0, -0.16, 0.42);
/// Height of a table's candle flame above the ground the table stands on.
pub const CANDLE_FLAME: Vec3 = Vec3::new(0.0, 0.845, 0.0);

/// A lantern cage: base plate, four corner bars and a pyramid cap, centred on x = z = 0
/// with its plate at y = 0.
pub fn lantern(metal: &mut MeshData, half: f32, height: f32) {
    let bar = 0.012;
    metal.cuboid(Vec3::new(-half, 0.0, -half), Vec3::new(half, 0.03, half));
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let c = Vec3::new(sx * (half - bar), 0.03, sz * (half - bar));
        metal.aabb(
            c - Vec3::new(bar, 0.0, bar),
            c + Vec3::new(bar, height, bar),
            true,
            12,
        );
    }
    metal.pyramid(Vec3::new(0.0, 0.03 + height, 0.0), half * 1.35, half * 1.1);
    metal.aabb(
        Vec3::new(-half * 1.35, height + 0.01, -half * 1.35),
        Vec3::new(half * 1.35, height + 0.03, half * 1.35),
        true,
        8,
    );
}

/// Lamp post standing on the origin; one primitive, glossy metal.
pub fn lamp_post() -> MeshData {
    let mut m = MeshData::new();
    m.cuboid(Vec3::new(-0.16, 0.0, -0.16), Vec3::new(0.16, 0.45, 0.16));
    m.prism(Vec3::new(0.0, 0.45, 0.0), 0.065, 3.2, 8);
    m.prism(Vec3::new(0.0, 3.55, 0.0), 0.1, 0.1, 8);
    let mut cage = MeshData::new();
    lantern(&mut cage, 0.17, 0.42);
    m.append(&cage, Mat4::from_translation(Vec3::new(0.0, 3.65, 0.0)));
    m
}

/// Wall lantern anchored at the origin on a wall facing +z: bracket and cage.
pub fn wall_lantern() -> MeshData {
    let mut m = MeshData::new();
    m.cuboid(Vec3::new(-0.08, -0.15, 0.0), Vec3::new(0.08, 0.15, 0.04));
    m.cuboid(Vec3::new(-0.02, 0.06, 0.0), Vec3::new(0.02, 0.1, 0.45));
    let mut cage = MeshData::new();
    lantern(&mut cage, 0.1, 0.26);
    m.append(&cage, Mat4::from_translation(Vec3::new(0.0, -0.32, 0.42)));
    m.cuboid(
        Vec3::new(-0.015, -0.02, 0.405),
        Vec3::new(0.015, 0.08, 0.435),
    );
    m
}

/// Bistro table on the origin: (top, frame) primitives.
pub fn table() -> (MeshData, MeshData) {
    let (mut top, mut frame) = (MeshData::new(), MeshData::new());
    top.prism(Vec3::new(0.0, 0.72, 0.0), 0.36, 0.03, 16);
    frame.prism(Vec3::new(0.0, 0.02, 0.0), 0.03, 0.7, 6);
    frame.prism(Vec3::ZERO, 0.24, 0.02, 12);
    (top, frame)
}

/// Bistro chair on the origin, facing +z (its back at −z): (seat, frame).
pub fn chair() -> (MeshData, MeshData) {
    let (mut seat, mut frame) = (MeshData::new(), MeshData::new());
    seat.cuboid(Vec3::new(-0.21, 0.44, -0.2), Vec3::new(0.21, 0.47, 0.2));
    seat.cuboid(Vec3::new(-0.2, 0.62, -0.23), Vec3::new(0.2, 0.88, -0.2));
    let leg = 0.014;
    for (x, z) in [(-0.18, -0.18), (0.18, -0.18), (0.18, 0.17), (-0.18, 0.17)] {
        frame.cuboid(
            Vec3::new(x - leg, 0.0, z - leg),
            Vec3::new(x + leg, 0.44, z + leg),
        );
    }
    for x in [-0.18, 0.18] {
        frame.cuboid(
            Vec3::new(x - leg, 0.47, -0.23),
            Vec3::new(x + leg, 0.9, -0.2),
        );
    }
    (seat, frame)
}

/// A small glass candle holder standing on the origin.
pub fn candle_holder() -> MeshData {
    let mut m = MeshData::new();
    m.prism(Vec3::ZERO, 0.035, 0.08, 8);
    m
}

/// Planter box on the origin: (box, foliage) primitives; the foliage is two crossed
/// quads mapped to the whole leaf texture.
pub fn planter() -> (MeshData, MeshData) {
    let mut pot = MeshData::new();
    pot.cuboid(Vec3::new(-0.5, 0.0, -0.25), Vec3::new(0.5, 0.45, 0.25));
    let mut leaves = MeshData::new();
    for angle in [0.35f32, 0.35 + std::f32::consts::FRAC_PI_2] {
        let r = Quat::from_rotation_y(angle);
        let (u, v) = (r * Vec3::X * 1.1, Vec3::Y * 1.0);
        leaves.rect_mapped(
            Vec3::new(0.0, 0.35, 0.0) - u * 0.5,
            u,
            v,
            Vec2::ZERO,
            Vec2::ONE,
        );
    }
    (pot, leaves)
}
