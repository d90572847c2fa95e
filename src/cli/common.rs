//! Argument groups shared by the commands that render (render, reference, compare,
//! bench), and the setup they all do from them.

use anyhow::{Context, Result};
use lanterna::files::FilePlan;
use lanterna::render::session::{self, DeviceOptions, LoadedScene};
use lanterna::render::{
    GuidedOutput, GuidingSettings, LightMix, LightSource, Method, RenderSettings, Strategy,
};
use lanterna::scene::{Camera, LoadOptions};
use lanterna::shaders::ShaderSource;
use lanterna::vk::DeviceSelector;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// The scene and the view.
#[derive(clap::Args, Clone, Debug)]
pub struct SceneArgs {
    /// glTF 2.0 scene (.gltf or .glb).
    pub scene: PathBuf,
    /// Camera of the file to use, by index or name (default: the first).
    #[arg(long)]
    pub camera: Option<String>,
    /// View from EYE to TARGET, as `ex,ey,ez,tx,ty,tz`, replacing the file's camera.
    #[arg(long, value_name = "EYE,TARGET", value_parser = parse_look_at)]
    pub look_at: Option<[f32; 6]>,
    /// Vertical field of view in degrees (overrides the camera's).
    #[arg(long)]
    pub fov: Option<f32>,
    /// See everything in front of the camera: ignore the file camera's clip planes
    /// (glTF `znear`, `zfar`), which camera rays otherwise honour.
    #[arg(long)]
    pub no_clip_planes: bool,
    /// Image width (default 512, or derived from --height and the camera's aspect).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: from the width and the camera's aspect ratio).
    #[arg(long)]
    pub height: Option<u32>,
    /// Follow buffer and image URIs that lead outside the scene's folder (absolute
    /// paths, `..`, `file:` URIs, symlinks out); by default they are refused.
    #[arg(long)]
    pub allow_outside_uris: bool,
    #[command(flatten)]
    pub version: VersionArgs,
}

impl SceneArgs {
    pub fn load_options(&self) -> LoadOptions {
        self.version.load_options(self.allow_outside_uris)
    }
}

/// Which version of the file to load: the pose of its animations, its material variant.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct VersionArgs {
    /// Pose the scene's animations at this time in seconds (nodes, cameras, lights,
    /// skins and morph weights, and by KHR_animation_pointer materials, light colours
    /// and intensities, fields of view and visibility; keys held before the first and
    /// after the last). Without it (and without --animation) the file's own values are
    /// rendered.
    #[arg(long, value_name = "SECONDS", value_parser = parse_time, allow_negative_numbers = true)]
    pub animation_time: Option<f32>,
    /// Play only this animation, by index or name (default: all of them; with no
    /// --animation-time, at time 0).
    #[arg(long, value_name = "INDEX|NAME")]
    pub animation: Option<String>,
    /// Render this material variant of the file (KHR_materials_variants), by name or
    /// index; primitives it does not map keep their own materials (default: every
    /// primitive's own material).
    #[arg(long, value_name = "NAME|INDEX")]
    pub variant: Option<String>,
}

impl VersionArgs {
    /// The loader's options for this version, following outside URIs or not.
    pub fn load_options(&self, allow_outside_uris: bool) -> LoadOptions {
        let posed = self.animation_time.is_some() || self.animation.is_some();
        LoadOptions {
            allow_outside_uris,
            pose: posed.then(|| lanterna::scene::Pose {
                time: self.animation_time.unwrap_or(0.0),
                animation: self.animation.clone(),
            }),
            variant: self.variant.clone(),
        }
    }
}

fn parse_time(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(t) if t.is_finite() => Ok(t),
        Ok(t) => Err(format!("{t} is not a finite number of seconds")),
        Err(e) => Err(format!("`{s}`: {e}")),
    }
}

