//! `street`: the stand-in for Amazon Lumberyard Bistro. A night-time street canyon 90 m
//! long with a cross street, lined by façades (`street_facade`): shops with lit interiors,
//! awnings, emissive textured signs, recessed windows (some glowing), balconies with
//! alpha-masked railings; on the sidewalks lamp posts, café tables with candles and
//! planters with alpha-masked foliage; overhead, garlands of small bulbs across the
//! street. No sky light: everything is lit by the light models.
//!
//! `--lamps N` is the exact number of light models (nodes with an emissive mesh). The
//! fixed lights of the layout (posts, wall lanterns, shop pendants, signs, glowing
//! windows, candles) are taken first, in that order of priority; the rest become garland
//! bulbs spread evenly over all garlands. Garlands keep their total power as N grows
//! (each bulb gets dimmer and smaller), so the image keeps its brightness while the light
//! count scales to tens of thousands. Emitted power per light model spans over three
//! orders of magnitude (a candle flame to a lamp-post bulb), and most lights sit in
//! recesses, shop rooms, under awnings or around the corner, hidden from most of the
//! street.
//!
//! World frame: metres, +y up; the main street runs along z with the camera near z = +7
//! looking toward −z; façades at x = ±7; the road is x ∈ [−4, 4].

use super::mesh::MeshData;
use super::rng::Rng;
use super::street_facade::{
    self as facade, BulbKind, FacadeMaterials, Frame, Prop, Run, Sink, Spot,
};
use super::street_props as props;
use super::textures;
use super::writer::{num, Filter, Gltf, Material, Node};
use super::{Built, GenerateError, Options};
use glam::{Quat, Vec3};
use serde_json::{json, Map};
use std::collections::BTreeMap;

const FACADE_X: f32 = 7.0;
const ROAD_X: f32 = 4.0;
const CURB: f32 = 0.15;
const Z_NEAR: f32 = 10.0;
const Z_FAR: f32 = -80.0;
/// The cross street spans z ∈ [CROSS_Z1, CROSS_Z0] and reaches x = ±SIDE_X.
const CROSS_Z0: f32 = -34.0;
const CROSS_Z1: f32 = -42.0;
const SIDE_X: f32 = 30.0;
const DEFAULT_LAMPS: u32 = 600;
const MAX_LAMPS: u32 = 250_000;

pub(super) const WARM: [f32; 3] = [1.0, 0.7, 0.4];
pub(super) const SIGN_WORDS: [(&str, [f32; 3]); 8] = [
    ("BISTRO", [1.0, 0.55, 0.15]),
    ("CAFE", [1.0, 0.25, 0.2]),
    ("BAR", [0.2, 0.6, 1.0]),
    ("HOTEL", [0.95, 0.85, 0.5]),
    ("PIZZA", [0.3, 1.0, 0.35]),
    ("VINS", [0.9, 0.3, 0.8]),
    ("TABAC", [1.0, 0.4, 0.1]),
    ("JAZZ", [0.4, 0.8, 1.0]),
];
/// Garland colours: warm white first (most garlands), then the festive ones.
const GARLAND_COLOURS: [[f32; 3]; 5] = [
    [1.0, 0.72, 0.42],
    [1.0, 0.18, 0.12],
    [0.25, 1.0, 0.3],
    [0.3, 0.45, 1.0],
    [1.0, 0.6, 0.1],
];
pub(super) const LEVELS: [f32; 3] = [0.6, 1.0, 1.6];
/// Garland power per metre of wire (W/m in radiometric units of the scene).
const GARLAND_POWER_PER_M: f32 = 12.0;

/// Bulb radius and radiance of each kind of fixed light.
fn bulb_spec(kind: BulbKind) -> (f32, f32, [f32; 3]) {
    match kind {
        BulbKind::Post => (0.08, 2200.0, WARM),
        BulbKind::WallLantern => (0.05, 1300.0, WARM),
        BulbKind::Pendant => (0.045, 1000.0, [1.0, 0.8, 0.55]),
        BulbKind::Candle => (0.012, 10.0, [1.0, 0.55, 0.2]),
    }
}

