//! Physical-device choice and the logical device.
//!
//! lanterna uses ray queries in compute shaders and acceleration structures where the
//! device has them (otherwise the kernels traverse a BVH of their own, see
//! `render::traversal`), and needs buffer device addresses, scalar block layout, bindless sampled images, 64-bit
//! integers (exact film accumulation) and, for the guided methods, float atomics. The
//! chooser prefers a hardware GPU that has all of them and falls back to lavapipe (Mesa's
//! CPU implementation); `--device` picks one by index or name substring.

use super::instance::Instance;
use super::{CheckVk, Result, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::CStr;
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

/// Which device to use.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum DeviceSelector {
    /// The best capable device (hardware GPUs before lavapipe).
    #[default]
    Auto,
    /// By position in `lanterna info`'s list.
    Index(usize),
    /// The first device whose name contains this (case-insensitive).
    Name(String),
}

impl std::str::FromStr for DeviceSelector {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> std::result::Result<Self, Self::Err> {
        Ok(match s.parse::<usize>() {
            _ if s.is_empty() || s.eq_ignore_ascii_case("auto") => DeviceSelector::Auto,
            Ok(i) => DeviceSelector::Index(i),
            Err(_) => DeviceSelector::Name(s.to_string()),
        })
    }
}

/// What a physical device supports of what lanterna needs.
#[derive(Clone, Debug, Default)]
pub struct FeatureReport {
    pub ray_query: bool,
    pub acceleration_structure: bool,
    /// Ray queries were reported unavailable by `LANTERNA_NO_RAY_QUERY` (a test and
    /// debugging override: the device is then used as if it had none).
    pub ray_queries_hidden: bool,
    pub buffer_device_address: bool,
    pub scalar_block_layout: bool,
    pub descriptor_indexing: bool,
    pub shader_int64: bool,
    pub host_query_reset: bool,
    pub float_atomics: bool,
    pub shader_clock: bool,
    pub non_semantic_info: bool,
    pub timestamps: bool,
}

impl FeatureReport {
    /// Names of the required features that are missing (empty: the device can render).
    pub fn missing(&self) -> Vec<&'static str> {
        let mut m = Vec::new();
        let req = [
            (self.buffer_device_address, "bufferDeviceAddress"),
            (self.scalar_block_layout, "scalarBlockLayout"),
            (
                self.descriptor_indexing,
                "descriptor indexing (runtime arrays, partially bound)",
            ),
            (self.shader_int64, "shaderInt64 + shaderBufferInt64Atomics"),
            (self.host_query_reset, "hostQueryReset"),
        ];
        for (ok, name) in req {
            if !ok {
                m.push(name);
            }
        }
        m
    }

    /// Ray queries and acceleration structures, both (the ray-query traversal).
    pub fn ray_queries(&self) -> bool {
        self.ray_query && self.acceleration_structure
    }

    /// Rows for `lanterna info`: (feature, supported, required).
    pub fn rows(&self) -> Vec<(&'static str, bool, &'static str)> {
        vec![
            ("VK_KHR_ray_query", self.ray_query, "ray-query traversal"),
            (
                "VK_KHR_acceleration_structure",
                self.acceleration_structure,
                "ray-query traversal",
            ),
            (
                "bufferDeviceAddress",
                self.buffer_device_address,
                "required",
            ),
            ("scalarBlockLayout", self.scalar_block_layout, "required"),
            ("descriptor indexing", self.descriptor_indexing, "required"),
            (
                "shaderInt64 + shaderBufferInt64Atomics",
                self.shader_int64,
                "required",
            ),
            ("hostQueryReset", self.host_query_reset, "required"),
            (
                "shaderBufferFloat32AtomicAdd",
                self.float_atomics,
                "guided methods",
            ),
            ("timestamp queries", self.timestamps, "GPU timings"),
            ("VK_KHR_shader_clock", self.shader_clock, "optional"),
            (
                "VK_KHR_shader_non_semantic_info",
                self.non_semantic_info,
                "--pixel traces",
            ),
        ]
    }
}

/// A physical device as `lanterna info` shows it.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    pub index: usize,
    pub name: String,
    pub kind: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub driver: String,
    pub features: FeatureReport,
    pub timestamp_period_ns: f32,
    pub min_scratch_alignment: u64,
}

impl DeviceInfo {
    pub fn kind_name(&self) -> &'static str {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
            vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
            vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
            vk::PhysicalDeviceType::CPU => "CPU",
            _ => "other",
        }
    }

    pub fn api_version_string(&self) -> String {
        let v = self.api_version;
        format!(
            "{}.{}.{}",
            vk::api_version_major(v),
            vk::api_version_minor(v),
            vk::api_version_patch(v)
        )
    }

    fn preference(&self) -> u32 {
        match self.kind {
            vk::PhysicalDeviceType::DISCRETE_GPU => 4,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 3,
            vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
            vk::PhysicalDeviceType::CPU => 1,
            _ => 0,
        }
    }
}