fn parse_look_at(s: &str) -> Result<[f32; 6], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    v.try_into()
        .map_err(|_| "expected six numbers: ex,ey,ez,tx,ty,tz".to_string())
        .and_then(|a: [f32; 6]| {
            if a.iter().all(|x| x.is_finite()) {
                Ok(a)
            } else {
                Err("numbers must be finite".into())
            }
        })
}

/// The device and the kernels.
#[derive(clap::Args, Clone, Debug)]
pub struct DeviceArgs {
    /// Vulkan device by index or name substring (see `lanterna info`); default: the best
    /// capable one, hardware GPUs before lavapipe.
    #[arg(long, default_value = "auto")]
    pub device: DeviceSelector,
    /// Turn on Vulkan validation layers (also LANTERNA_VALIDATION=1).
    #[arg(long)]
    pub validation: bool,
    /// Compile the GLSL kernels from this directory at run time instead of using the
    /// SPIR-V built into the binary (for shader debugging).
    #[arg(long, value_name = "DIR")]
    pub shader_dir: Option<PathBuf>,
}

impl DeviceArgs {
    pub fn options(&self) -> DeviceOptions {
        DeviceOptions {
            selector: self.device.clone(),
            validation: self.validation,
            debug_printf: false,
        }
    }

    pub fn shaders(&self) -> ShaderSource {
        match &self.shader_dir {
            Some(d) => ShaderSource::Directory(d.clone()),
            None => ShaderSource::Builtin,
        }
    }
}

/// The estimator.
#[derive(clap::Args, Clone, Debug)]
pub struct MethodArgs {
    /// pt: NEE from the light source distribution; ris: NEE by streaming RIS; guided:
    /// SD-tree path guiding with pt's NEE; guided-ris: guiding trained by RIS NEE.
    #[arg(long, default_value = "pt")]
    pub method: Method,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
}

impl MethodArgs {
    /// The settings of these options, the image size still to be set (see `prepare`).
    pub fn settings(&self) -> RenderSettings {
        self.estimator.settings(self.method, 0, 0)
    }
}

