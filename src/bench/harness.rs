//! Timed runs: one scene on the device at one image size, methods switched on the same
//! renderer, each configuration measured as a warm-up run (pipelines compiled and the
//! dispatch size calibrated, not recorded) followed by `repeat` recorded runs of the same
//! sample indices with the same seed, so that the repetitions do identical work and
//! their spread is the machine's noise alone.

use super::{BenchError, Result};
use crate::render::run::{run_method, Budget};
use crate::render::session::{self, LoadedScene};
use crate::render::{IterationStats, Method, RenderSettings, RenderStats, Renderer};
use crate::scene::CameraOverride;
use crate::shaders::ShaderSource;
use crate::vk::Device;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Instant;

/// What one recorded run measured.
#[derive(Clone, Debug)]
pub struct RunSample {
    /// Wall seconds of the whole run (training included).
    pub seconds: f64,
    /// Wall seconds of the training phase (guided methods).
    pub training_seconds: f64,
    /// Counters and GPU time over all passes (training included).
    pub stats: RenderStats,
    /// Samples per pixel of the final image (guided methods: the render phase with the
    /// training passes their output keeps, see `GuidedOutput`).
    pub film_spp: u64,
    /// Guided methods: one entry per training iteration.
    pub iterations: Vec<IterationStats>,
    /// The final image's film, when asked for.
    pub image: Option<crate::render::Film>,
    /// Guided methods: the trained tree.
    pub tree: Option<crate::guiding::SdTree>,
}

impl RunSample {
    /// Samples per pixel over all passes.
    pub fn total_spp(&self) -> u64 {
        self.stats.samples
    }

    /// Samples per pixel rendered after training (all of them for unguided methods).
    pub fn render_phase_spp(&self) -> u64 {
        let trained: u64 = self.iterations.iter().map(|i| i.spp).sum();
        self.total_spp().saturating_sub(trained)
    }

    /// GPU seconds of the training passes.
    pub fn training_gpu_seconds(&self) -> f64 {
        self.iterations.iter().map(|i| i.gpu_seconds).sum()
    }

    /// Wall seconds of the render phase (everything after training).
    pub fn render_phase_seconds(&self) -> f64 {
        (self.seconds - self.training_seconds).max(0.0)
    }

    /// GPU seconds of the render phase.
    pub fn render_phase_gpu_seconds(&self) -> f64 {
        (self.stats.gpu_seconds - self.training_gpu_seconds()).max(0.0)
    }
}

/// The settings every bench render starts from: the renderer's defaults (max depth 4,
/// uniform source distribution, M = 32, guiding as the paper) with a fixed seed.
pub fn base_settings(method: Method, width: u32, height: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        method,
        width,
        height,
        seed,
        ..RenderSettings::default()
    }
}

/// A scene loaded on the device with a renderer for one image size.
pub struct Session {
    pub path: PathBuf,
    pub loaded: LoadedScene,
    pub renderer: Renderer,
    pub width: u32,
    pub height: u32,
    /// Seconds to load the scene and build its device-side data.
    pub setup_seconds: f64,
    cancel: AtomicBool,
}

impl Session {
    /// Load `path` and set up a renderer at `width` × (height from the camera's aspect
    /// unless given) with `settings` (their size is replaced).
    pub fn open(
        device: &Arc<Device>,
        shaders: &ShaderSource,
        path: &Path,
        width: u32,
        height: Option<u32>,
        settings: RenderSettings,
    ) -> Result<Session> {
        let started = Instant::now();
        let loaded = session::load_scene(path).map_err(BenchError::Scene)?;
        let camera = session::choose_camera(&loaded.scene, None, &CameraOverride::default())
            .map_err(BenchError::Scene)?;
        let (width, height) = session::resolution(&camera, Some(width), height);
        let renderer = Renderer::new(
            device.clone(),
            &loaded.scene,
            &loaded.lights,
            camera,
            RenderSettings {
                width,
                height,
                ..settings
            },
            shaders.clone(),
        )?;
        Ok(Session {
            path: path.to_path_buf(),
            loaded,
            renderer,
            width,
            height,
            setup_seconds: started.elapsed().as_secs_f64(),
            cancel: AtomicBool::new(false),
        })
    }

    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }

    /// The scene file's name (`street.gltf`).
    pub fn scene_name(&self) -> String {
        self.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.path.display().to_string())
    }

    /// Default settings of `method` at this session's size.
    pub fn settings(&self, method: Method) -> RenderSettings {
        RenderSettings {
            traversal: self.renderer.settings.traversal,
            ..base_settings(method, self.width, self.height, self.renderer.settings.seed)
        }
    }

    /// Switch to `settings` and compile what they need; returns the seconds it took.
    pub fn configure(&mut self, settings: RenderSettings) -> Result<f64> {
        let started = Instant::now();
        self.renderer.set_settings(settings)?;
        self.renderer.prepare()?;
        Ok(started.elapsed().as_secs_f64())
    }

    /// One run of the current settings from sample index `first`.
    pub fn run(&mut self, budget: Budget, first: u64, keep_image: bool) -> Result<RunSample> {
        let out = run_method(&mut self.renderer, budget, first, &self.cancel, &mut |_| {})?;
        let (iterations, tree) = match out.guiding {
            Some(g) => (g.iterations, Some(g.tree)),
            None => (Vec::new(), None),
        };
        Ok(RunSample {
            seconds: out.seconds,
            training_seconds: out.training_seconds,
            stats: out.stats,
            film_spp: out.film.spp,
            iterations,
            image: keep_image.then_some(out.film),
            tree,
        })
    }

    /// Configure `settings`, run `warmup` once unrecorded, then `budget` `repeat` times
    /// from sample 0.
    pub fn measure(
        &mut self,
        settings: RenderSettings,
        warmup: Budget,
        budget: Budget,
        repeat: usize,
    ) -> Result<Vec<RunSample>> {
        let label = describe(&settings);
        let prepare = self.configure(settings)?;
        log::debug!("{label}: pipelines ready in {prepare:.1} s");
        let w = self.run(warmup, 0, false)?;
        log::debug!("{label}: warm-up {:.2} s", w.seconds);
        let mut runs = Vec::with_capacity(repeat);
        for k in 0..repeat.max(1) {
            let r = self.run(budget, 0, false)?;
            log::info!(
                "  {} {label} {budget:?} run {}/{}: {} spp in {:.2} s (GPU {:.2} s)",
                self.scene_name(),
                k + 1,
                repeat.max(1),
                r.total_spp(),
                r.seconds,
                r.stats.gpu_seconds
            );
            runs.push(r);
        }
        Ok(runs)
    }
}

/// `ris (M = 32, depth 4)`-style label of settings, for logs.
pub fn describe(s: &RenderSettings) -> String {
    let mut text = format!("{} depth {}", s.method, s.max_depth);
    if s.method.uses_ris() {
        text += &format!(" M {}", s.ris_candidates);
    }
    if s.strategy != crate::render::Strategy::Mis {
        text += &format!(" {:?}", s.strategy).to_lowercase();
    }
    text
}