fn has_ext(exts: &[vk::ExtensionProperties], name: &CStr) -> bool {
    exts.iter()
        .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == name))
}

/// `LANTERNA_NO_RAY_QUERY` set (to anything but `0` or empty): report every device as
/// having no ray queries, so the software traversal is chosen and the device is created
/// without the ray-query extensions (how the tests check that path on lavapipe).
pub fn ray_queries_hidden() -> bool {
    std::env::var_os("LANTERNA_NO_RAY_QUERY").is_some_and(|v| !v.is_empty() && v != "0")
}

/// Query what a physical device supports.
fn describe(instance: &Instance, index: usize, pd: vk::PhysicalDevice) -> Result<DeviceInfo> {
    let raw = &instance.raw;
    let exts = unsafe { raw.enumerate_device_extension_properties(pd) }
        .check("vkEnumerateDeviceExtensionProperties")?;
    let props = unsafe { raw.get_physical_device_properties(pd) };
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let has_as = has_ext(&exts, ash::khr::acceleration_structure::NAME);
    {
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
        if has_as {
            props2 = props2.push_next(&mut as_props);
        }
        unsafe { raw.get_physical_device_properties2(pd, &mut props2) };
    }

    let mut f12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut f_as = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut f_rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut f_af = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
    let mut f_clock = vk::PhysicalDeviceShaderClockFeaturesKHR::default();
    let has_rq = has_ext(&exts, ash::khr::ray_query::NAME);
    let has_af = has_ext(&exts, ash::ext::shader_atomic_float::NAME);
    let has_clock = has_ext(&exts, ash::khr::shader_clock::NAME);
    let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f12);
    if has_as {
        features2 = features2.push_next(&mut f_as);
    }
    if has_rq {
        features2 = features2.push_next(&mut f_rq);
    }
    if has_af {
        features2 = features2.push_next(&mut f_af);
    }
    if has_clock {
        features2 = features2.push_next(&mut f_clock);
    }
    unsafe { raw.get_physical_device_features2(pd, &mut features2) };
    let base = features2.features;

    let queue_families = unsafe { raw.get_physical_device_queue_family_properties(pd) };
    let timestamps = queue_families
        .iter()
        .any(|q| q.queue_flags.contains(vk::QueueFlags::COMPUTE) && q.timestamp_valid_bits > 0);

    let hidden = ray_queries_hidden();
    let features = FeatureReport {
        ray_query: !hidden && has_rq && f_rq.ray_query == vk::TRUE,
        acceleration_structure: !hidden
            && has_as
            && has_ext(&exts, ash::khr::deferred_host_operations::NAME)
            && f_as.acceleration_structure == vk::TRUE,
        ray_queries_hidden: hidden,
        buffer_device_address: f12.buffer_device_address == vk::TRUE,
        scalar_block_layout: f12.scalar_block_layout == vk::TRUE,
        descriptor_indexing: f12.runtime_descriptor_array == vk::TRUE
            && f12.descriptor_binding_partially_bound == vk::TRUE
            && f12.shader_sampled_image_array_non_uniform_indexing == vk::TRUE,
        // 64-bit integers, and 64-bit atomics on storage buffers (ray and sample counters
        // that would wrap at 2³² on large renders).
        shader_int64: base.shader_int64 == vk::TRUE && f12.shader_buffer_int64_atomics == vk::TRUE,
        host_query_reset: f12.host_query_reset == vk::TRUE,
        float_atomics: has_af && f_af.shader_buffer_float32_atomic_add == vk::TRUE,
        shader_clock: has_clock && f_clock.shader_subgroup_clock == vk::TRUE,
        // Enabled as an extension even on 1.3 devices: the instance asks for Vulkan 1.2.
        non_semantic_info: has_ext(&exts, ash::khr::shader_non_semantic_info::NAME),
        timestamps: timestamps && props.limits.timestamp_compute_and_graphics == vk::TRUE,
    };
    let name = props
        .device_name_as_c_str()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let driver = format!(
        "{} {}",
        driver_props
            .driver_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        driver_props
            .driver_info_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    )
    .trim()
    .to_string();
    Ok(DeviceInfo {
        index,
        name,
        kind: props.device_type,
        api_version: props.api_version,
        driver,
        features,
        timestamp_period_ns: props.limits.timestamp_period,
        min_scratch_alignment: (as_props.min_acceleration_structure_scratch_offset_alignment
            as u64)
            .max(1),
    })
}

/// Describe every Vulkan device (for `lanterna info`).
pub fn list_devices(instance: &Instance) -> Result<Vec<DeviceInfo>> {
    let pds =
        unsafe { instance.raw.enumerate_physical_devices() }.check("vkEnumeratePhysicalDevices")?;
    pds.iter()
        .enumerate()
        .map(|(i, &pd)| describe(instance, i, pd))
        .collect()
}

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
    debug_utils: Option<ash::ext::debug_utils::Device>,
    command_pool: Mutex<vk::CommandPool>,
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
            debug_utils,
            command_pool: Mutex::new(command_pool),
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