/// Options shared by all methods.
#[derive(clap::Args, Clone, Debug)]
pub struct EstimatorArgs {
    /// Maximum path length in segments, counted like Mitsuba's max_depth: 1 renders only
    /// emitters seen directly, 2 adds direct lighting, 3 one bounce of indirect light, …
    #[arg(long, default_value_t = 4)]
    pub max_depth: u32,
    /// Russian roulette from this path segment on (0 = off).
    #[arg(long, default_value_t = 0)]
    pub rr_depth: u32,
    /// Seed of the random numbers (the image is a deterministic function of it).
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Light source distribution for NEE and RIS candidates.
    #[arg(long, alias = "ris-source", value_enum, default_value = "uniform")]
    pub source: LightSource,
    /// RIS candidates per NEE (M).
    #[arg(long, default_value_t = 32)]
    pub ris_candidates: u32,
    /// Guiding: a fixed probability of sampling the BSDF instead of the SD-tree
    /// everywhere; without it each SD-tree leaf learns its own (from 0.5, Müller et
    /// al. 2019).
    #[arg(long)]
    pub bsdf_fraction: Option<f32>,
    /// Guiding: how each SD-tree leaf learns its BSDF selection probability: the
    /// minimiser of each training pass's second-moment estimate, weighted by the
    /// records behind it (variance), or Adam on the KL divergence (kl-adam, Müller et
    /// al. 2019's reference implementation).
    #[arg(long, value_enum, default_value = "variance")]
    pub selection_learner: lanterna::guiding::SelectionLearner,
    /// Guiding: what radiance the SD-tree learns: all incident light (with NEE's light
    /// samples, the paper's; the default), indirect light only, or what the direction
    /// estimator carries (MIS-weighted emission plus indirect).
    #[arg(long, value_enum, default_value = "all")]
    pub guide_target: lanterna::guiding::GuideTarget,
    /// Guiding: the quadtrees follow the target's mean (radiance, Müller et al.) or
    /// the square root of its second moment (variance-aware, Rath et al. 2020).
    #[arg(long, value_enum, default_value = "radiance")]
    pub guide_density: lanterna::guiding::GuideDensity,
    /// Guiding: weight of the earlier training iterations' statistics in each refit of
    /// the SD-tree, per record, against the iteration just finished: 0 rebuilds every
    /// tree from the last iteration alone (Müller et al.), 1 from every training record
    /// so far, equally (quadtrees and learned light tables).
    #[arg(long, default_value_t = lanterna::render::DEFAULT_GUIDE_HISTORY)]
    pub guide_history: f32,
    /// Guiding: share of the budget (spp, or time with --time) spent training.
    #[arg(long, default_value_t = 0.3)]
    pub train_fraction: f32,
    /// Guiding: do not record NEE contributions in the SD-tree (guiding then learns
    /// direct light from direction-sampled hits alone).
    #[arg(long)]
    pub no_record_nee: bool,
    /// Direct light from NEE and direction sampling combined by MIS, or from one of them
    /// alone (a debugging switch: all three converge to the same image).
    #[arg(long, value_enum, default_value = "mis")]
    pub strategy: Strategy,
    /// Emitters seen directly by the camera contribute nothing (Mitsuba's
    /// `hide_emitters`); the light they cast still counts.
    #[arg(long)]
    pub hide_emitters: bool,
    /// Camera rays per sample: the path continues from the first; the others, each at
    /// its own stratified position in the pixel, add only the emission they see directly.
    /// Cuts the pixel-coverage noise of small emitters in view (string lights, lamps) at
    /// the cost of a camera ray each (README, Rendering); 1 is the plain estimator. The
    /// camera positions are indexed K × sample index in 32 bits: beyond sample 2³²/K they
    /// repeat earlier samples' positions.
    #[arg(long, default_value_t = 1)]
    pub emission_rays: u32,
    /// Leave small emitters seen directly to the camera rays. By default, emissive
    /// triangles whose image is at most 16 pixels are sampled inside each pixel they cover:
    /// one ray per sample reaches them, without the coverage noise of sub-pixel lamps
    /// (README, Rendering).
    #[arg(long)]
    pub no_pixel_emitters: bool,
    /// Guiding: c in the spatial split threshold c·√(spp of the next iteration / 4)
    /// (Müller et al.'s 12000), for a 1280×720 image: it is scaled by the square root of
    /// the image's pixel count relative to that, since records per leaf scale with it.
    #[arg(long, default_value_t = 12000.0)]
    pub guiding_threshold: f32,
    /// Guiding: memory cap of the SD-tree in MiB (splits stop before it is exceeded).
    #[arg(long, default_value_t = 256)]
    pub guiding_memory: u64,
    /// Guiding: spatial filter of the training records.
    #[arg(long, value_enum, default_value = "nearest")]
    pub spatial_filter: SpatialFilterArg,
    /// Guiding: directional filter of the training records.
    #[arg(long, value_enum, default_value = "box")]
    pub directional_filter: DirectionalFilterArg,
    /// Guiding: which passes make the image: every pass, training and render phase,
    /// every sample weighted equally (unbiased, exact film sums over the whole range of
    /// sample indices; the default), the render phase with the last four training
    /// passes, the render phase alone, or all passes weighted by their inverse
    /// estimated variance (Müller et al.'s option; consistent rather than unbiased, and
    /// the EXR then has no exact film sums).
    #[arg(long, value_enum, default_value = "all-passes")]
    pub guided_output: GuidedOutput,
    /// Guiding (the default): learn, per SD-tree leaf, which lights deliver NEE
    /// contributions (and so are visible and bright there), and choose lights from a
    /// mixture of the source distribution and the learned table (visibility-aware light
    /// selection). Kept for scripts; `--no-learn-lights` turns it off.
    #[arg(long, overrides_with = "no_learn_lights")]
    pub learn_lights: bool,
    /// Guiding: choose lights from the source distribution alone, as the paper does.
    #[arg(long, overrides_with = "learn_lights")]
    pub no_learn_lights: bool,
    /// Guiding with learned light selection: probability of choosing the light from the
    /// leaf's table instead of the source distribution. A number: that, everywhere;
    /// `learned`: each SD-tree leaf chooses its own between passes (from 0.5), the one
    /// that minimises the predicted variance of its one-sample NEE; `auto`: learned for
    /// `guided`, 0.5 for `guided-ris` (measured better there).
    #[arg(long, value_name = "auto|learned|P", default_value = "auto", value_parser = LightMix::parse)]
    pub light_mix: LightMix,
    /// Ray traversal: the device's ray queries, or the kernels' own traversal of a BVH
    /// built on the CPU; auto takes software on CPU devices (lavapipe, where it is
    /// faster) and on devices without ray queries, ray queries on GPUs.
    #[arg(long, value_enum, default_value = "auto")]
    pub traversal: lanterna::render::Traversal,
    /// How the kernels read the scene's and the SD-tree's arrays: through their device
    /// addresses or through the bound storage buffers. auto: addresses on CPU devices
    /// (lavapipe loads a storage buffer one lane at a time, a buffer reference with one
    /// gather), bound buffers on GPUs (measured faster on the H200). Same image.
    #[arg(long, value_enum, default_value = "auto")]
    pub scene_arrays: SceneArraysArg,
    /// Keep the general BSDF everywhere (by default the kernels take the Lambertian lobe
    /// alone at Lambertian surfaces, and compile it alone where every material in use is
    /// Lambertian: faster, the same image). For measurements.
    #[arg(long)]
    pub general_bsdf: bool,
    /// World-space light reuse (ris, guided-ris): each RIS vertex also considers the
    /// light sample that a vertex of an earlier sample left in a cell of a hash grid
    /// over the scene near it, combined by generalized RIS (unbiased); off by default.
    #[arg(long, value_enum, default_value = "off")]
    pub light_reuse: LightReuseArg,
    /// World-space light reuse: a cell's edge in pixel footprints at its distance from
    /// the camera.
    #[arg(long, default_value_t = lanterna::render::DEFAULT_REUSE_CELL_PIXELS)]
    pub reuse_cell_pixels: f32,
    /// World-space light reuse: the most earlier reservoirs a reused one stands for
    /// against the vertex's own.
    #[arg(long, default_value_t = lanterna::render::DEFAULT_REUSE_CAP)]
    pub reuse_cap: f32,
    /// Learned light visibility (ris, guided-ris): RIS's target also weighs each light
    /// by how often shadow rays from near the shading point found it unoccluded in
    /// earlier dispatches (unbiased: the shadow ray still decides); off by default.
    #[arg(long, value_enum, default_value = "off")]
    pub light_visibility: LightVisibilityArg,
    /// Learned light visibility: a cell's edge in pixel footprints at its distance from
    /// the camera.
    #[arg(long, default_value_t = lanterna::render::DEFAULT_VISIBILITY_CELL_PIXELS)]
    pub visibility_cell_pixels: f32,
    /// Learned light visibility: the least factor it gives a light, in (0, 1].
    #[arg(long, default_value_t = lanterna::render::DEFAULT_VISIBILITY_FLOOR)]
    pub visibility_floor: f32,
}

