//! World-space light reuse on the host side: the hash grid's buffer and which of its two
//! halves a dispatch reads and writes (the kernel's side and why it is unbiased:
//! `shaders_glsl/inc/light_reuse.glsl`).
//!
//! A dispatch reads the half earlier dispatches wrote and writes the other, so no path
//! sees a reservoir that depends on its own random numbers. Each range of samples the
//! dispatch loop submits is one generation; with reuse on, the loop submits one sample
//! per dispatch (the dispatches of a range in one submission, with barriers between
//! them), so that a reservoir found in one sample is offered to the next.

use super::{Renderer, Result};
use crate::gpu;
use crate::vk::Buffer;
use ash::vk as raw;

/// Fewest and most cells in each half of the grid.
const MIN_CELLS: u64 = 1 << 12;
const MAX_CELLS: u64 = 1 << 20;
/// Cells per pixel (before rounding to a power of two): a cell spans several pixels'
/// footprint and paths reach other surfaces after the first, so collisions stay rare.
const CELLS_PER_PIXEL: u64 = 4;

/// Cells in each half of the grid for an image of `pixels` pixels: a power of two.
pub(super) fn cell_count(pixels: u64) -> u32 {
    (pixels * CELLS_PER_PIXEL)
        .next_power_of_two()
        .clamp(MIN_CELLS, MAX_CELLS) as u32
}

/// The high word of generation `generation`'s writers' tickets (ReuseCell.ticket_hi):
/// above every earlier generation's and above an empty cell's 0. Saturates, which would
/// take 2³² samples in one render.
fn ticket_generation(generation: u64) -> u32 {
    (generation + 1).min(u32::MAX as u64) as u32
}

impl Renderer {
    /// Whether the next dispatches reuse light samples.
    pub(super) fn reuses_lights(&self) -> bool {
        self.settings.light_reuse.world && self.settings.method.uses_ris()
    }

    /// Make the grid when the settings reuse and it does not exist yet (a cleared grid;
    /// the descriptor set is rebuilt and the frame parameters name its size).
    pub(super) fn ensure_reuse_cells(&mut self) -> Result<()> {
        if !self.reuses_lights() || self.reuse_cell_count > 0 {
            return Ok(());
        }
        let count = cell_count(self.settings.width as u64 * self.settings.height as u64);
        let bytes = 2 * count as u64 * std::mem::size_of::<gpu::ReuseCell>() as u64;
        self.reuse_cells = Buffer::zeroed(
            &self.device,
            bytes,
            raw::BufferUsageFlags::STORAGE_BUFFER,
            "light reuse cells",
        )?;
        log::info!(
            "light reuse: {count} cells per half ({:.1} MiB), cells of {} pixels, confidence cap {}",
            bytes as f64 / (1u64 << 20) as f64,
            self.settings.light_reuse.cell_pixels,
            self.settings.light_reuse.confidence_cap
        );
        self.reuse_cell_count = count;
        self.reuse_generation = 0;
        self.set = None;
        self.upload_params()
    }

    /// Empty every cell (a new render starts from nothing).
    pub(super) fn clear_reuse_cells(&mut self) -> Result<()> {
        if self.reuse_cell_count > 0 {
            self.reuse_cells.fill_zero()?;
        }
        self.reuse_generation = 0;
        Ok(())
    }

    /// Set `push`'s light reuse words for generation `generation`: the first cells of
    /// the halves it reads and writes, and its writers' tickets' high word.
    pub(super) fn set_reuse_generation(&self, push: &mut gpu::PushConstants, generation: u64) {
        let n = self.reuse_cell_count;
        (push.reuse_read, push.reuse_write) = if generation % 2 == 0 { (n, 0) } else { (0, n) };
        push.reuse_generation = ticket_generation(generation);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_counts_are_bounded_powers_of_two() {
        for pixels in [1u64, 80 * 45, 1024 * 576, 1 << 28] {
            let n = cell_count(pixels) as u64;
            assert!(n.is_power_of_two() && (MIN_CELLS..=MAX_CELLS).contains(&n));
        }
        assert_eq!(cell_count(80 * 45), 1 << 14);
    }

    /// The kernel reads a cell's ticket as the 64-bit word at index 8·cell + 7.
    #[test]
    fn the_ticket_is_the_last_64_bit_word_of_a_cell() {
        assert_eq!(std::mem::size_of::<gpu::ReuseCell>(), 64);
        assert_eq!(std::mem::offset_of!(gpu::ReuseCell, ticket_lo), 56);
        assert_eq!(std::mem::offset_of!(gpu::ReuseCell, ticket_hi), 60);
    }
}
