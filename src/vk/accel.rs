//! Ray-tracing acceleration structures: one BLAS per mesh primitive, one TLAS over the
//! instances. Builds are batched into as few submissions as the scratch memory budget
//! allows.

use super::buffer::Buffer;
use super::device::Device;
use super::{CheckVk, Result};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// An acceleration structure and the buffer that holds it.
pub struct AccelStructure {
    device: Arc<Device>,
    pub raw: vk::AccelerationStructureKHR,
    _buffer: Buffer,
    /// Device address (what TLAS instances reference).
    pub address: u64,
    pub size: u64,
}

impl Drop for AccelStructure {
    fn drop(&mut self) {
        unsafe {
            self.device
                .accel
                .destroy_acceleration_structure(self.raw, None)
        };
    }
}

/// One geometry (a run of triangles) of a BLAS, read from buffers by device address.
#[derive(Clone, Copy, Debug)]
pub struct BlasGeometry {
    /// Address of the first vertex position (vec3 f32 at the start of each vertex).
    pub vertex_address: u64,
    pub vertex_stride: u64,
    /// Highest vertex index the indices use.
    pub max_vertex: u32,
    /// Address of the first u32 index.
    pub index_address: u64,
    pub triangle_count: u32,
    /// Opaque geometry skips any-hit style candidate processing.
    pub opaque: bool,
}

/// One TLAS instance.
#[derive(Clone, Copy, Debug)]
pub struct TlasInstance {
    /// Row-major 3×4 object-to-world transform.
    pub transform: [f32; 12],
    /// `gl_InstanceCustomIndexEXT` / `rayQueryGetIntersectionInstanceCustomIndexEXT`.
    pub custom_index: u32,
    pub blas_address: u64,
    /// Mark the whole instance opaque (forces the opaque path even for non-opaque geometry).
    pub force_opaque: bool,
}

fn as_buffer(device: &Arc<Device>, size: u64, name: &str) -> Result<Buffer> {
    Buffer::new(
        device,
        size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
        name,
    )
}

fn create_as(
    device: &Arc<Device>,
    ty: vk::AccelerationStructureTypeKHR,
    size: u64,
    name: &str,
) -> Result<AccelStructure> {
    let buffer = as_buffer(device, size, name)?;
    let info = vk::AccelerationStructureCreateInfoKHR::default()
        .buffer(buffer.raw)
        .size(size)
        .ty(ty);
    let raw = unsafe { device.accel.create_acceleration_structure(&info, None) }
        .check("vkCreateAccelerationStructureKHR")?;
    device.set_name(raw, name);
    let address = unsafe {
        device.accel.get_acceleration_structure_device_address(
            &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
        )
    };
    Ok(AccelStructure {
        device: device.clone(),
        raw,
        _buffer: buffer,
        address,
        size,
    })
}

fn align(x: u64, a: u64) -> u64 {
    x.div_ceil(a) * a
}

/// Scratch memory one batch of BLAS builds may use.
const SCRATCH_BUDGET: u64 = 256 << 20;