pub(super) struct Materials {
    pub facade: FacadeMaterials,
    pub cobbles: usize,
    pub paving: usize,
    pub curb: usize,
    pub iron: usize,
    pub aluminium: usize,
    pub seat: usize,
    pub glass_red: usize,
    pub planter: usize,
    pub foliage: usize,
    pub wire: usize,
    pub signs: Vec<usize>,
}

pub(super) fn materials(g: &mut Gltf, rng: &mut Rng) -> Result<Materials, GenerateError> {
    let tex_cobbles = g.texture(
        "cobbles",
        textures::cobbles(&mut rng.fork(1)).png()?,
        Filter::Linear,
    );
    let tex_paving = g.texture(
        "paving",
        textures::paving(&mut rng.fork(2)).png()?,
        Filter::Linear,
    );
    let tex_railing = g.texture("railing", textures::railing().png()?, Filter::Linear);
    let tex_foliage = g.texture(
        "foliage",
        textures::foliage(&mut rng.fork(3)).png()?,
        Filter::Linear,
    );
    let atlas = textures::sign_atlas(&SIGN_WORDS);
    let tex_signs = g.texture("signs", atlas.image.png()?, Filter::Linear);

    let textured = |name: &str, tex: usize, masked: bool| Material {
        base_color: [1.0; 4],
        base_color_texture: Some(tex),
        alpha_cutoff: masked.then_some(0.5),
        double_sided: masked,
        ..Material::diffuse(name, [1.0; 3])
    };
    let walls = [
        ("plaster-cream", [0.55, 0.47, 0.34]),
        ("plaster-ochre", [0.55, 0.37, 0.17]),
        ("plaster-terracotta", [0.42, 0.19, 0.11]),
        ("plaster-grey", [0.38, 0.38, 0.36]),
        ("plaster-blue", [0.3, 0.38, 0.42]),
        ("plaster-rose", [0.52, 0.33, 0.3]),
        ("brick", [0.3, 0.12, 0.07]),
    ]
    .map(|(n, c)| g.material(Material::diffuse(n, c)))
    .to_vec();
    let shutters = [
        ("shutter-green", [0.08, 0.2, 0.1]),
        ("shutter-blue", [0.07, 0.12, 0.25]),
        ("shutter-brown", [0.2, 0.1, 0.05]),
    ]
    .map(|(n, c)| g.material(Material::diffuse(n, c)))
    .to_vec();
    let interior = [
        ("interior-warm", [0.6, 0.42, 0.28]),
        ("interior-green", [0.25, 0.35, 0.25]),
        ("interior-red", [0.45, 0.15, 0.12]),
    ]
    .map(|(n, c)| g.material(Material::diffuse(n, c)))
    .to_vec();
    let awnings = [
        ("awning-red", [0.5, 0.05, 0.04]),
        ("awning-green", [0.05, 0.25, 0.1]),
        ("awning-navy", [0.05, 0.07, 0.2]),
        ("awning-cream", [0.6, 0.55, 0.42]),
    ]
    .map(|(n, c)| {
        g.material(Material {
            double_sided: true,
            ..Material::diffuse(n, c)
        })
    })
    .to_vec();
    let facade = FacadeMaterials {
        walls,
        trim: g.material(Material::diffuse("stone-trim", [0.6, 0.57, 0.5])),
        glass: g.material(Material::glossy("window-glass", [0.02, 0.025, 0.03], 0.05)),
        shutters,
        door: g.material(Material::diffuse("door-wood", [0.12, 0.06, 0.03])),
        rolling_shutter: g.material(Material::metal("rolling-shutter", [0.55, 0.55, 0.56], 0.4)),
        interior,
        floor: g.material(Material::diffuse("floor-wood", [0.3, 0.17, 0.08])),
        counter: g.material(Material::diffuse("counter", [0.2, 0.09, 0.04])),
        awnings,
        sign_board: g.material(Material::diffuse("sign-board", [0.05, 0.04, 0.03])),
        railing: g.material(textured("railing", tex_railing, true)),
        cord: g.material(Material::diffuse("cord", [0.02, 0.02, 0.02])),
    };
    let signs = atlas
        .means
        .iter()
        .zip(&SIGN_WORDS)
        .map(|(&mean, (word, _))| {
            g.material(Material {
                emission: [10.0; 3],
                emissive_texture: Some(tex_signs),
                emissive_texture_mean: mean,
                ..Material::emitter(&format!("sign-{}", word.to_lowercase()), [10.0; 3])
            })
        })
        .collect();
    Ok(Materials {
        facade,
        cobbles: g.material(textured("cobbles", tex_cobbles, false)),
        paving: g.material(textured("paving", tex_paving, false)),
        curb: g.material(Material::diffuse("curb", [0.32, 0.31, 0.3])),
        iron: g.material(Material::metal("iron", [0.3, 0.31, 0.32], 0.3)),
        aluminium: g.material(Material::metal("aluminium", [0.9, 0.9, 0.88], 0.25)),
        seat: g.material(Material::diffuse("rattan", [0.35, 0.22, 0.1])),
        glass_red: g.material(Material::glossy("candle-glass", [0.5, 0.05, 0.03], 0.1)),
        planter: g.material(Material::diffuse("planter", [0.4, 0.16, 0.08])),
        foliage: g.material(textured("foliage", tex_foliage, true)),
        wire: g.material(Material {
            double_sided: true,
            ..Material::diffuse("wire", [0.02, 0.02, 0.02])
        }),
        signs,
    })
}

