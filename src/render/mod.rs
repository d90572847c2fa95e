//! Rendering: the device-side scene, the path-tracing pipelines of each method, and the
//! loop that dispatches ranges of samples over tiles of the image into an exact film.
//!
//! The film accumulates 64-bit fixed-point sums per pixel and channel; each sample is
//! rounded on its own, so a render split into any ranges of sample indices sums to
//! exactly the same film as a one-shot render. Dispatches are sized from measured times
//! so that no single submission runs much longer than half a second.
//!
//! The pieces: `kernel` (variants, the binding table, pipelines), `dispatch` (the sample
//! loop and per-pixel traces), `readback` (film, AOVs, outliers, counters),
//! `guide_buffers` (the SD-tree's arrays on the device), `gpu_scene` (the scene's
//! buffers and acceleration structures); `run`/`guided` run a method under a budget.

mod budget;
mod bvh;
mod dispatch;
mod film;
mod gpu_scene;
mod guide_buffers;
mod guided;
mod kernel;
mod light_reuse;
mod light_visibility;
mod limits;
pub mod output;
mod pass_output;
mod pixel_emitters;
mod readback;
pub mod run;
pub mod runner;
pub mod session;
mod settings;
pub mod trace;
pub mod traversal;

pub use film::Film;
pub use gpu_scene::{BvhStats, GpuScene};
pub use guide_buffers::GuideBuffers;
pub use guided::{train, GuidingOutcome, IterationStats, Training, TrainingPlan};
pub use readback::Outlier;
pub use settings::{
    GuidedOutput, GuidingSettings, LightMix, LightReuse, LightSource, LightVisibility, Method,
    RenderSettings, SettingsError, Strategy, DEFAULT_GUIDE_HISTORY, DEFAULT_REUSE_CAP,
    DEFAULT_REUSE_CELL_PIXELS, DEFAULT_VISIBILITY_CELL_PIXELS, DEFAULT_VISIBILITY_FLOOR,
};
pub use traversal::{Traversal, TraversalChoice, TraversalKind};

use crate::gpu;
use crate::lights::LightTable;
use crate::scene::{Camera, Projection, Scene};
use crate::shaders::ShaderSource;
use crate::vk::{self, Buffer, ComputePipeline, DescriptorSet, Device};
use ash::vk as raw;
use kernel::Variant;
use std::collections::HashMap;
use std::sync::Arc;

/// Errors while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vulkan(#[from] vk::VkError),
    #[error(transparent)]
    Shader(#[from] crate::shaders::ShaderError),
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error(transparent)]
    NoRayQueries(#[from] traversal::NoRayQueries),
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T> = std::result::Result<T, RenderError>;

/// Counters the kernel keeps, summed over a render.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct RenderStats {
    pub samples: u64,
    pub camera_rays: u64,
    pub bounce_rays: u64,
    pub shadow_rays: u64,
    /// Probes of bounce rays whose origin moved along their line (`bounce_origin` in
    /// shaders_glsl/inc/trace.glsl): short segments traced before the bounce ray with
    /// ray queries, tested in the bounce ray's own walk of the tree with the software
    /// traversal (where a blocked probe makes its bounce ray count twice in
    /// `bounce_rays`: it is traced again).
    pub probe_rays: u64,
    pub nonfinite_samples: u64,
    /// Samples with a channel above FILM_MAX_SAMPLE, clamped to it in the film.
    pub clamped_samples: u64,
    /// SIMD lane utilisation counters (zero unless rendered with `lane_stats`).
    pub lanes: LaneCounts,
    /// GPU time from timestamp queries (0 when the device has none).
    pub gpu_seconds: f64,
    /// Wall time spent in the dispatch loop.
    pub wall_seconds: f64,
}

impl RenderStats {
    pub fn rays(&self) -> u64 {
        self.camera_rays + self.bounce_rays + self.shadow_rays + self.probe_rays
    }
}

/// What the lane-statistics kernel counts (see `shaders_glsl/inc/lane_stats.glsl`): steps
/// its lanes took in the software traversal loop and in the path loop, and the lane slots
/// of the subgroup steps they took them in.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LaneCounts {
    pub traversal_steps: u64,
    pub traversal_slots: u64,
    pub path_steps: u64,
    pub path_slots: u64,
}

