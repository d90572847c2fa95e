//! A descriptor set for one compute pipeline, with its own pool.

use super::accel::AccelStructure;
use super::buffer::Buffer;
use super::device::Device;
use super::pipeline::ComputePipeline;
use super::{CheckVk, Result};
use ash::vk;
use std::sync::Arc;

/// One descriptor set matching a pipeline's layout.
pub struct DescriptorSet {
    device: Arc<Device>,
    pool: vk::DescriptorPool,
    pub raw: vk::DescriptorSet,
}

impl DescriptorSet {
    pub fn new(device: &Arc<Device>, pipeline: &ComputePipeline) -> Result<DescriptorSet> {
        let sizes: Vec<vk::DescriptorPoolSize> = pipeline
            .bindings
            .iter()
            .map(|b| {
                vk::DescriptorPoolSize::default()
                    .ty(b.descriptor_type())
                    .descriptor_count(b.count)
            })
            .collect();
        let pool_info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        let pool = unsafe { device.raw.create_descriptor_pool(&pool_info, None) }
            .check("vkCreateDescriptorPool")?;
        let layouts = [pipeline.set_layout];
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(&layouts);
        let raw = match unsafe { device.raw.allocate_descriptor_sets(&alloc) } {
            Ok(s) => s[0],
            Err(e) => {
                unsafe { device.raw.destroy_descriptor_pool(pool, None) };
                return Err(super::VkError::Call {
                    call: "vkAllocateDescriptorSets",
                    result: e,
                });
            }
        };
        device.set_name(raw, &format!("{} set", pipeline.name));
        Ok(DescriptorSet {
            device: device.clone(),
            pool,
            raw,
        })
    }

    /// Bind a storage buffer.
    pub fn write_buffer(&self, binding: u32, buffer: &Buffer) {
        let info = [vk::DescriptorBufferInfo::default()
            .buffer(buffer.raw)
            .range(vk::WHOLE_SIZE)];
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .buffer_info(&info)];
        unsafe { self.device.raw.update_descriptor_sets(&write, &[]) };
    }

    /// Bind an acceleration structure.
    pub fn write_accel(&self, binding: u32, accel: &AccelStructure) {
        let structures = [accel.raw];
        let mut as_info = vk::WriteDescriptorSetAccelerationStructureKHR::default()
            .acceleration_structures(&structures);
        let mut write = vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .push_next(&mut as_info);
        write.descriptor_count = 1;
        unsafe { self.device.raw.update_descriptor_sets(&[write], &[]) };
    }

    /// Bind combined image samplers at array elements 0..n.
    pub fn write_images(&self, binding: u32, images: &[(vk::ImageView, vk::Sampler)]) {
        if images.is_empty() {
            return;
        }
        let infos: Vec<vk::DescriptorImageInfo> = images
            .iter()
            .map(|&(view, sampler)| {
                vk::DescriptorImageInfo::default()
                    .image_view(view)
                    .sampler(sampler)
                    .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
            })
            .collect();
        let write = [vk::WriteDescriptorSet::default()
            .dst_set(self.raw)
            .dst_binding(binding)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .image_info(&infos)];
        unsafe { self.device.raw.update_descriptor_sets(&write, &[]) };
    }
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_descriptor_pool(self.pool, None) };
    }
}
