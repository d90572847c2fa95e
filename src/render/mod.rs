//! Rendering: the device-side scene, the path-tracing pipelines of each method, and the
//! loop that dispatches ranges of samples over tiles of the image into an exact film.
//!
//! The film accumulates 64-bit fixed-point sums per pixel and channel; each sample is
//! rounded on its own, so a render split into any ranges of sample indices sums to
//! exactly the same film as a one-shot render. Dispatches are sized from measured times
//! so that no single submission runs much longer than half a second.

mod film;
mod gpu_scene;
mod guided;
mod limits;
pub mod output;
pub mod run;
pub mod runner;
pub mod session;
mod settings;

pub use film::Film;
pub use gpu_scene::GpuScene;
pub use guided::{train, GuidingOutcome, IterationStats, Training, TrainingPlan};
pub use settings::{
    GuidedOutput, GuidingSettings, LightSource, Method, RenderSettings, SettingsError, Strategy,
};

use crate::gpu;
use crate::lights::LightTable;
use crate::scene::{Camera, Projection, Scene};
use crate::shaders::ShaderSource;
use crate::vk::{self, BindingSpec, Buffer, ComputePipeline, DescriptorSet, Device};
use ash::vk as raw;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Errors while rendering.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(transparent)]
    Vulkan(#[from] vk::VkError),
    #[error(transparent)]
    Shader(#[from] crate::shaders::ShaderError),
    #[error(transparent)]
    Settings(#[from] SettingsError),
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
    pub nonfinite_samples: u64,
    /// Samples with a channel above FILM_MAX_SAMPLE, clamped to it in the film.
    pub clamped_samples: u64,
    /// GPU time from timestamp queries (0 when the device has none).
    pub gpu_seconds: f64,
    /// Wall time spent in the dispatch loop.
    pub wall_seconds: f64,
}

impl RenderStats {
    pub fn rays(&self) -> u64 {
        self.camera_rays + self.bounce_rays + self.shadow_rays
    }
}

/// Specialization of the render kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Variant {
    ris: bool,
    guiding: bool,
    training: bool,
    aovs: bool,
    /// The debug-printf kernel (per-pixel traces).
    debug: bool,
}

/// The largest single-sample contribution seen at a pixel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Outlier {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
    pub luminance: f32,
    pub rgb: [f32; 3],
}

/// Buffers bound at the guiding bindings (the SD-tree's flat arrays).
pub struct GuideBuffers {
    pub spatial: Buffer,
    pub leaves: Buffer,
    pub sampling: Buffer,
    pub training: Buffer,
    /// Nodes in the training buffer (for the read-back).
    pub training_nodes: usize,
    /// Learned light tables and their training copy.
    pub lights: Buffer,
    pub light_training: Buffer,
    pub light_slots: usize,
    /// Records of the learned selection probability (GuideSelectionHead, then records);
    /// a head with capacity 0 unless `with_selection_records` made room.
    pub selection: Buffer,
    pub selection_capacity: u32,
}

/// A zero-capacity selection head: the kernel appends nothing.
fn empty_selection(device: &Arc<Device>) -> vk::Result<Buffer> {
    Buffer::zeroed(
        device,
        64,
        raw::BufferUsageFlags::STORAGE_BUFFER,
        "guide selection records (none)",
    )
}