impl LaneCounts {
    /// Share of the traversal loop's lane slots that did work (None: not measured, or
    /// no software traversal).
    pub fn traversal_utilisation(&self) -> Option<f64> {
        (self.traversal_slots > 0)
            .then(|| self.traversal_steps as f64 / self.traversal_slots as f64)
    }

    /// Steps of the software traversal loop (inner nodes and leaves visited) per ray
    /// traced (None: not measured, or no rays).
    pub fn traversal_steps_per_ray(&self, rays: u64) -> Option<f64> {
        (self.traversal_slots > 0 && rays > 0).then(|| self.traversal_steps as f64 / rays as f64)
    }

    /// Share of the path loop's lane slots that did work: a lane whose path ended waits
    /// for the longest path of its subgroup.
    pub fn path_utilisation(&self) -> Option<f64> {
        (self.path_slots > 0).then(|| self.path_steps as f64 / self.path_slots as f64)
    }

    fn add(&mut self, o: &LaneCounts) {
        self.traversal_steps += o.traversal_steps;
        self.traversal_slots += o.traversal_slots;
        self.path_steps += o.path_steps;
        self.path_slots += o.path_slots;
    }
}

/// A scene ready to render on a device.
pub struct Renderer {
    pub device: Arc<Device>,
    pub gpu_scene: GpuScene,
    /// The traversal the kernels use, and why (`settings.traversal` resolved).
    pub traversal: TraversalChoice,
    pub settings: RenderSettings,
    camera: Camera,
    scene_radius: f32,
    light_model_count: u32,
    /// Each light model's probability under power-proportional selection.
    model_power_pmf: Vec<f32>,
    light_triangle_count: u32,
    punctual_count: u32,
    shaders: ShaderSource,
    pipelines: HashMap<Variant, ComputePipeline>,
    set: Option<DescriptorSet>,
    /// The trace kernel and its rays and hits (`trace.rs`); placeholders until used.
    trace_pipeline: Option<ComputePipeline>,
    trace_rays: Buffer,
    trace_hits: Buffer,
    params: Buffer,
    film: Buffer,
    stats: Buffer,
    aov: Buffer,
    outliers: Buffer,
    /// Small emitters seen directly, per pixel (`pixel_emitters.rs`).
    pixel_emitter_offsets: Buffer,
    pixel_emitter_pieces: Buffer,
    pixel_emitter_flags: Buffer,
    /// Whether any pixel has pieces (else the kernel never reads the lists).
    has_pixel_emitters: bool,
    /// Whether any material bounds a solid (the kernels' SOLIDS constant).
    has_solids: bool,
    /// Whether any material has a clearcoat (the kernels' CLEARCOAT constant).
    has_clearcoat: bool,
    /// Whether any material has a sheen (the kernels' SHEEN constant).
    has_sheen: bool,
    /// Whether any material is anisotropic and not Lambertian (the kernels' ANISOTROPY
    /// constant).
    has_anisotropy: bool,
    /// Whether any material transmits diffusely (the kernels' DIFFUSE_TRANSMISSION
    /// constant; a metallic factor of 1 may still be lowered by its texture).
    has_diffuse_transmission: bool,
    /// Whether any material has a thin film (the kernels' IRIDESCENCE constant).
    has_iridescence: bool,
    /// Whether any solid's boundary disperses (the kernels' DISPERSION constant).
    has_dispersion: bool,
    /// Whether every material in use is Lambertian (the kernels' BSDF_KERNEL constant:
    /// `Renderer::bsdf_kernel`).
    only_lambertian: bool,
    guide: GuideBuffers,
    /// World-space light reuse's hash grid (`light_reuse.rs`): two halves of
    /// `reuse_cell_count` cells; a placeholder until a render reuses.
    reuse_cells: Buffer,
    reuse_cell_count: u32,
    /// Dispatch generations since the grid was cleared: generation g writes half g mod 2
    /// and reads the other.
    reuse_generation: u64,
    /// Learned light visibility's table (`light_visibility.rs`): a snapshot half and a
    /// live half of `visibility_slots` entries; a placeholder until a render learns.
    visibility: Buffer,
    visibility_slots: u32,
    /// Samples rendered since the table was cleared (sizes the next dispatches).
    visibility_samples: u64,
    /// A trained SD-tree to render with instead of training (`--load-guiding`).
    pub preloaded_tree: Option<crate::guiding::SdTree>,
    /// Scene bounds (the SD-tree's cube is made from them).
    pub bounds: (glam::Vec3, glam::Vec3),
    /// The scene's content hash (ties saved SD-trees to it).
    pub scene_hash: String,
    /// Samples per full-image dispatch that fit the time target, from measurements.
    seconds_per_sample: Option<f64>,
    /// Samples accumulated in the film, and the first sample index.
    film_spp: u64,
    film_offset: u64,
    /// Pixel index and sample traced by the debug kernel.
    debug_pixel: u32,
    debug_sample: u32,
}

