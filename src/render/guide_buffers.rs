//! The buffers bound at the guiding bindings: the SD-tree's flat arrays, uploaded after
//! each refit, and the training copies read back after each pass.

use super::gpu_scene::STORAGE;
use crate::gpu;
use crate::guiding::{SdTree, GUIDE_BUFFERS};
use crate::vk::{self, Buffer, Device, MemoryLocation, Staging};
use ash::vk as raw;
use std::sync::{Arc, Mutex};

/// Buffers bound at the guiding bindings (the SD-tree's flat arrays).
///
/// A training run uploads the tree and reads the training copies back after every pass,
/// so the buffers are kept and refilled ([`GuideBuffers::refill`]) while large enough,
/// and the transfers go through staging kept between passes, one submission each way.
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
    uploads: Staging,
    /// Behind a lock so that reading back needs no `&mut` (the bound buffers do not
    /// change).
    readbacks: Mutex<Staging>,
}

/// What a training pass left in the guiding buffers, as it lies in the read-back
/// staging memory (valid while `GuideBuffers::read_pass` runs its closure).
pub struct PassReadback<'a> {
    pub training: &'a [gpu::GuideQuadNode],
    /// Empty unless the pass recorded the selection.
    pub selection: &'a [gpu::GuideSelectionRecord],
    /// Empty unless asked for.
    pub lights: &'a [gpu::GuideLightTrainingSlot],
}

const HEAD_BYTES: usize = std::mem::size_of::<gpu::GuideSelectionHead>();
const RECORD_BYTES: usize = std::mem::size_of::<gpu::GuideSelectionRecord>();

/// A selection head recording nothing.
const NO_SELECTION: gpu::GuideSelectionHead = gpu::GuideSelectionHead {
    count: 0,
    capacity: 0,
    rate: 0.0,
    pad: 0,
};

/// A zero-capacity selection head: the kernel appends nothing.
fn empty_selection(device: &Arc<Device>) -> vk::Result<Buffer> {
    Buffer::zeroed(
        device,
        64,
        raw::BufferUsageFlags::STORAGE_BUFFER,
        "guide selection records (none)",
    )
}

/// Make `buffer` hold at least `len` bytes: kept if it does, else replaced by a new
/// device-local one with a quarter to spare (the tree grows over the training passes).
fn make_room(
    device: &Arc<Device>,
    buffer: &mut Buffer,
    len: usize,
    usage: raw::BufferUsageFlags,
    name: &str,
) -> vk::Result<()> {
    let len = len as u64;
    if buffer.size < len {
        *buffer = Buffer::new(
            device,
            len + len / 4,
            usage | raw::BufferUsageFlags::TRANSFER_DST | raw::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
            name,
        )?;
    }
    Ok(())
}