/// `--light-visibility`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LightVisibilityArg {
    Off,
    /// Unoccluded fractions per light model, counted in a hash grid in world space.
    Learned,
}

/// `--light-reuse`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LightReuseArg {
    Off,
    /// Reservoirs of earlier samples, shared through a hash grid in world space.
    World,
}

/// `--scene-arrays`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneArraysArg {
    Auto,
    Addresses,
    Bound,
}

/// `--spatial-filter`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SpatialFilterArg {
    /// Stochastic box: jitter the record within the leaf's size.
    Jitter,
    Nearest,
}

/// `--directional-filter`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum DirectionalFilterArg {
    /// Splat over a box the size of the quadtree cell the direction falls in (shared by
    /// area among the cells of that size it overlaps).
    Box,
    Nearest,
}

impl EstimatorArgs {
    /// The settings these options ask for (not validated yet: `common::prepare` and
    /// the renderer do that).
    pub fn settings(&self, method: Method, width: u32, height: u32) -> RenderSettings {
        use lanterna::guiding::{DirectionalFilter, SpatialFilter};
        let mut settings = RenderSettings {
            method,
            width,
            height,
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            seed: self.seed,
            source: self.source,
            ris_candidates: self.ris_candidates,
            strategy: self.strategy,
            hide_emitters: self.hide_emitters,
            emission_rays: self.emission_rays,
            pixel_emitters: !self.no_pixel_emitters,
            guiding: GuidingSettings {
                bsdf_fraction: self.bsdf_fraction.unwrap_or(0.5),
                learn_selection: self.bsdf_fraction.is_none(),
                selection_learner: self.selection_learner,
                target: self.guide_target,
                density: self.guide_density,
                history: self.guide_history,
                train_fraction: self.train_fraction,
                record_nee: !self.no_record_nee,
                spatial_filter: match self.spatial_filter {
                    SpatialFilterArg::Jitter => SpatialFilter::StochasticBox,
                    SpatialFilterArg::Nearest => SpatialFilter::Nearest,
                },
                directional_filter: match self.directional_filter {
                    DirectionalFilterArg::Box => DirectionalFilter::Box,
                    DirectionalFilterArg::Nearest => DirectionalFilter::Nearest,
                },
                spatial_threshold: self.guiding_threshold,
                memory_cap_bytes: self.guiding_memory.saturating_mul(1 << 20),
                // The last of --learn-lights / --no-learn-lights wins; neither: on.
                learn_lights: self.learn_lights || !self.no_learn_lights,
                output: self.guided_output,
                ..GuidingSettings::default()
            },
            traversal: self.traversal,
            scene_addresses: match self.scene_arrays {
                SceneArraysArg::Auto => None,
                SceneArraysArg::Addresses => Some(true),
                SceneArraysArg::Bound => Some(false),
            },
            lambertian_shortcut: !self.general_bsdf,
            light_reuse: lanterna::render::LightReuse {
                world: self.light_reuse == LightReuseArg::World,
                cell_pixels: self.reuse_cell_pixels,
                confidence_cap: self.reuse_cap,
            },
            light_visibility: lanterna::render::LightVisibility {
                learned: self.light_visibility == LightVisibilityArg::Learned,
                cell_pixels: self.visibility_cell_pixels,
                floor: self.visibility_floor,
            },
            ..RenderSettings::default()
        };
        settings.guiding.set_light_mix(self.light_mix);
        settings
    }
}

