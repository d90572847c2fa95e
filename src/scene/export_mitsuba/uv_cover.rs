//! Whether a mesh's texture coordinates map it one-to-one into the unit square: the
//! condition under which Mitsuba's texture-driven sampling of an area emitter is exact.
//!
//! Mitsuba samples such an emitter by drawing a point of the unit square by the
//! texture's luminance and finding the mesh point with that UV; its emitter pdf for a
//! point found by a BSDF ray is that of the point's UV. A point of the unit square that
//! no triangle covers is merely lost (its pdf share yields zero, as it should), but a
//! triangle whose UVs leave the square, overlap another's or collapse to a line is
//! never (or not always) the one found, while the pdf claims it is sampled: the MIS
//! weights then drop part of its light.

use glam::DVec2;

/// UVs may leave the unit square by this much (float rounding of exact atlas edges).
const INSIDE_TOLERANCE: f64 = 1e-4;
/// Two triangles overlap when their interiors share more than this depth along every
/// separating axis (in UV units); triangles sharing an edge or a vertex touch at 0.
const OVERLAP_TOLERANCE: f64 = 1e-6;
/// A UV triangle thinner than this (twice its area over its longest edge) is a line.
const DEGENERATE_HEIGHT: f64 = 1e-7;

/// `Ok(uv area)` when `faces` map one-to-one into [0,1]², else the reason it does not.
pub(super) fn one_to_one(uvs: &[[f32; 2]], faces: &[[u32; 3]]) -> Result<f64, String> {
    let mut tris = Vec::with_capacity(faces.len());
    let mut area = 0.0;
    for f in faces {
        let t = f.map(|i| {
            let [u, v] = uvs[i as usize];
            DVec2::new(u as f64, v as f64)
        });
        if let Some(p) = t.iter().find(|p| {
            p.min_element() < -INSIDE_TOLERANCE || p.max_element() > 1.0 + INSIDE_TOLERANCE
        }) {
            return Err(format!(
                "a texture coordinate ({}, {}) leaves the unit square",
                p.x, p.y
            ));
        }
        let twice = (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
        let longest = (0..3)
            .map(|k| (t[(k + 1) % 3] - t[k]).length())
            .fold(0.0, f64::max);
        if twice <= DEGENERATE_HEIGHT * longest.max(DEGENERATE_HEIGHT) {
            return Err("a triangle's texture coordinates lie on a line".into());
        }
        area += 0.5 * twice;
        tris.push(t);
    }
    if area > 1.0 + 1e-3 {
        return Err(format!(
            "the triangles cover UV area {area:.3}, more than the unit square"
        ));
    }
    // Bucket the triangles' bounding boxes on a grid of about one triangle per cell
    // and test each pair sharing a cell.
    let cells = ((tris.len() as f64).sqrt().ceil() as usize).clamp(1, 512);
    let cell_of = |x: f64| ((x * cells as f64).floor().max(0.0) as usize).min(cells - 1);
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); cells * cells];
    for (i, t) in tris.iter().enumerate() {
        let lo = t[0].min(t[1]).min(t[2]);
        let hi = t[0].max(t[1]).max(t[2]);
        for y in cell_of(lo.y)..=cell_of(hi.y) {
            for x in cell_of(lo.x)..=cell_of(hi.x) {
                let bucket = &mut grid[y * cells + x];
                for &j in bucket.iter() {
                    if interiors_overlap(&tris[j as usize], t) {
                        return Err(format!(
                            "the texture coordinates of triangles {j} and {i} overlap"
                        ));
                    }
                }
                bucket.push(i as u32);
            }
        }
    }
    Ok(area)
}

/// Separating-axis test on the six edge normals: the interiors overlap when no axis
/// separates the triangles by more than −`OVERLAP_TOLERANCE`.
fn interiors_overlap(a: &[DVec2; 3], b: &[DVec2; 3]) -> bool {
    let span = |t: &[DVec2; 3], n: DVec2| {
        let d = t.map(|p| p.dot(n));
        (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
    };
    for t in [a, b] {
        for k in 0..3 {
            let e = t[(k + 1) % 3] - t[k];
            let n = e.perp().normalize_or_zero();
            let (alo, ahi) = span(a, n);
            let (blo, bhi) = span(b, n);
            if ahi.min(bhi) - alo.max(blo) <= OVERLAP_TOLERANCE {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];

    #[test]
    fn a_quad_split_in_two_is_one_to_one() {
        let area = one_to_one(&QUAD, &[[0, 1, 2], [0, 2, 3]]).unwrap();
        assert!((area - 1.0).abs() < 1e-9);
        // A part of the square (a sign on an atlas) is one-to-one too.
        let part = QUAD.map(|[u, v]| [0.25 + 0.5 * u, 0.5 * v]);
        let area = one_to_one(&part, &[[0, 1, 2], [0, 2, 3]]).unwrap();
        assert!((area - 0.25).abs() < 1e-9);
    }

    #[test]
    fn overlapping_leaving_or_collapsed_maps_are_not() {
        // Two signs on the same atlas cell.
        let part = QUAD.map(|[u, v]| [0.5 * u, 0.5 * v]);
        let mut uvs = part.to_vec();
        uvs.extend(part.map(|[u, v]| [u + 0.1, v + 0.2]));
        let faces = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        assert!(one_to_one(&uvs, &faces).unwrap_err().contains("overlap"));
        assert!(one_to_one(&uvs, &faces[..2]).is_ok());
        // Folded: both triangles of the quad on the same half.
        assert!(one_to_one(&QUAD, &[[0, 1, 2], [0, 1, 2]]).is_err());
        // Repeated texture.
        let twice = QUAD.map(|[u, v]| [2.0 * u, v]);
        assert!(one_to_one(&twice, &[[0, 1, 2], [0, 2, 3]])
            .unwrap_err()
            .contains("leaves"));
        // Every point of a triangle on one texel.
        let line = [[0.3, 0.3], [0.6, 0.6], [0.9, 0.9]];
        assert!(one_to_one(&line, &[[0, 1, 2]])
            .unwrap_err()
            .contains("line"));
    }

    #[test]
    fn many_small_triangles_sharing_edges_are_one_to_one() {
        // A 40 × 40 grid of quads, two triangles each, over the whole square.
        let n = 40u32;
        let uvs: Vec<[f32; 2]> = (0..=n)
            .flat_map(|y| (0..=n).map(move |x| [x as f32 / n as f32, y as f32 / n as f32]))
            .collect();
        let mut faces = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let i = y * (n + 1) + x;
                faces.push([i, i + 1, i + n + 2]);
                faces.push([i, i + n + 2, i + n + 1]);
            }
        }
        let area = one_to_one(&uvs, &faces).unwrap();
        assert!((area - 1.0).abs() < 1e-6);
        // Move one interior vertex across its neighbours' edge: a fold.
        let mut folded = uvs.clone();
        let v = (20 * (n + 1) + 20) as usize;
        folded[v][0] += 1.5 / n as f32;
        assert!(one_to_one(&folded, &faces).is_err());
    }
}
