//! The film: exact 64-bit fixed-point sums per pixel and channel over `spp` samples.

use crate::gpu::FILM_FIXED_SCALE;

/// Accumulated samples of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel in the sums.
    pub spp: u64,
    /// First sample index.
    pub sample_offset: u64,
    /// Fixed-point sums, RGB per pixel, row-major from the top-left.
    pub sums: Vec<u64>,
}

impl Film {
    /// Mean linear RGB per pixel.
    pub fn mean(&self) -> Vec<f32> {
        let scale = 1.0 / (FILM_FIXED_SCALE as f64 * self.spp.max(1) as f64);
        self.sums
            .iter()
            .map(|&s| (s as f64 * scale) as f32)
            .collect()
    }

    /// Add another film of disjoint samples (exact).
    pub fn merge(&mut self, other: &Film) {
        assert_eq!((self.width, self.height), (other.width, other.height));
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            *a += *b;
        }
        self.sample_offset = self.sample_offset.min(other.sample_offset);
        self.spp += other.spp;
    }
}