/// Load the scene and choose the view: the camera and the image size.
pub fn load(args: &SceneArgs) -> Result<(LoadedScene, Camera, u32, u32)> {
    let loaded = session::load_scene_with(&args.scene, &args.load_options())?;
    let view = session::ViewOptions {
        camera: args.camera.clone(),
        look_at: args.look_at,
        fov: args.fov,
        no_clip_planes: args.no_clip_planes,
        width: args.width,
        height: args.height,
    };
    let (camera, w, h) = session::choose_view(&loaded.scene, &view)
        .with_context(|| format!("{}: cannot set up the view", args.scene.display()))?;
    Ok((loaded, camera, w, h))
}

/// What a rendering command starts from: the scene, the view, and the settings completed
/// with the view's size and fov and validated (the one check every command goes through;
/// the renderer repeats it).
pub fn prepare(
    args: &SceneArgs,
    mut settings: RenderSettings,
) -> Result<(LoadedScene, Camera, RenderSettings)> {
    settings.fov_degrees = args.fov;
    let (loaded, camera, width, height) = load(args)?;
    settings.width = width;
    settings.height = height;
    settings.validate()?;
    Ok((loaded, camera, settings))
}

/// Refuses a run whose outputs include one of its inputs (the scene, the files its
/// URIs name, `inputs`) or the same file twice, before anything is rendered.
pub fn check_outputs(
    scene: &SceneArgs,
    loaded: &LoadedScene,
    inputs: &[(&str, &Path)],
    outputs: &[(&str, &Path)],
) -> Result<()> {
    let mut plan = FilePlan::new();
    plan.input("the scene", &scene.scene)
        .inputs("a file the scene uses", &loaded.scene.files);
    for (what, path) in inputs {
        plan.input(what, path);
    }
    for (what, path) in outputs {
        plan.output(what, path);
    }
    Ok(plan.check()?)
}