impl AccelStructure {
    /// Build one bottom-level structure per list of geometries (geometry i of a BLAS is
    /// `rayQueryGetIntersectionGeometryIndexEXT` = i).
    pub fn build_blases(
        device: &Arc<Device>,
        blases: &[Vec<BlasGeometry>],
    ) -> Result<Vec<AccelStructure>> {
        let scratch_align = device.info.min_scratch_alignment;
        let geometries_of =
            |list: &[BlasGeometry]| -> Vec<vk::AccelerationStructureGeometryKHR<'static>> {
                list.iter()
                    .map(|g| {
                        vk::AccelerationStructureGeometryKHR::default()
                            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
                            .geometry(vk::AccelerationStructureGeometryDataKHR {
                                triangles: triangles(g),
                            })
                            .flags(geometry_flags(g))
                    })
                    .collect()
            };
        let mut out = Vec::with_capacity(blases.len());
        let mut start = 0;
        while start < blases.len() {
            // Size this batch.
            let mut batch = Vec::new();
            let mut scratch_total = 0u64;
            let mut i = start;
            while i < blases.len() {
                let geom = geometries_of(&blases[i]);
                let counts: Vec<u32> = blases[i].iter().map(|g| g.triangle_count).collect();
                let info = build_info(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, &geom);
                let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
                unsafe {
                    device.accel.get_acceleration_structure_build_sizes(
                        vk::AccelerationStructureBuildTypeKHR::DEVICE,
                        &info,
                        &counts,
                        &mut sizes,
                    )
                };
                let scratch = align(sizes.build_scratch_size, scratch_align);
                if !batch.is_empty() && scratch_total + scratch > SCRATCH_BUDGET {
                    break;
                }
                batch.push((i, sizes.acceleration_structure_size, scratch_total));
                scratch_total += scratch;
                i += 1;
            }
            let scratch = Buffer::new(
                device,
                scratch_total + scratch_align,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
                MemoryLocation::GpuOnly,
                "BLAS scratch",
            )?;
            let scratch_base = align(scratch.address, scratch_align);
            let structures: Vec<AccelStructure> = batch
                .iter()
                .map(|&(bi, size, _)| {
                    create_as(
                        device,
                        vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
                        size,
                        &format!("BLAS {bi}"),
                    )
                })
                .collect::<Result<_>>()?;
            let geoms: Vec<Vec<vk::AccelerationStructureGeometryKHR>> = batch
                .iter()
                .map(|&(bi, _, _)| geometries_of(&blases[bi]))
                .collect();
            let infos: Vec<vk::AccelerationStructureBuildGeometryInfoKHR> = batch
                .iter()
                .zip(&geoms)
                .zip(&structures)
                .map(|((&(_, _, scratch_off), geom), s)| {
                    build_info(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, geom)
                        .dst_acceleration_structure(s.raw)
                        .scratch_data(vk::DeviceOrHostAddressKHR {
                            device_address: scratch_base + scratch_off,
                        })
                })
                .collect();
            let ranges: Vec<Vec<vk::AccelerationStructureBuildRangeInfoKHR>> = batch
                .iter()
                .map(|&(bi, _, _)| {
                    blases[bi]
                        .iter()
                        .map(|g| {
                            vk::AccelerationStructureBuildRangeInfoKHR::default()
                                .primitive_count(g.triangle_count)
                        })
                        .collect()
                })
                .collect();
            let range_refs: Vec<&[vk::AccelerationStructureBuildRangeInfoKHR]> =
                ranges.iter().map(|r| &r[..]).collect();
            device.submit(|cmd| unsafe {
                device
                    .accel
                    .cmd_build_acceleration_structures(cmd, &infos, &range_refs);
            })?;
            drop(scratch);
            out.extend(structures);
            start = i;
        }
        Ok(out)
    }

    /// Build the top-level structure over `instances`.
    pub fn build_tlas(device: &Arc<Device>, instances: &[TlasInstance]) -> Result<AccelStructure> {
        let raw_instances: Vec<vk::AccelerationStructureInstanceKHR> = instances
            .iter()
            .map(|inst| vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: inst.transform,
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(inst.custom_index, 0xff),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    if inst.force_opaque {
                        vk::GeometryInstanceFlagsKHR::FORCE_OPAQUE.as_raw() as u8
                    } else {
                        0
                    },
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: inst.blas_address,
                },
            })
            .collect();
        let bytes: &[u8] = unsafe {
            std::slice::from_raw_parts(
                raw_instances.as_ptr() as *const u8,
                std::mem::size_of_val(raw_instances.as_slice()),
            )
        };
        let instance_buffer = Buffer::new(
            device,
            bytes.len() as u64,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
            "TLAS instances",
        )?;
        instance_buffer.upload(0, bytes)?;
        let geom = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: vk::AccelerationStructureGeometryInstancesDataKHR::default()
                    .array_of_pointers(false)
                    .data(vk::DeviceOrHostAddressConstKHR {
                        device_address: instance_buffer.address,
                    }),
            })];
        let count = instances.len() as u32;
        let info = build_info(vk::AccelerationStructureTypeKHR::TOP_LEVEL, &geom);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        unsafe {
            device.accel.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[count],
                &mut sizes,
            )
        };
        let tlas = create_as(
            device,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            sizes.acceleration_structure_size,
            "TLAS",
        )?;
        let scratch_align = device.info.min_scratch_alignment;
        let scratch = Buffer::new(
            device,
            sizes.build_scratch_size + scratch_align,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::GpuOnly,
            "TLAS scratch",
        )?;
        let info =
            info.dst_acceleration_structure(tlas.raw)
                .scratch_data(vk::DeviceOrHostAddressKHR {
                    device_address: align(scratch.address, scratch_align),
                });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
        device.submit(|cmd| unsafe {
            device
                .accel
                .cmd_build_acceleration_structures(cmd, &[info], &[&range]);
        })?;
        Ok(tlas)
    }
}

fn triangles(g: &BlasGeometry) -> vk::AccelerationStructureGeometryTrianglesDataKHR<'static> {
    vk::AccelerationStructureGeometryTrianglesDataKHR::default()
        .vertex_format(vk::Format::R32G32B32_SFLOAT)
        .vertex_data(vk::DeviceOrHostAddressConstKHR {
            device_address: g.vertex_address,
        })
        .vertex_stride(g.vertex_stride)
        .max_vertex(g.max_vertex)
        .index_type(vk::IndexType::UINT32)
        .index_data(vk::DeviceOrHostAddressConstKHR {
            device_address: g.index_address,
        })
}

fn geometry_flags(g: &BlasGeometry) -> vk::GeometryFlagsKHR {
    if g.opaque {
        vk::GeometryFlagsKHR::OPAQUE
    } else {
        // Alpha-tested geometry: each candidate must be reported exactly once.
        vk::GeometryFlagsKHR::NO_DUPLICATE_ANY_HIT_INVOCATION
    }
}

fn build_info<'a>(
    ty: vk::AccelerationStructureTypeKHR,
    geom: &'a [vk::AccelerationStructureGeometryKHR<'a>],
) -> vk::AccelerationStructureBuildGeometryInfoKHR<'a> {
    vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(geom)
}
