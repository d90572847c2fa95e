//! Small emitters seen directly, sampled inside the pixels they cover.
//!
//! A string-light bulb far smaller than a pixel is found by a camera ray only when the
//! ray happens to land on it: its pixel's value jumps between 0 and Le / coverage, and
//! at equal time that coverage noise was most of the error on `street-matte` (README,
//! Rendering). Yet the emission a pixel sees of one emissive triangle T is
//!
//!   ∫ over the pixel of Le · [the camera ray through x reaches T first] dx,
//!
//! an integral over the part of T's image inside the pixel, which is known exactly: the
//! image of a triangle in front of the camera is a triangle. So, once per render, the
//! host projects every emissive triangle whose image is small, clips that image to each
//! pixel it touches and keeps the pieces (as triangles) in a per-pixel list. Per sample,
//! the kernel picks one piece of its pixel (probability ∝ area × the triangle's radiance),
//! aims a camera ray at a uniform point of it, and counts Le · area / probability when
//! the ray reaches that very triangle first — occlusion, alpha masks and textured
//! emission are all the ray's. Camera rays count nothing of a triangle in the set, so
//! each triangle's share is estimated once: the sum is unbiased. A fully visible bulb
//! inside one pixel has no variance left at all.
//!
//! Triangles facing away (one-sided emission), crossing the camera plane, larger than
//! [`MAX_TRIANGLE_PIXELS`] on screen, with a bounding box over [`MAX_BOX_PIXELS`] (long
//! slivers), or past the memory cap stay with the camera rays.

use crate::gpu;
use crate::scene::{Camera, Projection};
use glam::{DMat4, DVec2, DVec3};

/// Emissive triangles whose image covers at most this many pixels are sampled in their
/// pixels; larger ones have coverage noise only along their edges.
pub const MAX_TRIANGLE_PIXELS: f64 = 16.0;
/// Triangles whose image's bounding box spans more pixels than this stay with the camera
/// rays: a long sliver of small area would otherwise be clipped against a large box.
pub const MAX_BOX_PIXELS: f64 = 64.0;
/// At most this many pieces (36 bytes each on the device); triangles beyond stay with
/// the camera rays.
pub const MAX_PIECES: usize = 1 << 20;

/// The per-pixel lists the kernel reads (`BINDING_PIXEL_EMITTER_*`).
#[derive(Clone, Debug, Default)]
pub struct PixelEmitters {
    /// Per pixel (y · width + x) the first piece of its list; one more entry at the end.
    /// Empty when there are no pieces (the kernel is then told to skip the lists).
    pub offsets: Vec<u32>,
    pub pieces: Vec<gpu::PixelEmitter>,
    /// One bit per light triangle: in the set (camera rays leave its emission out).
    pub flags: Vec<u32>,
    /// Light triangles in the set.
    pub triangles: usize,
    /// Pixels with a non-empty list.
    pub pixels: usize,
}

/// Camera space to image coordinates, as `camera_ray` in raygen.glsl maps them back.
struct ImageMap {
    world_to_camera: DMat4,
    camera_position: DVec3,
    /// Perspective: tan(fov/2) and the aspect ratio; orthographic: None.
    perspective: Option<(f64, f64)>,
    ortho: DVec2,
    view_dir: DVec3,
    size: DVec2,
}

impl ImageMap {
    fn new(camera: &Camera, width: u32, height: u32) -> ImageMap {
        let to_world = camera.rigid_to_world().as_dmat4();
        let (perspective, ortho) = match camera.projection {
            Projection::Perspective { yfov, .. } => (
                Some(((0.5 * yfov as f64).tan(), width as f64 / height as f64)),
                DVec2::ZERO,
            ),
            Projection::Orthographic { xmag, ymag } => (None, DVec2::new(xmag as f64, ymag as f64)),
        };
        ImageMap {
            world_to_camera: to_world.inverse(),
            camera_position: to_world.w_axis.truncate(),
            perspective,
            ortho,
            view_dir: -to_world.z_axis.truncate(),
            size: DVec2::new(width as f64, height as f64),
        }
    }

