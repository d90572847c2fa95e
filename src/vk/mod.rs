//! A thin RAII layer over Vulkan (ash + gpu-allocator) that knows nothing about rendering.
//!
//! Every object holds an `Arc<Device>` and frees itself in `Drop`; every object gets a
//! debug name at creation. The device waits idle and drops the allocator before it
//! destroys itself. Work is submitted one-shot (record, submit, wait), which is all an
//! offline renderer needs; timestamp queries measure GPU time around a submission.

mod accel;
mod buffer;
mod descriptor;
mod device;
mod device_info;
mod image;
mod instance;
pub mod lavapipe;
mod pipeline;
mod pipeline_cache;
mod staging;

pub use accel::{AccelStructure, BlasGeometry, TlasInstance};
pub use buffer::Buffer;
pub use descriptor::DescriptorSet;
pub use device::Device;
pub use device_info::{DeviceInfo, DeviceSelector, FeatureReport};
pub use image::{
    srgb_decode, srgb_decode16, Sampler, SamplerDesc, Texels, Texture, TextureFormat, WrapMode,
};
pub use instance::{take_debug_printf_messages, validation_error_count, Instance, InstanceOptions};
pub use pipeline::{BindingKind, BindingSpec, ComputePipeline};
pub use staging::Staging;

pub use ash::vk;
pub use gpu_allocator::MemoryLocation;

/// Errors raised by the Vulkan layer.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error(
        "cannot load the Vulkan library: {0} (is a Vulkan loader installed? run scripts/setup)"
    )]
    Loader(String),
    #[error("Vulkan call {call} failed: {result}")]
    Call {
        call: &'static str,
        result: vk::Result,
    },
    #[error("GPU memory allocation for `{name}` failed: {error}")]
    Alloc {
        name: String,
        error: gpu_allocator::AllocationError,
    },
    #[error("no Vulkan device found")]
    NoDevice,
    #[error("no Vulkan device matches `{0}` (see `lanterna info`)")]
    NoMatchingDevice(String),
    #[error("device `{name}` cannot run lanterna: missing {missing}")]
    Unsupported { name: String, missing: String },
    #[error("no Vulkan device supports ray queries; missing on each: {0} (on Debian 12, lavapipe from bookworm-backports has them: run scripts/setup)")]
    NoCapableDevice(String),
    #[error("{0}")]
    Other(String),
}

pub type Result<T> = std::result::Result<T, VkError>;

/// Attach the name of a failing Vulkan call to its result.
pub(crate) trait CheckVk<T> {
    fn check(self, call: &'static str) -> Result<T>;
}

impl<T> CheckVk<T> for std::result::Result<T, vk::Result> {
    fn check(self, call: &'static str) -> Result<T> {
        self.map_err(|result| VkError::Call { call, result })
    }
}
