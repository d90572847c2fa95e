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
    /// Records of the learned selection probability (GuideSelectionHead, then records);
    /// a head with capacity 0 unless `add_selection_records` made room.
    pub selection: Buffer,
    pub selection_capacity: u32,
}

/// A zero-capacity selection head: the kernel appends nothing.
fn empty_selection(device: &Arc<Device>) -> vk::Result<Buffer> {
    Buffer::zeroed(
        device,
        64,
        raw::BufferUsageFlags::STORAGE_BUFFER,
        "guide selection records (none)",
    )
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
            selection: empty_selection(device)?,
            selection_capacity: 0,
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
            lights: Buffer::from_slice(
                device,
                &arrays.light_buffer(),
                usage,
                "guide light tables",
            )?,
            light_training: Buffer::from_slice(
                device,
                &arrays.light_training,
                usage | raw::BufferUsageFlags::TRANSFER_SRC,
                "guide light training",
            )?,
            light_slots: arrays.light_training.len(),
            selection: empty_selection(device)?,
            selection_capacity: 0,
        })
    }

    /// Make room for `capacity` selection records, each guided direction sample being
    /// recorded with probability `rate` (a training pass of the learned selection).
    pub fn add_selection_records(
        &mut self,
        device: &Arc<Device>,
        capacity: u32,
        rate: f32,
    ) -> vk::Result<()> {
        let head = gpu::GuideSelectionHead {
            count: 0,
            capacity,
            rate,
            pad: 0,
        };
        let record = std::mem::size_of::<gpu::GuideSelectionRecord>();
        // Only the head needs contents: records are read up to its count.
        self.selection = Buffer::zeroed(
            device,
            (std::mem::size_of_val(&head) + record * capacity as usize) as u64,
            raw::BufferUsageFlags::STORAGE_BUFFER,
            "guide selection records",
        )?;
        self.selection.upload(0, bytemuck::bytes_of(&head))?;
        self.selection_capacity = capacity;
        Ok(())
    }

    /// Read the selection records a pass appended (at most the capacity).
    pub fn read_selection(&self) -> vk::Result<Vec<gpu::GuideSelectionRecord>> {
        if self.selection_capacity == 0 {
            return Ok(Vec::new());
        }
        let head: gpu::GuideSelectionHead = self.selection.read(1)?[0];
        let n = head.count.min(self.selection_capacity) as usize;
        let head_bytes = std::mem::size_of::<gpu::GuideSelectionHead>();
        let record = std::mem::size_of::<gpu::GuideSelectionRecord>();
        let bytes = self
            .selection
            .read_bytes((head_bytes + n * record) as u64)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes[head_bytes..]))
    }

    /// Read the light training tables back after a pass.
    pub fn read_light_training(&self) -> vk::Result<Vec<gpu::GuideLightTrainingSlot>> {
        self.light_training.read(self.light_slots)
    }

    /// Read the training quadtrees back after a pass.
    pub fn read_training(&self) -> vk::Result<Vec<gpu::GuideQuadNode>> {
        self.training.read(self.training_nodes)
    }
}