impl GuideBuffers {
    /// Placeholders for methods that do not guide (a zero header, nothing else).
    pub fn empty(device: &Arc<Device>) -> vk::Result<GuideBuffers> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(GuideBuffers {
            spatial: Buffer::zeroed(device, 64, usage, "guide spatial (unused)")?,
            leaves: Buffer::zeroed(device, 64, usage, "guide leaves (unused)")?,
            sampling: Buffer::zeroed(device, 64, usage, "guide sampling (unused)")?,
            training: Buffer::zeroed(device, 64, usage, "guide training (unused)")?,
            training_nodes: 0,
            lights: Buffer::zeroed(device, 64, usage, "guide lights (unused)")?,
            light_training: Buffer::zeroed(device, 64, usage, "guide light training (unused)")?,
            light_slots: 0,
            selection: empty_selection(device)?,
            selection_capacity: 0,
        })
    }

    /// Upload an SD-tree's arrays.
    pub fn upload(
        device: &Arc<Device>,
        arrays: &crate::guiding::GuideArrays,
    ) -> vk::Result<GuideBuffers> {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
        Ok(GuideBuffers {
            spatial: Buffer::from_slice(
                device,
                &arrays.spatial_buffer(),
                usage,
                "guide spatial tree",
            )?,
            leaves: Buffer::from_slice(device, &arrays.leaves, usage, "guide leaves")?,
            sampling: Buffer::from_slice(
                device,
                &arrays.sampling,
                usage,
                "guide sampling quadtrees",
            )?,
            training: Buffer::from_slice(
                device,
                &arrays.training,
                usage | raw::BufferUsageFlags::TRANSFER_SRC,
                "guide training quadtrees",
            )?,
            training_nodes: arrays.training.len(),
            lights: Buffer::from_slice(device, &arrays.lights, usage, "guide light tables")?,
            light_training: Buffer::from_slice(
                device,
                &arrays.light_training,
                usage | raw::BufferUsageFlags::TRANSFER_SRC,
                "guide light training",
            )?,
            light_slots: arrays.light_training.len(),
            selection: empty_selection(device)?,
            selection_capacity: 0,
        })
    }

    /// Make room for `capacity` selection records, each guided direction sample being
    /// recorded with probability `rate` (a training pass of the learned selection).
    pub fn with_selection_records(
        mut self,
        device: &Arc<Device>,
        capacity: u32,
        rate: f32,
    ) -> vk::Result<GuideBuffers> {
        let head = gpu::GuideSelectionHead {
            count: 0,
            capacity,
            rate,
            pad: 0,
        };
        let record = std::mem::size_of::<gpu::GuideSelectionRecord>();
        // Only the head needs contents: records are read up to its count.
        self.selection = Buffer::zeroed(
            device,
            (std::mem::size_of_val(&head) + record * capacity as usize) as u64,
            raw::BufferUsageFlags::STORAGE_BUFFER,
            "guide selection records",
        )?;
        self.selection.upload(0, bytemuck::bytes_of(&head))?;
        self.selection_capacity = capacity;
        Ok(self)
    }

    /// Read the selection records a pass appended (at most the capacity).
    pub fn read_selection(&self) -> vk::Result<Vec<gpu::GuideSelectionRecord>> {
        if self.selection_capacity == 0 {
            return Ok(Vec::new());
        }
        let head: gpu::GuideSelectionHead = self.selection.read(1)?[0];
        let n = head.count.min(self.selection_capacity) as usize;
        let head_bytes = std::mem::size_of::<gpu::GuideSelectionHead>();
        let record = std::mem::size_of::<gpu::GuideSelectionRecord>();
        let bytes = self
            .selection
            .read_bytes((head_bytes + n * record) as u64)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes[head_bytes..]))
    }

    /// Read the light training tables back after a pass.
    pub fn read_light_training(&self) -> vk::Result<Vec<gpu::GuideLightSlot>> {
        self.light_training.read(self.light_slots)
    }

    /// Read the training quadtrees back after a pass.
    pub fn read_training(&self) -> vk::Result<Vec<gpu::GuideQuadNode>> {
        self.training.read(self.training_nodes)
    }
}

/// A scene ready to render on a device.
pub struct Renderer {
    pub device: Arc<Device>,
    pub gpu_scene: GpuScene,
    pub settings: RenderSettings,
    camera: Camera,
    scene_radius: f32,
    light_model_count: u32,
    light_triangle_count: u32,
    punctual_count: u32,
    shaders: ShaderSource,
    pipelines: HashMap<Variant, ComputePipeline>,
    set: Option<DescriptorSet>,
    params: Buffer,
    film: Buffer,
    stats: Buffer,
    aov: Buffer,
    outliers: Buffer,
    guide: GuideBuffers,
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

/// Target duration of one submission (a GPU watchdog and Ctrl-C both want it short).
const TARGET_SUBMIT_SECONDS: f64 = 0.5;

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
        let gpu_scene = GpuScene::upload(&device, scene, lights)?;
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER;
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

