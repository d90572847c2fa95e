//! The buffers bound at the guiding bindings: the SD-tree's flat arrays, uploaded after
//! each refit, and the training copies read back after each pass.

use crate::gpu;
use crate::vk::{self, Buffer, Device};
use ash::vk as raw;
use std::sync::Arc;

/// Buffers bound at the guiding bindings (the SD-tree's flat arrays).
pub struct GuideBuffers {
    pub spatial: Buffer,
    pub leaves: Buffer,
    pub sampling: Buffer,
    pub training: Buffer,
    /// Nodes in the training buffer (for the read-back).
    pub training_nodes: usize,
    /// Learned light tables and their training copy.
    pub lights: Buffer,
    pub light_training: Buffer,
    pub light_slots: usize,
}

impl GuideBuffers {
    /// Placeholders for methods that do not guide (a zero header, nothing else).
    pub fn empty(device: &Arc<Device>) -> vk::Result<GuideBuffers> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(GuideBuffers {
            spatial: Buffer::zeroed(device, 64, usage, "guide spatial (unused)")?,
            leaves: Buffer::zeroed(device, 64, usage, "guide leaves (unused)")?,
            sampling: Buffer::zeroed(device, 64, usage, "guide sampling (unused)")?,
            training: Buffer::zeroed(device, 64, usage, "guide training (unused)")?,
            training_nodes: 0,
            lights: Buffer::zeroed(device, 64, usage, "guide lights (unused)")?,
            light_training: Buffer::zeroed(device, 64, usage, "guide light training (unused)")?,
            light_slots: 0,
        })
    }

    /// Upload an SD-tree's arrays.
    pub fn upload(
        device: &Arc<Device>,
        arrays: &crate::guiding::GuideArrays,
    ) -> vk::Result<GuideBuffers> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(GuideBuffers {
            spatial: Buffer::from_slice(
                device,
                &arrays.spatial_buffer(),
                usage,
                "guide spatial tree",
            )?,
            leaves: Buffer::from_slice(device, &arrays.leaves, usage, "guide leaves")?,
            sampling: Buffer::from_slice(
                device,
                &arrays.sampling,
                usage,
                "guide sampling quadtrees",
            )?,
            training: Buffer::from_slice(
                device,
                &arrays.training,
                usage | raw::BufferUsageFlags::TRANSFER_SRC,
                "guide training quadtrees",
            )?,
            training_nodes: arrays.training.len(),
            lights: Buffer::from_slice(device, &arrays.lights, usage, "guide light tables")?,
            light_training: Buffer::from_slice(
                device,
                &arrays.light_training,
                usage | raw::BufferUsageFlags::TRANSFER_SRC,
                "guide light training",
            )?,
            light_slots: arrays.light_training.len(),
        })
    }

    /// Read the light training tables back after a pass.
    pub fn read_light_training(&self) -> vk::Result<Vec<gpu::GuideLightSlot>> {
        self.light_training.read(self.light_slots)
    }

    /// Read the training quadtrees back after a pass.
    pub fn read_training(&self) -> vk::Result<Vec<gpu::GuideQuadNode>> {
        self.training.read(self.training_nodes)
    }
}