    /// Image coordinates of a world point strictly in front of the camera.
    fn project(&self, p: DVec3) -> Option<DVec2> {
        let q = self.world_to_camera.transform_point3(p);
        if q.z >= 0.0 {
            return None;
        }
        let ndc = match self.perspective {
            Some((tan_y, aspect)) => {
                DVec2::new(q.x / (-q.z * tan_y * aspect), q.y / (-q.z * tan_y))
            }
            None => DVec2::new(q.x / self.ortho.x, q.y / self.ortho.y),
        };
        let s = DVec2::new(
            (ndc.x + 1.0) * 0.5 * self.size.x,
            (1.0 - ndc.y) * 0.5 * self.size.y,
        );
        s.is_finite().then_some(s)
    }

    /// Whether a one-sided emitter with front normal `n` at `p` faces the camera.
    fn faces_camera(&self, p: DVec3, n: DVec3) -> bool {
        match self.perspective {
            Some(_) => n.dot(self.camera_position - p) > 0.0,
            None => n.dot(-self.view_dir) > 0.0,
        }
    }
}

fn area(poly: &[DVec2]) -> f64 {
    let mut a = 0.0;
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        a += p.perp_dot(q);
    }
    0.5 * a.abs()
}

/// `poly` clipped to the half-plane where `inside(p) ≥ 0` (`inside` linear in p).
fn clip(poly: &[DVec2], inside: impl Fn(DVec2) -> f64) -> Vec<DVec2> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (dp, dq) = (inside(p), inside(q));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            out.push(p + (q - p) * (dp / (dp - dq)));
        }
    }
    out
}

/// The part of triangle `t` inside pixel (x, y), as a convex polygon (maybe empty).
fn clip_to_pixel(t: [DVec2; 3], x: f64, y: f64) -> Vec<DVec2> {
    let mut poly = t.to_vec();
    poly = clip(&poly, |p| p.x - x);
    poly = clip(&poly, |p| x + 1.0 - p.x);
    poly = clip(&poly, |p| p.y - y);
    clip(&poly, |p| y + 1.0 - p.y)
}

