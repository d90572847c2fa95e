//! The dispatch loop: ranges of sample indices rendered over bands of the image, each
//! submission sized from measured times to stay near half a second (a GPU watchdog and
//! Ctrl-C both want it short), until a sample count or a deadline; and the debug kernel's
//! one-pixel traces.

use super::{RenderError, RenderStats, Renderer, Result};
use crate::gpu;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Target duration of one submission (a GPU watchdog and Ctrl-C both want it short).
const TARGET_SUBMIT_SECONDS: f64 = 0.5;

impl Renderer {
    /// Push constants of a dispatch over a tile of pixels and a range of sample indices,
    /// with the SD-tree arrays' addresses (a refit may have moved them).
    fn push_constants(
        &self,
        tile_origin: [u32; 2],
        tile_size: [u32; 2],
        sample_begin: u32,
        sample_count: u32,
    ) -> gpu::PushConstants {
        let g = &self.guide;
        let split = super::address_words;
        let mut push = gpu::PushConstants {
            tile_origin,
            tile_size,
            sample_begin,
            sample_count,
            guide_spatial_address: split(g.spatial.address),
            guide_leaves_address: split(g.leaves.address),
            guide_sampling_address: split(g.sampling.address),
            guide_training_address: split(g.training.address),
            guide_lights_address: split(g.lights.address),
            guide_light_training_address: split(g.light_training.address),
            reuse_read: 0,
            reuse_write: 0,
            reuse_generation: 0,
        };
        self.set_reuse_generation(&mut push, self.reuse_generation);
        push
    }

    /// Render samples [begin, begin + count) of pixel (x, y) alone with the debug kernel,
    /// printing a trace of every path vertex of sample `traced` (all when None) through
    /// debug printf; returns the printed lines (the device must have been opened with
    /// debug printf). The film then holds that pixel's samples.
    pub fn trace_pixel(
        &mut self,
        x: u32,
        y: u32,
        begin: u64,
        count: u64,
        traced: Option<u32>,
    ) -> Result<Vec<String>> {
        if x >= self.settings.width || y >= self.settings.height {
            return Err(RenderError::Invalid(format!(
                "pixel ({x}, {y}) is outside the {}×{} image",
                self.settings.width, self.settings.height
            )));
        }
        if !self.device.instance.debug_printf {
            return Err(RenderError::Invalid(
                "per-pixel traces need the validation layer's debug printf (package vulkan-validationlayers)".into(),
            ));
        }
        self.debug_pixel = y * self.settings.width + x;
        self.debug_sample = traced.unwrap_or(gpu::INVALID_INDEX);
        self.clear_film()?;
        self.ensure_reuse_cells()?;
        self.ensure_visibility_table()?;
        self.clear_light_visibility()?;
        self.film_offset = begin;
        self.upload_params()?;
        let mut v = self.variant(false);
        v.debug = true;
        v.lanes = false;
        self.pipeline(v)?;
        let set = self.descriptor_set(v)?;
        crate::vk::take_debug_printf_messages();
        let pipeline = &self.pipelines[&v];
        let push = self.push_constants([x, y], [1, 1], begin as u32, count as u32);
        self.device
            .submit(|cmd| pipeline.cmd_dispatch(cmd, set, bytemuck::bytes_of(&push), [1, 1, 1]))?;
        self.film_spp = count;
        self.debug_pixel = gpu::INVALID_INDEX;
        self.debug_sample = gpu::INVALID_INDEX;
        self.upload_params()?;
        Ok(crate::vk::take_debug_printf_messages())
    }

    /// Render sample indices [begin, begin + count) into the film. `training` records
    /// guiding data (guided methods). Stops early, at a chunk boundary, when `cancel` is
    /// set; returns the number of samples rendered.
    pub fn render_samples(
        &mut self,
        begin: u64,
        count: u64,
        training: bool,
        cancel: &AtomicBool,
        progress: &mut dyn FnMut(u64),
        stats: &mut RenderStats,
    ) -> Result<u64> {
        self.render_until(begin, Some(count), None, training, cancel, progress, stats)
    }

