//! The scene on the device: vertex, index, instance, material and light buffers,
//! textures and samplers, and what the traversal needs: for ray queries the BLASes and the
//! TLAS, for the software traversal the BVH of `bvh.rs` over the same instances in world
//! space (instance and primitive indices as the ray queries would report them).

use super::bvh::{BuildTriangle, Bvh, BvhOptions};
use super::traversal::TraversalKind;
use crate::gpu;
use crate::lights::LightTable;
use crate::scene::spatial_order::kd_order;
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
    /// `Scene::colors` (at least one element's worth, unread, when empty).
    pub vertex_colors: Buffer,
    pub indices: Buffer,
    pub instances: Buffer,
    pub materials: Buffer,
    pub light_triangles: Buffer,
    pub light_candidates: Buffer,
    pub light_models: Buffer,
    pub model_alias: Buffer,
    pub triangle_alias: Buffer,
    pub light_tree: Buffer,
    pub punctual: Buffer,
    /// `Scene::light_profiles` (one unread element when empty).
    pub light_profiles: Buffer,
    pub triangle_light_index: Buffer,
    pub textures: Vec<Texture>,
    /// Sampler of each texture (index into `samplers`).
    pub texture_samplers: Vec<usize>,
    pub samplers: Vec<Sampler>,
    pub traversal: TraversalKind,
    /// The TLAS (ray-query traversal).
    pub tlas: Option<AccelStructure>,
    _blases: Vec<AccelStructure>,
    _flat_positions: Option<Buffer>,
    /// Scene instance index of each GPU instance (the merge order).
    pub instance_order: Vec<usize>,
    /// Size of the software BVH (zeros with ray queries).
    pub bvh_stats: BvhStats,
    /// The BVH's nodes and triangles (software traversal).
    pub bvh: Option<(Buffer, Buffer)>,
    /// Seconds spent building acceleration structures.
    pub accel_seconds: f64,
    /// Seconds spent uploading buffers and textures.
    pub upload_seconds: f64,
    /// Bytes of device memory held (buffers, textures, acceleration structures).
    pub device_bytes: u64,
}

/// What the software BVH came out as.
#[derive(Clone, Copy, Debug, Default)]
pub struct BvhStats {
    pub nodes: usize,
    pub triangles: usize,
    pub max_leaf: usize,
    pub depth: usize,
}

/// The scene's and the SD-tree's arrays are bound as storage buffers and read through
/// their device addresses where `Renderer::scene_addresses` says (FrameParams and the
/// push constants, inc/scene_data.glsl and inc/guiding_buffers.glsl).
pub(super) const STORAGE: raw::BufferUsageFlags = raw::BufferUsageFlags::from_raw(
    raw::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | raw::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
);

