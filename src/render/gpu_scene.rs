//! The scene on the device: vertex, index, instance, material and light buffers,
//! textures and samplers, one BLAS per primitive and the TLAS.

use crate::gpu;
use crate::lights::LightTable;
use crate::scene::Scene;
use crate::vk::{
    self, AccelStructure, BlasGeometry, Buffer, Device, Sampler, SamplerDesc, Texture, TlasInstance,
};
use ash::vk as raw;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

/// Device-side copy of a scene.
pub struct GpuScene {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub instances: Buffer,
    pub materials: Buffer,
    pub light_triangles: Buffer,
    pub light_models: Buffer,
    pub model_alias: Buffer,
    pub triangle_alias: Buffer,
    pub punctual: Buffer,
    pub triangle_light_index: Buffer,
    pub textures: Vec<Texture>,
    /// Sampler of each texture (index into `samplers`).
    pub texture_samplers: Vec<usize>,
    pub samplers: Vec<Sampler>,
    pub tlas: AccelStructure,
    _blases: Vec<AccelStructure>,
    /// Seconds spent building acceleration structures.
    pub accel_seconds: f64,
    /// Seconds spent uploading buffers and textures.
    pub upload_seconds: f64,
    /// Bytes of device memory held (buffers, textures, acceleration structures).
    pub device_bytes: u64,
}

const STORAGE: raw::BufferUsageFlags = raw::BufferUsageFlags::STORAGE_BUFFER;

impl GpuScene {
    pub fn upload(
        device: &Arc<Device>,
        scene: &Scene,
        lights: &LightTable,
    ) -> vk::Result<GpuScene> {
        let started = Instant::now();
        let geometry_usage = STORAGE
            | raw::BufferUsageFlags::SHADER_DEVICE_ADDRESS
            | raw::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR;
        let vertices = Buffer::from_slice(device, &scene.vertices, geometry_usage, "vertices")?;
        let indices = Buffer::from_slice(device, &scene.indices, geometry_usage, "indices")?;

        let gpu_instances: Vec<gpu::Instance> = scene
            .instances
            .iter()
            .zip(&lights.instance_lights)
            .map(|(inst, &(light_index_offset, light_model))| {
                let p = &scene.primitives[inst.primitive as usize];
                let mut flags = 0;
                if p.opaque {
                    flags |= gpu::INSTANCE_FLAG_OPAQUE;
                }
                if inst.transform.determinant() < 0.0 {
                    flags |= gpu::INSTANCE_FLAG_FLIPPED;
                }
                gpu::Instance {
                    vertex_offset: p.vertex_offset,
                    index_offset: p.index_offset,
                    triangle_count: p.triangle_count,
                    material: p.material,
                    light_index_offset,
                    light_model,
                    flags,
                    pad: 0.0,
                }
            })
            .collect();
        let instances = Buffer::from_slice(device, &gpu_instances, STORAGE, "instances")?;
        let materials = Buffer::from_slice(device, &scene.materials, STORAGE, "materials")?;
        let light_triangles =
            Buffer::from_slice(device, &lights.triangles, STORAGE, "light triangles")?;
        let light_models = Buffer::from_slice(device, &lights.models, STORAGE, "light models")?;
        let model_alias = Buffer::from_slice(
            device,
            &lights.model_alias,
            STORAGE,
            "light model alias table",
        )?;
        let triangle_alias = Buffer::from_slice(
            device,
            &lights.triangle_alias,
            STORAGE,
            "light triangle alias tables",
        )?;
        let punctual = Buffer::from_slice(device, &scene.punctual, STORAGE, "punctual lights")?;
        let triangle_light_index = Buffer::from_slice(
            device,
            &lights.triangle_light_index,
            STORAGE,
            "triangle→light map",
        )?;

        let mut samplers: Vec<Sampler> = Vec::new();
        let mut sampler_ids: HashMap<SamplerDesc, usize> = HashMap::new();
        let mut textures = Vec::with_capacity(scene.textures.len());
        let mut texture_samplers = Vec::with_capacity(scene.textures.len());
        for t in &scene.textures {
            textures.push(Texture::new(
                device, t.width, t.height, &t.rgba, t.format, &t.name,
            )?);
            let id = match sampler_ids.get(&t.sampler) {
                Some(&id) => id,
                None => {
                    samplers.push(Sampler::new(device, t.sampler)?);
                    sampler_ids.insert(t.sampler, samplers.len() - 1);
                    samplers.len() - 1
                }
            };
            texture_samplers.push(id);
        }
        let upload_seconds = started.elapsed().as_secs_f64();

        let started = Instant::now();
        let stride = std::mem::size_of::<gpu::Vertex>() as u64;
        let geometries: Vec<BlasGeometry> = scene
            .primitives
            .iter()
            .map(|p| BlasGeometry {
                vertex_address: vertices.address + p.vertex_offset as u64 * stride,
                vertex_stride: stride,
                max_vertex: p.vertex_count.saturating_sub(1),
                index_address: indices.address + p.index_offset as u64 * 4,
                triangle_count: p.triangle_count,
                opaque: p.opaque,
            })
            .collect();
        let blases = AccelStructure::build_blases(device, &geometries)?;
        let tlas_instances: Vec<TlasInstance> = scene
            .instances
            .iter()
            .enumerate()
            .map(|(i, inst)| {
                let m = inst.transform.transpose().to_cols_array();
                TlasInstance {
                    // Row-major 3×4: the first three rows of the matrix.
                    transform: m[..12].try_into().unwrap(),
                    custom_index: i as u32,
                    blas_address: blases[inst.primitive as usize].address,
                    force_opaque: false,
                }
            })
            .collect();
        let tlas = AccelStructure::build_tlas(device, &tlas_instances)?;
        let accel_seconds = started.elapsed().as_secs_f64();

        let device_bytes = [
            &vertices,
            &indices,
            &instances,
            &materials,
            &light_triangles,
            &light_models,
            &model_alias,
            &triangle_alias,
            &punctual,
            &triangle_light_index,
        ]
        .iter()
        .map(|b| b.size)
        .sum::<u64>()
            + scene
                .textures
                .iter()
                .map(|t| t.rgba.len() as u64)
                .sum::<u64>()
            + blases.iter().map(|b| b.size).sum::<u64>()
            + tlas.size;
        log::info!(
            "scene on device: {:.1} MiB, uploads {:.2} s, acceleration structures {:.2} s ({} BLAS)",
            device_bytes as f64 / (1 << 20) as f64,
            upload_seconds,
            accel_seconds,
            blases.len()
        );
        Ok(GpuScene {
            vertices,
            indices,
            instances,
            materials,
            light_triangles,
            light_models,
            model_alias,
            triangle_alias,
            punctual,
            triangle_light_index,
            textures,
            texture_samplers,
            samplers,
            tlas,
            _blases: blases,
            accel_seconds,
            upload_seconds,
            device_bytes,
        })
    }

    /// (view, sampler) pairs in bindless slot order.
    pub fn texture_descriptors(&self) -> Vec<(raw::ImageView, raw::Sampler)> {
        self.textures
            .iter()
            .zip(&self.texture_samplers)
            .map(|(t, &s)| (t.view, self.samplers[s].raw))
            .collect()
    }
}
