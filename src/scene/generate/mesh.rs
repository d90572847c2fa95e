//! Triangle-mesh building blocks for the generators: quads, boxes, prisms, octahedral
//! bulbs and ribbons, each emitted with counter-clockwise winding toward its front side
//! and flat per-face normals (so the geometric and shading normals agree, which keeps
//! emission and Lambertian shading unambiguous). UVs are in metres divided by
//! `uv_tile`, so tiled textures keep a constant physical size across differently sized
//! parts.

use glam::{Mat4, Vec2, Vec3};

#[derive(Clone, Debug)]
pub struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
    /// Metres per texture repeat for the automatic UVs of `rect`.
    pub uv_tile: f32,
}

impl Default for MeshData {
    fn default() -> Self {
        MeshData {
            positions: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            indices: Vec::new(),
            uv_tile: 1.0,
        }
    }
}

impl MeshData {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn with_uv_tile(uv_tile: f32) -> Self {
        MeshData {
            uv_tile,
            ..Self::default()
        }
    }

    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// A planar quad with corners in counter-clockwise order seen from its front.
    pub fn quad(&mut self, p: [Vec3; 4], uv: [Vec2; 4]) {
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        if n == Vec3::ZERO {
            return;
        }
        let base = self.positions.len() as u32;
        for i in 0..4 {
            self.positions.push(p[i]);
            self.normals.push(n);
            self.uvs.push(uv[i]);
        }
        self.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// The parallelogram `o, o+u, o+u+v, o+v`; its front faces along `u × v`. UVs follow
    /// the edges in metres over `uv_tile`, starting at `uv0`.
    pub fn rect_uv(&mut self, o: Vec3, u: Vec3, v: Vec3, uv0: Vec2) {
        let (lu, lv) = (u.length() / self.uv_tile, v.length() / self.uv_tile);
        self.quad(
            [o, o + u, o + u + v, o + v],
            [
                uv0,
                uv0 + Vec2::new(lu, 0.0),
                uv0 + Vec2::new(lu, lv),
                uv0 + Vec2::new(0.0, lv),
            ],
        );
    }

    pub fn rect(&mut self, o: Vec3, u: Vec3, v: Vec3) {
        self.rect_uv(o, u, v, Vec2::ZERO);
    }

    /// A rectangle whose texture coordinates span exactly [uv_min, uv_max] (for atlases).
    pub fn rect_mapped(&mut self, o: Vec3, u: Vec3, v: Vec3, uv_min: Vec2, uv_max: Vec2) {
        // glTF's v axis points down the image, the rectangle's v edge points up.
        self.quad(
            [o, o + u, o + u + v, o + v],
            [
                Vec2::new(uv_min.x, uv_max.y),
                Vec2::new(uv_max.x, uv_max.y),
                Vec2::new(uv_max.x, uv_min.y),
                Vec2::new(uv_min.x, uv_min.y),
            ],
        );
    }

    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3) {
        let n = (b - a).cross(c - a).normalize_or_zero();
        if n == Vec3::ZERO {
            return;
        }
        let base = self.positions.len() as u32;
        for p in [a, b, c] {
            self.positions.push(p);
            self.normals.push(n);
            self.uvs.push(Vec2::new(p.x + p.z, p.y) / self.uv_tile);
        }
        self.indices.extend_from_slice(&[base, base + 1, base + 2]);
    }

    /// An axis-aligned box. `outward` picks which side the faces look at; `skip` names
    /// faces to leave out as a bitmask: 1 −x, 2 +x, 4 −y, 8 +y, 16 −z, 32 +z.
    pub fn aabb(&mut self, min: Vec3, max: Vec3, outward: bool, skip: u32) {
        let d = max - min;
        let (ex, ey, ez) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
        // Each face as (origin, u, v) with u × v pointing outward.
        let faces = [
            (min, ez, ey),
            (min + ex, ey, ez),
            (min, ex, ez),
            (min + ey, ez, ex),
            (min, ey, ex),
            (min + ez, ex, ey),
        ];
        for (i, (o, u, v)) in faces.into_iter().enumerate() {
            if skip & (1 << i) != 0 {
                continue;
            }
            if outward {
                self.rect(o, u, v);
            } else {
                self.rect(o, v, u);
            }
        }
    }

    pub fn cuboid(&mut self, min: Vec3, max: Vec3) {
        self.aabb(min, max, true, 0);
    }