static CANCELLED: AtomicBool = AtomicBool::new(false);

/// Exit status of a run stopped by SIGINT, SIGTERM or SIGHUP that wrote its partial
/// result (render: the image of the samples finished; reference: its checkpoint):
/// EX_TEMPFAIL, "try again" — `reference --resume` continues where it stopped.
pub const EXIT_INTERRUPTED_SAVED: u8 = 75;
/// Exit status of a run interrupted before anything could be written (or by a second
/// signal, which exits at once): 128 + SIGINT, as shells report it.
pub const EXIT_INTERRUPTED_NOTHING: u8 = 130;

/// A run ended by a signal; `main` turns it into one of the two exit statuses above.
#[derive(Debug, thiserror::Error)]
pub enum Interrupted {
    /// The partial result was written; the text says what and where.
    #[error("interrupted: {0}")]
    Saved(String),
    #[error("interrupted before the first sample finished; nothing written")]
    Nothing,
}

/// SIGINT (Ctrl-C), SIGTERM (what cluster schedulers send at the time limit) and SIGHUP
/// stop the render at the next chunk boundary, and what is consistent is still written;
/// a second signal exits at once without writing.
pub fn cancel_flag() -> &'static AtomicBool {
    static INSTALLED: std::sync::Once = std::sync::Once::new();
    INSTALLED.call_once(|| {
        let installed = ctrlc::set_handler(|| {
            if CANCELLED.swap(true, Ordering::SeqCst) {
                eprintln!("\ninterrupted twice: exiting without writing");
                // _exit, not exit: exit runs the Vulkan driver's teardown, which can crash
                // while a dispatch is in flight on its worker threads (the run then died
                // by a signal instead of exiting with the documented status).
                unsafe { libc::_exit(i32::from(EXIT_INTERRUPTED_NOTHING)) }
            }
            eprintln!(
                "\ninterrupted: finishing the current chunk and writing what has been rendered"
            );
        });
        if let Err(e) = installed {
            log::warn!("cannot handle interruption signals ({e}): they will end the run at once");
        }
    });
    &CANCELLED
}

/// Make sure an output's directory exists.
pub fn ensure_parent(path: &std::path::Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create directory {}", dir.display()))?;
    }
    Ok(())
}

/// Metadata every render's EXR carries (see `lanterna::render::output::render_meta`).
pub fn render_meta(
    settings: &RenderSettings,
    scene: &SceneArgs,
    loaded: &lanterna::scene::Scene,
    device: &lanterna::vk::Device,
) -> lanterna::image_io::RenderMeta {
    lanterna::render::output::render_meta(
        settings,
        &scene.scene.display().to_string(),
        loaded,
        &device.info.name,
    )
}

/// The image a run outputs (see `lanterna::render::output::outcome_image`).
pub fn outcome_image(
    out: &lanterna::render::run::RunOutcome,
    width: u32,
    height: u32,
    meta: lanterna::image_io::RenderMeta,
) -> anyhow::Result<lanterna::image_io::Image> {
    Ok(lanterna::render::output::outcome_image(
        out, width, height, meta,
    )?)
}
