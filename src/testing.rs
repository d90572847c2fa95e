//! Support for the test suite: a shared device with validation on, and a runner for the
//! small test kernels in `shaders_glsl/tests/` (real GLSL on the device, statistics in
//! Rust). Test kernels bind three storage buffers (TEST_BINDING_IN, _OUT, _AUX) and take
//! up to 128 bytes of push constants.

use crate::gpu;
use crate::shaders::ShaderSource;
use crate::vk::{
    self, BindingSpec, Buffer, ComputePipeline, DescriptorSet, Device, DeviceSelector, Instance,
    InstanceOptions,
};
use ash::vk as raw;
use std::sync::{Arc, OnceLock};

/// One device per test process, with validation layers on.
pub fn device() -> Arc<Device> {
    static DEVICE: OnceLock<Arc<Device>> = OnceLock::new();
    DEVICE
        .get_or_init(|| {
            let instance = Instance::new(&InstanceOptions {
                validation: true,
                debug_printf: false,
            })
            .expect("Vulkan instance (run scripts/setup)");
            Device::new(Arc::new(instance), &DeviceSelector::Auto)
                .expect("a Vulkan device with ray queries")
        })
        .clone()
}

/// Fail if the validation layer reported any error so far in this process.
pub fn assert_no_validation_errors() {
    let n = vk::validation_error_count();
    assert_eq!(
        n, 0,
        "{n} Vulkan validation error(s) were reported (see the log above)"
    );
}

/// Run test kernel `name` (e.g. `tests/reservoir`) over `invocations` (x dimension,
/// local size 64), with `input` and `aux` bound as read buffers and an output buffer of
/// `output_bytes`, returned after the run.
pub fn run_kernel(
    name: &str,
    input: &[u8],
    aux: &[u8],
    output_bytes: usize,
    push: &[u8],
    invocations: u32,
) -> vk::Result<Vec<u8>> {
    let device = device();
    let spirv = ShaderSource::Builtin
        .load(name)
        .map_err(|e| vk::VkError::Other(e.to_string()))?;
    let bindings = [
        BindingSpec::buffer(gpu::TEST_BINDING_IN),
        BindingSpec::buffer(gpu::TEST_BINDING_OUT),
        BindingSpec::buffer(gpu::TEST_BINDING_AUX),
    ];
    let pipeline = ComputePipeline::new(&device, &spirv, &bindings, 128, &[], name)?;
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
    let pad = |b: &[u8]| {
        if b.is_empty() {
            vec![0u8; 16]
        } else {
            b.to_vec()
        }
    };
    let input = Buffer::from_slice(&device, &pad(input), usage, "test input")?;
    let aux = Buffer::from_slice(&device, &pad(aux), usage, "test aux")?;
    let output = Buffer::zeroed(&device, output_bytes as u64, usage, "test output")?;
    let set = DescriptorSet::new(&device, &pipeline)?;
    set.write_buffer(gpu::TEST_BINDING_IN, &input);
    set.write_buffer(gpu::TEST_BINDING_OUT, &output);
    set.write_buffer(gpu::TEST_BINDING_AUX, &aux);
    let mut push_bytes = [0u8; 128];
    push_bytes[..push.len()].copy_from_slice(push);
    device.submit(|cmd| {
        pipeline.cmd_dispatch(cmd, set.raw, &push_bytes, [invocations.div_ceil(64), 1, 1])
    })?;
    output.read_bytes(output_bytes as u64)
}