/// A device address as the kernels take it (`uvec2`, GL_EXT_buffer_reference_uvec2):
/// low word first.
fn address_words(address: u64) -> [u32; 2] {
    [address as u32, (address >> 32) as u32]
}

impl Renderer {
    pub fn new(
        device: Arc<Device>,
        scene: &Scene,
        lights: &LightTable,
        camera: Camera,
        settings: RenderSettings,
        shaders: ShaderSource,
    ) -> Result<Renderer> {
        settings.validate()?;
        limits::check_image_size(&device, &settings)?;
        let traversal = settings.traversal.resolve(&device.info)?;
        log::info!("traversal: {} ({})", traversal.kind, traversal.reason);
        let gpu_scene = GpuScene::upload(&device, scene, lights, traversal.kind)?;
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        let trace_rays = Buffer::zeroed(&device, 64, usage, "trace rays (unused)")?;
        let trace_hits = Buffer::zeroed(&device, 64, usage, "trace hits (unused)")?;
        let pixels = settings.width as u64 * settings.height as u64;
        let params = Buffer::zeroed(
            &device,
            std::mem::size_of::<gpu::FrameParams>() as u64,
            usage,
            "frame params",
        )?;
        let film = Buffer::zeroed(&device, pixels * 3 * 8, usage, "film")?;
        let stats = Buffer::zeroed(&device, gpu::STAT_COUNT as u64 * 8, usage, "stats")?;
        let (aov_floats, outlier_floats) = if settings.aovs {
            (
                pixels * gpu::AOV_CHANNELS as u64,
                pixels * gpu::OUTLIER_FLOATS as u64,
            )
        } else {
            (4, 4)
        };
        let aov = Buffer::zeroed(&device, aov_floats * 4, usage, "aovs")?;
        let outliers = Buffer::zeroed(&device, outlier_floats * 4, usage, "outliers")?;
        let guide = GuideBuffers::empty(&device)?;
        let reuse_cells = Buffer::zeroed(&device, 64, usage, "light reuse cells (unused)")?;
        let visibility = Buffer::zeroed(&device, 64, usage, "light visibility (unused)")?;
        let emitters =
            pixel_emitters::build(&camera, settings.width, settings.height, &lights.triangles);
        log::info!(
            "pixel emitters: {} light triangles in {} pieces over {} pixels",
            emitters.triangles,
            emitters.pieces.len(),
            emitters.pixels
        );
        // Empty lists make 16-byte buffers the kernel never reads (`has_pixel_emitters`).
        let pixel_emitter_offsets =
            Buffer::from_slice(&device, &emitters.offsets, usage, "pixel emitter offsets")?;
        let pixel_emitter_pieces =
            Buffer::from_slice(&device, &emitters.pieces, usage, "pixel emitter pieces")?;
        let pixel_emitter_flags =
            Buffer::from_slice(&device, &emitters.flags, usage, "pixel emitter flags")?;

        let mut r = Renderer {
            device,
            gpu_scene,
            traversal,
            settings,
            camera,
            scene_radius: 0.5 * scene.extent(),
            light_model_count: lights.models.len() as u32,
            model_power_pmf: lights.model_alias.iter().map(|a| a.pmf).collect(),
            light_triangle_count: lights.triangles.len() as u32,
            punctual_count: scene.punctual.len() as u32,
            shaders,
            pipelines: HashMap::new(),
            set: None,
            trace_pipeline: None,
            trace_rays,
            trace_hits,
            params,
            film,
            stats,
            aov,
            outliers,
            pixel_emitter_offsets,
            pixel_emitter_pieces,
            pixel_emitter_flags,
            has_pixel_emitters: !emitters.pieces.is_empty(),
            has_solids: scene.materials.iter().any(crate::scene::bounds_solid),
            has_clearcoat: scene.materials.iter().any(|m| m.clearcoat > 0.0),
            has_sheen: scene
                .materials
                .iter()
                .any(|m| m.sheen_color.iter().any(|&c| c > 0.0)),
            has_anisotropy: scene
                .materials
                .iter()
                .any(|m| m.anisotropy_strength > 0.0 && !crate::scene::is_lambertian(m)),
            has_diffuse_transmission: scene.materials.iter().any(|m| m.diffuse_transmission > 0.0),
            has_iridescence: scene.materials.iter().any(|m| m.iridescence > 0.0),
            has_dispersion: scene.materials.iter().any(crate::scene::disperses),
            only_lambertian: scene.only_lambertian(),
            guide,
            reuse_cells,
            reuse_cell_count: 0,
            reuse_generation: 0,
            visibility,
            visibility_slots: 0,
            visibility_samples: 0,
            preloaded_tree: None,
            bounds: (scene.bounds_min, scene.bounds_max),
            scene_hash: scene.hash.clone(),
            seconds_per_sample: None,
            film_spp: 0,
            film_offset: 0,
            debug_pixel: gpu::INVALID_INDEX,
            debug_sample: gpu::INVALID_INDEX,
        };
        log::info!(
            "scene arrays: {} ({})",
            if r.scene_addresses() {
                "through device addresses"
            } else {
                "from the bound storage buffers"
            },
            match r.settings.scene_addresses {
                Some(_) => "asked for",
                None => "auto: addresses on CPU devices",
            }
        );
        log::info!(
            "BSDF: {}",
            match r.bsdf_kernel() {
                gpu::BSDF_KERNEL_LAMBERTIAN =>
                    "every material in use is Lambertian; the kernels take that lobe alone",
                gpu::BSDF_KERNEL_PER_SURFACE => "the Lambertian lobe alone at Lambertian surfaces",
                _ => "the general BSDF everywhere, as asked (--general-bsdf)",
            }
        );
        r.upload_params()?;
        Ok(r)
    }

