//! Building façades for the `street` scene. A façade run is a straight row of buildings
//! built in a local frame (x along the street, y up, z out of the wall toward the street;
//! the wall plane is z = 0) and then placed in the world by its `Frame`. Each building
//! gets a ground-floor shop (open, with a lit interior room, awning, sign, café tables;
//! or closed behind a metal shutter), upper storeys of recessed windows (some glowing,
//! some French doors with balconies and alpha-masked railings), shutters, ledges and a
//! cornice. Walls are cut around every opening so recesses are real geometry that hides
//! the lights inside them from most of the street. The run reports, in local coordinates,
//! where light models, props and garlands of bulbs go; `street` decides which lights
//! exist and places them.

use super::mesh::MeshData;
use super::rng::Rng;
use glam::{Mat4, Quat, Vec3};
use std::collections::BTreeMap;

pub const GROUND_FLOOR: f32 = 4.2;
pub const STOREY: f32 = 3.2;
/// Depth of a building behind its façade (for party walls).
const DEPTH: f32 = 12.0;

/// Geometry grouped by material index.
#[derive(Default)]
pub struct Sink {
    pub parts: BTreeMap<usize, MeshData>,
    pub tiles: BTreeMap<usize, f32>,
}

impl Sink {
    pub fn at(&mut self, material: usize) -> &mut MeshData {
        let tile = self.tiles.get(&material).copied().unwrap_or(1.0);
        self.parts
            .entry(material)
            .or_insert_with(|| MeshData::with_uv_tile(tile))
    }

    pub fn append(&mut self, other: &Sink, m: Mat4) {
        for (&mat, geo) in &other.parts {
            self.at(mat).append(geo, m);
        }
    }
}

/// A façade's placement: world origin of its local (0, 0, 0) and the horizontal unit
/// vector of its local x. Local z is x × y, so the frame is a proper rotation.
#[derive(Clone, Copy)]
pub struct Frame {
    pub origin: Vec3,
    pub u: Vec3,
}

impl Frame {
    pub fn normal(&self) -> Vec3 {
        self.u.cross(Vec3::Y)
    }
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_cols(
            self.u.extend(0.0),
            Vec3::Y.extend(0.0),
            self.normal().extend(0.0),
            self.origin.extend(1.0),
        )
    }
    pub fn rotation(&self) -> Quat {
        Quat::from_mat3(&glam::Mat3::from_cols(self.u, Vec3::Y, self.normal())).normalize()
    }
    pub fn point(&self, p: Vec3) -> Vec3 {
        self.origin + self.u * p.x + Vec3::Y * p.y + self.normal() * p.z
    }
}

