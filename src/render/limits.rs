//! The device limits the per-pixel buffers of a render (film, AOVs, outliers) must fit,
//! checked before anything is allocated, so that a too-large image is an error saying
//! which limit it hits and what to do, instead of a failed `vkCreateBuffer` or a
//! descriptor beyond `maxStorageBufferRange`.

use super::{RenderError, RenderSettings};
use crate::gpu;
use crate::vk::Device;
use ash::vk as raw;

/// The largest storage buffer the kernels may bind on `device`: the smaller of
/// `maxStorageBufferRange` and `maxMemoryAllocationSize`, with the limit's name.
fn storage_limit(device: &Device) -> (u64, &'static str) {
    let mut m3 = raw::PhysicalDeviceMaintenance3Properties::default();
    let mut props = raw::PhysicalDeviceProperties2::default().push_next(&mut m3);
    // SAFETY: the physical device belongs to this instance; the chain is well formed.
    unsafe {
        device
            .instance
            .raw
            .get_physical_device_properties2(device.physical, &mut props)
    };
    let range = u64::from(props.properties.limits.max_storage_buffer_range);
    let alloc = m3.max_memory_allocation_size;
    if alloc > 0 && alloc < range {
        (alloc, "maxMemoryAllocationSize")
    } else {
        (range, "maxStorageBufferRange")
    }
}

/// Refuses settings whose per-pixel buffers exceed what `device` can bind.
pub fn check_image_size(device: &Device, s: &RenderSettings) -> Result<(), RenderError> {
    let pixels = u64::from(s.width) * u64::from(s.height);
    let mut buffers = vec![("film", 3 * 8)];
    if s.aovs {
        buffers.push(("AOV", u64::from(gpu::AOV_CHANNELS) * 4));
        buffers.push(("outlier", u64::from(gpu::OUTLIER_FLOATS) * 4));
    }
    let (limit, name) = storage_limit(device);
    let mib = |b: u64| b as f64 / f64::from(1 << 20);
    for (what, per_pixel) in buffers {
        let bytes = pixels.saturating_mul(per_pixel);
        if bytes <= limit {
            continue;
        }
        let max_pixels = limit / per_pixel;
        let aspect = f64::from(s.width) / f64::from(s.height);
        let width = ((max_pixels as f64 * aspect).sqrt().floor() as u64).max(1);
        return Err(RenderError::Invalid(format!(
            "a {}×{} image needs {:.0} MiB for its {what} buffer, but {} binds at most \
             {:.0} MiB in one storage buffer ({name}): render at most {max_pixels} pixels \
             (at this aspect, --width {width} or less){}",
            s.width,
            s.height,
            mib(bytes),
            device.info.name,
            mib(limit),
            if what == "film" {
                ""
            } else {
                ", or without --aov/--pixel/--report-outliers"
            }
        )));
    }
    Ok(())
}
