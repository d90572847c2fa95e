//! `cornell-lights`: the classic Cornell box (pure Lambertian white, red and green walls,
//! open toward the camera) lit only by N small coloured emissive squares whose radiances
//! span 200×, a quarter of them placed behind the tall blocker where the camera cannot
//! see them. Small and quick: the many-light scene of the tests and the README.
//!
//! The box spans x ∈ [−1, 1], y ∈ [0, 2], z ∈ [−1, 1]; every wall and every emitter has
//! its front face toward the interior.

use super::mesh::MeshData;
use super::rng::Rng;
use super::writer::{num, Gltf, Material, Node};
use super::{Built, GenerateError, Options};
use glam::Vec3;
use serde_json::{json, Map};

const WHITE: [f32; 3] = [0.73, 0.73, 0.73];
const RED: [f32; 3] = [0.63, 0.065, 0.05];
const GREEN: [f32; 3] = [0.14, 0.45, 0.091];
const PALETTE: [[f32; 3]; 6] = [
    [1.0, 0.75, 0.45],
    [1.0, 0.3, 0.2],
    [0.3, 0.6, 1.0],
    [0.4, 1.0, 0.4],
    [1.0, 0.9, 0.3],
    [0.9, 0.4, 1.0],
];
/// Radiance of the weakest and strongest emitters (a 200× span).
const L_MIN: f32 = 2.0;
const L_MAX: f32 = 400.0;
/// Tall blocker's footprint and height; the hidden emitters sit behind it.
const TALL: (Vec3, Vec3) = (Vec3::new(-0.75, 0.0, -0.7), Vec3::new(-0.1, 1.25, -0.2));
const SHORT: (Vec3, Vec3) = (Vec3::new(0.15, 0.0, -0.1), Vec3::new(0.7, 0.6, 0.45));

/// A wall region holding a grid of emitter slots: origin corner, two in-plane edges whose
/// cross product points into the box, and whether it is hidden from the camera.
struct Region {
    o: Vec3,
    u: Vec3,
    v: Vec3,
    hidden: bool,
}