        let mut r = Renderer {
            device,
            gpu_scene,
            settings,
            camera,
            scene_radius: 0.5 * scene.extent(),
            light_model_count: lights.models.len() as u32,
            light_triangle_count: lights.triangles.len() as u32,
            punctual_count: scene.punctual.len() as u32,
            shaders,
            pipelines: HashMap::new(),
            set: None,
            params,
            film,
            stats,
            aov,
            outliers,
            guide,
            preloaded_tree: None,
            bounds: (scene.bounds_min, scene.bounds_max),
            scene_hash: scene.hash.clone(),
            seconds_per_sample: None,
            film_spp: 0,
            film_offset: 0,
            debug_pixel: gpu::INVALID_INDEX,
            debug_sample: gpu::INVALID_INDEX,
        };
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
        self.settings = settings;
        // Another method has another cost per sample: measure it again.
        self.seconds_per_sample = None;
        self.upload_params()
    }

    /// Replace the guiding buffers (after a refit).
    pub fn set_guide_buffers(&mut self, buffers: GuideBuffers) {
        self.guide = buffers;
        self.set = None;
    }

    pub fn guide_buffers(&self) -> &GuideBuffers {
        &self.guide
    }

    fn bindings(&self) -> Vec<BindingSpec> {
        let mut b: Vec<BindingSpec> = [
            gpu::BINDING_PARAMS,
            gpu::BINDING_VERTICES,
            gpu::BINDING_INDICES,
            gpu::BINDING_INSTANCES,
            gpu::BINDING_MATERIALS,
            gpu::BINDING_LIGHT_TRIANGLES,
            gpu::BINDING_LIGHT_MODELS,
            gpu::BINDING_MODEL_ALIAS,
            gpu::BINDING_TRIANGLE_ALIAS,
            gpu::BINDING_PUNCTUAL_LIGHTS,
            gpu::BINDING_TRIANGLE_LIGHT_INDEX,
            gpu::BINDING_FILM,
            gpu::BINDING_AOV,
            gpu::BINDING_STATS,
            gpu::BINDING_GUIDE_SPATIAL,
            gpu::BINDING_GUIDE_LEAVES,
            gpu::BINDING_GUIDE_SAMPLING,
            gpu::BINDING_GUIDE_TRAINING,
            gpu::BINDING_GUIDE_LIGHTS,
            gpu::BINDING_GUIDE_LIGHT_TRAINING,
            gpu::BINDING_GUIDE_SELECTION,
            gpu::BINDING_OUTLIERS,
        ]
        .into_iter()
        .map(BindingSpec::buffer)
        .collect();
        b.push(BindingSpec::accel(gpu::BINDING_TLAS));
        b.push(BindingSpec::images(
            gpu::BINDING_TEXTURES,
            self.gpu_scene.textures.len() as u32,
        ));
        b
    }

    fn pipeline(&mut self, v: Variant) -> Result<()> {
        if self.pipelines.contains_key(&v) {
            return Ok(());
        }
        let spirv = self
            .shaders
            .load(if v.debug { "render_debug" } else { "render" })?;
        let spec = [
            if v.ris {
                gpu::NEE_RIS
            } else {
                gpu::NEE_UNIFORM
            },
            v.guiding as u32,
            v.training as u32,
            v.aovs as u32,
        ];
        let started = Instant::now();
        let name = format!(
            "render (ris={}, guiding={}, training={}, aovs={}, debug={})",
            v.ris, v.guiding, v.training, v.aovs, v.debug
        );
        let p = ComputePipeline::new(
            &self.device,
            &spirv,
            &self.bindings(),
            std::mem::size_of::<gpu::PushConstants>() as u32,
            &spec,
            &name,
        )?;
        log::debug!(
            "compiled {name} in {:.1} s",
            started.elapsed().as_secs_f64()
        );
        self.pipelines.insert(v, p);
        Ok(())
    }

    fn descriptor_set(&mut self, v: Variant) -> Result<raw::DescriptorSet> {
        if let Some(s) = &self.set {
            return Ok(s.raw);
        }
        let pipeline = &self.pipelines[&v];
        let set = DescriptorSet::new(&self.device, pipeline)?;
        let g = &self.gpu_scene;
        set.write_accel(gpu::BINDING_TLAS, &g.tlas);
        for (binding, buffer) in [
            (gpu::BINDING_PARAMS, &self.params),
            (gpu::BINDING_VERTICES, &g.vertices),
            (gpu::BINDING_INDICES, &g.indices),
            (gpu::BINDING_INSTANCES, &g.instances),
            (gpu::BINDING_MATERIALS, &g.materials),
            (gpu::BINDING_LIGHT_TRIANGLES, &g.light_triangles),
            (gpu::BINDING_LIGHT_MODELS, &g.light_models),
            (gpu::BINDING_MODEL_ALIAS, &g.model_alias),
            (gpu::BINDING_TRIANGLE_ALIAS, &g.triangle_alias),
            (gpu::BINDING_PUNCTUAL_LIGHTS, &g.punctual),
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
        ] {
            set.write_buffer(binding, buffer);
        }
        set.write_images(gpu::BINDING_TEXTURES, &g.texture_descriptors());
        let raw_set = set.raw;
        self.set = Some(set);
        Ok(raw_set)
    }

    /// Compile the pipeline(s) the current method needs (pipeline creation can take a
    /// while on lavapipe; call this before timing a render).
    pub fn prepare(&mut self) -> Result<()> {
        let mut variants = vec![self.variant(false)];
        if self.settings.method.uses_guiding() {
            variants.push(self.variant(true));
        }
        for v in variants {
            self.pipeline(v)?;
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

    fn variant(&self, training: bool) -> Variant {
        Variant {
            ris: self.settings.method.uses_ris(),
            guiding: self.settings.method.uses_guiding(),
            training,
            aovs: self.settings.aovs,
            debug: false,
        }
    }

    /// Drop the compiled pipelines so the next render loads the kernels again (after
    /// they changed on disk, with a directory shader source).
    pub fn reload_shaders(&mut self) {
        self.device.wait_idle();
        self.set = None;
        self.pipelines.clear();
    }

    /// Samples per pixel in the film.
    pub fn film_spp(&self) -> u64 {
        self.film_spp
    }

    /// Clear the film (and its sample count), the AOVs and the outliers.
    pub fn clear_film(&mut self) -> Result<()> {
        self.film.fill_zero()?;
        self.aov.fill_zero()?;
        self.outliers.fill_zero()?;
        self.film_spp = 0;
        self.film_offset = 0;
        Ok(())
    }

    /// Mean AOV channels per pixel (`AOV_CHANNELS` floats each), when `settings.aovs`.
    pub fn aovs(&self) -> Result<Vec<f32>> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let mut a: Vec<f32> = self.aov.read(pixels * gpu::AOV_CHANNELS as usize)?;
        let n = self.film_spp.max(1) as f32;
        for px in a.chunks_exact_mut(gpu::AOV_CHANNELS as usize) {
            for (c, v) in px.iter_mut().enumerate() {
                if c != gpu::AOV_SELECTED_LIGHT as usize {
                    *v /= n;
                }
            }
        }
        Ok(a)
    }

    /// The `n` pixels with the largest single-sample contributions, largest first.
    pub fn outliers(&self, n: usize) -> Result<Vec<Outlier>> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let raw: Vec<f32> = self.outliers.read(pixels * gpu::OUTLIER_FLOATS as usize)?;
        let mut list: Vec<Outlier> = raw
            .chunks_exact(gpu::OUTLIER_FLOATS as usize)
            .enumerate()
            .filter(|(_, o)| o[0] > 0.0)
            .map(|(i, o)| Outlier {
                x: (i % self.settings.width as usize) as u32,
                y: (i / self.settings.width as usize) as u32,
                sample: o[1].to_bits(),
                luminance: o[0],
                rgb: [o[2], o[3], o[4]],
            })
            .collect();
        list.sort_by(|a, b| b.luminance.total_cmp(&a.luminance));
        list.truncate(n);
        Ok(list)
    }

    /// Render samples [begin, begin + count) of pixel (x, y) alone with the debug kernel,
    /// printing a trace of every path vertex of sample `traced` (all when None) through
    /// debug printf; returns the printed lines (the device must have been opened with
    /// debug printf). The film then holds that pixel's samples.
    pub fn trace_pixel(
        &mut self,
        x: u32,
        y: u32,
        begin: u64,
        count: u64,
        traced: Option<u32>,
    ) -> Result<Vec<String>> {
        if x >= self.settings.width || y >= self.settings.height {
            return Err(RenderError::Invalid(format!(
                "pixel ({x}, {y}) is outside the {}×{} image",
                self.settings.width, self.settings.height
            )));
        }
        if !self.device.instance.debug_printf {
            return Err(RenderError::Invalid(
                "per-pixel traces need the validation layer's debug printf (package vulkan-validationlayers)".into(),
            ));
        }
        self.debug_pixel = y * self.settings.width + x;
        self.debug_sample = traced.unwrap_or(gpu::INVALID_INDEX);
        self.clear_film()?;
        self.film_offset = begin;
        self.upload_params()?;
        let mut v = self.variant(false);
        v.debug = true;
        self.pipeline(v)?;
        let set = self.descriptor_set(v)?;
        crate::vk::take_debug_printf_messages();
        let pipeline = &self.pipelines[&v];
        let push = gpu::PushConstants {
            tile_origin: [x, y],
            tile_size: [1, 1],
            sample_begin: begin as u32,
            sample_count: count as u32,
        };
        self.device
            .submit(|cmd| pipeline.cmd_dispatch(cmd, set, bytemuck::bytes_of(&push), [1, 1, 1]))?;
        self.film_spp = count;
        self.debug_pixel = gpu::INVALID_INDEX;
        self.debug_sample = gpu::INVALID_INDEX;
        self.upload_params()?;
        Ok(crate::vk::take_debug_printf_messages())
    }

    /// Render sample indices [begin, begin + count) into the film. `training` records
    /// guiding data (guided methods). Stops early, at a chunk boundary, when `cancel` is
    /// set; returns the number of samples rendered.
    pub fn render_samples(
        &mut self,
        begin: u64,
        count: u64,
        training: bool,
        cancel: &AtomicBool,
        progress: &mut dyn FnMut(u64),
        stats: &mut RenderStats,
    ) -> Result<u64> {
        self.render_until(begin, Some(count), None, training, cancel, progress, stats)
    }

    /// Render from sample index `begin` until `count` samples are done or `deadline`
    /// passes (checked between chunks; every pixel always has the same sample count).
    #[allow(clippy::too_many_arguments)]
    pub fn render_until(
        &mut self,
        begin: u64,
        count: Option<u64>,
        deadline: Option<Instant>,
        training: bool,
        cancel: &AtomicBool,
        progress: &mut dyn FnMut(u64),
        stats: &mut RenderStats,
    ) -> Result<u64> {
        if begin + count.unwrap_or(0) > u32::MAX as u64 {
            return Err(RenderError::Invalid(
                "sample indices beyond 2^32 are not supported".into(),
            ));
        }
        let v = self.variant(training);
        self.pipeline(v)?;
        let set = self.descriptor_set(v)?;
        if self.film_spp == 0 && self.film_offset != begin {
            self.film_offset = begin;
            self.upload_params()?;
        }
        let (w, h) = (self.settings.width, self.settings.height);
        let started = Instant::now();
        let mut done = 0u64;
        while count.is_none_or(|c| done < c) {
            if cancel.load(Ordering::SeqCst) || deadline.is_some_and(|d| Instant::now() >= d) {
                break;
            }
            // Size the chunk: bands of rows × samples per dispatch near the target time.
            let (bands, spp) = match self.seconds_per_sample {
                None => (((w as u64 * h as u64) / 65536).max(1) as u32, 1u32),
                Some(t) if t > TARGET_SUBMIT_SECONDS => {
                    ((t / TARGET_SUBMIT_SECONDS).ceil() as u32, 1)
                }
                Some(t) => (
                    1,
                    ((TARGET_SUBMIT_SECONDS / t.max(1e-6)).floor() as u32).clamp(1, 256),
                ),
            };
            let mut spp = spp as u64;
            if let Some(c) = count {
                spp = spp.min(c - done);
            }
            if let (Some(d), Some(t)) = (deadline, self.seconds_per_sample) {
                // Do not overshoot the time budget by more than one sample's worth.
                let left = d.saturating_duration_since(Instant::now()).as_secs_f64();
                spp = spp.min(((left / t).ceil() as u64).max(1));
            }
            let bands = bands.min(h);
            let band_rows = h.div_ceil(bands);
            let chunk_started = Instant::now();
            let pipeline = &self.pipelines[&v];
            for band in 0..bands {
                let y0 = band * band_rows;
                if y0 >= h {
                    break;
                }
                let rows = band_rows.min(h - y0);
                let push = gpu::PushConstants {
                    tile_origin: [0, y0],
                    tile_size: [w, rows],
                    sample_begin: (begin + done) as u32,
                    sample_count: spp as u32,
                };
                let (_, gpu_time) = self.device.submit_timed(
                    |cmd| {
                        pipeline.cmd_dispatch(
                            cmd,
                            set,
                            bytemuck::bytes_of(&push),
                            [w.div_ceil(8), rows.div_ceil(8), 1],
                        )
                    },
                    true,
                )?;
                stats.gpu_seconds += gpu_time.unwrap_or(0.0);
            }
            let elapsed = chunk_started.elapsed().as_secs_f64();
            self.seconds_per_sample = Some(elapsed / spp as f64);
            done += spp;
            self.film_spp += spp;
            progress(done);
        }
        self.collect_stats(stats)?;
        stats.samples += done;
        stats.wall_seconds += started.elapsed().as_secs_f64();
        Ok(done)
    }

    fn collect_stats(&mut self, stats: &mut RenderStats) -> Result<()> {
        let counters: Vec<u64> = self.stats.read(gpu::STAT_COUNT as usize)?;
        stats.camera_rays += counters[gpu::STAT_CAMERA_RAYS as usize];
        stats.bounce_rays += counters[gpu::STAT_BOUNCE_RAYS as usize];
        stats.shadow_rays += counters[gpu::STAT_SHADOW_RAYS as usize];
        stats.nonfinite_samples += counters[gpu::STAT_NONFINITE_SAMPLES as usize];
        stats.clamped_samples += counters[gpu::STAT_CLAMPED_SAMPLES as usize];
        self.stats.fill_zero()?;
        Ok(())
    }

    /// Read the film back.
    pub fn film(&self) -> Result<Film> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        let sums: Vec<u64> = self.film.read(pixels * 3)?;
        Ok(Film {
            width: self.settings.width,
            height: self.settings.height,
            spp: self.film_spp,
            sample_offset: self.film_offset,
            sums,
        })
    }

    /// Replace the film's contents (resuming a checkpoint).
    pub fn load_film(&mut self, film: &Film) -> Result<()> {
        if film.width != self.settings.width || film.height != self.settings.height {
            return Err(RenderError::Invalid(
                "film size does not match the render size".into(),
            ));
        }
        self.film.upload(0, bytemuck::cast_slice(&film.sums))?;
        self.film_spp = film.spp;
        self.film_offset = film.sample_offset;
        Ok(())
    }
}