    /// A closed vertical prism (cylinder approximation) standing on `base`.
    pub fn prism(&mut self, base: Vec3, radius: f32, height: f32, segments: u32) {
        let up = Vec3::Y * height;
        let ring = |i: u32| {
            let a = i as f32 / segments as f32 * std::f32::consts::TAU;
            base + Vec3::new(a.cos(), 0.0, -a.sin()) * radius
        };
        for i in 0..segments {
            let (a, b) = (ring(i), ring(i + 1));
            self.quad(
                [a, b, b + up, a + up],
                [
                    Vec2::new(0.0, 0.0),
                    Vec2::new(1.0, 0.0),
                    Vec2::new(1.0, 1.0),
                    Vec2::new(0.0, 1.0),
                ],
            );
            self.triangle(base + up, a + up, b + up);
            self.triangle(base, b, a);
        }
    }

    /// A square pyramid roof (four triangles) over the square of half-side `r` at `base`.
    pub fn pyramid(&mut self, base: Vec3, r: f32, height: f32) {
        let apex = base + Vec3::Y * height;
        let c = [
            Vec3::new(-r, 0.0, r),
            Vec3::new(r, 0.0, r),
            Vec3::new(r, 0.0, -r),
            Vec3::new(-r, 0.0, -r),
        ];
        for i in 0..4 {
            self.triangle(base + c[i], base + c[(i + 1) % 4], apex);
        }
    }

    /// An octahedron (eight faces, outward): the bulb shape of the light models.
    pub fn octahedron(&mut self, center: Vec3, radius: f32) {
        let axes = [Vec3::X, Vec3::Z, -Vec3::X, -Vec3::Z];
        for i in 0..4 {
            let (a, b) = (
                center + axes[i] * radius,
                center + axes[(i + 1) % 4] * radius,
            );
            self.triangle(a, center + Vec3::Y * radius, b);
            self.triangle(b, center - Vec3::Y * radius, a);
        }
    }

    /// A flat strip of width `w` along a polyline, facing `side` (used for wires).
    pub fn ribbon(&mut self, points: &[Vec3], w: f32, side: Vec3) {
        for s in points.windows(2) {
            let t = (s[1] - s[0]).normalize_or_zero();
            let across = t.cross(side).normalize_or_zero() * (0.5 * w);
            self.quad(
                [s[0] - across, s[0] + across, s[1] + across, s[1] - across],
                [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            );
        }
    }

    /// Appends `other` transformed by `m` (rigid motions and positive scales only).
    pub fn append(&mut self, other: &MeshData, m: Mat4) {
        let base = self.positions.len() as u32;
        let nm = m.inverse().transpose();
        for i in 0..other.positions.len() {
            self.positions.push(m.transform_point3(other.positions[i]));
            self.normals
                .push(nm.transform_vector3(other.normals[i]).normalize());
            self.uvs.push(other.uvs[i]);
        }
        self.indices.extend(other.indices.iter().map(|i| i + base));
    }

    /// Total area of the triangles after transformation by `m`.
    pub fn area(&self, m: Mat4) -> f64 {
        self.indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] =
                    [0, 1, 2].map(|k| m.transform_point3(self.positions[t[k] as usize]));
                0.5 * (b - a).cross(c - a).length() as f64
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_faces_point_outward_and_inward() {
        for outward in [true, false] {
            let mut m = MeshData::new();
            m.aabb(Vec3::splat(-1.0), Vec3::splat(1.0), outward, 0);
            assert_eq!(m.triangle_count(), 12);
            for t in m.indices.chunks_exact(3) {
                let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
                let n = (b - a).cross(c - a);
                let centroid = (a + b + c) / 3.0;
                assert_eq!(n.dot(centroid) > 0.0, outward);
                assert!(m.normals[t[0] as usize].dot(n) > 0.0);
            }
        }
    }

    #[test]
    fn octahedron_is_closed_and_outward() {
        let mut m = MeshData::new();
        m.octahedron(Vec3::new(1.0, 2.0, 3.0), 0.5);
        assert_eq!(m.triangle_count(), 8);
        let expected = 8.0 * 3f64.sqrt() / 4.0 * (0.5f64 * 2f64.sqrt()).powi(2);
        assert!((m.area(Mat4::IDENTITY) - expected).abs() < 1e-5);
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
            assert!(
                (b - a)
                    .cross(c - a)
                    .dot((a + b + c) / 3.0 - Vec3::new(1.0, 2.0, 3.0))
                    > 0.0
            );
        }
    }
}
