//! `bistro-night`: a night square with the character of Amazon Lumberyard Bistro's
//! exterior, built so that most of what the camera sees is lit indirectly or through
//! openings. Four façade runs (`street_facade`: shops with real interior rooms behind
//! their openings, awnings, signs, recessed windows, balconies) close a cobbled square;
//! along the west side the ground floor is an arcade whose ceiling is washed by LED strips
//! hidden on a ledge of the lintel (cove lights) and hung with lanterns. The lights are
//! the Bistro's kinds (`bistro_lamps`): panelled lanterns with several emitting glass
//! panes per side on façade sconces, on lamp posts with several arms and under the
//! arcade; globe lights on the café ceilings, seen through shop openings; strings of
//! small bulbs across the square and along awnings and balconies; candles on the café
//! tables; a few glowing windows and signs. Materials are mostly diffuse, with glossy
//! metal (lamps, tables, rolling shutters) and glass-like glossy dielectric panels
//! (window glass, café wind screens; opaque, the shipped scene's measurements were made
//! so; `--glass` makes the wind screens thin transmitting glass). No sky.
//!
//! `--detail N` scales the square's area by N (more buildings per side, more lamp posts,
//! N × 1000 string-light bulbs); N = 1 is the shipped scene, with more than 10,000
//! emissive triangles. World frame: metres, +y up; the square spans x ∈ [x0, x1] between
//! the arcade's columns and the east façade, z ∈ [zf, ZN]; the camera stands near the
//! south-east corner looking north-west.

use super::bistro_lamps::{self as lamps, Fixture};
use super::mesh::MeshData;
use super::rng::Rng;
use super::street::{self, LightMeshes, Materials, WARM};
use super::street_facade::{self as facade, BulbKind, Frame, Prop, Run, Sink, Spot};
use super::writer::{num, Gltf, Material, Node};
use super::{Built, GenerateError, Options};
use glam::{Quat, Vec3};
use serde_json::{json, Map};

const DEFAULT_DETAIL: u32 = 1;
const MAX_DETAIL: u32 = 16;
/// The square at detail 1: width (x, column line to east façade) and depth (z).
const SQUARE_W: f32 = 18.0;
const SQUARE_D: f32 = 22.0;
/// South edge of the square (behind the camera).
const ZN: f32 = 4.0;
/// Depth of the arcade from its columns to the shop fronts, and its ceiling height.
const ARCADE: f32 = 3.6;
const ARCADE_H: f32 = 4.2;
/// String-light bulbs per unit of detail.
const BULBS: usize = 1000;
/// Emitted radiance (before the warm tint) of each kind of fixture.
const SCONCE_L: f32 = 90.0;
const POST_L: f32 = 110.0;
const HANGING_L: f32 = 80.0;
const GLOBE_L: f32 = 450.0;
const COVE_L: f32 = 30.0;
/// String lights are decoration here, dimmer than the street's (12 W/m): the square is
/// meant to be lit mostly by the lanterns, the arcade and the shops.
const GARLAND_POWER_PER_M: f32 = 3.0;
/// Relative brightness levels, as in the street.
const LEVELS: [f32; 3] = [0.7, 1.0, 1.4];

struct Extra {
    stone: usize,
    column: usize,
    screen_glass: usize,
    cove: usize,
}

/// Caches one mesh per (fixture kind, level): every placed node is one light model.
#[derive(Default)]
struct FixtureMeshes {
    meshes: std::collections::BTreeMap<(&'static str, usize), usize>,
    counts: std::collections::BTreeMap<&'static str, usize>,
}

impl FixtureMeshes {
    #[allow(clippy::too_many_arguments)]
    fn place(
        &mut self,
        g: &mut Gltf,
        iron: usize,
        kind: &'static str,
        build: impl FnOnce() -> Fixture,
        radiance: f32,
        level: usize,
        at: Vec3,
        rotation: Quat,
    ) {
        let mesh = *self.meshes.entry((kind, level)).or_insert_with(|| {
            let f = build();
            let name = format!("{kind}-{level}");
            let l = radiance * LEVELS[level];
            let glow = g.material(Material::emitter(&name, WARM.map(|c| c * l)));
            g.mesh(&name, &[(&f.metal, iron), (&f.glow, glow)])
        });
        *self.counts.entry(kind).or_default() += 1;
        g.node(Node {
            rotation,
            ..Node::mesh(mesh, at)
        });
    }
}

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let detail = o.detail.unwrap_or(DEFAULT_DETAIL);
    if !(1..=MAX_DETAIL).contains(&detail) {
        return Err(GenerateError::InvalidOption {
            option: "detail",
            value: detail.to_string(),
            reason: format!("must be between 1 and {MAX_DETAIL}"),
        });
    }
    let aspect = o.aspect.unwrap_or(16.0 / 9.0);
    let scale = (detail as f32).sqrt();
    let (x0, x1) = (-SQUARE_W * scale / 2.0, SQUARE_W * scale / 2.0);
    let zf = ZN - SQUARE_D * scale;
    let xa = x0 - ARCADE;

