//! Learned light visibility on the host side: the table's buffer, its snapshot, and the
//! schedule of dispatches that refreshes it (the kernel's side and why it is unbiased:
//! `shaders_glsl/inc/light_visibility.glsl`).
//!
//! The buffer holds two halves of `visibility_slots` entries: kernels read the first (the
//! snapshot) and count into the second (live). Between two dispatches the live half is
//! copied over the snapshot, so a dispatch's RIS target depends only on shadow rays of
//! earlier dispatches, never on its own samples. Dispatches grow as the counts do: the
//! first renders one sample, each later one as many samples as all before it (1, 1, 2,
//! 4, …), so that the early samples already learn from a snapshot and a render of n
//! samples refreshes it about log2(n) times.

use super::{Renderer, Result};
use crate::vk::Buffer;
use ash::vk as raw;

/// Fewest and most entries in each half of the table.
const MIN_SLOTS: u64 = 1 << 14;
const MAX_SLOTS: u64 = 1 << 22;
/// Entries per pixel (before rounding to a power of two): a cell spans several pixels,
/// and each cell holds an entry for every light its vertices tried.
const SLOTS_PER_PIXEL: u64 = 8;

/// Entries in each half of the table for an image of `pixels` pixels: a power of two.
pub(super) fn slot_count(pixels: u64) -> u32 {
    (pixels * SLOTS_PER_PIXEL)
        .next_power_of_two()
        .clamp(MIN_SLOTS, MAX_SLOTS) as u32
}

/// The sample counts of the dispatches that render `spp` samples when `learned`
/// samples were rendered since the table was cleared: each as many as all before it.
pub(super) fn generations(learned: u64, spp: u64) -> Vec<u64> {
    let mut sizes = Vec::new();
    let (mut learned, mut left) = (learned, spp);
    while left > 0 {
        let n = learned.max(1).min(left);
        sizes.push(n);
        learned += n;
        left -= n;
    }
    sizes
}

impl Renderer {
    /// Whether the next dispatches learn light visibility.
    pub(super) fn learns_visibility(&self) -> bool {
        self.settings.light_visibility.learned && self.settings.method.uses_ris()
    }

    /// Make the table when the settings learn visibility and it does not exist yet (a
    /// cleared table; the descriptor set is rebuilt and the frame parameters name it).
    pub(super) fn ensure_visibility_table(&mut self) -> Result<()> {
        if !self.learns_visibility() || self.visibility_slots > 0 {
            return Ok(());
        }
        let slots = slot_count(self.settings.width as u64 * self.settings.height as u64);
        let bytes = 2 * slots as u64 * 4;
        self.visibility = Buffer::zeroed(
            &self.device,
            bytes,
            raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            "light visibility",
        )?;
        log::info!(
            "light visibility: {slots} entries per half ({:.1} MiB), cells of {} pixels, floor {}",
            bytes as f64 / (1u64 << 20) as f64,
            self.settings.light_visibility.cell_pixels,
            self.settings.light_visibility.floor
        );
        self.visibility_slots = slots;
        self.visibility_samples = 0;
        self.set = None;
        self.upload_params()
    }

    /// Forget every count (a new render starts from nothing; run_method calls this, so
    /// that no render's target depends on another render of the same sample indices).
    pub fn clear_light_visibility(&mut self) -> Result<()> {
        if self.visibility_slots > 0 {
            self.visibility.fill_zero()?;
        }
        self.visibility_samples = 0;
        Ok(())
    }

    /// Record the copy of the live half over the snapshot, between barriers.
    pub(super) fn cmd_refresh_visibility(&self, cmd: raw::CommandBuffer) {
        let half = self.visibility_slots as u64 * 4;
        self.device.full_barrier(cmd);
        self.visibility.cmd_copy_within(cmd, half, 0, half);
        self.device.full_barrier(cmd);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slot_counts_are_bounded_powers_of_two() {
        for pixels in [1u64, 80 * 45, 1024 * 576, 1 << 28] {
            let n = slot_count(pixels) as u64;
            assert!(n.is_power_of_two() && (MIN_SLOTS..=MAX_SLOTS).contains(&n));
        }
        assert_eq!(slot_count(80 * 45), 1 << 15);
    }

    #[test]
    fn generations_double_and_cover_the_samples() {
        assert_eq!(generations(0, 1), vec![1]);
        assert_eq!(generations(0, 10), vec![1, 1, 2, 4, 2]);
        assert_eq!(generations(3, 8), vec![3, 5]);
        assert_eq!(generations(64, 16), vec![16]);
        assert!(generations(5, 0).is_empty());
        for (learned, spp) in [(0u64, 1000u64), (7, 300), (1 << 20, 256)] {
            let g = generations(learned, spp);
            assert_eq!(g.iter().sum::<u64>(), spp);
            assert!(g.len() <= 12, "{g:?}");
        }
    }
}
