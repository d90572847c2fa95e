//! Sampled 2D textures (RGBA at 8 or 16 bits, sRGB or linear) and samplers.

use super::buffer::Buffer;
use super::device::Device;
use super::{CheckVk, Result, VkError};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Texel encoding of a texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureFormat {
    /// Colour data (base colour, emission), sRGB-encoded: decoded on the CPU with the
    /// exact sRGB curve and stored as linear half floats. (Drivers' `_SRGB` formats may
    /// decode approximately: lavapipe's is off by up to 2.6 % for dark codes, which a
    /// comparison with Mitsuba showed.)
    Srgb,
    /// Non-colour data (normals, metallic-roughness): used as stored (RGBA8 UNORM, or
    /// half floats for 16-bit images).
    Linear,
}

/// A texture's texels as its image stores them, RGBA, top row first: 8 bits per channel
/// (8-bit PNG, JPEG), or 16 (16-bit PNG), which are kept instead of being rounded to 8:
/// a dark sRGB code of an 8-bit image is a step of several per cent.
#[derive(Clone, Debug, PartialEq)]
pub enum Texels {
    Rgba8(Vec<u8>),
    Rgba16(Vec<u16>),
}

impl Texels {
    /// Number of channel values (four per texel).
    pub fn len(&self) -> usize {
        match self {
            Texels::Rgba8(v) => v.len(),
            Texels::Rgba16(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values' bytes (16-bit values little-endian), e.g. to hash them.
    pub fn bytes(&self) -> std::borrow::Cow<'_, [u8]> {
        match self {
            Texels::Rgba8(v) => v.as_slice().into(),
            Texels::Rgba16(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
        }
    }

    /// Channel value `i` in [0, 1].
    pub fn unorm(&self, i: usize) -> f32 {
        match self {
            Texels::Rgba8(v) => v[i] as f32 / 255.0,
            Texels::Rgba16(v) => v[i] as f32 / 65535.0,
        }
    }

    /// Channel value `i` decoded from sRGB to linear, exactly.
    pub fn srgb(&self, i: usize) -> f32 {
        match self {
            Texels::Rgba8(v) => srgb_decode(v[i]),
            Texels::Rgba16(v) => srgb_decode16(v[i]),
        }
    }

    /// Bytes the device holds for them in `format` (see [`Texture::new`]).
    pub fn device_bytes(&self, format: TextureFormat) -> u64 {
        let wide = format == TextureFormat::Srgb || matches!(self, Texels::Rgba16(_));
        self.len() as u64 * if wide { 2 } else { 1 }
    }
}

/// The exact sRGB decode of an 8-bit code, from a table made once: the light table
/// reads emissive textures millions of times on large scenes, where `powf` per read
/// was a fifth of the setup.
pub fn srgb_decode(code: u8) -> f32 {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| std::array::from_fn(|k| srgb_curve(k as f32 / 255.0)))[code as usize]
}

/// The exact sRGB decode of a 16-bit code, from a table made once (as [`srgb_decode`]).
pub fn srgb_decode16(code: u16) -> f32 {
    static TABLE: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        (0..=u16::MAX)
            .map(|k| srgb_curve(k as f32 / 65535.0))
            .collect()
    })[code as usize]
}