    let mut rng = Rng::new(o.seed);
    let mut g = Gltf::new();
    let mats = street::materials(&mut g, &mut rng)?;
    let extra = Extra {
        stone: g.material(Material::diffuse("arcade-stone", [0.5, 0.46, 0.4])),
        column: g.material(Material::diffuse("column-stone", [0.56, 0.52, 0.45])),
        screen_glass: g.material(if o.glass {
            // Clear glass, slightly green: the café behind shows through.
            Material {
                double_sided: true,
                transmission: 1.0,
                ..Material::glossy("screen-glass", [0.9, 0.95, 0.92], 0.03)
            }
        } else {
            Material {
                double_sided: true,
                ..Material::glossy("screen-glass", [0.08, 0.09, 0.1], 0.03)
            }
        }),
        cove: g.material(Material::emitter(
            "cove-strip",
            [COVE_L, COVE_L * 0.85, COVE_L * 0.65],
        )),
    };
    let mut sink = Sink::default();
    sink.tiles.insert(mats.cobbles, 2.0);
    sink.tiles.insert(mats.paving, 1.6);

    // Ground: paving under the arcade, cobbles in the square.
    sink.at(mats.paving).rect(
        Vec3::new(xa, 0.0, ZN),
        Vec3::X * ARCADE,
        Vec3::Z * (zf - ZN),
    );
    sink.at(mats.cobbles).rect(
        Vec3::new(x0, 0.0, ZN),
        Vec3::X * (x1 - x0),
        Vec3::Z * (zf - ZN),
    );

    // Façades: west (behind the arcade), north, east, south (behind the camera).
    let mut frng = rng.fork(20);
    let signs = street::SIGN_WORDS.len();
    let mut runs: Vec<(Frame, Run)> = Vec::new();
    let sides = [
        (Vec3::new(xa, 0.0, ZN), -Vec3::Z, ZN - zf, true),
        (Vec3::new(xa, 0.0, zf), Vec3::X, x1 - xa, true),
        (Vec3::new(x1, 0.0, zf), Vec3::Z, ZN - zf, true),
        (Vec3::new(x1, 0.0, ZN), -Vec3::X, x1 - xa, false),
    ];
    for (origin, u, width, cafes) in sides {
        let first = runs.last().map(|(_, r)| r.end_heights.1);
        let run = facade::build_run(&mut frng, &mats.facade, width, 0.0, first, signs, cafes);
        runs.push((Frame { origin, u }, run));
    }
    for (frame, run) in &runs {
        sink.append(&run.sink, frame.matrix());
    }

    let mut fixtures = FixtureMeshes::default();
    let mut lrng = rng.fork(21);
    arcade(
        &mut g,
        &mut sink,
        &mats,
        &extra,
        &mut fixtures,
        &mut lrng,
        x0,
        xa,
        zf,
    );
    let mut grng = rng.fork(22);
    let garlands = square(
        &mut g,
        &mut sink,
        &mats,
        &extra,
        &mut fixtures,
        &mut grng,
        (x0, x1, zf),
        detail,
    );

    // Props and the façades' lights: sconces and café globes become this scene's
    // fixtures; candles, glowing windows and signs are the street's.
    let props = street::prop_meshes(&mut g, &mats);
    let mut street_lights = LightMeshes::default();
    let mut srng = rng.fork(23);
    let mut candles = 0;
    for (frame, run) in &runs {
        let rot = frame.rotation();
        for &(prop, pos, yaw) in &run.props {
            if matches!(prop, Prop::WallLantern) {
                continue;
            }
            g.node(Node {
                rotation: rot * Quat::from_rotation_y(yaw),
                ..Node::mesh(props[prop as usize], frame.point(pos))
            });
        }
        for spot in &run.spots {
            match *spot {
                Spot::Bulb {
                    kind: BulbKind::WallLantern,
                    pos,
                } => {
                    let anchor = pos - super::street_props::WALL_BULB;
                    let level = srng.below(LEVELS.len());
                    fixtures.place(
                        &mut g,
                        mats.iron,
                        "sconce",
                        lamps::sconce,
                        SCONCE_L,
                        level,
                        frame.point(anchor),
                        rot,
                    );
                }
                Spot::Bulb {
                    kind: BulbKind::Pendant,
                    pos,
                } => {
                    let level = srng.below(LEVELS.len());
                    fixtures.place(
                        &mut g,
                        mats.aluminium,
                        "globe",
                        || lamps::globe_light(0.07, 3),
                        GLOBE_L,
                        level,
                        frame.point(pos),
                        rot,
                    );
                }
                _ => {
                    if matches!(
                        spot,
                        Spot::Bulb {
                            kind: BulbKind::Candle,
                            ..
                        }
                    ) {
                        candles += 1;
                    }
                    street::place_spot(
                        &mut g,
                        &mut sink,
                        &mats,
                        &mut street_lights,
                        &mut srng,
                        *frame,
                        spot,
                        true,
                    );
                }
            }
        }
    }
    let mut all_garlands = garlands;
    for (frame, run) in &runs {
        for line in &run.garlands {
            all_garlands.push(line.iter().map(|&q| frame.point(q)).collect());
        }
    }
    let bulbs = BULBS * detail as usize;
    street::place_garlands(
        &mut g,
        &mut sink,
        &mats,
        &mut grng,
        &all_garlands,
        bulbs,
        GARLAND_POWER_PER_M,
    );

