//! The path-tracing kernel on the device: its variants (one pipeline per combination of
//! specialization constants), its one binding table — from which both the descriptor-set
//! layout and the descriptor writes are made, so the two cannot disagree — and the
//! pipelines' creation and warm-up.

use super::{Renderer, Result};
use crate::gpu;
use crate::vk::{AccelStructure, BindingSpec, Buffer, ComputePipeline, DescriptorSet};
use ash::vk as raw;
use std::time::Instant;

/// Specialization of the render kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct Variant {
    pub ris: bool,
    pub guiding: bool,
    pub training: bool,
    pub aovs: bool,
    /// The debug-printf kernel (per-pixel traces).
    pub debug: bool,
    /// The kernel with SIMD lane-utilisation counters (`settings.lane_stats`).
    pub lanes: bool,
    /// The scene has solids (KHR_materials_volume): refraction and absorption.
    pub solids: bool,
    /// The scene has coated materials (KHR_materials_clearcoat).
    pub clearcoat: bool,
    /// The scene has materials with sheen (KHR_materials_sheen).
    pub sheen: bool,
    /// The scene has anisotropic materials that are not Lambertian
    /// (KHR_materials_anisotropy).
    pub anisotropy: bool,
    /// The scene has diffusely transmitting materials
    /// (KHR_materials_diffuse_transmission).
    pub diffuse_transmission: bool,
    /// The scene has iridescent materials (KHR_materials_iridescence).
    pub iridescence: bool,
    /// The scene has dispersive solids (KHR_materials_dispersion).
    pub dispersion: bool,
    /// Where the kernels take the Lambertian lobe alone (`gpu::BSDF_KERNEL_*`).
    pub bsdf: u32,
    /// World-space light reuse (`light_reuse.rs`; RIS methods).
    pub reuse: bool,
    /// Learned light visibility in RIS's target (`light_visibility.rs`; RIS methods).
    pub visibility: bool,
}

/// Texture slots of the descriptor-set layout come in multiples of this many.
const TEXTURE_SLOT_STEP: usize = 16;

/// The layout's texture slots for a scene with `textures` textures: a multiple of
/// [`TEXTURE_SLOT_STEP`], at least one step. The slot count is part of the pipeline
/// layout, and lavapipe's shader cache keys its compiled kernels by the layout: with the
/// exact count every scene with another number of textures recompiled every kernel
/// variant (10–30 s each), and most of the test suite's time on a fresh machine went to
/// recompiling kernels it already had.
fn texture_slots(textures: usize) -> u32 {
    (textures.div_ceil(TEXTURE_SLOT_STEP).max(1) * TEXTURE_SLOT_STEP) as u32
}

/// The scene's textures padded to [`texture_slots`] with copies of the first, which the
/// kernel never reads (material texture indices stay below the scene's count). Without
/// textures nothing is written: the kernel reads no slot then.
fn padded_texture_slots(
    mut textures: Vec<(raw::ImageView, raw::Sampler)>,
) -> Vec<(raw::ImageView, raw::Sampler)> {
    if let Some(&first) = textures.first() {
        textures.resize(texture_slots(textures.len()) as usize, first);
    }
    textures
}