impl GpuScene {
    pub fn upload(
        device: &Arc<Device>,
        scene: &Scene,
        lights: &LightTable,
        traversal: TraversalKind,
    ) -> vk::Result<GpuScene> {
        let started = Instant::now();
        let ray_query = traversal == TraversalKind::RayQuery;
        let geometry_usage = if ray_query {
            STORAGE | raw::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
        } else {
            STORAGE
        };
        let vertices = Buffer::from_slice(device, &scene.vertices, geometry_usage, "vertices")?;
        let indices = Buffer::from_slice(device, &scene.indices, geometry_usage, "indices")?;
        let vertex_colors = Buffer::from_slice(device, &scene.colors, STORAGE, "vertex colours")?;

        // Small instanced meshes are copied into world space and merged into shared
        // BLASes; the instance buffer lists them first, in merge order.
        let plan = FlattenPlan::new(scene);
        let gpu_instances: Vec<gpu::Instance> = plan
            .order
            .iter()
            .map(|&i| {
                let inst = &scene.instances[i];
                let (light_index_offset, light_model) = lights.instance_lights[i];
                let p = &scene.primitives[inst.primitive as usize];
                let mut flags = 0;
                if p.opaque {
                    flags |= gpu::INSTANCE_FLAG_OPAQUE;
                }
                if inst.transform.determinant() < 0.0 {
                    flags |= gpu::INSTANCE_FLAG_FLIPPED;
                }
                let rows = inst.transform.transpose().to_cols_array_2d();
                gpu::Instance {
                    to_world_row0: rows[0],
                    to_world_row1: rows[1],
                    to_world_row2: rows[2],
                    vertex_offset: p.vertex_offset,
                    index_offset: p.index_offset,
                    triangle_count: p.triangle_count,
                    material: p.material,
                    light_index_offset,
                    light_model,
                    flags,
                    color_offset: p.color_offset,
                }
            })
            .collect();
        let instances = Buffer::from_slice(device, &gpu_instances, STORAGE, "instances")?;
        let materials = Buffer::from_slice(device, &scene.materials, STORAGE, "materials")?;
        // Light triangles of alpha-masked or vertex-tinted emitters name their instance, in
        // kernel order.
        let mut kernel_index = vec![gpu::INVALID_INDEX; scene.instances.len()];
        for (k, &i) in plan.order.iter().enumerate() {
            kernel_index[i] = k as u32;
        }
        let light_triangles: Vec<gpu::LightTriangle> = lights
            .triangles
            .iter()
            .map(|t| gpu::LightTriangle {
                instance: if t.instance == gpu::INVALID_INDEX {
                    gpu::INVALID_INDEX
                } else {
                    kernel_index[t.instance as usize]
                },
                ..*t
            })
            .collect();
        let light_triangles =
            Buffer::from_slice(device, &light_triangles, STORAGE, "light triangles")?;
        let light_candidates = Buffer::from_slice(
            device,
            &lights.candidates,
            STORAGE,
            "light candidate triangles",
        )?;
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
        let light_tree = Buffer::from_slice(device, &lights.tree, STORAGE, "light tree")?;
        let punctual = Buffer::from_slice(device, &scene.punctual, STORAGE, "punctual lights")?;
        let light_profiles = Buffer::from_slice(
            device,
            if scene.light_profiles.is_empty() {
                &[0.0f32]
            } else {
                &scene.light_profiles
            },
            STORAGE,
            "light profiles",
        )?;
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
                device, t.width, t.height, &t.texels, t.format, &t.name,
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
        let mut bvh_stats = BvhStats::default();
        let (tlas, blases, flat_buffer, bvh) = if ray_query {
            let (tlas, blases, flat) = build_ray_query_structures(
                device,
                scene,
                &plan,
                &vertices,
                &indices,
                geometry_usage,
            )?;
            (Some(tlas), blases, Some(flat), None)
        } else {
            let options = BvhOptions::from_env();
            let bvh = build_bvh(scene, &plan, options);
            bvh_stats = BvhStats {
                nodes: bvh.nodes.len(),
                triangles: bvh.triangles.len(),
                max_leaf: options.max_leaf,
                depth: bvh.depth,
            };
            log::info!(
                "software BVH: {} nodes, {} triangles, depth {}",
                bvh.nodes.len(),
                bvh.triangles.len(),
                bvh.depth
            );
            let nodes = Buffer::from_slice(device, &bvh.nodes, STORAGE, "BVH nodes")?;
            let tris = Buffer::from_slice(device, &bvh.triangles, STORAGE, "BVH triangles")?;
            (None, Vec::new(), None, Some((nodes, tris)))
        };
        let accel_seconds = started.elapsed().as_secs_f64();

        let device_bytes = [
            &vertices,
            &indices,
            &instances,
            &materials,
            &light_triangles,
            &light_candidates,
            &light_models,
            &model_alias,
            &triangle_alias,
            &light_tree,
            &punctual,
            &light_profiles,
            &triangle_light_index,
        ]
        .iter()
        .map(|b| b.size)
        .sum::<u64>()
            + scene
                .textures
                .iter()
                .map(|t| t.texels.device_bytes(t.format))
                .sum::<u64>()
            + blases.iter().map(|b| b.size).sum::<u64>()
            + tlas.as_ref().map_or(0, |t| t.size)
            + flat_buffer.as_ref().map_or(0, |b| b.size)
            + bvh.as_ref().map_or(0, |(n, t)| n.size + t.size);
        log::info!(
            "scene on device: {:.1} MiB, uploads {:.2} s, {} traversal structures {:.2} s ({} BLAS; {} of {} instances flattened)",
            device_bytes as f64 / (1 << 20) as f64,
            upload_seconds,
            traversal,
            accel_seconds,
            blases.len(),
            plan.flattened,
            scene.instances.len()
        );
        Ok(GpuScene {
            vertices,
            vertex_colors,
            indices,
            instances,
            materials,
            light_triangles,
            light_candidates,
            light_models,
            model_alias,
            triangle_alias,
            light_tree,
            punctual,
            light_profiles,
            triangle_light_index,
            textures,
            texture_samplers,
            samplers,
            traversal,
            tlas,
            _blases: blases,
            _flat_positions: flat_buffer,
            bvh,
            instance_order: plan.order.clone(),
            bvh_stats,
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

/// The ray-query structures: merged BLASes of the flattened instances, one BLAS per
/// primitive that stays instanced, and the TLAS over them.
fn build_ray_query_structures(
    device: &Arc<Device>,
    scene: &Scene,
    plan: &FlattenPlan,
    vertices: &Buffer,
    indices: &Buffer,
    geometry_usage: raw::BufferUsageFlags,
) -> vk::Result<(AccelStructure, Vec<AccelStructure>, Buffer)> {
    let stride = std::mem::size_of::<gpu::Vertex>() as u64;
    let geometry =
        |p: &crate::scene::MeshPrimitive, vertex_address: u64, vertex_stride: u64| BlasGeometry {
            vertex_address,
            vertex_stride,
            max_vertex: p.vertex_count.saturating_sub(1),
            index_address: indices.address + p.index_offset as u64 * 4,
            triangle_count: p.triangle_count,
            opaque: p.opaque,
        };
    // World-space positions of the flattened instances, then one geometry each.
    let mut flat_positions: Vec<[f32; 3]> = Vec::with_capacity(plan.flattened_vertices as usize);
    let mut flat_geometries = Vec::with_capacity(plan.flattened);
    for &i in &plan.order[..plan.flattened] {
        let inst = &scene.instances[i];
        let p = &scene.primitives[inst.primitive as usize];
        let first = flat_positions.len() as u64;
        flat_positions.extend(
            scene.vertices[p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize]
                .iter()
                .map(|v| {
                    inst.transform
                        .transform_point3(glam::Vec3::from(v.position))
                        .to_array()
                }),
        );
        flat_geometries.push((p, first));
    }
    let flat_buffer = Buffer::from_slice(
        device,
        &flat_positions,
        geometry_usage,
        "flattened positions",
    )?;
    let mut blas_lists: Vec<Vec<BlasGeometry>> = plan
        .groups
        .iter()
        .map(|g| {
            flat_geometries[g.clone()]
                .iter()
                .map(|&(p, first)| geometry(p, flat_buffer.address + first * 12, 12))
                .collect()
        })
        .collect();
    // Then one BLAS per primitive that stays instanced.
    let mut primitive_blas: HashMap<u32, usize> = HashMap::new();
    for &i in &plan.order[plan.flattened..] {
        let prim = scene.instances[i].primitive;
        primitive_blas.entry(prim).or_insert_with(|| {
            let p = &scene.primitives[prim as usize];
            blas_lists.push(vec![geometry(
                p,
                vertices.address + p.vertex_offset as u64 * stride,
                stride,
            )]);
            blas_lists.len() - 1
        });
    }
    let blases = AccelStructure::build_blases(device, &blas_lists)?;
    const IDENTITY: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut tlas_instances: Vec<TlasInstance> = plan
        .groups
        .iter()
        .enumerate()
        .map(|(b, g)| TlasInstance {
            transform: IDENTITY,
            custom_index: g.start as u32,
            blas_address: blases[b].address,
            force_opaque: false,
        })
        .collect();
    for (k, &i) in plan.order.iter().enumerate().skip(plan.flattened) {
        let inst = &scene.instances[i];
        let m = inst.transform.transpose().to_cols_array();
        tlas_instances.push(TlasInstance {
            // Row-major 3×4: the first three rows of the matrix.
            transform: m[..12].try_into().unwrap(),
            custom_index: k as u32,
            blas_address: blases[primitive_blas[&inst.primitive]].address,
            force_opaque: false,
        });
    }
    let tlas = AccelStructure::build_tlas(device, &tlas_instances)?;
    Ok((tlas, blases, flat_buffer))
}

/// The software traversal's BVH over every instance's triangles in world space, each
/// tagged with the instance index ray queries report (its position in the GPU instance
/// buffer, `plan.order`) and its index within its primitive.
fn build_bvh(scene: &Scene, plan: &FlattenPlan, options: BvhOptions) -> Bvh {
    let total: usize = plan
        .order
        .iter()
        .map(|&i| scene.primitives[scene.instances[i].primitive as usize].triangle_count as usize)
        .sum();
    let mut tris = Vec::with_capacity(total);
    for (k, &i) in plan.order.iter().enumerate() {
        let inst = &scene.instances[i];
        let p = &scene.primitives[inst.primitive as usize];
        for t in 0..p.triangle_count {
            let base = (p.index_offset + 3 * t) as usize;
            let v = |j: usize| {
                let idx = p.vertex_offset + scene.indices[base + j];
                inst.transform
                    .transform_point3(glam::Vec3::from(scene.vertices[idx as usize].position))
            };
            tris.push(BuildTriangle {
                v: [v(0), v(1), v(2)],
                instance: k as u32,
                primitive: t,
                opaque: p.opaque,
            });
        }
    }
    Bvh::build(&tris, options)
}

/// Which instances are copied into world space and merged into shared BLASes.
///
/// lavapipe (and, less so, hardware) traverses a TLAS of many small instances slowly: the
/// street scene's 882 instances ran camera rays 20× slower than a Cornell box. Instances
/// of primitives up to `FLATTEN_MAX_TRIANGLES` are flattened while the copies stay within
/// `FLATTEN_BUDGET_TRIANGLES`; large meshes keep real instancing, so heavy instancing of
/// big meshes does not multiply memory.
struct FlattenPlan {
    /// Scene instance indices in GPU order: the flattened ones first.
    order: Vec<usize>,
    /// How many of `order` are flattened.
    flattened: usize,
    flattened_vertices: u64,
    /// Ranges of `order` that share one BLAS.
    groups: Vec<std::ops::Range<usize>>,
}

const FLATTEN_MAX_TRIANGLES: u32 = 65_536;
const FLATTEN_BUDGET_TRIANGLES: u64 = 8 << 20;
const FLATTEN_MAX_GEOMETRIES: usize = 1 << 16;

impl FlattenPlan {
    fn new(scene: &Scene) -> FlattenPlan {
        let mut flat = Vec::new();
        let mut rest = Vec::new();
        let (mut triangles, mut vertices) = (0u64, 0u64);
        for (i, inst) in scene.instances.iter().enumerate() {
            let p = &scene.primitives[inst.primitive as usize];
            if p.triangle_count <= FLATTEN_MAX_TRIANGLES
                && triangles + p.triangle_count as u64 <= FLATTEN_BUDGET_TRIANGLES
            {
                triangles += p.triangle_count as u64;
                vertices += p.vertex_count as u64;
                flat.push(i);
            } else {
                rest.push(i);
            }
        }
        // Instances in kd order of their world-space bounds' centres, both the merged
        // geometries and the TLAS instances (see `scene::spatial_order`).
        let centre = |i: usize| {
            let inst = &scene.instances[i];
            let p = &scene.primitives[inst.primitive as usize];
            let (lo, hi) = scene.vertices
                [p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize]
                .iter()
                .map(|v| {
                    inst.transform
                        .transform_point3(glam::Vec3::from(v.position))
                })
                .fold(
                    (
                        glam::Vec3::splat(f32::INFINITY),
                        glam::Vec3::splat(f32::NEG_INFINITY),
                    ),
                    |(lo, hi), w| (lo.min(w), hi.max(w)),
                );
            0.5 * (lo + hi)
        };
        let sorted = |list: Vec<usize>| -> Vec<usize> {
            let centres: Vec<glam::Vec3> = list.iter().map(|&i| centre(i)).collect();
            kd_order(&centres)
                .into_iter()
                .map(|k| list[k as usize])
                .collect()
        };
        let mut flat = sorted(flat);
        let rest = sorted(rest);
        let flattened = flat.len();
        let groups = (0..flattened)
            .step_by(FLATTEN_MAX_GEOMETRIES)
            .map(|s| s..(s + FLATTEN_MAX_GEOMETRIES).min(flattened))
            .collect();
        flat.extend(rest);
        FlattenPlan {
            order: flat,
            flattened,
            flattened_vertices: vertices,
            groups,
        }
    }
}