    fn frame_params(&self) -> gpu::FrameParams {
        let s = &self.settings;
        let (camera_type, tan_half_fov_y, ortho) = match self.camera.projection {
            Projection::Perspective { yfov, .. } => {
                (gpu::CAMERA_PERSPECTIVE, (0.5 * yfov).tan(), [0.0, 0.0])
            }
            Projection::Orthographic { xmag, ymag } => {
                (gpu::CAMERA_ORTHOGRAPHIC, 0.0, [xmag, ymag])
            }
        };

        let g = &self.gpu_scene;
        let (bvh_nodes, bvh_triangles) = g
            .bvh
            .as_ref()
            .map_or((0, 0), |(n, t)| (n.address, t.address));
        let split = address_words;
        gpu::FrameParams {
            camera_to_world: self.camera.rigid_to_world().to_cols_array_2d(),
            camera_type,
            tan_half_fov_y,
            ortho_half_extent: ortho,
            width: s.width,
            height: s.height,
            max_depth: s.max_depth,
            rr_depth: s.rr_depth,
            seed: s.seed,
            light_model_count: self.light_model_count,
            light_triangle_count: self.light_triangle_count,
            punctual_count: self.punctual_count,
            ris_candidates: s.ris_candidates,
            ris_source: match s.source {
                LightSource::Uniform => gpu::RIS_SOURCE_UNIFORM,
                LightSource::Power => gpu::RIS_SOURCE_POWER,
                LightSource::Tree => gpu::RIS_SOURCE_TREE,
            },

            debug_pixel: self.debug_pixel,
            debug_sample: self.debug_sample,
            scene_radius: self.scene_radius,
            strategy: match s.strategy {
                Strategy::Mis => gpu::STRATEGY_MIS,
                Strategy::Nee => gpu::STRATEGY_NEE_ONLY,
                Strategy::Bsdf => gpu::STRATEGY_BSDF_ONLY,
            },
            aov_first_sample: self.film_offset as u32,
            hide_emitters: u32::from(s.hide_emitters),
            emission_rays: s.emission_rays,
            pixel_emitters: u32::from(s.pixel_emitters && self.has_pixel_emitters),
            vertices_address: split(g.vertices.address),
            vertex_colors_address: split(g.vertex_colors.address),
            indices_address: split(g.indices.address),
            instances_address: split(g.instances.address),
            materials_address: split(g.materials.address),
            light_triangles_address: split(g.light_triangles.address),
            light_candidates_address: split(g.light_candidates.address),
            light_models_address: split(g.light_models.address),
            model_alias_address: split(g.model_alias.address),
            triangle_alias_address: split(g.triangle_alias.address),
            punctual_lights_address: split(g.punctual.address),
            triangle_light_index_address: split(g.triangle_light_index.address),
            bvh_nodes_address: split(bvh_nodes),
            bvh_triangles_address: split(bvh_triangles),
            light_tree_address: split(g.light_tree.address),
            light_profiles_address: split(g.light_profiles.address),
            reuse_cells: if s.light_reuse.world {
                self.reuse_cell_count
            } else {
                0
            },
            reuse_cell_pixels: s.light_reuse.cell_pixels,
            reuse_confidence_cap: s.light_reuse.confidence_cap,
            visibility_address: split(if self.scene_addresses() {
                self.visibility.address
            } else {
                0
            }),
            visibility_slots: if s.light_visibility.learned {
                self.visibility_slots
            } else {
                0
            },
            visibility_cell_pixels: s.light_visibility.cell_pixels,
            visibility_floor: s.light_visibility.floor,
            clip_near: self.camera.clip.near,
            clip_far: self.camera.clip.far.min(f32::MAX),
        }
    }