/// The materials a façade uses (indices into the document's materials).
pub struct FacadeMaterials {
    pub walls: Vec<usize>,
    pub trim: usize,
    pub glass: usize,
    pub shutters: Vec<usize>,
    pub door: usize,
    pub rolling_shutter: usize,
    pub interior: Vec<usize>,
    pub floor: usize,
    pub counter: usize,
    pub awnings: Vec<usize>,
    pub sign_board: usize,
    pub railing: usize,
    pub cord: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum BulbKind {
    Post,
    WallLantern,
    Pendant,
    Candle,
}

/// A light model the façade offers, in local coordinates.
pub enum Spot {
    Bulb {
        kind: BulbKind,
        pos: Vec3,
    },
    /// A glowing window pane filling the back of a recess: corner, width, height.
    Pane {
        corner: Vec3,
        w: f32,
        h: f32,
    },
    /// An emissive sign face: corner, width, height, atlas row.
    Sign {
        corner: Vec3,
        w: f32,
        h: f32,
        row: usize,
    },
}

#[derive(Clone, Copy)]
pub enum Prop {
    WallLantern,
    Table,
    Chair,
    Candle,
    Planter,
    Post,
}

#[derive(Default)]
pub struct Run {
    pub sink: Sink,
    pub spots: Vec<Spot>,
    /// (prop, local position, yaw about local y).
    pub props: Vec<(Prop, Vec3, f32)>,
    pub garlands: Vec<Vec<Vec3>>,
    /// Heights of the first and last building (to match neighbours at corners).
    pub end_heights: (f32, f32),
}

struct Opening {
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
}

/// Wall pieces of the rectangle `area` at depth z minus the openings, facing +z (or −z
/// when `back`), cut into horizontal bands at every opening edge.
fn wall_with_holes(geo: &mut MeshData, area: Opening, z: f32, holes: &[Opening], back: bool) {
    let Opening { x0, x1, y0, y1 } = area;
    let mut ys = vec![y0, y1];
    for h in holes {
        ys.extend([h.y0.clamp(y0, y1), h.y1.clamp(y0, y1)]);
    }
    ys.sort_by(f32::total_cmp);
    ys.dedup();
    for band in ys.windows(2) {
        let (ya, yb) = (band[0], band[1]);
        if yb - ya < 1e-4 {
            continue;
        }
        let mut cuts: Vec<(f32, f32)> = holes
            .iter()
            .filter(|h| h.y0 <= ya && h.y1 >= yb)
            .map(|h| (h.x0.max(x0), h.x1.min(x1)))
            .collect();
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut x = x0;
        for (c0, c1) in cuts.into_iter().chain([(x1, x1)]) {
            if c0 - x > 1e-4 {
                let (o, u, v) = (Vec3::new(x, ya, z), Vec3::X * (c0 - x), Vec3::Y * (yb - ya));
                if back {
                    geo.rect(o, v, u)
                } else {
                    geo.rect(o, u, v)
                }
            }
            x = x.max(c1);
        }
    }
}

/// The four inner faces of an opening's recess from z = 0 back to z = −depth.
fn reveals(geo: &mut MeshData, o: &Opening, depth: f32, with_sill: bool) {
    let (w, h, d) = (o.x1 - o.x0, o.y1 - o.y0, Vec3::Z * depth);
    geo.rect(Vec3::new(o.x0, o.y0, -depth), Vec3::Y * h, d); // left side, faces +x
    geo.rect(Vec3::new(o.x1, o.y0, -depth), d, Vec3::Y * h); // right side, faces −x
    geo.rect(Vec3::new(o.x0, o.y1, -depth), Vec3::X * w, d); // soffit, faces down
    if with_sill {
        geo.rect(Vec3::new(o.x0, o.y0, -depth), d, Vec3::X * w); // sill, faces up
    }
}

/// Builds a run of buildings of total `width` whose ground level (sidewalk top) is
/// `ground`. `first_height` forces the height of the first building (corners).
pub fn build_run(
    rng: &mut Rng,
    m: &FacadeMaterials,
    width: f32,
    ground: f32,
    first_height: Option<f32>,
    signs: usize,
    cafes: bool,
) -> Run {
    let mut run = Run::default();
    // Split into buildings 6–10 m wide; a short remainder joins the last one.
    let mut bounds = vec![0.0f32];
    while width - bounds.last().unwrap() > 0.0 {
        let b = *bounds.last().unwrap();
        let w = rng.range(6.0, 10.0);
        bounds.push(if width - (b + w) < 5.0 { width } else { b + w });
    }
    let mut prev_height = 0.0f32;
    let n_buildings = bounds.len() - 1;
    for i in 0..n_buildings {
        let storeys = 3 + rng.below(3) as u32;
        let mut height = ground + GROUND_FLOOR + (storeys - 1) as f32 * STOREY + 0.7;
        if i == 0 {
            if let Some(h) = first_height {
                height = h;
            }
        }
        let (b0, b1) = (bounds[i], bounds[i + 1]);
        building(rng, m, &mut run, b0, b1, ground, height, signs, cafes);
        // Party wall where this building rises above its predecessor (faces −x) or the
        // predecessor rises above it (faces +x).
        if i > 0 && (height - prev_height).abs() > 1e-3 {
            let (lo, hi) = (height.min(prev_height), height.max(prev_height));
            let geo = run.sink.at(m.trim);
            let (o, d, v) = (
                Vec3::new(b0, lo, -DEPTH),
                Vec3::Z * DEPTH,
                Vec3::Y * (hi - lo),
            );
            if height > prev_height {
                geo.rect(o, d, v)
            } else {
                geo.rect(o, v, d)
            }
        }
        if i == 0 {
            run.end_heights.0 = height;
        }
        run.end_heights.1 = height;
        prev_height = height;
    }
    run
}

#[allow(clippy::too_many_arguments)]
fn building(
    rng: &mut Rng,
    m: &FacadeMaterials,
    run: &mut Run,
    b0: f32,
    b1: f32,
    g: f32,
    height: f32,
    signs: usize,
    cafes: bool,
) {
    let w = b1 - b0;
    let wall = *rng.pick(&m.walls);
    let shutter_mat = rng.chance(0.6).then(|| *rng.pick(&m.shutters));
    let mut holes: Vec<Opening> = Vec::new();

    // Ground floor: a shop and, if there is room, a door to the flats above.
    let shop_w = rng.range(2.6, 3.8).min(w - 2.0);
    let slack = w - shop_w - 1.6;
    let shop_x0 = b0 + 0.8 + slack * rng.range(0.15, 0.85);
    let shop = Opening {
        x0: shop_x0,
        x1: shop_x0 + shop_w,
        y0: g,
        y1: g + 3.0,
    };
    let open = rng.chance(0.7);
    if open {
        shop_interior(rng, m, run, &shop, b0, b1, g);
    } else {
        reveals(run.sink.at(wall), &shop, 0.3, false);
        run.sink.at(m.rolling_shutter).rect(
            Vec3::new(shop.x0, shop.y0, -0.3),
            Vec3::X * shop_w,
            Vec3::Y * 3.0,
        );
    }
    // Door in the wider pier beside the shop.
    let (left, right) = (shop.x0 - b0, b1 - shop.x1);
    if left.max(right) > 1.8 {
        let cx = if left > right {
            b0 + left / 2.0
        } else {
            shop.x1 + right / 2.0
        };
        let door = Opening {
            x0: cx - 0.55,
            x1: cx + 0.55,
            y0: g,
            y1: g + 2.4,
        };
        reveals(run.sink.at(wall), &door, 0.25, false);
        run.sink.at(m.door).rect(
            Vec3::new(door.x0, door.y0, -0.25),
            Vec3::X * 1.1,
            Vec3::Y * 2.4,
        );
        holes.push(door);
    }
    // Awning, sign and café furniture for open shops.
    let cx = (shop.x0 + shop.x1) / 2.0;
    if open && rng.chance(0.85) {
        awning(rng, m, run, shop.x0 - 0.3, shop.x1 + 0.3, g);
    }
    if signs > 0 {
        let sw = (shop_w + 0.2).min(2.6);
        run.sink.at(m.sign_board).cuboid(
            Vec3::new(cx - sw / 2.0 - 0.05, g + 3.53, 0.0),
            Vec3::new(cx + sw / 2.0 + 0.05, g + 4.0, 0.06),
        );
        run.spots.push(Spot::Sign {
            corner: Vec3::new(cx - sw / 2.0, g + 3.56, 0.062),
            w: sw,
            h: 0.41,
            row: rng.below(signs),
        });
    }
    if open && cafes && rng.chance(0.7) {
        let n = ((shop_w / 1.25) as usize).clamp(1, 3);
        for k in 0..n {
            let x = shop.x0 + shop_w * (k as f32 + 0.5) / n as f32;
            let z = rng.range(1.05, 1.3);
            run.props
                .push((Prop::Table, Vec3::new(x, g, z), rng.range(0.0, 1.0)));
            run.props.push((
                Prop::Chair,
                Vec3::new(x - 0.52, g, z),
                std::f32::consts::FRAC_PI_2,
            ));
            run.props.push((
                Prop::Chair,
                Vec3::new(x + 0.52, g, z),
                -std::f32::consts::FRAC_PI_2,
            ));
            run.props
                .push((Prop::Candle, Vec3::new(x, g + 0.75, z), 0.0));
            run.spots.push(Spot::Bulb {
                kind: BulbKind::Candle,
                pos: Vec3::new(x, g, z) + super::street_props::CANDLE_FLAME,
            });
        }
    }
    // A wall lantern on the pier left of the shop.
    if shop.x0 - b0 > 0.7
        && holes.iter().all(|h| h.x1 < shop.x0 - 0.6 || h.x0 > shop.x0)
        && rng.chance(0.75)
    {
        let anchor = Vec3::new(shop.x0 - 0.35, g + 2.75, 0.0);
        run.props.push((Prop::WallLantern, anchor, 0.0));
        run.spots.push(Spot::Bulb {
            kind: BulbKind::WallLantern,
            pos: anchor + super::street_props::WALL_BULB,
        });
    }
    holes.push(shop);

    // Upper storeys.
    let storeys = ((height - g - GROUND_FLOOR - 0.7) / STOREY).round() as u32 + 1;
    let cols = (((w - 0.8) / 2.4) as u32).max(2);
    let balcony_cols: Vec<bool> = (0..cols).map(|_| rng.chance(0.3)).collect();
    let trim = run.sink.at(m.trim);
    for s in 1..storeys {
        let yf = g + GROUND_FLOOR + (s - 1) as f32 * STOREY;
        trim.cuboid(Vec3::new(b0, yf - 0.14, 0.0), Vec3::new(b1, yf + 0.02, 0.1));
    }
    trim.cuboid(
        Vec3::new(b0, height - 0.45, 0.0),
        Vec3::new(b1, height - 0.15, 0.35),
    );
    for s in 1..storeys {
        let yf = g + GROUND_FLOOR + (s - 1) as f32 * STOREY;
        for c in 0..cols {
            let x = b0 + w * (c as f32 + 0.5) / cols as f32;
            let balcony = s <= 2 && balcony_cols[c as usize];
            let o = if balcony {
                Opening {
                    x0: x - 0.6,
                    x1: x + 0.6,
                    y0: yf + 0.05,
                    y1: yf + 2.45,
                }
            } else {
                Opening {
                    x0: x - 0.55,
                    x1: x + 0.55,
                    y0: yf + 0.9,
                    y1: yf + 2.5,
                }
            };
            let depth = 0.3;
            reveals(run.sink.at(wall), &o, depth, true);
            let corner = Vec3::new(o.x0, o.y0, -depth);
            let (ow, oh) = (o.x1 - o.x0, o.y1 - o.y0);
            if rng.chance(0.3) {
                run.spots.push(Spot::Pane {
                    corner,
                    w: ow,
                    h: oh,
                });
            } else {
                run.sink
                    .at(m.glass)
                    .rect(corner, Vec3::X * ow, Vec3::Y * oh);
            }
            if let (Some(sm), false) = (shutter_mat, balcony) {
                let geo = run.sink.at(sm);
                geo.rect(
                    Vec3::new(o.x0 - 0.56, o.y0, 0.02),
                    Vec3::X * 0.54,
                    Vec3::Y * oh,
                );
                geo.rect(
                    Vec3::new(o.x1 + 0.02, o.y0, 0.02),
                    Vec3::X * 0.54,
                    Vec3::Y * oh,
                );
            }
            if balcony {
                balcony_at(rng, m, run, o.x0 - 0.3, o.x1 + 0.3, yf + 0.05);
            }
            holes.push(o);
        }
    }
    let area = Opening {
        x0: b0,
        x1: b1,
        y0: 0.0,
        y1: height,
    };
    wall_with_holes(run.sink.at(wall), area, 0.0, &holes, false);
}

/// The lit room behind an open shop front.
fn shop_interior(
    rng: &mut Rng,
    m: &FacadeMaterials,
    run: &mut Run,
    shop: &Opening,
    b0: f32,
    b1: f32,
    g: f32,
) {
    let (front, back) = (-0.3, -5.5);
    let (rx0, rx1) = (
        (shop.x0 - 0.8).max(b0 + 0.15),
        (shop.x1 + 0.8).min(b1 - 0.15),
    );
    let top = g + 3.4;
    let inner = *rng.pick(&m.interior);
    reveals(run.sink.at(inner), shop, -front, false);
    // Room: inward faces except the floor (wood) and the front (cut around the opening).
    run.sink.at(inner).aabb(
        Vec3::new(rx0, g, back),
        Vec3::new(rx1, top, front),
        false,
        4 | 32,
    );
    let area = Opening {
        x0: rx0,
        x1: rx1,
        y0: g,
        y1: top,
    };
    wall_with_holes(
        run.sink.at(inner),
        area,
        front,
        std::slice::from_ref(shop),
        true,
    );
    run.sink.at(m.floor).rect(
        Vec3::new(rx0, g, back),
        Vec3::Z * (front - back),
        Vec3::X * (rx1 - rx0),
    );
    let cx = rng.range(rx0 + 0.3, rx1 - 2.0).max(rx0 + 0.1);
    run.sink
        .at(m.counter)
        .cuboid(Vec3::new(cx, g, -4.3), Vec3::new(cx + 1.8, g + 1.05, -3.7));
    let pendants = if rx1 - rx0 > 3.5 { 3 } else { 2 };
    for k in 0..pendants {
        let x = rx0 + (rx1 - rx0) * (k as f32 + 0.5) / pendants as f32;
        let z = rng.range(-2.6, -1.8);
        let bulb = Vec3::new(x, g + 2.65, z);
        run.sink.at(m.cord).cuboid(
            bulb + Vec3::new(-0.006, 0.05, -0.006),
            Vec3::new(x + 0.006, top, z + 0.006),
        );
        run.spots.push(Spot::Bulb {
            kind: BulbKind::Pendant,
            pos: bulb,
        });
    }
}

/// A sloped fabric awning over [x0, x1] with a valance, and a garland under its edge.
fn awning(rng: &mut Rng, m: &FacadeMaterials, run: &mut Run, x0: f32, x1: f32, g: f32) {
    let fabric = *rng.pick(&m.awnings);
    let (top, front, out) = (g + 3.45, g + 2.8, 1.5);
    let geo = run.sink.at(fabric);
    let slope = Vec3::new(0.0, front - top, out);
    geo.rect(Vec3::new(x0, top, 0.0), slope, Vec3::X * (x1 - x0));
    geo.rect(
        Vec3::new(x0, front - 0.25, out),
        Vec3::X * (x1 - x0),
        Vec3::Y * 0.25,
    );
    for x in [x0, x1] {
        geo.triangle(
            Vec3::new(x, top, 0.0),
            Vec3::new(x, front, out),
            Vec3::new(x, front - 0.25, out),
        );
    }
    run.garlands.push(sagging(
        Vec3::new(x0 + 0.1, front - 0.3, out - 0.06),
        Vec3::new(x1 - 0.1, front - 0.3, out - 0.06),
        0.06,
        12,
    ));
}

/// A balcony slab with alpha-masked railings on three sides, and sometimes a garland.
fn balcony_at(rng: &mut Rng, m: &FacadeMaterials, run: &mut Run, x0: f32, x1: f32, y: f32) {
    let depth = 0.9;
    run.sink
        .at(m.trim)
        .cuboid(Vec3::new(x0, y - 0.15, 0.0), Vec3::new(x1, y, depth));
    let rail = run.sink.at(m.railing);
    let h = Vec3::Y * 1.0;
    rail.rect(Vec3::new(x0, y, depth - 0.02), Vec3::X * (x1 - x0), h);
    rail.rect(Vec3::new(x0 + 0.02, y, 0.0), h, Vec3::Z * (depth - 0.02));
    rail.rect(Vec3::new(x1 - 0.02, y, 0.0), Vec3::Z * (depth - 0.02), h);
    if rng.chance(0.5) {
        run.garlands.push(sagging(
            Vec3::new(x0, y + 1.0, depth + 0.02),
            Vec3::new(x1, y + 1.0, depth + 0.02),
            0.12,
            12,
        ));
    }
}

/// A hanging wire from a to b sagging by `sag` in the middle (a parabola), as a polyline.
pub fn sagging(a: Vec3, b: Vec3, sag: f32, segments: usize) -> Vec<Vec3> {
    (0..=segments)
        .map(|i| {
            let t = i as f32 / segments as f32;
            a.lerp(b, t) - Vec3::Y * (4.0 * sag * t * (1.0 - t))
        })
        .collect()
}
