//! Spatially coherent orders for triangles and instances.
//!
//! Some acceleration-structure builders take the primitives in the order the application
//! submits them and split the list at its index median without sorting (lavapipe's does,
//! for triangles and TLAS instances alike). The tree they build is then only as good as
//! that order: glTF exporters emit triangles in modelling order and our loader emits
//! instances in node-traversal order, both far from spatial. Putting the primitives in
//! the leaf order of an object-median kd-tree (recursively split at the median centroid
//! along the longest axis of the centroids' bounds) makes an index-median split a
//! spatial split at every level. Builders that sort for themselves (hardware drivers)
//! are unaffected. Reordering changes which triangle has which index, never the scene:
//! everything downstream (light table, instance buffer) is built from the new order.

use glam::Vec3;

/// A permutation of `0..centroids.len()` in object-median kd-tree leaf order.
pub fn kd_order(centroids: &[Vec3]) -> Vec<u32> {
    let mut order: Vec<u32> = (0..centroids.len() as u32).collect();
    // An explicit stack of ranges: deep recursion on millions of triangles is avoided.
    let mut stack: Vec<std::ops::Range<usize>> = Vec::new();
    stack.push(0..order.len());
    while let Some(range) = stack.pop() {
        if range.len() <= 2 {
            continue;
        }
        let items = &mut order[range.clone()];
        let (lo, hi) = items.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &i| (lo.min(centroids[i as usize]), hi.max(centroids[i as usize])),
        );
        let extent = hi - lo;
        // (NaN extents compare false too.)
        if extent.max_element().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            continue; // all centroids coincide (or are not finite): nothing to split
        }
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        // Ties broken by index, so the order is deterministic.
        items.select_nth_unstable_by(mid, |&a, &b| {
            centroids[a as usize][axis]
                .total_cmp(&centroids[b as usize][axis])
                .then(a.cmp(&b))
        });
        stack.push(range.start..range.start + mid);
        stack.push(range.start + mid..range.end);
    }
    order
}

/// Reorder the triangles of one primitive (`indices`: 3 per triangle, `positions` the
/// vertices they refer to) into kd order, in place.
pub fn reorder_triangles(positions: &[Vec3], indices: &mut [u32]) {
    let centroids: Vec<Vec3> = indices
        .chunks_exact(3)
        .map(|t| {
            (positions[t[0] as usize] + positions[t[1] as usize] + positions[t[2] as usize]) / 3.0
        })
        .collect();
    let order = kd_order(&centroids);
    let old = indices.to_vec();
    for (new, &from) in order.iter().enumerate() {
        let from = from as usize * 3;
        indices[new * 3..new * 3 + 3].copy_from_slice(&old[from..from + 3]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kd_order_is_a_permutation_that_halves_space() {
        // A shuffled 8×8 grid: after ordering, each half of the list covers one half of
        // the grid along x, each quarter one quadrant.
        let mut points = Vec::new();
        for k in 0..64u32 {
            let s = (k * 37) % 64; // a fixed shuffle
            points.push(Vec3::new((s % 8) as f32, (s / 8) as f32, 0.0));
        }
        let order = kd_order(&points);
        let mut seen = order.clone();
        seen.sort_unstable();
        assert_eq!(seen, (0..64).collect::<Vec<_>>());
        let xs: Vec<f32> = order.iter().map(|&i| points[i as usize].x).collect();
        assert!(xs[..32].iter().all(|&x| x < 4.0) && xs[32..].iter().all(|&x| x >= 4.0));
        for q in 0..4 {
            let ys: Vec<f32> = order[q * 16..q * 16 + 16]
                .iter()
                .map(|&i| points[i as usize].y)
                .collect();
            let low = ys.iter().all(|&y| y < 4.0);
            let high = ys.iter().all(|&y| y >= 4.0);
            assert!(low || high, "quarter {q} straddles y = 4: {ys:?}");
        }
        assert_eq!(kd_order(&points), order, "deterministic");
    }

    #[test]
    fn degenerate_inputs() {
        assert!(kd_order(&[]).is_empty());
        assert_eq!(kd_order(&[Vec3::ONE; 5]), vec![0, 1, 2, 3, 4]);
        let nan = Vec3::splat(f32::NAN);
        let mut o = kd_order(&[nan, Vec3::ZERO, nan, Vec3::X]);
        o.sort_unstable();
        assert_eq!(o, vec![0, 1, 2, 3]);
    }

    #[test]
    fn triangles_keep_their_vertices() {
        let positions: Vec<Vec3> = (0..12).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        let mut indices: Vec<u32> = vec![9, 10, 11, 0, 1, 2, 6, 7, 8, 3, 4, 5];
        reorder_triangles(&positions, &mut indices);
        assert_eq!(indices, vec![0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]);
    }
}