    fn upload_params(&mut self) -> Result<()> {
        let p = self.frame_params();
        self.params.upload(0, bytemuck::bytes_of(&p))?;
        Ok(())
    }

    /// Switch to other settings of the same image size (another method, seed, …).
    pub fn set_settings(&mut self, settings: RenderSettings) -> Result<()> {
        if (settings.width, settings.height, settings.aovs)
            != (
                self.settings.width,
                self.settings.height,
                self.settings.aovs,
            )
        {
            return Err(RenderError::Invalid(
                "set_settings cannot change the image size or AOVs".into(),
            ));
        }
        settings.validate()?;
        if settings.traversal.resolve(&self.device.info)?.kind != self.traversal.kind {
            return Err(RenderError::Invalid(
                "set_settings cannot change the traversal".into(),
            ));
        }
        self.settings = settings;
        // Another method has another cost per sample: measure it again.
        self.seconds_per_sample = None;
        self.upload_params()
    }

    /// The view being rendered.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Replace the guiding buffers (after a refit).
    pub fn set_guide_buffers(&mut self, buffers: GuideBuffers) {
        self.guide = buffers;
        self.set = None;
    }

    pub fn guide_buffers(&self) -> &GuideBuffers {
        &self.guide
    }

    /// Each light model's probability under the settings' source distribution
    /// (`source_model_pmf` in shaders_glsl/inc/lights.glsl).
    pub fn source_model_pmf(&self) -> Vec<f32> {
        match self.settings.source {
            // The tree's probabilities depend on the shading point; the power source's
            // stand in for them where a whole-scene pmf is asked for (the learned light
            // mix's prediction, a heuristic: the kernels use the tree's own).
            LightSource::Power | LightSource::Tree => self.model_power_pmf.clone(),
            LightSource::Uniform => {
                vec![1.0 / self.light_model_count.max(1) as f32; self.light_model_count as usize]
            }
        }
    }

    /// Change the bound guiding buffers in place (the descriptor set is rebuilt).
    pub fn update_guide_buffers(
        &mut self,
        f: impl FnOnce(&mut GuideBuffers, &Arc<Device>) -> crate::vk::Result<()>,
    ) -> crate::vk::Result<()> {
        self.set = None;
        f(&mut self.guide, &self.device)
    }
}
