//! Staging kept between transfers: a host-visible buffer that several uploads (or
//! read-backs) share in one submission, reused while it is large enough.
//!
//! `Buffer::upload` and `Buffer::read_bytes` make a staging buffer per call, which is
//! right for one-off transfers (the scene). Transfers repeated every few hundred
//! milliseconds — the guided methods' tree upload and training read-back after each
//! training pass — went through six fresh staging buffers and six submissions per pass:
//! new host memory to allocate and fault in each time, and a wait per buffer.

use super::buffer::Buffer;
use super::device::Device;
use super::Result;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Offsets of the parts within the staging buffer are multiples of this.
const ALIGN: u64 = 16;

/// A host-visible buffer for uploads (`CpuToGpu`) or read-backs (`GpuToCpu`), grown to
/// the largest transfer asked of it and kept.
pub struct Staging {
    location: MemoryLocation,
    name: &'static str,
    buffer: Option<Buffer>,
}

/// Where each part of a transfer lies in the staging buffer.
fn layout(sizes: impl Iterator<Item = u64>) -> (Vec<u64>, u64) {
    let mut offsets = Vec::new();
    let mut end = 0u64;
    for size in sizes {
        offsets.push(end);
        end += size.div_ceil(ALIGN) * ALIGN;
    }
    (offsets, end)
}

impl Staging {
    /// Staging for uploads to device-local buffers.
    pub fn for_uploads(name: &'static str) -> Staging {
        Staging {
            location: MemoryLocation::CpuToGpu,
            name,
            buffer: None,
        }
    }

    /// Staging for read-backs from device-local buffers.
    pub fn for_readbacks(name: &'static str) -> Staging {
        Staging {
            location: MemoryLocation::GpuToCpu,
            name,
            buffer: None,
        }
    }

    /// The staging buffer, at least `size` bytes (grown by a quarter beyond the request
    /// when it must grow, so that a slowly growing transfer does not reallocate each
    /// time).
    fn at_least(&mut self, device: &Arc<Device>, size: u64) -> Result<&mut Buffer> {
        if self.buffer.as_ref().is_none_or(|b| b.size < size) {
            // Free the old one first: both at once could exceed host-visible memory.
            self.buffer = None;
            let usage = match self.location {
                MemoryLocation::GpuToCpu => vk::BufferUsageFlags::TRANSFER_DST,
                _ => vk::BufferUsageFlags::TRANSFER_SRC,
            };
            let size = size + size / 4;
            self.buffer = Some(Buffer::new(device, size, usage, self.location, self.name)?);
        }
        Ok(self.buffer.as_mut().expect("made above"))
    }

    /// Copy each part's bytes to the start of its buffer, in one submission.
    pub fn upload(&mut self, device: &Arc<Device>, parts: &[(&Buffer, &[u8])]) -> Result<()> {
        let lens: Vec<(&Buffer, usize)> =
            parts.iter().map(|(b, bytes)| (*b, bytes.len())).collect();
        self.upload_with(device, &lens, |dst| {
            for (d, (_, bytes)) in dst.iter_mut().zip(parts) {
                d.copy_from_slice(bytes);
            }
        })
    }

    /// Upload `len` bytes to the start of each buffer, in one submission, written by
    /// `fill` straight into the staging memory. `fill` gets one slice per part, exactly
    /// `len` long, at offsets from the mapping's start that are multiples of 16. The
    /// slices hold whatever the last transfer left there: every byte must be written
    /// (and none should be read: the memory may be write-combined).
    pub fn upload_with(
        &mut self,
        device: &Arc<Device>,
        parts: &[(&Buffer, usize)],
        fill: impl FnOnce(&mut [&mut [u8]]),
    ) -> Result<()> {
        for &(dst, len) in parts {
            assert!(
                len as u64 <= dst.size,
                "upload out of bounds of {}",
                dst.name
            );
        }
        let (offsets, total) = layout(parts.iter().map(|&(_, len)| len as u64));
        if total == 0 {
            return Ok(());
        }
        let staging = self.at_least(device, total)?;
        let mapped = staging.write_mapping();
        let mut slices: Vec<&mut [u8]> = Vec::with_capacity(parts.len());
        let mut rest = &mut mapped[..total as usize];
        let mut at = 0u64;
        for (&(_, len), &offset) in parts.iter().zip(&offsets) {
            let (_, tail) = std::mem::take(&mut rest).split_at_mut((offset - at) as usize);
            let (part, tail) = tail.split_at_mut(len);
            slices.push(part);
            rest = tail;
            at = offset + len as u64;
        }
        fill(&mut slices);
        let src = staging.raw;
        device.submit(|cmd| {
            for (&(dst, len), &offset) in parts.iter().zip(&offsets) {
                if len == 0 {
                    continue;
                }
                let region = [vk::BufferCopy::default()
                    .src_offset(offset)
                    .size(len as u64)];
                unsafe { device.raw.cmd_copy_buffer(cmd, src, dst.raw, &region) };
            }
        })
    }

    /// Read the first `len` bytes of each buffer back, in one submission, and hand them
    /// to `f` (they are the staging buffer's mapping, valid until its next use).
    pub fn read<R>(
        &mut self,
        device: &Arc<Device>,
        parts: &[(&Buffer, u64)],
        f: impl FnOnce(&[&[u8]]) -> R,
    ) -> Result<R> {
        let lens: Vec<u64> = parts.iter().map(|(b, len)| (*len).min(b.size)).collect();
        let (offsets, total) = layout(lens.iter().copied());
        let staging = self.at_least(device, total.max(ALIGN))?;
        let dst = staging.raw;
        device.submit(|cmd| {
            for (((src, _), &len), &offset) in parts.iter().zip(&lens).zip(&offsets) {
                if len == 0 {
                    continue;
                }
                let region = [vk::BufferCopy::default().dst_offset(offset).size(len)];
                unsafe { device.raw.cmd_copy_buffer(cmd, src.raw, dst, &region) };
            }
        })?;
        let mapped = staging.read_mapped();
        let slices: Vec<&[u8]> = offsets
            .iter()
            .zip(&lens)
            .map(|(&o, &len)| &mapped[o as usize..(o + len) as usize])
            .collect();
        Ok(f(&slices))
    }
}

#[cfg(test)]
mod tests {
    use super::layout;

    #[test]
    fn parts_are_aligned_and_do_not_overlap() {
        let (offsets, total) = layout([5u64, 0, 16, 17].into_iter());
        assert_eq!(offsets, vec![0, 16, 16, 32]);
        assert_eq!(total, 64);
    }
}
