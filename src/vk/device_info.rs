//! Physical devices: what each offers (extensions, features, limits) as a
//! [`DeviceInfo`], the report of what lanterna needs from it, and the selector the
//! command line's `--device` parses.

use super::instance::Instance;
use super::{CheckVk, Result};
use ash::vk;
use std::ffi::CStr;

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
    /// VK_KHR_pipeline_executable_properties: the driver's statistics of each compiled
    /// kernel (registers, spills, instructions), logged at `--log debug`.
    pub executable_statistics: bool,
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
            (
                "VK_KHR_pipeline_executable_properties",
                self.executable_statistics,
                "kernel statistics at --log debug",
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
    /// Invocations per subgroup (SIMD lanes on a CPU device: 8 on lavapipe with AVX2,
    /// 4 with `LP_NATIVE_VECTOR_WIDTH=128`).
    pub subgroup_size: u32,
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

    pub(super) fn preference(&self) -> u32 {
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
pub(super) fn describe(
    instance: &Instance,
    index: usize,
    pd: vk::PhysicalDevice,
) -> Result<DeviceInfo> {
    let raw = &instance.raw;
    let exts = unsafe { raw.enumerate_device_extension_properties(pd) }
        .check("vkEnumerateDeviceExtensionProperties")?;
    let props = unsafe { raw.get_physical_device_properties(pd) };
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut as_props = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut subgroup_props = vk::PhysicalDeviceSubgroupProperties::default();
    let has_as = has_ext(&exts, ash::khr::acceleration_structure::NAME);
    {
        let mut props2 = vk::PhysicalDeviceProperties2::default()
            .push_next(&mut driver_props)
            .push_next(&mut subgroup_props);
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
    let mut f_exec = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default();
    let has_exec = has_ext(&exts, ash::khr::pipeline_executable_properties::NAME);
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
    if has_exec {
        features2 = features2.push_next(&mut f_exec);
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
        executable_statistics: has_exec && f_exec.pipeline_executable_info == vk::TRUE,
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
        subgroup_size: subgroup_props.subgroup_size.max(1),
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
