//! The binary files a Mitsuba export writes besides the XML: triangle meshes as binary
//! little-endian PLY (positions, optional vertex normals, texture coordinates and
//! colours, one `vertex_indices` list per face) and linear float images as PFM (used
//! where texel values must reach Mitsuba exactly, unquantised and unclamped).

use std::io::Write;

/// A world-space triangle mesh ready to be written.
#[derive(Default)]
pub struct PlyMesh {
    pub positions: Vec<[f32; 3]>,
    /// Empty, or one unit normal per vertex.
    pub normals: Vec<[f32; 3]>,
    /// Empty, or one texture coordinate per vertex.
    pub uvs: Vec<[f32; 2]>,
    /// Empty, or one linear RGB colour per vertex (Mitsuba's `vertex_color` attribute).
    pub colors: Vec<[f32; 3]>,
    pub faces: Vec<[u32; 3]>,
}

impl PlyMesh {
    /// The PLY file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let n = self.positions.len();
        let with_normals = self.normals.len() == n && n > 0;
        let with_uvs = self.uvs.len() == n && n > 0;
        let with_colors = self.colors.len() == n && n > 0;
        let mut header = String::from("ply\nformat binary_little_endian 1.0\n");
        header.push_str("comment written by lanterna scene export-mitsuba\n");
        header.push_str(&format!("element vertex {n}\n"));
        for p in ["x", "y", "z"] {
            header.push_str(&format!("property float {p}\n"));
        }
        if with_normals {
            for p in ["nx", "ny", "nz"] {
                header.push_str(&format!("property float {p}\n"));
            }
        }
        if with_uvs {
            header.push_str("property float u\nproperty float v\n");
        }
        if with_colors {
            header.push_str("property float r\nproperty float g\nproperty float b\n");
        }
        header.push_str(&format!("element face {}\n", self.faces.len()));
        header.push_str("property list uchar int vertex_indices\nend_header\n");

        let per_vertex =
            4 * (3 + 3 * with_normals as usize + 2 * with_uvs as usize + 3 * with_colors as usize);
        let mut out = Vec::with_capacity(header.len() + n * per_vertex + self.faces.len() * 13);
        out.extend_from_slice(header.as_bytes());
        for i in 0..n {
            let mut put = |v: f32| out.extend_from_slice(&v.to_le_bytes());
            self.positions[i].iter().for_each(|&v| put(v));
            if with_normals {
                self.normals[i].iter().for_each(|&v| put(v));
            }
            if with_uvs {
                self.uvs[i].iter().for_each(|&v| put(v));
            }
            if with_colors {
                self.colors[i].iter().for_each(|&v| put(v));
            }
        }
        for f in &self.faces {
            out.push(3u8);
            for &i in f {
                out.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
        out
    }
}

/// A colour PFM (`PF`, little-endian) of `rgb` given top row first; PFM stores rows
/// bottom to top.
pub fn pfm_bytes(width: u32, height: u32, rgb: &[[f32; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(32 + rgb.len() * 12);
    let _ = write!(out, "PF\n{width} {height}\n-1.0\n");
    for y in (0..height as usize).rev() {
        for px in &rgb[y * width as usize..(y + 1) * width as usize] {
            for c in px {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_layout() {
        let m = PlyMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            normals: vec![],
            uvs: vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            colors: vec![],
            faces: vec![[0, 1, 2]],
        };
        let b = m.to_bytes();
        let text = String::from_utf8_lossy(&b);
        let end = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert!(text[..end].contains("element vertex 3\n"));
        assert!(!text[..end].contains("nx"));
        assert_eq!(b.len() - end, 3 * 5 * 4 + 13);
        // The last face's indices.
        assert_eq!(&b[b.len() - 12..b.len() - 8], &0i32.to_le_bytes());
        assert_eq!(&b[b.len() - 4..], &2i32.to_le_bytes());
        // Colours follow the texture coordinates as float r, g, b.
        let coloured = PlyMesh {
            colors: vec![[0.25, 0.5, 1.0]; 3],
            ..m
        };
        let b = coloured.to_bytes();
        let text = String::from_utf8_lossy(&b);
        let end = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert!(text[..end]
            .contains("property float v\nproperty float r\nproperty float g\nproperty float b\n"));
        assert_eq!(b.len() - end, 3 * 8 * 4 + 13);
        assert_eq!(&b[end + 5 * 4..end + 6 * 4], &0.25f32.to_le_bytes());
    }

    #[test]
    fn pfm_rows_bottom_up() {
        let b = pfm_bytes(1, 2, &[[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]]);
        let data = &b[b.len() - 24..];
        assert_eq!(&data[..4], &2.0f32.to_le_bytes());
        assert_eq!(&data[12..16], &1.0f32.to_le_bytes());
    }
}