pub fn build(o: &Options) -> Result<Built, GenerateError> {
    let n = o.lights.unwrap_or(16);
    if !(1..=4096).contains(&n) {
        return Err(GenerateError::InvalidOption {
            option: "lights",
            value: n.to_string(),
            reason: "must be between 1 and 4096".into(),
        });
    }
    let aspect = o.aspect.unwrap_or(1.0);
    let mut rng = Rng::new(o.seed);
    let mut g = Gltf::new();

    let (white, red, green) = (
        g.material(Material::diffuse("white", WHITE)),
        g.material(Material::diffuse("red", RED)),
        g.material(Material::diffuse("green", GREEN)),
    );
    let (mut w, mut r, mut gr) = (MeshData::new(), MeshData::new(), MeshData::new());
    let (x0, x1, y1, z0, z1) = (-1.0, 1.0, 2.0, -1.0, 1.0);
    w.rect(Vec3::new(x0, 0.0, z0), Vec3::Z * 2.0, Vec3::X * 2.0); // floor, up
    w.rect(Vec3::new(x0, y1, z0), Vec3::X * 2.0, Vec3::Z * 2.0); // ceiling, down
    w.rect(Vec3::new(x0, 0.0, z0), Vec3::X * 2.0, Vec3::Y * 2.0); // back, +z
    r.rect(Vec3::new(x0, 0.0, z0), Vec3::Y * 2.0, Vec3::Z * (z1 - z0)); // left, +x
    gr.rect(Vec3::new(x1, 0.0, z0), Vec3::Z * (z1 - z0), Vec3::Y * 2.0); // right, −x
    let walls = g.mesh("walls", &[(&w, white), (&r, red), (&gr, green)]);
    g.node(Node::mesh(walls, Vec3::ZERO).named("walls"));
    let mut blockers = MeshData::new();
    blockers.aabb(TALL.0, TALL.1, true, 4);
    blockers.aabb(SHORT.0, SHORT.1, true, 4);
    let blockers = g.mesh("blockers", &[(&blockers, white)]);
    g.node(Node::mesh(blockers, Vec3::ZERO).named("blockers"));

    // Emitter slots: a grid on each region, finer when many lights are asked for.
    let k = ((n as f32 / 16.0).sqrt().ceil() as u32).max(1);
    let e = 0.002; // off the wall, so emitter and wall never share a plane
    let regions = [
        Region {
            o: Vec3::new(-0.8, y1 - e, -0.8),
            u: Vec3::X * 1.6,
            v: Vec3::Z * 1.6,
            hidden: false,
        },
        Region {
            o: Vec3::new(-0.05, 0.15, z0 + e),
            u: Vec3::X * 0.85,
            v: Vec3::Y * 1.6,
            hidden: false,
        },
        Region {
            o: Vec3::new(-0.7, 1.45, z0 + e),
            u: Vec3::X * 0.6,
            v: Vec3::Y * 0.4,
            hidden: false,
        },
        Region {
            o: Vec3::new(x0 + e, 0.2, -0.8),
            u: Vec3::Y * 1.6,
            v: Vec3::Z * 1.5,
            hidden: false,
        },
        Region {
            o: Vec3::new(x1 - e, 0.2, -0.8),
            u: Vec3::Z * 1.5,
            v: Vec3::Y * 1.6,
            hidden: false,
        },
        Region {
            o: Vec3::new(-0.68, 0.08, z0 + e),
            u: Vec3::X * 0.5,
            v: Vec3::Y * 0.75,
            hidden: true,
        },
        Region {
            o: Vec3::new(-0.7, e, z0 + 0.05),
            u: Vec3::Z * 0.2,
            v: Vec3::X * 0.55,
            hidden: true,
        },
    ];
    let mut visible_slots = Vec::new();
    let mut hidden_slots = Vec::new();
    for reg in &regions {
        // Slot count along each edge in proportion to its length (≥ 1).
        let (nu, nv) = (
            (reg.u.length() * 4.0 * k as f32).round().max(1.0) as u32,
            (reg.v.length() * 4.0 * k as f32).round().max(1.0) as u32,
        );
        for i in 0..nu {
            for j in 0..nv {
                let centre = reg.o
                    + reg.u * ((i as f32 + 0.5) / nu as f32)
                    + reg.v * ((j as f32 + 0.5) / nv as f32);
                let cell = (reg.u.length() / nu as f32).min(reg.v.length() / nv as f32);
                let slot = (centre, reg.u.normalize(), reg.v.normalize(), cell);
                if reg.hidden {
                    hidden_slots.push(slot)
                } else {
                    visible_slots.push(slot)
                }
            }
        }
    }
    shuffle(&mut rng, &mut visible_slots);
    shuffle(&mut rng, &mut hidden_slots);
    let n_hidden = ((n as usize).div_ceil(4)).min(hidden_slots.len());
    let n_visible = n as usize - n_hidden;
    if n_visible > visible_slots.len() {
        return Err(GenerateError::InvalidOption {
            option: "lights",
            value: n.to_string(),
            reason: "too many lights for the box".into(),
        });
    }
    // Radiances log-spaced over the full span (so it is exactly 200× whenever n ≥ 2), then
    // dealt to slots at random.
    let mut radiances: Vec<f32> = (0..n)
        .map(|i| {
            if n == 1 {
                L_MAX
            } else {
                L_MIN * (L_MAX / L_MIN).powf(i as f32 / (n - 1) as f32)
            }
        })
        .collect();
    shuffle(&mut rng, &mut radiances);
    let slots = hidden_slots[..n_hidden]
        .iter()
        .chain(&visible_slots[..n_visible]);
    let mut hidden_power_share = 0.0f64;
    let mut total_power = 0.0f64;
    for (i, (&(c, u, v, cell), &l)) in slots.zip(&radiances).enumerate() {
        let side = cell * rng.range(0.35, 0.6);
        let color = *rng.pick(&PALETTE);
        let mut q = MeshData::new();
        q.rect(c - (u + v) * (side / 2.0), u * side, v * side);
        let m = g.material(Material::emitter(
            &format!("light{i}"),
            color.map(|x| x * l),
        ));
        let mesh = g.mesh(&format!("light{i}"), &[(&q, m)]);
        g.node(Node::mesh(mesh, Vec3::ZERO).named(format!("light{i}")));
        let p = std::f64::consts::PI
            * (side * side) as f64
            * (l * (color[0] + color[1] + color[2]) / 3.0) as f64;
        total_power += p;
        if i < n_hidden {
            hidden_power_share += p;
        }
    }
    let cam = g.camera("front", 40.0, aspect);
    g.camera_node(cam, Vec3::new(0.0, 1.0, 3.85), Vec3::new(0.0, 1.0, 0.0));

    let mut options = Map::new();
    options.insert("lights".into(), json!(n));
    options.insert("aspect".into(), num(aspect));
    let analytic = json!({
        "hidden_lights": n_hidden,
        "radiance_min": num(L_MIN),
        "radiance_max": num(L_MAX),
        "hidden_power_fraction": hidden_power_share / total_power,
    });
    Ok(Built {
        gltf: g,
        options,
        analytic: Some(analytic),
    })
}

fn shuffle<T>(rng: &mut Rng, v: &mut [T]) {
    for i in (1..v.len()).rev() {
        v.swap(i, rng.below(i + 1));
    }
}