impl GuideBuffers {
    /// Placeholders for methods that do not guide (a zero header, nothing else).
    pub fn empty(device: &Arc<Device>) -> vk::Result<GuideBuffers> {
        let usage = STORAGE;
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
            uploads: Staging::for_uploads("guide upload staging"),
            readbacks: Mutex::new(Staging::for_readbacks("guide read-back staging")),
        })
    }

    /// Upload an SD-tree's arrays into new buffers.
    pub fn upload(device: &Arc<Device>, tree: &SdTree) -> vk::Result<GuideBuffers> {
        let mut buffers = GuideBuffers::empty(device)?;
        buffers.refill(device, tree)?;
        Ok(buffers)
    }

    /// Upload an SD-tree's arrays, into the buffers already made where they are large
    /// enough, in one submission: the tree is flattened straight into the staging
    /// memory (`SdTree::write_gpu_buffers`), kept between passes, so no array is made
    /// on the host. The selection head is reset to record nothing (a pass that learns
    /// the selection asks with `add_selection_records`).
    pub fn refill(&mut self, device: &Arc<Device>, tree: &SdTree) -> vk::Result<()> {
        let storage = STORAGE;
        let lens = tree.gpu_buffer_lens();
        let buffers: [(&mut Buffer, &str); GUIDE_BUFFERS] = [
            (&mut self.spatial, "guide spatial tree"),
            (&mut self.leaves, "guide leaves"),
            (&mut self.sampling, "guide sampling quadtrees"),
            (&mut self.training, "guide training quadtrees"),
            (&mut self.lights, "guide light tables"),
            (&mut self.light_training, "guide light training"),
        ];
        let mut parts: Vec<(&Buffer, usize)> = Vec::with_capacity(GUIDE_BUFFERS + 1);
        for ((buffer, name), len) in buffers.into_iter().zip(lens) {
            make_room(device, buffer, len, storage, name)?;
            parts.push((buffer, len));
        }
        parts.push((&self.selection, HEAD_BYTES));
        self.uploads.upload_with(device, &parts, |dst| {
            let [spatial, leaves, sampling, training, lights, light_training, head] = dst else {
                unreachable!("seven parts asked for")
            };
            tree.write_gpu_buffers([spatial, leaves, sampling, training, lights, light_training]);
            head.copy_from_slice(bytemuck::bytes_of(&NO_SELECTION));
        })?;
        self.training_nodes = lens[3] / std::mem::size_of::<gpu::GuideQuadNode>();
        self.light_slots = lens[5] / std::mem::size_of::<gpu::GuideLightTrainingSlot>();
        self.selection_capacity = 0;
        Ok(())
    }

    /// Make room for `capacity` selection records, each guided direction sample being
    /// recorded with probability `rate` (a training pass of the learned selection). The
    /// buffer is kept for later passes; only its head is written (records are read up
    /// to its count).
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
        let size = (HEAD_BYTES + RECORD_BYTES * capacity as usize) as u64;
        if self.selection.size < size {
            self.selection = Buffer::new(
                device,
                size,
                raw::BufferUsageFlags::STORAGE_BUFFER
                    | raw::BufferUsageFlags::TRANSFER_DST
                    | raw::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::GpuOnly,
                "guide selection records",
            )?;
        }
        self.uploads
            .upload(device, &[(&self.selection, bytemuck::bytes_of(&head))])?;
        self.selection_capacity = capacity;
        Ok(())
    }

    /// Read back what a training pass recorded and hand it to `take`: the training
    /// quadtrees, the selection records if it made room for them, the light training
    /// tables if `lights`. Two submissions: the selection head (how many records), then
    /// everything else. `take` reads them where the copy put them, in the staging
    /// memory kept between passes (host-cached), so no array is made for them.
    pub fn read_pass<R>(
        &self,
        device: &Arc<Device>,
        lights: bool,
        take: impl FnOnce(PassReadback<'_>) -> R,
    ) -> vk::Result<R> {
        let mut staging = self.readbacks.lock().unwrap();
        let records = if self.selection_capacity > 0 {
            let head: gpu::GuideSelectionHead =
                staging.read(device, &[(&self.selection, HEAD_BYTES as u64)], |b| {
                    bytemuck::pod_read_unaligned(b[0])
                })?;
            head.count.min(self.selection_capacity) as usize
        } else {
            0
        };
        let node = std::mem::size_of::<gpu::GuideQuadNode>();
        let slot = std::mem::size_of::<gpu::GuideLightTrainingSlot>();
        let parts = [
            (&self.training, (self.training_nodes * node) as u64),
            (
                &self.selection,
                (HEAD_BYTES + records * RECORD_BYTES) as u64,
            ),
            (
                &self.light_training,
                (lights as usize * self.light_slots * slot) as u64,
            ),
        ];
        staging.read(device, &parts, |b| {
            take(PassReadback {
                training: bytemuck::cast_slice(b[0]),
                selection: match records {
                    0 => &[],
                    _ => bytemuck::cast_slice(&b[1][HEAD_BYTES..]),
                },
                lights: bytemuck::cast_slice(b[2]),
            })
        })
    }

    /// Read the training quadtrees back after a pass.
    pub fn read_training(&self, device: &Arc<Device>) -> vk::Result<Vec<gpu::GuideQuadNode>> {
        self.read_pass(device, false, |pass| pass.training.to_vec())
    }
}