    let parts: Vec<(&MeshData, usize)> = sink.parts.iter().map(|(&m, geo)| (geo, m)).collect();
    let city = g.mesh("square", &parts);
    g.node(Node::mesh(city, Vec3::ZERO).named("square"));

    let cam = g.camera("square-view", 62.0, aspect);
    g.camera_node(
        cam,
        Vec3::new(x1 - 3.5, 1.7, ZN - 4.5),
        Vec3::new(x0 - 1.0, 2.4, zf + 4.0),
    );

    let mut options = Map::new();
    options.insert("detail".into(), json!(detail));
    options.insert("aspect".into(), num(aspect));
    if o.glass {
        options.insert("glass".into(), json!(true));
    }
    let count = |k: &str| fixtures.counts.get(k).copied().unwrap_or(0);
    let analytic = json!({
        "light_models_by_kind": {
            "sconces": count("sconce"),
            "lamp_posts": count("lamp-post"),
            "arcade_lanterns": count("hanging-lantern"),
            "cafe_globes": count("globe"),
            "cove_strip_segments": count("cove"),
            "string_bulbs": bulbs,
            "candles": candles,
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

/// The arcade along the west side: columns on x = x0, a lintel with a cove ledge whose
/// hidden LED strip washes the ceiling, the ceiling slab, and a lantern in every bay.
#[allow(clippy::too_many_arguments)]
fn arcade(
    g: &mut Gltf,
    sink: &mut Sink,
    m: &Materials,
    e: &Extra,
    fixtures: &mut FixtureMeshes,
    rng: &mut Rng,
    x0: f32,
    xa: f32,
    zf: f32,
) {
    let h = ARCADE_H;
    sink.at(e.stone)
        .cuboid(Vec3::new(xa, h, zf), Vec3::new(x0 + 0.3, h + 0.5, ZN));
    sink.at(e.stone)
        .cuboid(Vec3::new(x0 - 0.3, h - 0.5, zf), Vec3::new(x0 + 0.3, h, ZN));
    // Cove: a ledge on the lintel's inner face with the strip on its top, 0.3 m under
    // the ceiling; nobody standing below or in the square sees the strip itself.
    let ledge_top = h - 0.3;
    sink.at(e.stone).cuboid(
        Vec3::new(x0 - 0.55, ledge_top - 0.08, zf),
        Vec3::new(x0 - 0.3, ledge_top, ZN),
    );
    sink.at(e.stone).cuboid(
        Vec3::new(x0 - 0.58, ledge_top - 0.08, zf),
        Vec3::new(x0 - 0.55, ledge_top + 0.07, ZN),
    );
    let length = ZN - zf;
    let segments = (length / 0.3).round().max(1.0) as usize;
    let seg = length / segments as f32;
    for k in 0..segments {
        let z = ZN - k as f32 * seg;
        let mut strip = MeshData::new();
        strip.rect(
            Vec3::new(x0 - 0.53, 0.0, z),
            Vec3::Z * -(seg - 0.02),
            Vec3::X * 0.2,
        );
        let mesh = g.mesh(&format!("cove-{k}"), &[(&strip, e.cove)]);
        g.node(Node::mesh(mesh, Vec3::Y * (ledge_top + 0.002)));
        *fixtures.counts.entry("cove").or_default() += 1;
    }
    // Columns and a lantern in every bay.
    let bays = ((length - 1.0) / 3.6).round().max(1.0) as usize;
    let bay = (length - 1.0) / bays as f32;
    for k in 0..=bays {
        let z = ZN - 0.5 - k as f32 * bay;
        let geo = sink.at(e.column);
        geo.cuboid(
            Vec3::new(x0 - 0.3, 0.0, z - 0.3),
            Vec3::new(x0 + 0.3, 0.35, z + 0.3),
        );
        geo.prism(Vec3::new(x0, 0.35, z), 0.22, h - 0.85, 12);
        geo.cuboid(
            Vec3::new(x0 - 0.3, h - 0.5 - 0.15, z - 0.3),
            Vec3::new(x0 + 0.3, h - 0.5, z + 0.3),
        );
        if k < bays {
            let level = rng.below(LEVELS.len());
            fixtures.place(
                g,
                m.iron,
                "hanging-lantern",
                || lamps::hanging_lantern(0.9),
                HANGING_L,
                level,
                Vec3::new((x0 + xa) / 2.0 + 0.2, h, z - bay / 2.0),
                Quat::IDENTITY,
            );
        }
    }
}

/// The open square: lamp posts, a café terrace behind glass wind screens, and the
/// string lights across it (returned as polylines for `place_garlands`).
#[allow(clippy::too_many_arguments)]
fn square(
    g: &mut Gltf,
    sink: &mut Sink,
    m: &Materials,
    e: &Extra,
    fixtures: &mut FixtureMeshes,
    rng: &mut Rng,
    (x0, x1, zf): (f32, f32, f32),
    detail: u32,
) -> Vec<Vec<Vec3>> {
    // Lamp posts: two rows, 2.5 m in from the column line and the east façade, 8 m apart.
    let mut z = ZN - 4.0;
    while z > zf + 3.0 {
        for (x, dz) in [(x0 + 2.5, 0.0), (x1 - 2.6, -3.0)] {
            let arms = if rng.chance(0.5) { 3 } else { 4 };
            let level = rng.below(LEVELS.len());
            let name = if arms == 3 { "lamp-post" } else { "lamp-post4" };
            fixtures.place(
                g,
                m.iron,
                name,
                || lamps::lamp_post(arms),
                POST_L,
                level,
                Vec3::new(x, 0.0, z + dz),
                Quat::from_rotation_y(rng.range(0.0, 1.0)),
            );
        }
        z -= 8.0;
    }
    if let Some(n) = fixtures.counts.remove("lamp-post4") {
        *fixtures.counts.entry("lamp-post").or_default() += n;
    }

    // Café terrace in the middle of the square: tables with candles behind wind screens.
    let props = street::prop_meshes(g, m);
    let (tx0, tx1) = (x0 + 5.0, x1 - 5.5);
    let (tz0, tz1) = (zf + 0.35 * (ZN - zf), zf + 0.6 * (ZN - zf));
    let mut x = tx0 + 0.8;
    while x < tx1 - 0.6 {
        let mut z = tz0 + 0.9;
        while z < tz1 - 0.6 {
            let yaw = rng.range(0.0, 1.0);
            g.node(Node::mesh(props[Prop::Table as usize], Vec3::new(x, 0.0, z)).rotated_y(yaw));
            for (dx, a) in [
                (-0.52, std::f32::consts::FRAC_PI_2),
                (0.52, -std::f32::consts::FRAC_PI_2),
            ] {
                g.node(
                    Node::mesh(props[Prop::Chair as usize], Vec3::new(x + dx, 0.0, z)).rotated_y(a),
                );
            }
            z += 2.0;
        }
        x += 2.2;
    }
    let screen = |sink: &mut Sink, a: Vec3, b: Vec3| {
        let d = b - a;
        let n = (d.length() / 1.2).ceil().max(1.0) as usize;
        for k in 0..n {
            let p = a + d * (k as f32 / n as f32);
            let q = a + d * ((k + 1) as f32 / n as f32);
            sink.at(e.screen_glass)
                .rect(p + Vec3::Y * 0.15, q - p, Vec3::Y * 0.95);
            sink.at(m.iron)
                .cuboid(p - Vec3::splat(0.025), p + Vec3::new(0.025, 1.15, 0.025));
        }
        sink.at(m.iron)
            .cuboid(b - Vec3::splat(0.025), b + Vec3::new(0.025, 1.15, 0.025));
    };
    screen(sink, Vec3::new(tx0, 0.0, tz1), Vec3::new(tx1, 0.0, tz1));
    screen(sink, Vec3::new(tx0, 0.0, tz0), Vec3::new(tx0, 0.0, tz1));
    screen(sink, Vec3::new(tx1, 0.0, tz1), Vec3::new(tx1, 0.0, tz0));

    // String lights: across the square from the arcade roof to the east façade.
    let mut garlands = Vec::new();
    let step = 3.5 / (detail as f32).sqrt().sqrt();
    let mut z = ZN - 2.0;
    while z > zf + 1.0 {
        let a = Vec3::new(x0 + 0.2, ARCADE_H + 0.6, z + rng.range(-0.4, 0.4));
        let b = Vec3::new(x1 - 0.05, rng.range(5.6, 6.4), z + rng.range(-0.8, 0.8));
        garlands.push(facade::sagging(a, b, rng.range(0.5, 0.8), 24));
        z -= step;
    }
    garlands
}