/// What one binding of the kernel's descriptor set holds.
enum Bound<'a> {
    Buffer(&'a Buffer),
    Accel(&'a AccelStructure),
    Images(Vec<(raw::ImageView, raw::Sampler)>),
}

impl Renderer {
    /// Every binding of the kernel and what is bound there.
    fn binding_table(&self) -> Vec<(u32, Bound<'_>)> {
        let g = &self.gpu_scene;
        let buffers = [
            (gpu::BINDING_PARAMS, &self.params),
            (gpu::BINDING_VERTICES, &g.vertices),
            (gpu::BINDING_VERTEX_COLORS, &g.vertex_colors),
            (gpu::BINDING_INDICES, &g.indices),
            (gpu::BINDING_INSTANCES, &g.instances),
            (gpu::BINDING_MATERIALS, &g.materials),
            (gpu::BINDING_LIGHT_TRIANGLES, &g.light_triangles),
            (gpu::BINDING_LIGHT_CANDIDATES, &g.light_candidates),
            (gpu::BINDING_LIGHT_MODELS, &g.light_models),
            (gpu::BINDING_MODEL_ALIAS, &g.model_alias),
            (gpu::BINDING_TRIANGLE_ALIAS, &g.triangle_alias),
            (gpu::BINDING_LIGHT_TREE, &g.light_tree),
            (gpu::BINDING_PUNCTUAL_LIGHTS, &g.punctual),
            (gpu::BINDING_LIGHT_PROFILES, &g.light_profiles),
            (gpu::BINDING_TRIANGLE_LIGHT_INDEX, &g.triangle_light_index),
            (gpu::BINDING_FILM, &self.film),
            (gpu::BINDING_AOV, &self.aov),
            (gpu::BINDING_STATS, &self.stats),
            (gpu::BINDING_GUIDE_SPATIAL, &self.guide.spatial),
            (gpu::BINDING_GUIDE_LEAVES, &self.guide.leaves),
            (gpu::BINDING_GUIDE_SAMPLING, &self.guide.sampling),
            (gpu::BINDING_GUIDE_TRAINING, &self.guide.training),
            (gpu::BINDING_GUIDE_LIGHTS, &self.guide.lights),
            (
                gpu::BINDING_GUIDE_LIGHT_TRAINING,
                &self.guide.light_training,
            ),
            (gpu::BINDING_GUIDE_SELECTION, &self.guide.selection),
            (gpu::BINDING_OUTLIERS, &self.outliers),
            (gpu::BINDING_TRACE_RAYS, &self.trace_rays),
            (gpu::BINDING_TRACE_HITS, &self.trace_hits),
            (
                gpu::BINDING_PIXEL_EMITTER_OFFSETS,
                &self.pixel_emitter_offsets,
            ),
            (gpu::BINDING_PIXEL_EMITTERS, &self.pixel_emitter_pieces),
            (gpu::BINDING_PIXEL_EMITTER_FLAGS, &self.pixel_emitter_flags),
            (gpu::BINDING_REUSE_CELLS, &self.reuse_cells),
            (gpu::BINDING_LIGHT_VISIBILITY, &self.visibility),
        ];
        let mut table: Vec<(u32, Bound<'_>)> = buffers
            .into_iter()
            .map(|(binding, buffer)| (binding, Bound::Buffer(buffer)))
            .collect();
        // Only the variant's traversal structures: a device without ray queries cannot
        // have an acceleration-structure binding.
        if let Some(tlas) = &g.tlas {
            table.push((gpu::BINDING_TLAS, Bound::Accel(tlas)));
        }
        if let Some((nodes, triangles)) = &g.bvh {
            table.push((gpu::BINDING_BVH_NODES, Bound::Buffer(nodes)));
            table.push((gpu::BINDING_BVH_TRIANGLES, Bound::Buffer(triangles)));
        }
        table.push((
            gpu::BINDING_TEXTURES,
            Bound::Images(padded_texture_slots(g.texture_descriptors())),
        ));
        table
    }

    /// The descriptor-set layout's bindings, from the table.
    pub(super) fn bindings(&self) -> Vec<BindingSpec> {
        self.binding_table()
            .iter()
            .map(|(binding, bound)| match bound {
                Bound::Buffer(_) => BindingSpec::buffer(*binding),
                Bound::Accel(_) => BindingSpec::accel(*binding),
                Bound::Images(images) => BindingSpec::images(*binding, texture_slots(images.len())),
            })
            .collect()
    }

    pub(super) fn pipeline(&mut self, v: Variant) -> Result<()> {
        self.pipelines_for(&[v])
    }

    /// Create the pipelines of `variants` that the renderer does not have yet, each on a
    /// thread of its own: lavapipe translates and optimises a kernel on the calling
    /// thread for 2–6 s even when its machine code is cached, so a guided method's
    /// training and render variants take the time of one.
    fn pipelines_for(&mut self, variants: &[Variant]) -> Result<()> {
        let mut wanted: Vec<Variant> = Vec::new();
        for &v in variants {
            if !self.pipelines.contains_key(&v) && !wanted.contains(&v) {
                wanted.push(v);
            }
        }
        if wanted.is_empty() {
            return Ok(());
        }
        let mut requests = Vec::new();
        for &v in &wanted {
            let spirv = self.shaders.load(&self.traversal.kind.kernel(if v.debug {
                "render_debug"
            } else if v.lanes {
                "render_lanes"
            } else {
                "render"
            }))?;
            let spec = [
                if v.ris {
                    gpu::NEE_RIS
                } else {
                    gpu::NEE_UNIFORM
                },
                v.guiding as u32,
                v.training as u32,
                v.aovs as u32,
                v.solids as u32,
                v.clearcoat as u32,
                v.sheen as u32,
                self.scene_addresses() as u32,
                v.bsdf,
                v.reuse as u32,
                v.visibility as u32,
                v.anisotropy as u32,
                v.diffuse_transmission as u32,
                v.iridescence as u32,
                v.dispersion as u32,
            ];
            let name = format!(
                "render (ris={}, guiding={}, training={}, aovs={}, solids={}, clearcoat={}, sheen={}, anisotropy={}, diffuse_transmission={}, iridescence={}, dispersion={}, bsdf={}, reuse={}, visibility={}, debug={}, lanes={}, traversal={})",
                v.ris, v.guiding, v.training, v.aovs, v.solids, v.clearcoat, v.sheen, v.anisotropy, v.diffuse_transmission, v.iridescence, v.dispersion, v.bsdf, v.reuse, v.visibility, v.debug, v.lanes, self.traversal.kind
            );
            requests.push((v, spirv, spec, name));
        }
        let bindings = self.bindings();
        let device = &self.device;
        let create = |(v, spirv, spec, name): &(Variant, Vec<u32>, [u32; 15], String)| {
            let started = Instant::now();
            let p = ComputePipeline::new(
                device,
                spirv,
                &bindings,
                std::mem::size_of::<gpu::PushConstants>() as u32,
                spec,
                name,
            );
            log::debug!(
                "compiled {name} in {:.1} s",
                started.elapsed().as_secs_f64()
            );
            (*v, p)
        };
        // At most one thread per core: more would only share the cores.
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let made: Vec<_> = if requests.len() == 1 || threads == 1 {
            requests.iter().map(create).collect()
        } else {
            requests
                .chunks(threads)
                .flat_map(|chunk| {
                    std::thread::scope(|scope| {
                        let handles: Vec<_> = chunk
                            .iter()
                            .map(|r| scope.spawn(move || create(r)))
                            .collect();
                        handles
                            .into_iter()
                            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                            .collect::<Vec<_>>()
                    })
                })
                .collect()
        };
        for (v, p) in made {
            self.pipelines.insert(v, p?);
        }
        Ok(())
    }

    pub(super) fn descriptor_set(&mut self, v: Variant) -> Result<raw::DescriptorSet> {
        if let Some(s) = &self.set {
            return Ok(s.raw);
        }
        let set = DescriptorSet::new(&self.device, &self.pipelines[&v])?;
        self.write_scene_descriptors(&set);
        let raw_set = set.raw;
        self.set = Some(set);
        Ok(raw_set)
    }

    /// Write every binding of the table into `set` (a set of a pipeline made with
    /// [`Self::bindings`]).
    pub(super) fn write_scene_descriptors(&self, set: &DescriptorSet) {
        for (binding, bound) in self.binding_table() {
            match bound {
                Bound::Buffer(buffer) => set.write_buffer(binding, buffer),
                Bound::Accel(accel) => set.write_accel(binding, accel),
                Bound::Images(images) => set.write_images(binding, &images),
            }
        }
    }

    /// Whether the kernels read the scene's and the SD-tree's arrays through their
    /// device addresses (specialization constant 7, `SCENE_ADDRESSES` in
    /// inc/scene_data.glsl and inc/guiding_buffers.glsl) rather than
    /// the bound storage buffers: by default on CPU devices, where lavapipe loads a
    /// storage buffer one lane at a time and a buffer reference with a gather (`pt`
    /// 1.1–1.7×, `ris` 1.5–2× as fast); GPUs keep the storage buffers, measured faster on
    /// the H200. `RenderSettings::scene_addresses` overrides it.
    pub(super) fn scene_addresses(&self) -> bool {
        self.settings
            .scene_addresses
            .unwrap_or(self.device.info.kind == raw::PhysicalDeviceType::CPU)
    }

    /// Compile the pipeline(s) the current method needs (pipeline creation can take a
    /// while on lavapipe; call this before timing a render).
    pub fn prepare(&mut self) -> Result<()> {
        let variants = self.method_variants(self.settings.method);
        self.pipelines_for(&variants)?;
        for v in variants {
            // Some drivers (lavapipe) compile at the first dispatch: run an empty one.
            let set = self.descriptor_set(v)?;
            let push = gpu::PushConstants::default();
            let pipeline = &self.pipelines[&v];
            let t = Instant::now();
            self.device.submit(|cmd| {
                pipeline.cmd_dispatch(cmd, set, bytemuck::bytes_of(&push), [1, 1, 1])
            })?;
            log::debug!(
                "{}: first dispatch (driver compile) {:.1} s",
                pipeline.name,
                t.elapsed().as_secs_f64()
            );
        }
        Ok(())
    }

    /// Create, side by side, the pipelines every one of `methods` needs with the current
    /// settings, so that a run switching methods (`compare`) does not wait for each in
    /// turn. [`Self::prepare`] still warms each before it is timed.
    pub fn prepare_methods(&mut self, methods: &[super::Method]) -> Result<()> {
        let variants: Vec<Variant> = methods
            .iter()
            .flat_map(|&m| self.method_variants(m))
            .collect();
        self.pipelines_for(&variants)
    }

    /// The variants `method` renders with under the current settings: its render pass,
    /// and for guided methods the training pass.
    fn method_variants(&self, method: super::Method) -> Vec<Variant> {
        let mut variants = vec![self.variant_of(method, false)];
        if method.uses_guiding() {
            variants.push(self.variant_of(method, true));
        }
        variants
    }

    pub(super) fn variant(&self, training: bool) -> Variant {
        self.variant_of(self.settings.method, training)
    }

    fn variant_of(&self, method: super::Method, training: bool) -> Variant {
        Variant {
            ris: method.uses_ris(),
            guiding: method.uses_guiding(),
            training,
            aovs: self.settings.aovs,
            debug: false,
            lanes: self.settings.lane_stats,
            solids: self.has_solids,
            clearcoat: self.has_clearcoat,
            sheen: self.has_sheen,
            anisotropy: self.has_anisotropy,
            diffuse_transmission: self.has_diffuse_transmission,
            iridescence: self.has_iridescence,
            dispersion: self.has_dispersion,
            bsdf: self.bsdf_kernel(),
            reuse: self.settings.light_reuse.world && method.uses_ris(),
            visibility: self.settings.light_visibility.learned && method.uses_ris(),
        }
    }

    /// Where the kernels take the Lambertian lobe alone (specialization constant 8,
    /// `BSDF_KERNEL` in inc/specialization.glsl; `gpu::BSDF_KERNEL_*`): everywhere when
    /// every material the scene uses is Lambertian (the other lobes compile away), else at
    /// each Lambertian surface (a branch), unless `RenderSettings::lambertian_shortcut` is
    /// off (the general BSDF everywhere). The image is the same bit for bit; on lavapipe
    /// `ris` is 1.08–1.09× as fast on the street and `bistro-night` and 1.14–1.17× on
    /// `cornell-lights`.
    pub fn bsdf_kernel(&self) -> u32 {
        match (self.settings.lambertian_shortcut, self.only_lambertian) {
            (false, _) => gpu::BSDF_KERNEL_GENERAL,
            (true, true) => gpu::BSDF_KERNEL_LAMBERTIAN,
            (true, false) => gpu::BSDF_KERNEL_PER_SURFACE,
        }
    }

    /// Drop the compiled pipelines so the next render loads the kernels again (after
    /// they changed on disk, with a directory shader source).
    pub fn reload_shaders(&mut self) {
        self.device.wait_idle();
        self.set = None;
        self.pipelines.clear();
    }
}
