//! Reading the device's results back: the exact film, the AOVs, the per-pixel outliers
//! and the kernel's counters; and putting a film back (resuming a checkpoint).

use super::{Film, RenderError, RenderStats, Renderer, Result};
use crate::gpu;

/// The largest single-sample contribution seen at a pixel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Outlier {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
    pub luminance: f32,
    pub rgb: [f32; 3],
}

impl Renderer {
    /// Samples per pixel in the film.
    pub fn film_spp(&self) -> u64 {
        self.film_spp
    }

    /// Clear the film (and its sample count), the AOVs and the outliers.
    pub fn clear_film(&mut self) -> Result<()> {
        self.film.fill_zero()?;
        self.aov.fill_zero()?;
        self.outliers.fill_zero()?;
        self.clear_reuse_cells()?;
        self.film_spp = 0;
        self.film_offset = 0;
        Ok(())
    }

    /// Mean AOV channels per pixel (`AOV_CHANNELS` floats each), when `settings.aovs`.
    pub fn aovs(&self) -> Result<Vec<f32>> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let mut a: Vec<f32> = self.aov.read(pixels * gpu::AOV_CHANNELS as usize)?;
        let n = self.film_spp.max(1) as f32;
        for px in a.chunks_exact_mut(gpu::AOV_CHANNELS as usize) {
            for (c, v) in px.iter_mut().enumerate() {
                if c != gpu::AOV_SELECTED_LIGHT as usize {
                    *v /= n;
                }
            }
        }
        Ok(a)
    }

    /// The `n` pixels with the largest single-sample contributions, largest first.
    pub fn outliers(&self, n: usize) -> Result<Vec<Outlier>> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let raw: Vec<f32> = self.outliers.read(pixels * gpu::OUTLIER_FLOATS as usize)?;
        let mut list: Vec<Outlier> = raw
            .chunks_exact(gpu::OUTLIER_FLOATS as usize)
            .enumerate()
            .filter(|(_, o)| o[0] > 0.0)
            .map(|(i, o)| Outlier {
                x: (i % self.settings.width as usize) as u32,
                y: (i / self.settings.width as usize) as u32,
                sample: o[1].to_bits(),
                luminance: o[0],
                rgb: [o[2], o[3], o[4]],
            })
            .collect();
        list.sort_by(|a, b| b.luminance.total_cmp(&a.luminance));
        list.truncate(n);
        Ok(list)
    }

    pub(super) fn collect_stats(&mut self, stats: &mut RenderStats) -> Result<()> {
        let counters: Vec<u64> = self.stats.read(gpu::STAT_COUNT as usize)?;
        stats.camera_rays += counters[gpu::STAT_CAMERA_RAYS as usize];
        stats.bounce_rays += counters[gpu::STAT_BOUNCE_RAYS as usize];
        stats.shadow_rays += counters[gpu::STAT_SHADOW_RAYS as usize];
        stats.probe_rays += counters[gpu::STAT_PROBE_RAYS as usize];
        stats.nonfinite_samples += counters[gpu::STAT_NONFINITE_SAMPLES as usize];
        stats.clamped_samples += counters[gpu::STAT_CLAMPED_SAMPLES as usize];
        stats.lanes.add(&super::LaneCounts {
            traversal_steps: counters[gpu::STAT_TRAVERSAL_LANE_STEPS as usize],
            traversal_slots: counters[gpu::STAT_TRAVERSAL_LANE_SLOTS as usize],
            path_steps: counters[gpu::STAT_PATH_LANE_STEPS as usize],
            path_slots: counters[gpu::STAT_PATH_LANE_SLOTS as usize],
        });
        self.stats.fill_zero()?;
        Ok(())
    }

    /// Read the film back.
    pub fn film(&self) -> Result<Film> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let sums: Vec<u64> = self.film.read(pixels * 3)?;
        Ok(Film {
            width: self.settings.width,
            height: self.settings.height,
            spp: self.film_spp,
            sample_offset: self.film_offset,
            sums,
        })
    }

    /// Replace the film's contents (resuming a checkpoint).
    pub fn load_film(&mut self, film: &Film) -> Result<()> {
        if film.width != self.settings.width || film.height != self.settings.height {
            return Err(RenderError::Invalid(
                "film size does not match the render size".into(),
            ));
        }
        self.film.upload(0, bytemuck::cast_slice(&film.sums))?;
        self.film_spp = film.spp;
        self.film_offset = film.sample_offset;
        Ok(())
    }
}