    /// Render from sample index `begin` until `count` samples are done or `deadline`
    /// passes (checked between chunks; every pixel always has the same sample count).
    #[allow(clippy::too_many_arguments)]
    pub fn render_until(
        &mut self,
        begin: u64,
        count: Option<u64>,
        deadline: Option<Instant>,
        training: bool,
        cancel: &AtomicBool,
        progress: &mut dyn FnMut(u64),
        stats: &mut RenderStats,
    ) -> Result<u64> {
        if begin + count.unwrap_or(0) > u32::MAX as u64 {
            return Err(RenderError::Invalid(
                "sample indices beyond 2^32 are not supported".into(),
            ));
        }
        self.ensure_reuse_cells()?;
        self.ensure_visibility_table()?;
        let v = self.variant(training);
        self.pipeline(v)?;
        let set = self.descriptor_set(v)?;
        let reuse = self.reuses_lights();
        let visibility = self.learns_visibility();
        if self.film_spp == 0 && self.film_offset != begin {
            self.film_offset = begin;
            self.upload_params()?;
        }
        let (w, h) = (self.settings.width, self.settings.height);
        let started = Instant::now();
        let mut done = 0u64;
        while count.is_none_or(|c| done < c) {
            if cancel.load(Ordering::SeqCst) || deadline.is_some_and(|d| Instant::now() >= d) {
                break;
            }
            // Size the chunk: bands of rows × samples per dispatch near the target time.
            let (bands, spp) = match self.seconds_per_sample {
                None => (((w as u64 * h as u64) / 65536).max(1) as u32, 1u32),
                Some(t) if t > TARGET_SUBMIT_SECONDS => {
                    ((t / TARGET_SUBMIT_SECONDS).ceil() as u32, 1)
                }
                Some(t) => (
                    1,
                    ((TARGET_SUBMIT_SECONDS / t.max(1e-6)).floor() as u32).clamp(1, 256),
                ),
            };
            let mut spp = spp as u64;
            if let Some(c) = count {
                spp = spp.min(c - done);
            }
            if let (Some(d), Some(t)) = (deadline, self.seconds_per_sample) {
                // Do not overshoot the time budget by more than one sample's worth.
                let left = d.saturating_duration_since(Instant::now()).as_secs_f64();
                spp = spp.min(((left / t).ceil() as u64).max(1));
            }
            let bands = bands.min(h);
            let band_rows = h.div_ceil(bands);
            let chunk_started = Instant::now();
            let pipeline = &self.pipelines[&v];
            // With light reuse each sample is a generation of its own (light_reuse.rs):
            // one dispatch per sample, in one submission with barriers between them.
            // (Four samples per generation cost lavapipe less, ×1.10–1.20 against
            // ×1.14–1.43, but lost the gain: a pixel's samples then reuse the same
            // reservoirs; README, "World-space light reuse".)
            // With learned light visibility the samples go in dispatches that grow as the
            // counts do, the snapshot refreshed between them (light_visibility.rs).
            let sizes: Vec<u64> = if reuse {
                vec![1; spp as usize]
            } else if visibility {
                super::light_visibility::generations(self.visibility_samples, spp)
            } else {
                vec![spp]
            };
            for band in 0..bands {
                let y0 = band * band_rows;
                if y0 >= h {
                    break;
                }
                let rows = band_rows.min(h - y0);
                let mut first = begin + done;
                let pushes: Vec<gpu::PushConstants> = sizes
                    .iter()
                    .enumerate()
                    .map(|(g, &count)| {
                        let mut push =
                            self.push_constants([0, y0], [w, rows], first as u32, count as u32);
                        first += count;
                        self.set_reuse_generation(&mut push, self.reuse_generation + g as u64);
                        push
                    })
                    .collect();
                let device = &self.device;
                // The snapshot is refreshed before every dispatch but a render's first
                // (earlier submissions' counts included).
                let learned = self.visibility_samples > 0 || band > 0;
                let (_, gpu_time) = self.device.submit_timed(
                    |cmd| {
                        for (i, push) in pushes.iter().enumerate() {
                            if visibility && (i > 0 || learned) {
                                self.cmd_refresh_visibility(cmd);
                            } else if i > 0 {
                                device.full_barrier(cmd);
                            }
                            pipeline.cmd_dispatch(
                                cmd,
                                set,
                                bytemuck::bytes_of(push),
                                [w.div_ceil(8), rows.div_ceil(8), 1],
                            );
                        }
                    },
                    true,
                )?;
                stats.gpu_seconds += gpu_time.unwrap_or(0.0);
            }
            let elapsed = chunk_started.elapsed().as_secs_f64();
            self.seconds_per_sample = Some(elapsed / spp as f64);
            self.reuse_generation += sizes.len() as u64;
            if visibility {
                self.visibility_samples += spp;
            }
            done += spp;
            self.film_spp += spp;
            progress(done);
        }
        self.collect_stats(stats)?;
        stats.samples += done;
        stats.wall_seconds += started.elapsed().as_secs_f64();
        Ok(done)
    }
}