/// The lists for `camera` at `width` × `height` over the light table's triangles.
pub fn build(
    camera: &Camera,
    width: u32,
    height: u32,
    light_triangles: &[gpu::LightTriangle],
) -> PixelEmitters {
    let map = ImageMap::new(camera, width, height);
    let pixel_count = width as usize * height as usize;
    // (pixel, corners, area, light triangle, selection weight) of every piece.
    let mut pieces: Vec<(u32, [DVec2; 3], f64, u32, f64)> = Vec::new();
    let mut flags = vec![0u32; light_triangles.len().div_ceil(32)];
    let mut triangles = 0;
    for (index, t) in light_triangles.iter().enumerate() {
        let corners = [t.p0, t.p1, t.p2].map(|p| DVec3::from(p.map(f64::from)));
        let normal = DVec3::from(t.normal.map(f64::from));
        if t.two_sided == 0 && !map.faces_camera(corners[0], normal) {
            continue;
        }
        let Some(image) = corners
            .iter()
            .map(|&p| map.project(p))
            .collect::<Option<Vec<DVec2>>>()
        else {
            continue;
        };
        let image = [image[0], image[1], image[2]];
        let image_area = area(&image);
        if !(image_area > 0.0 && image_area <= MAX_TRIANGLE_PIXELS) {
            continue;
        }
        let lo = image.iter().fold(DVec2::INFINITY, |m, &p| m.min(p));
        let hi = image.iter().fold(DVec2::NEG_INFINITY, |m, &p| m.max(p));
        let (x0, y0) = (lo.x.floor().max(0.0), lo.y.floor().max(0.0));
        let (x1, y1) = (
            hi.x.floor().min(map.size.x - 1.0),
            hi.y.floor().min(map.size.y - 1.0),
        );
        if (x1 - x0 + 1.0) * (y1 - y0 + 1.0) > MAX_BOX_PIXELS {
            continue;
        }
        // Radiance ∝ power / area: brighter emitters are chosen more often.
        let radiance = t.power as f64 / t.area as f64;
        let weight = if radiance.is_finite() && radiance > 0.0 {
            radiance
        } else {
            1.0
        };
        let mut mine = Vec::new();
        let mut y = y0;
        while y <= y1 {
            let mut x = x0;
            while x <= x1 {
                let poly = clip_to_pixel(image, x, y);
                let pixel = (y as u32) * width + x as u32;
                for k in 1..poly.len().saturating_sub(1) {
                    let piece = [poly[0], poly[k], poly[k + 1]];
                    let a = area(&piece);
                    if a > 0.0 {
                        mine.push((pixel, piece, a, index as u32, a * weight));
                    }
                }
                x += 1.0;
            }
            y += 1.0;
        }
        if mine.is_empty() || pieces.len() + mine.len() > MAX_PIECES {
            continue;
        }
        pieces.extend(mine);
        flags[index / 32] |= 1 << (index % 32);
        triangles += 1;
    }
    if pieces.is_empty() {
        return PixelEmitters::default();
    }
    pieces.sort_by_key(|p| p.0);

    let mut offsets = vec![0u32; pixel_count + 1];
    for p in &pieces {
        offsets[p.0 as usize + 1] += 1;
    }
    for i in 0..pixel_count {
        offsets[i + 1] += offsets[i];
    }
    let mut out = Vec::with_capacity(pieces.len());
    let mut pixels = 0;
    for i in 0..pixel_count {
        let list = &pieces[offsets[i] as usize..offsets[i + 1] as usize];
        if list.is_empty() {
            continue;
        }
        pixels += 1;
        let total: f64 = list.iter().map(|p| p.4).sum();
        let mut running = 0.0;
        for (k, p) in list.iter().enumerate() {
            running += p.4;
            let probability = p.4 / total;
            let f = |v: DVec2| [v.x as f32, v.y as f32];
            out.push(gpu::PixelEmitter {
                a: f(p.1[0]),
                b: f(p.1[1]),
                c: f(p.1[2]),
                cdf: if k + 1 == list.len() {
                    1.0
                } else {
                    (running / total) as f32
                },
                scale: (p.2 / probability) as f32,
                light_tri: p.3,
            });
        }
    }
    PixelEmitters {
        offsets,
        pieces: out,
        flags,
        triangles,
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ClipPlanes;
    use glam::{Mat4, Vec3};

    /// A one-sided emissive triangle with corners `p`, facing +z (toward a camera on +z).
    fn triangle(p: [Vec3; 3], two_sided: bool) -> gpu::LightTriangle {
        let mut t: gpu::LightTriangle = bytemuck::Zeroable::zeroed();
        t.p0 = p[0].into();
        t.p1 = p[1].into();
        t.p2 = p[2].into();
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        t.normal = n.normalize().into();
        t.area = 0.5 * n.length();
        t.two_sided = two_sided as u32;
        t.power = 1.0;
        t
    }

    fn camera() -> Camera {
        // At +z looking down -z, 90° vertical field of view.
        Camera {
            name: "test".into(),
            to_world: Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)),
            projection: Projection::Perspective {
                yfov: std::f32::consts::FRAC_PI_2,
                aspect: None,
            },
            clip: ClipPlanes::NONE,
        }
    }

    /// Only small triangles (in area and in extent) wholly in front of the camera and
    /// facing it are in the set;
    /// their pieces lie in their pixels, and area = weight × probability sums to the
    /// triangle's image. Seen to fail with the facing test removed and with the box
    /// limit removed.
    #[test]
    fn a_small_triangle_is_cut_into_its_pixels_and_weighted_by_area() {
        // 16×16 image over [-5, 5]² at z = 0: a pixel is 0.625 units wide.
        let small = triangle(
            [
                Vec3::new(0.1, 0.1, 0.0),
                Vec3::new(1.3, 0.2, 0.0),
                Vec3::new(0.4, 1.1, 0.0),
            ],
            false,
        );
        let facing_away = triangle(
            [
                Vec3::new(0.1, 0.1, 0.0),
                Vec3::new(0.4, 1.1, 0.0),
                Vec3::new(1.3, 0.2, 0.0),
            ],
            false,
        );
        let behind = triangle(
            [
                Vec3::new(0.1, 0.1, 6.0),
                Vec3::new(1.3, 0.2, 6.0),
                Vec3::new(0.4, 1.1, 6.0),
            ],
            true,
        );
        let large = triangle(
            [
                Vec3::new(-4.0, -4.0, 0.0),
                Vec3::new(4.0, -4.0, 0.0),
                Vec3::new(0.0, 4.0, 0.0),
            ],
            false,
        );
        // Small in area (1.2 pixels²) but 13 pixels long: its box spans 13 × 13 pixels.
        let sliver = triangle(
            [
                Vec3::new(-4.0, -4.0, 0.0),
                Vec3::new(4.0, 4.0, 0.0),
                Vec3::new(-3.9, -4.0, 0.0),
            ],
            true,
        );
        let e = build(
            &camera(),
            16,
            16,
            &[small, facing_away, behind, large, sliver],
        );
        assert_eq!(e.triangles, 1, "only the small triangle facing the camera");
        assert_eq!(e.flags, vec![1]);
        assert_eq!(e.offsets.len(), 16 * 16 + 1);
        assert_eq!(*e.offsets.last().unwrap() as usize, e.pieces.len());
        // Image area of the triangle, in pixels: world area / 0.625².
        let expected = 0.5 * (1.2f64 * 1.0 - 0.1 * 0.3) / (0.625 * 0.625);
        let mut area = 0.0;
        for p in 0..16 * 16 {
            let list = &e.pieces[e.offsets[p] as usize..e.offsets[p + 1] as usize];
            if list.is_empty() {
                continue;
            }
            let (x, y) = ((p % 16) as f32, (p / 16) as f32);
            assert_eq!(list.last().unwrap().cdf, 1.0);
            for (k, piece) in list.iter().enumerate() {
                for c in [piece.a, piece.b, piece.c] {
                    assert!(
                        c[0] >= x - 1e-4 && c[0] <= x + 1.0 + 1e-4,
                        "{c:?} outside pixel {p}"
                    );
                    assert!(
                        c[1] >= y - 1e-4 && c[1] <= y + 1.0 + 1e-4,
                        "{c:?} outside pixel {p}"
                    );
                }
                // One radiance: probability ∝ area, so area = scale × probability.
                let before = if k == 0 { 0.0 } else { list[k - 1].cdf };
                area += (piece.scale * (piece.cdf - before)) as f64;
            }
        }
        assert!(
            (area - expected).abs() < 1e-4 * expected,
            "{area} vs {expected}"
        );
        // Nothing to sample: no lists at all.
        let none = build(&camera(), 16, 16, &[facing_away, behind, large]);
        assert!(none.pieces.is_empty() && none.offsets.is_empty());
    }

    #[test]
    fn a_triangle_clipped_to_pixels_keeps_its_area() {
        let t = [
            DVec2::new(0.3, 0.2),
            DVec2::new(2.7, 0.9),
            DVec2::new(1.1, 2.6),
        ];
        let mut sum = 0.0;
        for y in 0..3 {
            for x in 0..3 {
                let poly = clip_to_pixel(t, x as f64, y as f64);
                if poly.len() >= 3 {
                    sum += area(&poly);
                    for p in &poly {
                        assert!(p.x >= x as f64 - 1e-12 && p.x <= x as f64 + 1.0 + 1e-12);
                        assert!(p.y >= y as f64 - 1e-12 && p.y <= y as f64 + 1.0 + 1e-12);
                    }
                }
            }
        }
        assert!((sum - area(&t)).abs() < 1e-12, "{sum} vs {}", area(&t));
    }
}