fn srgb_curve(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A sampled RGBA image with one mip level.
pub struct Texture {
    device: Arc<Device>,
    pub image: vk::Image,
    pub view: vk::ImageView,
    allocation: Option<Allocation>,
    pub width: u32,
    pub height: u32,
}

impl Texture {
    /// Upload `texels` (width × height × 4 values) into a new texture: sRGB colour as
    /// linear half floats, linear data as RGBA8 UNORM from 8-bit images and as half
    /// floats (11 significant bits) from 16-bit ones.
    pub fn new(
        device: &Arc<Device>,
        width: u32,
        height: u32,
        texels: &Texels,
        format: TextureFormat,
        name: &str,
    ) -> Result<Texture> {
        assert_eq!(
            texels.len(),
            (width * height * 4) as usize,
            "texture {name}: wrong texel count"
        );
        let halves = |value: &dyn Fn(usize) -> f32| -> Vec<u8> {
            (0..texels.len())
                .flat_map(|i| half::f16::from_f32(value(i)).to_le_bytes())
                .collect()
        };
        let (vk_format, texels): (vk::Format, std::borrow::Cow<'_, [u8]>) = match (format, texels) {
            (TextureFormat::Srgb, Texels::Rgba8(rgba)) => {
                let lut: Vec<half::f16> = (0..=255u8)
                    .map(|c| half::f16::from_f32(srgb_decode(c)))
                    .collect();
                let bytes: Vec<u8> = rgba
                    .chunks_exact(4)
                    .flat_map(|p| {
                        let a = half::f16::from_f32(p[3] as f32 / 255.0);
                        [
                            lut[p[0] as usize],
                            lut[p[1] as usize],
                            lut[p[2] as usize],
                            a,
                        ]
                    })
                    .flat_map(|h| h.to_le_bytes())
                    .collect();
                (vk::Format::R16G16B16A16_SFLOAT, bytes.into())
            }
            (TextureFormat::Srgb, t @ Texels::Rgba16(_)) => {
                let bytes = halves(&|i| if i % 4 == 3 { t.unorm(i) } else { t.srgb(i) });
                (vk::Format::R16G16B16A16_SFLOAT, bytes.into())
            }
            (TextureFormat::Linear, Texels::Rgba8(rgba)) => {
                (vk::Format::R8G8B8A8_UNORM, rgba.as_slice().into())
            }
            (TextureFormat::Linear, t @ Texels::Rgba16(_)) => (
                vk::Format::R16G16B16A16_SFLOAT,
                halves(&|i| t.unorm(i)).into(),
            ),
        };
        let rgba: &[u8] = &texels;
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(vk_format)
            .extent(vk::Extent3D {
                width,
                height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let image = unsafe { device.raw.create_image(&info, None) }.check("vkCreateImage")?;
        let requirements = unsafe { device.raw.get_image_memory_requirements(image) };
        let allocation = device
            .allocator()
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|error| {
                unsafe { device.raw.destroy_image(image, None) };
                VkError::Alloc {
                    name: name.to_string(),
                    error,
                }
            })?;
        // From here on the value owns the image and its memory (and the view once it
        // exists; destroying a null view is a no-op): an error drops it, and Drop frees
        // them.
        let mut texture = Texture {
            device: device.clone(),
            image,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            width,
            height,
        };
        let (memory, offset) = {
            let a = texture.allocation.as_ref().expect("just allocated");
            (unsafe { a.memory() }, a.offset())
        };
        unsafe { device.raw.bind_image_memory(image, memory, offset) }
            .check("vkBindImageMemory")?;
        device.set_name(image, name);

        let mut staging = Buffer::new(
            device,
            rgba.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
            &format!("{name} (staging)"),
        )?;
        staging.write_mapped(0, rgba);
        let range = vk::ImageSubresourceRange::default()
            .aspect_mask(vk::ImageAspectFlags::COLOR)
            .level_count(1)
            .layer_count(1);
        device.submit(|cmd| unsafe {
            let to_dst = [vk::ImageMemoryBarrier::default()
                .old_layout(vk::ImageLayout::UNDEFINED)
                .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .dst_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range)];
            device.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::PipelineStageFlags::TRANSFER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_dst,
            );
            let copy = [vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .layer_count(1),
                )
                .image_extent(vk::Extent3D {
                    width,
                    height,
                    depth: 1,
                })];
            device.raw.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &copy,
            );
            let to_read = [vk::ImageMemoryBarrier::default()
                .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
                .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                .dst_access_mask(vk::AccessFlags::SHADER_READ)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range)];
            device.raw.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TRANSFER,
                vk::PipelineStageFlags::COMPUTE_SHADER,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &to_read,
            );
        })?;

        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(vk_format)
            .subresource_range(range);
        texture.view =
            unsafe { device.raw.create_image_view(&view_info, None) }.check("vkCreateImageView")?;
        device.set_name(texture.view, name);
        Ok(texture)
    }
}

impl Drop for Texture {
    fn drop(&mut self) {
        unsafe {
            self.device.raw.destroy_image_view(self.view, None);
            self.device.raw.destroy_image(self.image, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
    }
}

/// Texture coordinate wrapping (glTF sampler wrapS / wrapT).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum WrapMode {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// Sampler parameters (glTF sampler).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct SamplerDesc {
    pub wrap_u: WrapMode,
    pub wrap_v: WrapMode,
    /// Nearest-neighbour magnification/minification instead of bilinear.
    pub nearest: bool,
}

/// A sampler object.
pub struct Sampler {
    device: Arc<Device>,
    pub raw: vk::Sampler,
    pub desc: SamplerDesc,
}

impl Sampler {
    pub fn new(device: &Arc<Device>, desc: SamplerDesc) -> Result<Sampler> {
        let mode = |w: WrapMode| match w {
            WrapMode::Repeat => vk::SamplerAddressMode::REPEAT,
            WrapMode::MirroredRepeat => vk::SamplerAddressMode::MIRRORED_REPEAT,
            WrapMode::ClampToEdge => vk::SamplerAddressMode::CLAMP_TO_EDGE,
        };
        let filter = if desc.nearest {
            vk::Filter::NEAREST
        } else {
            vk::Filter::LINEAR
        };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(mode(desc.wrap_u))
            .address_mode_v(mode(desc.wrap_v))
            .address_mode_w(vk::SamplerAddressMode::REPEAT)
            .max_lod(0.0);
        let raw = unsafe { device.raw.create_sampler(&info, None) }.check("vkCreateSampler")?;
        device.set_name(raw, &format!("sampler {desc:?}"));
        Ok(Sampler {
            device: device.clone(),
            raw,
            desc,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.device.raw.destroy_sampler(self.raw, None) };
    }
}
