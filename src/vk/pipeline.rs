//! Compute pipelines: descriptor-set layout, push constants and specialization constants
//! in one object.

use super::device::Device;
use super::{CheckVk, Result};
use ash::vk;
use std::sync::Arc;

/// What a binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    StorageBuffer,
    AccelStructure,
    /// An array of combined image samplers (partially bound).
    SampledImages,
}

/// One binding of the pipeline's single descriptor set.
#[derive(Clone, Copy, Debug)]
pub struct BindingSpec {
    pub binding: u32,
    pub kind: BindingKind,
    /// Array length (1 for plain bindings).
    pub count: u32,
}

impl BindingSpec {
    pub fn buffer(binding: u32) -> Self {
        BindingSpec {
            binding,
            kind: BindingKind::StorageBuffer,
            count: 1,
        }
    }
    pub fn accel(binding: u32) -> Self {
        BindingSpec {
            binding,
            kind: BindingKind::AccelStructure,
            count: 1,
        }
    }
    pub fn images(binding: u32, count: u32) -> Self {
        BindingSpec {
            binding,
            kind: BindingKind::SampledImages,
            count: count.max(1),
        }
    }

    pub(crate) fn descriptor_type(&self) -> vk::DescriptorType {
        match self.kind {
            BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::AccelStructure => vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
            BindingKind::SampledImages => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        }
    }
}

/// A compute pipeline with one descriptor set.
pub struct ComputePipeline {
    device: Arc<Device>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pub bindings: Vec<BindingSpec>,
    pub push_constant_size: u32,
    pub name: String,
}

impl ComputePipeline {
    /// Create a pipeline from SPIR-V. `specialization[i]` sets `constant_id = i`.
    pub fn new(
        device: &Arc<Device>,
        spirv: &[u32],
        bindings: &[BindingSpec],
        push_constant_size: u32,
        specialization: &[u32],
        name: &str,
    ) -> Result<ComputePipeline> {
        let raw_bindings: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.descriptor_type())
                    .descriptor_count(b.count)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let flags: Vec<vk::DescriptorBindingFlags> = bindings
            .iter()
            .map(|b| match b.kind {
                BindingKind::SampledImages => vk::DescriptorBindingFlags::PARTIALLY_BOUND,
                _ => vk::DescriptorBindingFlags::empty(),
            })
            .collect();
        let mut flags_info =
            vk::DescriptorSetLayoutBindingFlagsCreateInfo::default().binding_flags(&flags);
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .bindings(&raw_bindings)
            .push_next(&mut flags_info);
        // The value owns every handle from its first one on (destroying null handles is
        // a no-op), so an error at any later step frees what was made before it.
        let mut pipeline = ComputePipeline {
            device: device.clone(),
            raw: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            bindings: bindings.to_vec(),
            push_constant_size,
            name: name.to_string(),
        };
        pipeline.set_layout = unsafe { device.raw.create_descriptor_set_layout(&set_info, None) }
            .check("vkCreateDescriptorSetLayout")?;
        device.set_name(pipeline.set_layout, &format!("{name} set layout"));

        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(push_constant_size)];
        let set_layouts = [pipeline.set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_constant_size > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        pipeline.layout = unsafe { device.raw.create_pipeline_layout(&layout_info, None) }
            .check("vkCreatePipelineLayout")?;
        device.set_name(pipeline.layout, &format!("{name} layout"));

        let module_info = vk::ShaderModuleCreateInfo::default().code(spirv);
        let module = unsafe { device.raw.create_shader_module(&module_info, None) }
            .check("vkCreateShaderModule")?;
        let entries: Vec<vk::SpecializationMapEntry> = (0..specialization.len() as u32)
            .map(|i| {
                vk::SpecializationMapEntry::default()
                    .constant_id(i)
                    .offset(i * 4)
                    .size(4)
            })
            .collect();
        let spec_data: &[u8] = bytemuck::cast_slice(specialization);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(spec_data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&spec_info);
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(pipeline.layout)];
        let started = std::time::Instant::now();
        let created = unsafe {
            device
                .raw
                .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
        };
        unsafe { device.raw.destroy_shader_module(module, None) };
        pipeline.raw = match created {
            Ok(p) => p[0],
            Err((_, e)) => {
                return Err(super::VkError::Call {
                    call: "vkCreateComputePipelines",
                    result: e,
                })
            }
        };
        log::debug!(
            "pipeline {name} created in {:.2} s",
            started.elapsed().as_secs_f64()
        );
        device.set_name(pipeline.raw, name);
        Ok(pipeline)
    }

    /// Record a dispatch with `set` bound and `push` as push constants.
    pub fn cmd_dispatch(
        &self,
        cmd: vk::CommandBuffer,
        set: vk::DescriptorSet,
        push: &[u8],
        groups: [u32; 3],
    ) {
        let d = &self.device.raw;
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &[set],
                &[],
            );
            if !push.is_empty() {
                d.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            d.cmd_dispatch(cmd, groups[0], groups[1], groups[2]);
        }
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        unsafe {
            self.device.raw.destroy_pipeline(self.raw, None);
            self.device.raw.destroy_pipeline_layout(self.layout, None);
            self.device
                .raw
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
