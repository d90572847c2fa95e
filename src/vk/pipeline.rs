//! Compute pipelines: descriptor-set layout, push constants and specialization constants
//! in one object.

use super::device::Device;
use super::pipeline_cache::{PipelineKey, PipelineObjects};
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
///
/// Its Vulkan objects come from the device's pipeline cache: a second pipeline made on the
/// same device from the same SPIR-V, bindings, push-constant size and specialization
/// constants shares the first one's objects instead of compiling again. On lavapipe a
/// path kernel takes 2–6 s to create even when Mesa's disk cache holds its machine code
/// (the SPIR-V is translated and optimised as NIR before the cache is consulted), and a
/// process that renders several times (the tests, `compare`, the Python package) paid
/// that per render.
pub struct ComputePipeline {
    device: Arc<Device>,
    /// Keeps the shared objects alive; `raw`, `layout` and `set_layout` are its handles.
    _objects: Arc<PipelineObjects>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pub bindings: Vec<BindingSpec>,
    pub push_constant_size: u32,
    pub name: String,
}

impl ComputePipeline {
    /// Create a pipeline from SPIR-V. `specialization[i]` sets `constant_id = i`. The
    /// device's cache serves one made before from the same inputs (see the type's
    /// documentation).
    pub fn new(
        device: &Arc<Device>,
        spirv: &[u32],
        bindings: &[BindingSpec],
        push_constant_size: u32,
        specialization: &[u32],
        name: &str,
    ) -> Result<ComputePipeline> {
        let key = PipelineKey {
            bindings: bindings
                .iter()
                .map(|b| (b.binding, b.descriptor_type(), b.count))
                .collect(),
            push_constant_size,
            specialization: specialization.to_vec(),
            spirv: spirv.to_vec(),
        };
        let objects = device.pipeline_cache().get_or_create(key, || {
            create_objects(
                device,
                spirv,
                bindings,
                push_constant_size,
                specialization,
                name,
            )
        })?;
        Ok(ComputePipeline {
            device: device.clone(),
            raw: objects.raw,
            layout: objects.layout,
            set_layout: objects.set_layout,
            _objects: objects,
            bindings: bindings.to_vec(),
            push_constant_size,
            name: name.to_string(),
        })
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

/// Compile a compute pipeline and make its layouts.
fn create_objects(
    device: &Device,
    spirv: &[u32],
    bindings: &[BindingSpec],
    push_constant_size: u32,
    specialization: &[u32],
    name: &str,
) -> Result<PipelineObjects> {
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
    // The value owns every handle from its first one on (destroying null handles is a
    // no-op), so an error at any later step frees what was made before it.
    let mut objects = PipelineObjects {
        device: device.raw.clone(),
        raw: vk::Pipeline::null(),
        layout: vk::PipelineLayout::null(),
        set_layout: vk::DescriptorSetLayout::null(),
    };
    objects.set_layout = unsafe { device.raw.create_descriptor_set_layout(&set_info, None) }
        .check("vkCreateDescriptorSetLayout")?;
    device.set_name(objects.set_layout, &format!("{name} set layout"));

    let ranges = [vk::PushConstantRange::default()
        .stage_flags(vk::ShaderStageFlags::COMPUTE)
        .size(push_constant_size)];
    let set_layouts = [objects.set_layout];
    let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
    if push_constant_size > 0 {
        layout_info = layout_info.push_constant_ranges(&ranges);
    }
    objects.layout = unsafe { device.raw.create_pipeline_layout(&layout_info, None) }
        .check("vkCreatePipelineLayout")?;
    device.set_name(objects.layout, &format!("{name} layout"));

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
    let flags = if device.executable_statistics.is_some() {
        vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR
    } else {
        vk::PipelineCreateFlags::empty()
    };
    let info = [vk::ComputePipelineCreateInfo::default()
        .flags(flags)
        .stage(stage)
        .layout(objects.layout)];
    let started = std::time::Instant::now();
    let created = unsafe {
        device
            .raw
            .create_compute_pipelines(vk::PipelineCache::null(), &info, None)
    };
    unsafe { device.raw.destroy_shader_module(module, None) };
    objects.raw = match created {
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
    device.set_name(objects.raw, name);
    log_statistics(device, objects.raw, name);
    Ok(objects)
}

/// Log the driver's statistics of a compiled kernel (registers, spills, instruction
/// counts: whatever the driver reports), where it reports them (`--log debug`).
fn log_statistics(device: &Device, pipeline: vk::Pipeline, name: &str) {
    let Some(ext) = &device.executable_statistics else {
        return;
    };
    let info = vk::PipelineInfoKHR::default().pipeline(pipeline);
    let Ok(executables) = (unsafe { ext.get_pipeline_executable_properties(&info) }) else {
        log::debug!("pipeline {name}: the driver reported no executables");
        return;
    };
    for (i, exe) in executables.iter().enumerate() {
        let exe_info = vk::PipelineExecutableInfoKHR::default()
            .pipeline(pipeline)
            .executable_index(i as u32);
        let Ok(stats) = (unsafe { ext.get_pipeline_executable_statistics(&exe_info) }) else {
            continue;
        };
        let values: Vec<String> = stats
            .iter()
            .map(|s| {
                let value = unsafe {
                    match s.format {
                        vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                            (s.value.b32 == vk::TRUE).to_string()
                        }
                        vk::PipelineExecutableStatisticFormatKHR::INT64 => s.value.i64.to_string(),
                        vk::PipelineExecutableStatisticFormatKHR::UINT64 => s.value.u64.to_string(),
                        vk::PipelineExecutableStatisticFormatKHR::FLOAT64 => {
                            s.value.f64.to_string()
                        }
                        _ => "?".into(),
                    }
                };
                format!("{} = {value}", c_text(s.name_as_c_str()))
            })
            .collect();
        log::debug!(
            "pipeline {name}, executable {i} ({}, subgroup {}): {}",
            c_text(exe.name_as_c_str()),
            exe.subgroup_size,
            values.join(", ")
        );
    }
}

fn c_text(s: std::result::Result<&std::ffi::CStr, std::ffi::FromBytesUntilNulError>) -> String {
    s.map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