/// A façade run placed in the world, with its frame kept for its spots and props.
struct Placed {
    frame: Frame,
    run: Run,
}

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let lamps = o.lamps.unwrap_or(DEFAULT_LAMPS);
    if !(1..=MAX_LAMPS).contains(&lamps) {
        return Err(GenerateError::InvalidOption {
            option: "lamps",
            value: lamps.to_string(),
            reason: format!("must be between 1 and {MAX_LAMPS}"),
        });
    }
    let aspect = o.aspect.unwrap_or(16.0 / 9.0);
    let mut rng = Rng::new(o.seed);
    let mut g = Gltf::new();
    let mats = materials(&mut g, &mut rng)?;
    let mut sink = Sink::default();
    sink.tiles.insert(mats.cobbles, 2.0);
    sink.tiles.insert(mats.paving, 1.6);

    ground(&mut sink, &mats);

    // Façade runs: main street (two per side, broken by the cross street), the street's
    // two ends, and the cross street's four sides and two ends.
    let mut frng = rng.fork(10);
    let fm = &mats.facade;
    let signs = SIGN_WORDS.len();
    let mut placed = Vec::new();
    let mut run = |rng: &mut Rng,
                   origin: Vec3,
                   u: Vec3,
                   width: f32,
                   ground: f32,
                   first: Option<f32>,
                   cafes: bool| {
        let r = facade::build_run(rng, fm, width, ground, first, signs, cafes);
        let h = r.end_heights;
        placed.push(Placed {
            frame: Frame { origin, u },
            run: r,
        });
        h
    };
    let left1 = run(
        &mut frng,
        Vec3::new(-FACADE_X, 0.0, Z_NEAR),
        -Vec3::Z,
        Z_NEAR - CROSS_Z0,
        CURB,
        None,
        true,
    );
    let left2 = run(
        &mut frng,
        Vec3::new(-FACADE_X, 0.0, CROSS_Z1),
        -Vec3::Z,
        CROSS_Z1 - Z_FAR,
        CURB,
        None,
        true,
    );
    let right1 = run(
        &mut frng,
        Vec3::new(FACADE_X, 0.0, CROSS_Z0),
        Vec3::Z,
        Z_NEAR - CROSS_Z0,
        CURB,
        None,
        true,
    );
    let right2 = run(
        &mut frng,
        Vec3::new(FACADE_X, 0.0, Z_FAR),
        Vec3::Z,
        CROSS_Z1 - Z_FAR,
        CURB,
        None,
        true,
    );
    run(
        &mut frng,
        Vec3::new(-FACADE_X, 0.0, Z_FAR),
        Vec3::X,
        2.0 * FACADE_X,
        CURB,
        Some(left2.1),
        true,
    );
    run(
        &mut frng,
        Vec3::new(FACADE_X, 0.0, Z_NEAR),
        -Vec3::X,
        2.0 * FACADE_X,
        CURB,
        Some(right1.1),
        true,
    );
    let side = SIDE_X - FACADE_X;
    run(
        &mut frng,
        Vec3::new(-FACADE_X, 0.0, CROSS_Z0),
        -Vec3::X,
        side,
        0.0,
        Some(left1.1),
        false,
    );
    run(
        &mut frng,
        Vec3::new(-SIDE_X, 0.0, CROSS_Z1),
        Vec3::X,
        side,
        0.0,
        None,
        false,
    );
    run(
        &mut frng,
        Vec3::new(SIDE_X, 0.0, CROSS_Z0),
        -Vec3::X,
        side,
        0.0,
        None,
        false,
    );
    run(
        &mut frng,
        Vec3::new(FACADE_X, 0.0, CROSS_Z1),
        Vec3::X,
        side,
        0.0,
        Some(right2.1),
        false,
    );
    run(
        &mut frng,
        Vec3::new(SIDE_X, 0.0, CROSS_Z1),
        Vec3::Z,
        CROSS_Z0 - CROSS_Z1,
        0.0,
        None,
        false,
    );
    run(
        &mut frng,
        Vec3::new(-SIDE_X, 0.0, CROSS_Z0),
        -Vec3::Z,
        CROSS_Z0 - CROSS_Z1,
        0.0,
        None,
        false,
    );

    // Sidewalk furniture along the four main-street runs (local z = distance from wall).
    let mut prng = rng.fork(11);
    for (i, p) in placed.iter_mut().take(4).enumerate() {
        let width = if i % 2 == 0 {
            Z_NEAR - CROSS_Z0
        } else {
            CROSS_Z1 - Z_FAR
        };
        sidewalk_props(&mut prng, &mut p.run, width, i);
    }
    // Cross-street lamp posts close to the walls.
    for (i, p) in placed.iter_mut().enumerate().skip(6).take(4) {
        for k in 0..2 {
            let x = 6.0 + 9.0 * k as f32 + if i % 2 == 0 { 0.0 } else { 4.5 };
            p.run.props.push((Prop::Post, Vec3::new(x, 0.0, 0.6), 0.0));
            p.run.spots.push(Spot::Bulb {
                kind: BulbKind::Post,
                pos: Vec3::new(x, 0.0, 0.6) + props::POST_BULB,
            });
        }
    }
    for p in &placed {
        sink.append(&p.run.sink, p.frame.matrix());
    }

    // Garlands across the main street and the cross street (world coordinates).
    let mut grng = rng.fork(12);
    let mut garlands: Vec<Vec<Vec3>> = Vec::new();
    let interval = (8.0 * (DEFAULT_LAMPS as f32 / lamps as f32).sqrt()).clamp(2.0, 8.0);
    let mut z = Z_NEAR - 4.0;
    while z > Z_FAR + 2.0 {
        if !(CROSS_Z1 - 1.5..=CROSS_Z0 + 1.5).contains(&z) {
            let (ya, yb) = (grng.range(5.9, 7.0), grng.range(5.9, 7.0));
            let dz = if grng.chance(0.3) {
                -interval * 0.5
            } else {
                0.0
            };
            let a = Vec3::new(-FACADE_X + 0.05, ya, z);
            let b = Vec3::new(FACADE_X - 0.05, yb, z + dz);
            garlands.push(facade::sagging(a, b, grng.range(0.5, 0.9), 24));
        }
        z -= interval;
    }
    let mut x = FACADE_X + 3.0;
    while x < SIDE_X - 1.0 {
        for sx in [-1.0, 1.0] {
            let (ya, yb) = (grng.range(5.0, 6.0), grng.range(5.0, 6.0));
            let a = Vec3::new(sx * x, ya, CROSS_Z0 - 0.05);
            let b = Vec3::new(sx * x, yb, CROSS_Z1 + 0.05);
            garlands.push(facade::sagging(a, b, grng.range(0.4, 0.7), 16));
        }
        x += interval * 0.75;
    }
    for p in &placed {
        for line in &p.run.garlands {
            garlands.push(line.iter().map(|&q| p.frame.point(q)).collect());
        }
    }

    // Instanced props.
    let prop_meshes = prop_meshes(&mut g, &mats);
    for p in &placed {
        let rot = p.frame.rotation();
        for &(prop, pos, yaw) in &p.run.props {
            let node = Node::mesh(prop_meshes[prop as usize], p.frame.point(pos));
            g.node(Node {
                rotation: rot * Quat::from_rotation_y(yaw),
                ..node
            });
        }
    }

    // Light models: fixed lights by priority, then garland bulbs.
    let mut spots: Vec<(u32, f32, usize, usize)> = Vec::new(); // (priority, tie, run, spot)
    let mut lrng = rng.fork(13);
    for (ri, p) in placed.iter().enumerate() {
        for (si, s) in p.run.spots.iter().enumerate() {
            let priority = match s {
                Spot::Bulb {
                    kind: BulbKind::Post,
                    ..
                } => 0,
                Spot::Sign { .. } => 1,
                Spot::Bulb {
                    kind: BulbKind::Pendant,
                    ..
                } => 2,
                Spot::Bulb {
                    kind: BulbKind::WallLantern,
                    ..
                } => 3,
                Spot::Pane { .. } => 4,
                Spot::Bulb {
                    kind: BulbKind::Candle,
                    ..
                } => 5,
            };
            spots.push((priority, lrng.f32(), ri, si));
        }
    }
    spots.sort_by(|a, b| (a.0, a.1).partial_cmp(&(b.0, b.1)).unwrap());
    let fixed = spots.len().min(lamps as usize);
    let mut lights = LightMeshes::default();
    let mut chosen = vec![false; spots.len()];
    for (k, &(_, _, ri, si)) in spots.iter().enumerate() {
        let p = &placed[ri];
        let lit = k < fixed;
        chosen[k] = lit;
        place_spot(
            &mut g,
            &mut sink,
            &mats,
            &mut lights,
            &mut lrng,
            p.frame,
            &p.run.spots[si],
            lit,
        );
    }
    let garland_bulbs = lamps as usize - fixed;
    place_garlands(
        &mut g,
        &mut sink,
        &mats,
        &mut grng,
        &garlands,
        garland_bulbs,
        GARLAND_POWER_PER_M,
    );

    // All static geometry as one mesh, one primitive per material.
    let parts: Vec<(&MeshData, usize)> = sink.parts.iter().map(|(&m, geo)| (geo, m)).collect();
    let city = g.mesh("street", &parts);
    g.node(Node::mesh(city, Vec3::ZERO).named("street"));

    let cam = g.camera("street-view", 55.0, aspect);
    g.camera_node(cam, Vec3::new(-1.2, 1.7, 7.0), Vec3::new(0.6, 3.4, -40.0));

    let count = |p: u32| {
        spots
            .iter()
            .zip(&chosen)
            .filter(|(s, &c)| c && s.0 == p)
            .count()
    };
    let mut options = Map::new();
    options.insert("lamps".into(), json!(lamps));
    options.insert("aspect".into(), num(aspect));
    let analytic = json!({
        "light_models_by_kind": {
            "lamp_post_bulbs": count(0),
            "signs": count(1),
            "shop_pendants": count(2),
            "wall_lanterns": count(3),
            "window_panes": count(4),
            "candles": count(5),
            "garland_bulbs": garland_bulbs,
        },
        "sky": "none (black)",
        "units": "metres",
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}

/// Road (cobbles), raised sidewalks (paving) with curbs, along the main street; the cross
/// street is cobbled wall to wall.
fn ground(sink: &mut Sink, m: &Materials) {
    let road = sink.at(m.cobbles);
    road.rect(
        Vec3::new(-ROAD_X, 0.0, Z_NEAR),
        Vec3::X * 2.0 * ROAD_X,
        Vec3::Z * (Z_FAR - Z_NEAR),
    );
    for (x0, x1) in [(-SIDE_X, -ROAD_X), (ROAD_X, SIDE_X)] {
        road.rect(
            Vec3::new(x0, 0.0, CROSS_Z0),
            Vec3::X * (x1 - x0),
            Vec3::Z * (CROSS_Z1 - CROSS_Z0),
        );
    }
    for (z0, z1) in [(CROSS_Z0, Z_NEAR), (Z_FAR, CROSS_Z1)] {
        for sx in [-1.0f32, 1.0] {
            let (xa, xb) = if sx < 0.0 {
                (-FACADE_X, -ROAD_X)
            } else {
                (ROAD_X, FACADE_X)
            };
            sink.at(m.paving).rect(
                Vec3::new(xa, CURB, z1),
                Vec3::X * (xb - xa),
                Vec3::Z * (z0 - z1),
            );
            // Curb faces toward the road and toward the cross street.
            let curb = sink.at(m.curb);
            let kerb_x = sx * ROAD_X;
            let (o, along) = if sx < 0.0 {
                (Vec3::new(kerb_x, 0.0, z1), Vec3::Z * (z0 - z1))
            } else {
                (Vec3::new(kerb_x, 0.0, z0), Vec3::Z * (z1 - z0))
            };
            curb.rect(o, along, Vec3::Y * CURB);
            // The end facing the cross street: −z for the near segment, +z for the far one.
            if z0 == CROSS_Z0 {
                curb.rect(Vec3::new(xb, 0.0, z0), Vec3::X * (xa - xb), Vec3::Y * CURB);
            } else {
                curb.rect(Vec3::new(xa, 0.0, z1), Vec3::X * (xb - xa), Vec3::Y * CURB);
            }
        }
    }
}

fn sidewalk_props(rng: &mut Rng, run: &mut Run, width: f32, index: usize) {
    let post_z = FACADE_X - ROAD_X - 0.5;
    let mut posts = Vec::new();
    let mut x = if index < 2 { 3.0 } else { 9.5 };
    while x < width - 1.0 {
        posts.push(x);
        run.props
            .push((Prop::Post, Vec3::new(x, CURB, post_z), 0.0));
        run.spots.push(Spot::Bulb {
            kind: BulbKind::Post,
            pos: Vec3::new(x, CURB, post_z) + props::POST_BULB,
        });
        x += 13.0;
    }
    let mut x = 2.0;
    while x < width - 1.5 {
        if posts.iter().all(|p| (p - x).abs() > 1.6) && rng.chance(0.55) {
            run.props
                .push((Prop::Planter, Vec3::new(x, CURB, post_z + 0.1), 0.0));
        }
        x += rng.range(4.0, 7.0);
    }
}

pub(super) fn prop_meshes(g: &mut Gltf, m: &Materials) -> Vec<usize> {
    let (top, frame) = props::table();
    let (seat, chair_frame) = props::chair();
    let (pot, leaves) = props::planter();
    // Index order follows `Prop` (WallLantern, Table, Chair, Candle, Planter, Post).
    vec![
        g.mesh("wall-lantern", &[(&props::wall_lantern(), m.iron)]),
        g.mesh("table", &[(&top, m.aluminium), (&frame, m.iron)]),
        g.mesh("chair", &[(&seat, m.seat), (&chair_frame, m.iron)]),
        g.mesh("candle-holder", &[(&props::candle_holder(), m.glass_red)]),
        g.mesh("planter", &[(&pot, m.planter), (&leaves, m.foliage)]),
        g.mesh("lamp-post", &[(&props::lamp_post(), m.iron)]),
    ]
}

/// Light meshes shared by many light models, created on first use.
#[derive(Default)]
pub(super) struct LightMeshes {
    bulbs: BTreeMap<(BulbKind, usize), usize>,
    panes: BTreeMap<usize, usize>,
}

#[allow(clippy::too_many_arguments)]
pub(super) fn place_spot(
    g: &mut Gltf,
    sink: &mut Sink,
    m: &Materials,
    lights: &mut LightMeshes,
    rng: &mut Rng,
    frame: Frame,
    spot: &Spot,
    lit: bool,
) {
    match *spot {
        Spot::Bulb { kind, pos } => {
            if !lit {
                return;
            }
            let level = rng.below(LEVELS.len());
            let mesh = *lights.bulbs.entry((kind, level)).or_insert_with(|| {
                let (r, l, c) = bulb_spec(kind);
                let mut geo = MeshData::new();
                geo.octahedron(Vec3::ZERO, r);
                let name = format!("{kind:?}-{level}").to_lowercase();
                let mat = g.material(Material::emitter(&name, c.map(|x| x * l * LEVELS[level])));
                g.mesh(&name, &[(&geo, mat)])
            });
            g.node(Node::mesh(mesh, frame.point(pos)));
        }
        Spot::Pane { corner, w, h } => {
            if !lit {
                let mut geo = MeshData::new();
                geo.rect(corner, Vec3::X * w, Vec3::Y * h);
                sink.at(m.facade.glass).append(&geo, frame.matrix());
                return;
            }
            let level = rng.below(4);
            let mesh = *lights.panes.entry(level).or_insert_with(|| {
                let mut geo = MeshData::new();
                geo.rect(Vec3::ZERO, Vec3::X, Vec3::Y);
                let l = 0.6 * 1.6f32.powi(level as i32);
                let name = format!("window-glow-{level}");
                let mat = g.material(Material::emitter(&name, [l, l * 0.78, l * 0.5]));
                g.mesh(&name, &[(&geo, mat)])
            });
            g.node(Node {
                rotation: frame.rotation(),
                scale: Vec3::new(w, h, 1.0),
                ..Node::mesh(mesh, frame.point(corner))
            });
        }
        Spot::Sign { corner, w, h, row } => {
            if !lit {
                return;
            }
            let rows = SIGN_WORDS.len().next_power_of_two() as f32;
            let mut geo = MeshData::new();
            let (v0, v1) = (row as f32 / rows, (row + 1) as f32 / rows);
            geo.rect_mapped(
                corner,
                Vec3::X * w,
                Vec3::Y * h,
                glam::Vec2::new(0.0, v0),
                glam::Vec2::new(1.0, v1),
            );
            let mut world = MeshData::new();
            world.append(&geo, frame.matrix());
            let mesh = g.mesh(&format!("sign-{row}"), &[(&world, m.signs[row])]);
            g.node(Node::mesh(mesh, Vec3::ZERO));
        }
    }
}

/// Spreads `count` bulbs evenly (by arc length) over all garlands and draws their wires;
/// together they emit `power_per_m` per metre of wire.
pub(super) fn place_garlands(
    g: &mut Gltf,
    sink: &mut Sink,
    m: &Materials,
    rng: &mut Rng,
    garlands: &[Vec<Vec3>],
    count: usize,
    power_per_m: f32,
) {
    let lengths: Vec<f32> = garlands
        .iter()
        .map(|l| l.windows(2).map(|s| s[0].distance(s[1])).sum())
        .collect();
    let total: f32 = lengths.iter().sum();
    for line in garlands {
        sink.at(m.wire).ribbon(line, 0.012, Vec3::Y);
    }
    if count == 0 {
        return;
    }
    // Largest-remainder apportionment: the counts add up to exactly `count`.
    let shares: Vec<f32> = lengths.iter().map(|l| l / total * count as f32).collect();
    let mut counts: Vec<usize> = shares.iter().map(|s| s.floor() as usize).collect();
    let mut order: Vec<usize> = (0..shares.len()).collect();
    order.sort_by(|&a, &b| {
        (shares[b] - shares[b].floor())
            .total_cmp(&(shares[a] - shares[a].floor()))
            .then(a.cmp(&b))
    });
    let missing = count - counts.iter().sum::<usize>();
    for &i in order.iter().cycle().take(missing) {
        counts[i] += 1;
    }
    let spacing = total / count as f32;
    let radius = (0.22 * spacing).clamp(0.003, 0.04);
    let area = 4.0 * 3f32.sqrt() * radius * radius;
    let base_radiance = power_per_m * spacing / (std::f32::consts::PI * area);
    let mut cache: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for (line, (&n, &len)) in garlands.iter().zip(counts.iter().zip(&lengths)) {
        let festive = rng.chance(0.35);
        let level = rng.below(LEVELS.len());
        let step = len / n.max(1) as f32;
        for k in 0..n {
            let pos = point_at(line, (k as f32 + 0.5) * step) - Vec3::Y * (radius * 1.2);
            let colour = if festive {
                1 + k % (GARLAND_COLOURS.len() - 1)
            } else {
                0
            };
            let mesh = *cache.entry((colour, level)).or_insert_with(|| {
                let mut geo = MeshData::new();
                geo.octahedron(Vec3::ZERO, radius);
                let l = base_radiance * LEVELS[level];
                let name = format!("garland-{colour}-{level}");
                let mat = g.material(Material::emitter(
                    &name,
                    GARLAND_COLOURS[colour].map(|x| x * l),
                ));
                g.mesh(&name, &[(&geo, mat)])
            });
            g.node(Node::mesh(mesh, pos));
        }
    }
}

fn point_at(line: &[Vec3], mut s: f32) -> Vec3 {
    for seg in line.windows(2) {
        let d = seg[0].distance(seg[1]);
        if s <= d {
            return seg[0].lerp(seg[1], s / d.max(1e-6));
        }
        s -= d;
    }
    *line.last().unwrap()
}
