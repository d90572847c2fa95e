//! The logical device: creation with the features the kernels use, the queue, the
//! allocator and one-shot submissions. What each physical device offers, and the choice
//! among them, is in `device_info.rs`.
//!
//! lanterna uses ray queries in compute shaders and acceleration structures where the
//! device has them (otherwise the kernels traverse a BVH of their own, see
//! `render::traversal`), and needs buffer device addresses, scalar block layout, bindless sampled images, 64-bit
//! integers (exact film accumulation) and, for the guided methods, float atomics. The
//! chooser prefers a hardware GPU that has all of them and falls back to lavapipe (Mesa's
//! CPU implementation); `--device` picks one by index or name substring.

use super::device_info::{describe, list_devices, DeviceInfo, DeviceSelector};
use super::instance::Instance;
use super::pipeline_cache::PipelineCache;
use super::{CheckVk, Result, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

/// The logical device with its queue, allocator and extension loaders.
pub struct Device {
    pub instance: Arc<Instance>,
    pub physical: vk::PhysicalDevice,
    pub info: DeviceInfo,
    pub raw: ash::Device,
    pub queue_family: u32,
    queue: Mutex<vk::Queue>,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    pub accel: ash::khr::acceleration_structure::Device,
    /// The driver's statistics of compiled kernels, where it reports them and `--log
    /// debug` asks for them (see `pipeline.rs`).
    pub executable_statistics: Option<ash::khr::pipeline_executable_properties::Device>,
    debug_utils: Option<ash::ext::debug_utils::Device>,
    command_pool: Mutex<vk::CommandPool>,
    /// Compute pipelines by what they are made from (see [`super::ComputePipeline`]).
    pipelines: PipelineCache,
}

impl Device {
    /// List the devices of a fresh instance.
    pub fn list(instance: &Instance) -> Result<Vec<DeviceInfo>> {
        list_devices(instance)
    }

    /// Choose a device and create it.
    pub fn new(instance: Arc<Instance>, selector: &DeviceSelector) -> Result<Arc<Device>> {
        let pds = unsafe { instance.raw.enumerate_physical_devices() }
            .check("vkEnumeratePhysicalDevices")?;
        if pds.is_empty() {
            return Err(VkError::NoDevice);
        }
        let infos: Vec<DeviceInfo> = pds
            .iter()
            .enumerate()
            .map(|(i, &pd)| describe(&instance, i, pd))
            .collect::<Result<_>>()?;
        let chosen = match selector {
            DeviceSelector::Auto => {
                let best = infos
                    .iter()
                    .filter(|d| d.features.missing().is_empty())
                    .max_by_key(|d| (d.preference(), std::cmp::Reverse(d.index)));
                match best {
                    Some(d) => d.index,
                    None => {
                        let why = infos
                            .iter()
                            .map(|d| format!("{} ({})", d.name, d.features.missing().join(", ")))
                            .collect::<Vec<_>>()
                            .join("; ");
                        return Err(VkError::NoCapableDevice(why));
                    }
                }
            }
            DeviceSelector::Index(i) => infos
                .get(*i)
                .map(|d| d.index)
                .ok_or_else(|| VkError::NoMatchingDevice(i.to_string()))?,
            DeviceSelector::Name(n) => infos
                .iter()
                .find(|d| d.name.to_lowercase().contains(&n.to_lowercase()))
                .map(|d| d.index)
                .ok_or_else(|| VkError::NoMatchingDevice(n.clone()))?,
        };
        let info = infos[chosen].clone();
        let missing = info.features.missing();
        if !missing.is_empty() {
            return Err(VkError::Unsupported {
                name: info.name.clone(),
                missing: missing.join(", "),
            });
        }
        Self::create(instance, pds[chosen], info)
    }

    fn create(
        instance: Arc<Instance>,
        physical: vk::PhysicalDevice,
        info: DeviceInfo,
    ) -> Result<Arc<Device>> {
        let raw_instance = &instance.raw;
        let families =
            unsafe { raw_instance.get_physical_device_queue_family_properties(physical) };
        let queue_family = families
            .iter()
            .position(|q| {
                q.queue_flags
                    .contains(vk::QueueFlags::COMPUTE | vk::QueueFlags::GRAPHICS)
            })
            .or_else(|| {
                families
                    .iter()
                    .position(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE))
            })
            .ok_or_else(|| VkError::Other(format!("{} has no compute queue", info.name)))?
            as u32;

        let f = &info.features;
        let mut ext_names = Vec::new();
        if f.ray_queries() {
            ext_names.extend([
                ash::khr::acceleration_structure::NAME.as_ptr(),
                ash::khr::ray_query::NAME.as_ptr(),
                ash::khr::deferred_host_operations::NAME.as_ptr(),
            ]);
        }
        if f.float_atomics {
            ext_names.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        if f.shader_clock {
            ext_names.push(ash::khr::shader_clock::NAME.as_ptr());
        }
        if f.non_semantic_info {
            ext_names.push(ash::khr::shader_non_semantic_info::NAME.as_ptr());
        }
        // Capturing statistics may cost compile time, so only when they will be logged.
        let statistics = f.executable_statistics && log::log_enabled!(log::Level::Debug);
        if statistics {
            ext_names.push(ash::khr::pipeline_executable_properties::NAME.as_ptr());
        }

        let base = vk::PhysicalDeviceFeatures::default().shader_int64(true);
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
            .buffer_device_address(true)
            .scalar_block_layout(true)
            .shader_buffer_int64_atomics(true)
            .runtime_descriptor_array(true)
            .descriptor_binding_partially_bound(true)
            .shader_sampled_image_array_non_uniform_indexing(true)
            .host_query_reset(true);
        let mut f_as = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
            .acceleration_structure(true);
        let mut f_rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
        let mut f_af = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default()
            .shader_buffer_float32_atomic_add(true);
        let mut f_clock =
            vk::PhysicalDeviceShaderClockFeaturesKHR::default().shader_subgroup_clock(true);
        let mut f_exec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
            .pipeline_executable_info(true);
        let mut features2 = vk::PhysicalDeviceFeatures2::default()
            .features(base)
            .push_next(&mut f12);
        if f.ray_queries() {
            features2 = features2.push_next(&mut f_as).push_next(&mut f_rq);
        }
        if f.float_atomics {
            features2 = features2.push_next(&mut f_af);
        }
        if f.shader_clock {
            features2 = features2.push_next(&mut f_clock);
        }
        if statistics {
            features2 = features2.push_next(&mut f_exec);
        }
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let create_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&ext_names)
            .push_next(&mut features2);
        let raw = unsafe { raw_instance.create_device(physical, &create_info, None) }
            .check("vkCreateDevice")?;
        let queue = unsafe { raw.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: raw_instance.clone(),
            device: raw.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })
        .map_err(|error| VkError::Alloc {
            name: "allocator".into(),
            error,
        })?;
        let accel = ash::khr::acceleration_structure::Device::new(raw_instance, &raw);
        let executable_statistics = statistics
            .then(|| ash::khr::pipeline_executable_properties::Device::new(raw_instance, &raw));
        let debug_utils = instance
            .has_debug_utils()
            .then(|| ash::ext::debug_utils::Device::new(raw_instance, &raw));
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(
                vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER
                    | vk::CommandPoolCreateFlags::TRANSIENT,
            );
        let command_pool =
            unsafe { raw.create_command_pool(&pool_info, None) }.check("vkCreateCommandPool")?;
        log::info!(
            "device: {} ({}, {})",
            info.name,
            info.kind_name(),
            info.driver
        );
        Ok(Arc::new(Device {
            instance,
            physical,
            info,
            raw,
            queue_family,
            queue: Mutex::new(queue),
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            accel,
            executable_statistics,
            debug_utils,
            command_pool: Mutex::new(command_pool),
            pipelines: PipelineCache::default(),
        }))
    }

    /// Give a Vulkan object a name that validation messages and debuggers show.
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.debug_utils {
            let Ok(cname) = std::ffi::CString::new(name) else {
                return;
            };
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&cname);
            unsafe {
                let _ = du.set_debug_utils_object_name(&info);
            }
        }
    }

    pub(crate) fn allocator(&self) -> std::sync::MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap()
    }

    /// Record commands with `record`, submit them, and wait for completion.
    ///
    /// Every submission is bracketed by two barriers, so that callers need none between
    /// submissions: at its start, all earlier device writes (earlier submissions: uploads,
    /// acceleration-structure builds, dispatches) are made visible to every command; at its
    /// end, its writes are made visible to host reads of mapped memory, which the fence
    /// wait alone does not do.
    pub fn submit<R>(&self, record: impl FnOnce(vk::CommandBuffer) -> R) -> Result<R> {
        Ok(self.submit_timed(record, false)?.0)
    }

    /// Like [`submit`](Self::submit), and also measure the GPU time of the commands with
    /// timestamp queries when `timed` (None when the device has no timestamps).
    pub fn submit_timed<R>(
        &self,
        record: impl FnOnce(vk::CommandBuffer) -> R,
        timed: bool,
    ) -> Result<(R, Option<f64>)> {
        let timed = timed && self.info.features.timestamps;
        let pool = self.command_pool.lock().unwrap();
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { self.raw.allocate_command_buffers(&alloc_info) }
            .check("vkAllocateCommandBuffers")?[0];
        // Owns the command buffer (and the query pool once made) from here on, so that
        // every return, early or not, frees them.
        let mut guard = SubmissionGuard {
            device: &self.raw,
            pool,
            cmd,
            query_pool: None,
        };
        if timed {
            let qp_info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(2);
            let qp =
                unsafe { self.raw.create_query_pool(&qp_info, None) }.check("vkCreateQueryPool")?;
            unsafe { self.raw.reset_query_pool(qp, 0, 2) };
            guard.query_pool = Some(qp);
        }
        let query_pool = guard.query_pool;
        let begin = vk::CommandBufferBeginInfo::default()
            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        let result = (|| {
            unsafe { self.raw.begin_command_buffer(cmd, &begin) }.check("vkBeginCommandBuffer")?;
            if let Some(qp) = query_pool {
                unsafe {
                    self.raw
                        .cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, qp, 0)
                };
            }
            self.full_barrier(cmd);
            let r = record(cmd);
            self.host_read_barrier(cmd);
            if let Some(qp) = query_pool {
                unsafe {
                    self.raw
                        .cmd_write_timestamp(cmd, vk::PipelineStageFlags::BOTTOM_OF_PIPE, qp, 1)
                };
            }
            unsafe { self.raw.end_command_buffer(cmd) }.check("vkEndCommandBuffer")?;
            let fence = unsafe { self.raw.create_fence(&vk::FenceCreateInfo::default(), None) }
                .check("vkCreateFence")?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let submitted = {
                let queue = self.queue.lock().unwrap();
                unsafe { self.raw.queue_submit(*queue, &submit, fence) }.check("vkQueueSubmit")
            };
            let waited = submitted.and_then(|_| {
                unsafe { self.raw.wait_for_fences(&[fence], true, u64::MAX) }
                    .check("vkWaitForFences")
            });
            unsafe { self.raw.destroy_fence(fence, None) };
            waited?;
            let seconds = match query_pool {
                Some(qp) => {
                    let mut stamps = [0u64; 2];
                    unsafe {
                        self.raw.get_query_pool_results(
                            qp,
                            0,
                            &mut stamps,
                            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                        )
                    }
                    .check("vkGetQueryPoolResults")?;
                    let ticks = stamps[1].wrapping_sub(stamps[0]) as f64;
                    Some(ticks * self.info.timestamp_period_ns as f64 * 1e-9)
                }
                None => None,
            };
            Ok((r, seconds))
        })();
        drop(guard);
        result
    }

    /// A full memory barrier between compute/transfer/AS-build work in `cmd`.
    pub fn full_barrier(&self, cmd: vk::CommandBuffer) {
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)];
        unsafe {
            self.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            )
        };
    }

    /// Make all device writes recorded so far in `cmd` visible to host reads.
    pub fn host_read_barrier(&self, cmd: vk::CommandBuffer) {
        let barrier = [vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ)];
        unsafe {
            self.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            )
        };
    }

    /// The device's compute pipelines.
    pub(crate) fn pipeline_cache(&self) -> &PipelineCache {
        &self.pipelines
    }

    /// How many compute pipelines the device holds, in use or kept for reuse (tests).
    pub fn cached_pipelines(&self) -> usize {
        self.pipelines.len()
    }

    pub fn wait_idle(&self) {
        unsafe {
            let _ = self.raw.device_wait_idle();
        }
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        unsafe {
            let _ = self.raw.device_wait_idle();
            // Every ComputePipeline holds the device, so only the cache still holds
            // pipelines here.
            self.pipelines.clear();
            self.raw
                .destroy_command_pool(*self.command_pool.lock().unwrap(), None);
            ManuallyDrop::drop(&mut self.allocator);
            self.raw.destroy_device(None);
        }
    }
}

/// The command buffer of one submission and its timestamp query pool, freed on drop (with
/// the command pool's lock held until then).
struct SubmissionGuard<'a> {
    device: &'a ash::Device,
    pool: std::sync::MutexGuard<'a, vk::CommandPool>,
    cmd: vk::CommandBuffer,
    query_pool: Option<vk::QueryPool>,
}

impl Drop for SubmissionGuard<'_> {
    fn drop(&mut self) {
        unsafe {
            self.device.free_command_buffers(*self.pool, &[self.cmd]);
            if let Some(qp) = self.query_pool.take() {
                self.device.destroy_query_pool(qp, None);
            }
        }
    }
}
