//! Buffers: device memory from gpu-allocator, freed in `Drop`, with helpers to upload
//! and read back through staging buffers.

use super::device::Device;
use super::{CheckVk, Result, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A buffer and its memory.
pub struct Buffer {
    device: Arc<Device>,
    pub raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// Size in bytes (at least 16: Vulkan forbids empty buffers).
    pub size: u64,
    /// Device address, or 0 when the buffer was made without `SHADER_DEVICE_ADDRESS`.
    pub address: u64,
    pub name: String,
}

impl Buffer {
    /// A new buffer of `size` bytes (rounded up to at least 16).
    pub fn new(
        device: &Arc<Device>,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
        name: &str,
    ) -> Result<Buffer> {
        let size = size.max(16);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.raw.create_buffer(&info, None) }.check("vkCreateBuffer")?;
        let requirements = unsafe { device.raw.get_buffer_memory_requirements(raw) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear: true,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|error| {
                unsafe { device.raw.destroy_buffer(raw, None) };
                VkError::Alloc {
                    name: name.to_string(),
                    error,
                }
            })?;
        // From here on the value owns the buffer and its memory: an error drops it, and
        // Drop frees both.
        let mut buffer = Buffer {
            device: device.clone(),
            raw,
            allocation: Some(allocation),
            size,
            address: 0,
            name: name.to_string(),
        };
        let (memory, offset) = {
            let a = buffer.allocation.as_ref().expect("just allocated");
            (unsafe { a.memory() }, a.offset())
        };
        unsafe { device.raw.bind_buffer_memory(raw, memory, offset) }
            .check("vkBindBufferMemory")?;
        if usage.contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS) {
            buffer.address = unsafe {
                device
                    .raw
                    .get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(raw))
            };
        }
        device.set_name(raw, name);
        Ok(buffer)
    }

    /// A device-local storage buffer holding `data` (uploaded through a staging buffer).
    pub fn from_slice<T: bytemuck::Pod>(
        device: &Arc<Device>,
        data: &[T],
        usage: vk::BufferUsageFlags,
        name: &str,
    ) -> Result<Buffer> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buffer = Buffer::new(
            device,
            bytes.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
            name,
        )?;
        buffer.upload(0, bytes)?;
        Ok(buffer)
    }

    /// A storage buffer of `size` zeroed bytes.
    pub fn zeroed(
        device: &Arc<Device>,
        size: u64,
        usage: vk::BufferUsageFlags,
        name: &str,
    ) -> Result<Buffer> {
        let buffer = Buffer::new(
            device,
            size,
            usage | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
            name,
        )?;
        buffer.fill_zero()?;
        Ok(buffer)
    }

    /// Host pointer when the memory is mapped.
    fn mapped(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut().and_then(|a| a.mapped_slice_mut())
    }

    /// Write into the buffer's host mapping (buffers made in `CpuToGpu` memory).
    pub fn write_mapped(&mut self, offset: usize, bytes: &[u8]) {
        self.write_mapping()[offset..offset + bytes.len()].copy_from_slice(bytes);
    }

    /// The buffer's host mapping to write into (buffers made in `CpuToGpu` memory).
    pub fn write_mapping(&mut self) -> &mut [u8] {
        let name = self.name.clone();
        self.mapped()
            .unwrap_or_else(|| panic!("buffer {name} is not host visible"))
    }

    /// Read from the buffer's host mapping (buffers made in `GpuToCpu` memory).
    pub fn read_mapped(&mut self) -> &[u8] {
        let name = self.name.clone();
        self.mapped()
            .unwrap_or_else(|| panic!("buffer {name} is not host visible"))
    }

    /// Copy `bytes` to `offset` through a staging buffer.
    pub fn upload(&self, offset: u64, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        assert!(
            offset + bytes.len() as u64 <= self.size,
            "upload out of bounds of {}",
            self.name
        );
        let mut staging = Buffer::new(
            &self.device,
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
            &format!("{} (staging)", self.name),
        )?;
        staging.write_mapped(0, bytes);
        self.device.submit(|cmd| unsafe {
            let region = [vk::BufferCopy::default()
                .src_offset(0)
                .dst_offset(offset)
                .size(bytes.len() as u64)];
            self.device
                .raw
                .cmd_copy_buffer(cmd, staging.raw, self.raw, &region);
        })
    }

    /// Zero the whole buffer.
    pub fn fill_zero(&self) -> Result<()> {
        self.device.submit(|cmd| unsafe {
            self.device
                .raw
                .cmd_fill_buffer(cmd, self.raw, 0, vk::WHOLE_SIZE, 0);
        })
    }

    /// Record a zero fill into `cmd`.
    pub fn cmd_fill_zero(&self, cmd: vk::CommandBuffer) {
        unsafe {
            self.device
                .raw
                .cmd_fill_buffer(cmd, self.raw, 0, vk::WHOLE_SIZE, 0)
        };
    }

    /// Record a copy of `size` bytes at `from` to `to` in the same buffer (the ranges
    /// must not overlap).
    pub fn cmd_copy_within(&self, cmd: vk::CommandBuffer, from: u64, to: u64, size: u64) {
        let region = [vk::BufferCopy::default()
            .src_offset(from)
            .dst_offset(to)
            .size(size)];
        unsafe {
            self.device
                .raw
                .cmd_copy_buffer(cmd, self.raw, self.raw, &region)
        };
    }

    /// Read the first `len` bytes back (through a staging buffer).
    pub fn read_bytes(&self, len: u64) -> Result<Vec<u8>> {
        self.read_with(len, <[u8]>::to_vec)
    }

    /// Read `count` elements of `T` back, copied once from the staging memory.
    pub fn read<T: bytemuck::Pod>(&self, count: usize) -> Result<Vec<T>> {
        self.read_with(
            (count * std::mem::size_of::<T>()) as u64,
            bytemuck::pod_collect_to_vec,
        )
    }

    /// Copy the first `len` bytes (at most the buffer's size) into a staging buffer and
    /// hand its mapping to `take`.
    fn read_with<R>(&self, len: u64, take: impl FnOnce(&[u8]) -> R) -> Result<R> {
        let len = len.min(self.size);
        let mut staging = Buffer::new(
            &self.device,
            len,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
            &format!("{} (readback)", self.name),
        )?;
        self.device.submit(|cmd| unsafe {
            let region = [vk::BufferCopy::default().size(len)];
            self.device
                .raw
                .cmd_copy_buffer(cmd, self.raw, staging.raw, &region);
        })?;
        Ok(take(&staging.read_mapped()[..len as usize]))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
    }
}
