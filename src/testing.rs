//! Support for the test suite: a shared device with validation on, and a runner for the
//! small test kernels in `shaders_glsl/tests/` (real GLSL on the device, statistics in
//! Rust). Test kernels bind three storage buffers (TEST_BINDING_IN, _OUT, _AUX) and take
//! up to 128 bytes of push constants.

use crate::gpu;
use crate::shaders::ShaderSource;
use crate::vk::{
    self, BindingSpec, Buffer, ComputePipeline, DescriptorSet, Device, DeviceSelector, Instance,
    InstanceOptions,
};
use ash::vk as raw;
use std::sync::{Arc, OnceLock};

/// One device per test process, with validation layers on.
pub fn device() -> Arc<Device> {
    static DEVICE: OnceLock<Arc<Device>> = OnceLock::new();
    DEVICE
        .get_or_init(|| {
            let instance = Instance::new(&InstanceOptions {
                validation: true,
                debug_printf: false,
            })
            .expect("Vulkan instance (run scripts/setup)");
            Device::new(Arc::new(instance), &DeviceSelector::Auto).expect("a Vulkan device")
        })
        .clone()
}

/// A Python that imports mitsuba, for the peer checks against Mitsuba 3: the first of
/// `LANTERNA_PYTHON`, the project's `.cache/venv` (where `scripts/setup --mitsuba`
/// installs it) and `python3` that can; None when none can. Looked up once per process.
pub fn mitsuba_python() -> Option<&'static std::path::Path> {
    static FOUND: OnceLock<Option<std::path::PathBuf>> = OnceLock::new();
    FOUND
        .get_or_init(|| {
            let mut candidates = Vec::new();
            if let Ok(p) = std::env::var("LANTERNA_PYTHON") {
                candidates.push(std::path::PathBuf::from(p));
            }
            candidates.push(
                std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".cache/venv/bin/python"),
            );
            candidates.push(std::path::PathBuf::from("python3"));
            candidates.into_iter().find(|p| {
                std::process::Command::new(p)
                    .args(["-c", "import mitsuba"])
                    .output()
                    .is_ok_and(|o| o.status.success())
            })
        })
        .as_deref()
}

/// Fail if the validation layer reported any error so far in this process.
pub fn assert_no_validation_errors() {
    let n = vk::validation_error_count();
    assert_eq!(
        n, 0,
        "{n} Vulkan validation error(s) were reported (see the log above)"
    );
}

/// Run test kernel `name` (e.g. `tests/reservoir`) over `invocations` (x dimension,
/// local size 64), with `input` and `aux` bound as read buffers and an output buffer of
/// `output_bytes`, returned after the run.
pub fn run_kernel(
    name: &str,
    input: &[u8],
    aux: &[u8],
    output_bytes: usize,
    push: &[u8],
    invocations: u32,
) -> vk::Result<Vec<u8>> {
    let zeros = vec![0u8; output_bytes];
    let mut out = dispatch(
        name,
        &[
            (gpu::TEST_BINDING_IN, input),
            (gpu::TEST_BINDING_OUT, &zeros),
            (gpu::TEST_BINDING_AUX, aux),
        ],
        push,
        invocations,
    )?;
    Ok(out.swap_remove(1))
}

/// Run test kernel `name` over `invocations` (local size 64) with one storage buffer per
/// `(binding, initial contents)`; returns every buffer's contents after the run, in order.
/// The kernel comes from [`shader_source`], so `LANTERNA_TEST_SHADER_DIR` reaches it.
pub fn dispatch(
    name: &str,
    buffers: &[(u32, &[u8])],
    push: &[u8],
    invocations: u32,
) -> vk::Result<Vec<Vec<u8>>> {
    let device = device();
    let spirv = shader_source()
        .load(name)
        .map_err(|e| vk::VkError::Other(e.to_string()))?;
    let bindings: Vec<BindingSpec> = buffers
        .iter()
        .map(|(b, _)| BindingSpec::buffer(*b))
        .collect();
    let pipeline = ComputePipeline::new(&device, &spirv, &bindings, 128, &[], name)?;
    let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_SRC;
    let gpu_buffers: Vec<Buffer> = buffers
        .iter()
        .map(|(b, data)| {
            let data = if data.is_empty() {
                vec![0u8; 16]
            } else {
                data.to_vec()
            };
            Buffer::from_slice(&device, &data, usage, &format!("test binding {b}"))
        })
        .collect::<vk::Result<_>>()?;
    let set = DescriptorSet::new(&device, &pipeline)?;
    for ((b, _), buffer) in buffers.iter().zip(&gpu_buffers) {
        set.write_buffer(*b, buffer);
    }
    let mut push_bytes = [0u8; 128];
    push_bytes[..push.len()].copy_from_slice(push);
    device.submit(|cmd| {
        pipeline.cmd_dispatch(cmd, set.raw, &push_bytes, [invocations.div_ceil(64), 1, 1])
    })?;
    buffers
        .iter()
        .zip(&gpu_buffers)
        .map(|((_, data), buffer)| buffer.read_bytes(data.len().max(16) as u64))
        .collect()
}

// ---- image statistics ------------------------------------------------------------------

use crate::lights::LightTable;
use crate::render::{RenderSettings, RenderStats, Renderer};
use crate::scene::{Camera, Scene};
use std::sync::atomic::AtomicBool;

/// A render split into independent batches (disjoint ranges of sample indices): the
/// spread of the batch means estimates the variance of the estimator.
pub struct Batches {
    pub width: u32,
    pub height: u32,
    /// Mean linear RGB of each batch, row-major.
    pub images: Vec<Vec<f32>>,
}

/// A renderer on the test device with the kernels of [`shader_source`].
fn test_renderer(scene: &Scene, camera: &Camera, settings: &RenderSettings) -> Renderer {
    test_renderer_on(device(), scene, camera, settings)
}

/// A renderer on `device` with the kernels of [`shader_source`].
pub fn test_renderer_on(
    device: Arc<Device>,
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
) -> Renderer {
    let lights = LightTable::build(scene).expect("light table");
    Renderer::new(
        device,
        scene,
        &lights,
        camera.clone(),
        settings.clone(),
        shader_source(),
    )
    .expect("renderer")
}

/// A renderer on the test device after rendering samples [0, `spp`) with `settings`, and
/// the render's counters (the film holds those samples).
pub fn render_once(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    spp: u64,
) -> (Renderer, RenderStats) {
    let mut r = test_renderer(scene, camera, settings);
    let mut stats = RenderStats::default();
    r.render_samples(
        0,
        spp,
        false,
        &AtomicBool::new(false),
        &mut |_| {},
        &mut stats,
    )
    .expect("render");
    (r, stats)
}

/// The SD-tree a guided method trains with `settings` over a budget of `spp` samples per
/// pixel, training passes included, as `lanterna render` trains it.
pub fn trained_tree(
    scene: &Scene,
    camera: &Camera,
    settings: &RenderSettings,
    spp: u64,
) -> crate::guiding::SdTree {
    use crate::render::run::{run_method, Budget};
    let mut r = test_renderer(scene, camera, settings);
    let out = run_method(
        &mut r,
        Budget::Spp(spp),
        0,
        &AtomicBool::new(false),
        &mut |_| {},
    )
    .expect("render");
    out.guiding.expect("a guided method").tree
}

/// The kernels tests render with: built in, or, when `LANTERNA_TEST_SHADER_DIR` names a
/// copy of `shaders_glsl/`, compiled from it — the way to inject a defect into the
/// estimators and see which tests fail, without rebuilding.
pub fn shader_source() -> ShaderSource {
    match std::env::var_os("LANTERNA_TEST_SHADER_DIR") {
        Some(dir) => ShaderSource::Directory(dir.into()),
        None => ShaderSource::Builtin,
    }
}

/// Render `batches` × `spp` samples with `settings`.
pub fn render_batches(
    scene: &Scene,
    camera: &Camera,
    settings: RenderSettings,
    batches: u32,
    spp: u64,
) -> Batches {
    render_batches_on(device(), scene, camera, settings, batches, spp)
}

/// [`render_batches`] on a given device (e.g. one created with ray queries hidden).
pub fn render_batches_on(
    device: Arc<Device>,
    scene: &Scene,
    camera: &Camera,
    settings: RenderSettings,
    batches: u32,
    spp: u64,
) -> Batches {
    let mut r = test_renderer_on(device, scene, camera, &settings);
    let cancel = AtomicBool::new(false);
    let mut stats = RenderStats::default();
    let mut images = Vec::new();
    for b in 0..batches as u64 {
        r.clear_film().unwrap();
        r.clear_light_visibility().unwrap();
        r.render_samples(b * spp, spp, false, &cancel, &mut |_| {}, &mut stats)
            .expect("render");
        images.push(r.film().unwrap().mean());
    }
    assert_eq!(
        stats.nonfinite_samples, 0,
        "the kernel produced non-finite samples"
    );
    Batches {
        width: settings.width,
        height: settings.height,
        images,
    }
}

impl Batches {
    /// Per block of `block`×`block` pixels and channel: the batch means.
    pub fn block_estimates(&self, block: u32) -> Vec<Vec<f64>> {
        let bx = self.width.div_ceil(block);
        let by = self.height.div_ceil(block);
        let mut out = vec![vec![0.0; self.images.len()]; (bx * by * 3) as usize];
        let mut counts = vec![0.0; (bx * by) as usize];
        for y in 0..self.height {
            for x in 0..self.width {
                counts[((y / block) * bx + x / block) as usize] += 1.0;
            }
        }
        for (k, img) in self.images.iter().enumerate() {
            for y in 0..self.height {
                for x in 0..self.width {
                    let b = ((y / block) * bx + x / block) as usize;
                    let p = ((y * self.width + x) * 3) as usize;
                    for c in 0..3 {
                        out[b * 3 + c][k] += img[p + c] as f64 / counts[b];
                    }
                }
            }
        }
        out
    }

    /// The image mean of each batch, per channel.
    pub fn channel_means(&self) -> Vec<[f64; 3]> {
        self.images
            .iter()
            .map(|img| {
                let mut s = [0.0; 3];
                for px in img.chunks(3) {
                    for c in 0..3 {
                        s[c] += px[c] as f64;
                    }
                }
                s.map(|x| x / (img.len() / 3) as f64)
            })
            .collect()
    }

    /// Mean over all batches.
    pub fn mean(&self) -> Vec<f64> {
        let n = self.images.len() as f64;
        let mut m = vec![0.0; self.images[0].len()];
        for img in &self.images {
            for (a, &b) in m.iter_mut().zip(img) {
                *a += b as f64 / n;
            }
        }
        m
    }

    /// The variance of one batch's pixel value (each channel's, from the spread of the
    /// batches), averaged over pixels and channels: what a method's noise is at this
    /// batch size.
    pub fn mean_pixel_variance(&self) -> f64 {
        let mean = self.mean();
        let n = self.images.len() as f64;
        mean.iter()
            .enumerate()
            .map(|(i, &m)| {
                self.images
                    .iter()
                    .map(|img| (img[i] as f64 - m).powi(2))
                    .sum::<f64>()
                    / (n - 1.0)
            })
            .sum::<f64>()
            / mean.len() as f64
    }

    /// The whole image's mean over batches, pixels and channels.
    pub fn image_mean(&self) -> f64 {
        let means = self.channel_means();
        means.iter().flatten().sum::<f64>() / (3 * means.len()) as f64
    }

    /// Estimates of the mean over a rectangle (x0, y0, w, h), one per batch, per channel.
    pub fn region_estimates(&self, x0: u32, y0: u32, w: u32, h: u32) -> [Vec<f64>; 3] {
        let mut out = [Vec::new(), Vec::new(), Vec::new()];
        for img in &self.images {
            let mut s = [0.0f64; 3];
            for y in y0..y0 + h {
                for x in x0..x0 + w {
                    let p = ((y * self.width + x) * 3) as usize;
                    for c in 0..3 {
                        s[c] += img[p + c] as f64;
                    }
                }
            }
            for c in 0..3 {
                out[c].push(s[c] / (w * h) as f64);
            }
        }
        out
    }

    /// The pixel least likely under a closed form: `expected` holds, per pixel
    /// (row-major), the closed form by a fine quadrature and by a coarser one. Each pixel
    /// and channel is a t-test of the batch estimates against the fine value; a pixel
    /// also passes within the film's arithmetic precision and four times the
    /// quadrature's own error (its change from the coarse to the fine). Returns the
    /// smallest p of the pixels that do not pass that way (1 if none) and where it is.
    pub fn worst_pixel_against(&self, expected: &[([f64; 3], [f64; 3])]) -> (f64, String) {
        assert_eq!(expected.len(), (self.width * self.height) as usize);
        let mut worst = (1.0f64, String::new());
        for y in 0..self.height {
            for x in 0..self.width {
                let (fine, coarse) = expected[(y * self.width + x) as usize];
                let est = self.region_estimates(x, y, 1, 1);
                for c in 0..3 {
                    let (m, v) = crate::stats::mean_var(&est[c]);
                    let p = crate::stats::t_test_against(&est[c], fine[c]);
                    let slack = 1.0 / gpu::FILM_FIXED_SCALE as f64
                        + 1e-5 * fine[c]
                        + 4.0 * (fine[c] - coarse[c]).abs();
                    if (m - fine[c]).abs() > slack && p < worst.0 {
                        let se = (v / est[c].len() as f64).sqrt();
                        worst = (
                            p,
                            format!(
                                "pixel ({x}, {y}) channel {c}: {m:.5} ± {se:.5} vs {:.5}",
                                fine[c]
                            ),
                        );
                    }
                }
            }
        }
        worst
    }
}

/// Welch tests of the whole image's mean, per channel, between two sets of batches of the
/// same image: an error that scales the whole image (a weight, a missing term) shows here
/// first. `what` names the comparison in the failure message.
pub fn assert_same_image_mean(a: &Batches, b: &Batches, alpha: f64, what: &str) {
    let wa = a.region_estimates(0, 0, a.width, a.height);
    let wb = b.region_estimates(0, 0, b.width, b.height);
    for c in 0..3 {
        let p = crate::stats::welch(&wa[c], &wb[c]);
        let (ma, mb) = (
            crate::stats::mean_var(&wa[c]).0,
            crate::stats::mean_var(&wb[c]).0,
        );
        assert!(
            p > alpha,
            "{what}: image means {ma} vs {mb} (channel {c}), p = {p:.2e}"
        );
    }
}

/// Mann–Whitney's rank-sum test ([`crate::stats::mann_whitney`]) of the whole image's
/// mean per channel, batch against batch, at `alpha` per channel: for an estimator whose
/// defect shows as batches that are nearly all bright and a few enormously so, which
/// Welch's test reads as noise. It holds its level only where both sides' batch means
/// are symmetric about their expectation: on a plane 0.3 m under a 1 m quad, light reuse
/// with one RIS candidate correlates a batch's pixels so much that its batch means are
/// skewed (median below the mean), and clean runs were rejected at p = 10⁻⁶. `what`
/// names the comparison in the failure message.
pub fn assert_same_image_ranks(a: &Batches, b: &Batches, alpha: f64, what: &str) {
    let wa = a.region_estimates(0, 0, a.width, a.height);
    let wb = b.region_estimates(0, 0, b.width, b.height);
    for c in 0..3 {
        let p = crate::stats::mann_whitney(&wa[c], &wb[c]);
        let median = |x: &[f64]| {
            let mut v = x.to_vec();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        assert!(
            p > alpha,
            "{what}: image means rank apart (channel {c}): medians {} vs {}, p = {p:.2e}",
            median(&wa[c]),
            median(&wb[c])
        );
    }
}

/// Two renders agree in expectation, block by block ([`assert_same_expectation`], family
/// level `alpha`) and in the whole image's mean per channel ([`assert_same_image_mean`],
/// `mean_alpha` per channel). `what` names the comparison. Returns the smallest block
/// p-value.
pub fn assert_agree(
    a: &Batches,
    b: &Batches,
    block: u32,
    alpha: f64,
    mean_alpha: f64,
    what: &str,
) -> f64 {
    let p = assert_same_expectation(a, b, block, alpha);
    assert_same_image_mean(a, b, mean_alpha, what);
    p
}

/// Asserts that `better` renders `t` with less noise than `base`: its per-pixel variance
/// ([`Batches::mean_pixel_variance`], `batches` of `spp` each) below `bound` times
/// `base`'s. For estimators whose efficiency no agreement test can see (a worse choice
/// stays unbiased). Where both settings are [`repeatable`] the ratio moves only when the
/// code changes what they draw; a fresh draw's bound must leave room for its spread
/// between runs.
pub fn assert_lowers_variance(
    t: &TestScene,
    base: RenderSettings,
    better: RenderSettings,
    batches: u32,
    spp: u64,
    bound: f64,
    what: &str,
) {
    let variance = |s| render_batches(&t.scene, &t.camera, s, batches, spp).mean_pixel_variance();
    let (a, b) = (variance(base), variance(better));
    println!(
        "{what}: per-pixel variance {b:.4e} against {a:.4e} ({:.3}×)",
        b / a
    );
    assert!(
        b < bound * a,
        "{what}: per-pixel variance {b:.4e} is {:.3}× {a:.4e}, not below {bound}×",
        b / a
    );
    assert_no_validation_errors();
}

/// Significance level of a comparison whose renders are [`repeatable`]: the same seed
/// draws the same image, so a test that passes keeps passing until the code changes
/// what it draws, and a false alarm shows once, when it is written.
pub const REPEATABLE_ALPHA: f64 = 1e-3;

/// Family-wise level of the block tests ([`assert_same_expectation`]) of a comparison
/// whose renders are a fresh draw each run (not [`repeatable`]). Every CI run re-rolls
/// such a test, so its level is what it adds to the suite's false alarms per run: about
/// forty such comparisons at 10⁻³ for blocks and per channel for the means failed a
/// sound tree now and then (light reuse on `cornell-lights` at p = 6·10⁻⁴, 2026-11-29).
pub const FRESH_BLOCK_ALPHA: f64 = 1e-4;

/// Per-channel level of the whole image's mean ([`assert_same_image_mean`]) of a
/// comparison whose renders are a fresh draw each run; see [`FRESH_BLOCK_ALPHA`].
pub const FRESH_MEAN_ALPHA: f64 = 1e-5;

/// Whether a render is a function of its settings and seed alone. Not so where lanes
/// learn from what other lanes wrote in the device's order: SD-tree training (the guided
/// methods, float atomics), world-space light reuse (two writers racing for a cell) and
/// learned light visibility (counts shared between dispatches).
pub fn repeatable(settings: &RenderSettings) -> bool {
    !(settings.method.uses_guiding()
        || settings.light_reuse.world
        || settings.light_visibility.learned)
}

/// The (block, image-mean) significance levels for comparing renders of `settings`
/// with a repeatable one: [`REPEATABLE_ALPHA`] for both where `settings` is
/// [`repeatable`], [`FRESH_BLOCK_ALPHA`] and [`FRESH_MEAN_ALPHA`] where it is not.
pub fn levels(settings: &RenderSettings) -> (f64, f64) {
    if repeatable(settings) {
        (REPEATABLE_ALPHA, REPEATABLE_ALPHA)
    } else {
        (FRESH_BLOCK_ALPHA, FRESH_MEAN_ALPHA)
    }
}

/// How many more batches the repeatable `pt` side of [`assert_agrees_with_pt`] renders
/// than the side under test: `pt` is cheap on these small images, and its fixed draw
/// then sits closer to the expectation, so that a fresh draw of the other side is
/// neither flagged more often than its level says (a fixed `pt` mean 1.8 of its standard
/// errors low helped fail a sound light reuse run) nor passed with a bias its own
/// batches could show.
pub const PT_BATCHES_PER_BATCH: u32 = 4;

/// `settings` (any method; guided ones train on each batch's own sample range, as in
/// [`run_batches`]) converges to `pt`'s image of the same size: `batches` independent
/// batches of `spp` against [`PT_BATCHES_PER_BATCH`] times as many of `pt` (seed 21),
/// compared with [`assert_agree`] over 4-pixel blocks at the [`levels`] of `settings`;
/// then no validation errors. Returns both sides' batches (`pt`'s first) for further
/// tests.
pub fn assert_agrees_with_pt(
    t: &TestScene,
    settings: RenderSettings,
    batches: u32,
    spp: u64,
    what: &str,
) -> (Batches, Batches) {
    let mut pt = self::settings(crate::render::Method::Pt, settings.width, settings.height);
    pt.seed = 21;
    let a = render_batches(&t.scene, &t.camera, pt, PT_BATCHES_PER_BATCH * batches, spp);
    let (block_alpha, mean_alpha) = levels(&settings);
    let b = if settings.method.uses_guiding() {
        run_batches(&t.scene, &t.camera, settings, batches, spp)
    } else {
        render_batches(&t.scene, &t.camera, settings, batches, spp)
    };
    assert_agree(&a, &b, 4, block_alpha, mean_alpha, what);
    assert_no_validation_errors();
    (a, b)
}

/// Two renders agree in expectation: Welch's t-test per block and channel, with the
/// family-wise significance `alpha` split over all comparisons (Šidák). Returns the
/// smallest p-value; panics naming the worst block. A bias spread over the whole image
/// hides below the per-block tests' power; [`assert_same_image_mean`] is the check for it.
pub fn assert_same_expectation(a: &Batches, b: &Batches, block: u32, alpha: f64) -> f64 {
    let ea = a.block_estimates(block);
    let eb = b.block_estimates(block);
    let threshold = crate::stats::sidak(alpha, ea.len());
    let mut worst = (1.0f64, 0usize);
    for (i, (x, y)) in ea.iter().zip(&eb).enumerate() {
        // Blocks that are identically zero in both (sky) carry no information.
        if x.iter().chain(y).all(|v| *v == 0.0) {
            continue;
        }
        let p = crate::stats::welch(x, y);
        if p < worst.0 {
            worst = (p, i);
        }
    }
    let (p, i) = worst;
    if p < threshold {
        let bx = a.width.div_ceil(block);
        let (blk, c) = (i / 3, i % 3);
        let (ma, _) = crate::stats::mean_var(&ea[i]);
        let (mb, _) = crate::stats::mean_var(&eb[i]);
        panic!(
            "renders differ: block ({}, {}) channel {c}: means {ma} vs {mb}, p = {p:.3e} < {threshold:.3e} (Šidák over {} tests at α = {alpha})",
            (blk as u32 % bx) * block,
            (blk as u32 / bx) * block,
            ea.len()
        );
    }
    p
}

// ---- scenes ----------------------------------------------------------------------------

/// A generated scene in a temporary directory (removed on drop).
pub struct TestScene {
    pub dir: tempfile_dir::TempDir,
    pub path: std::path::PathBuf,
    pub scene: Scene,
    pub camera: Camera,
}

/// A tiny temporary-directory guard (the crate's dev-dependency is not visible here).
pub mod tempfile_dir {
    /// Removes the directory when dropped.
    pub struct TempDir(pub std::path::PathBuf);
    impl TempDir {
        pub fn new(tag: &str) -> TempDir {
            use std::sync::atomic::{AtomicU64, Ordering};
            static N: AtomicU64 = AtomicU64::new(0);
            let p = std::env::temp_dir().join(format!(
                "lanterna-test-{tag}-{}-{}",
                std::process::id(),
                N.fetch_add(1, Ordering::SeqCst)
            ));
            std::fs::create_dir_all(&p).unwrap();
            TempDir(p)
        }
    }
    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Generate `kind` with `options` and load it with its first camera.
pub fn generated(
    kind: crate::scene::generate::Kind,
    options: &crate::scene::generate::Options,
) -> TestScene {
    let dir = tempfile_dir::TempDir::new(kind.name());
    let path = dir.0.join(format!("{}.gltf", kind.name()));
    crate::scene::generate::generate(kind, options, &path).expect("generate scene");
    let scene = Scene::load(&path, &Default::default()).expect("load generated scene");
    let camera = scene
        .cameras
        .first()
        .cloned()
        .expect("generated scenes have a camera");
    TestScene {
        dir,
        path,
        scene,
        camera,
    }
}

/// The generated street with 120 lamps at aspect 1.5: many lights in a scene small enough
/// for the agreement tests at 24×16.
pub fn small_street() -> TestScene {
    generated(
        crate::scene::generate::Kind::Street,
        &crate::scene::generate::Options {
            lamps: Some(120),
            aspect: Some(1.5),
            ..Default::default()
        },
    )
}

/// The `asset.extras.lanterna.analytic` object of a generated scene.
pub fn analytic(scene: &Scene) -> serde_json::Value {
    scene
        .extras
        .as_ref()
        .and_then(|e| e.get("lanterna"))
        .and_then(|l| l.get("analytic"))
        .cloned()
        .expect("analytic extras")
}

/// Settings for a test of direct light alone: depth 2, emission seen directly hidden
/// (its edges would dominate the noise), seed 3.
pub fn direct_light_settings(
    method: crate::render::Method,
    width: u32,
    height: u32,
) -> RenderSettings {
    RenderSettings {
        max_depth: 2,
        hide_emitters: true,
        seed: 3,
        ..settings(method, width, height)
    }
}

/// Settings for a small test render.
pub fn settings(method: crate::render::Method, width: u32, height: u32) -> RenderSettings {
    RenderSettings {
        method,
        width,
        height,
        ..RenderSettings::default()
    }
}

/// Like [`render_batches`], for any method: each batch is a full `run_method` (guided
/// methods train their own SD-tree on the batch's own sample range), so the batches are
/// independent estimates of the whole estimator.
pub fn run_batches(
    scene: &Scene,
    camera: &Camera,
    settings: RenderSettings,
    batches: u32,
    spp: u64,
) -> Batches {
    use crate::render::run::{run_method, Budget};
    let mut r = test_renderer(scene, camera, &settings);
    let cancel = AtomicBool::new(false);
    let mut images = Vec::new();
    for b in 0..batches as u64 {
        let out =
            run_method(&mut r, Budget::Spp(spp), b * spp, &cancel, &mut |_| {}).expect("render");
        assert_eq!(
            out.stats.nonfinite_samples, 0,
            "the kernel produced non-finite samples"
        );
        images.push(out.image());
    }
    Batches {
        width: settings.width,
        height: settings.height,
        images,
    }
}

/// Mean absolute error of each batch against `reference` (mean RGB per pixel).
pub fn batch_mae(b: &Batches, reference: &[f64]) -> Vec<f64> {
    b.images
        .iter()
        .map(|img| {
            img.iter()
                .zip(reference)
                .map(|(&x, &r)| (x as f64 - r).abs())
                .sum::<f64>()
                / reference.len() as f64
        })
        .collect()
}

/// A GLB file: the JSON chunk and, when given, a binary chunk, each padded to 4 bytes.
pub fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let padded = |v: &[u8], pad: u8| {
        let mut v = v.to_vec();
        v.resize(v.len().div_ceil(4) * 4, pad);
        v
    };
    let json = padded(json, b' ');
    let bin = bin.map(|b| padded(b, 0));
    let total = 12 + 8 + json.len() + bin.as_ref().map_or(0, |b| 8 + b.len());
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if let Some(bin) = bin {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

/// A GLB file's JSON chunk and binary chunk (empty where it has none).
pub fn glb_chunks(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    assert_eq!(&bytes[..4], b"glTF", "not a GLB");
    let json_len = u32_at(12);
    let json = bytes[20..20 + json_len].to_vec();
    let bin = if bytes.len() > 28 + json_len {
        bytes[28 + json_len..28 + json_len + u32_at(20 + json_len)].to_vec()
    } else {
        Vec::new()
    };
    (json, bin)
}

/// Every triangle's corners in world space: position, normal, tangent (xyz, then its
/// handedness w), both texture coordinate sets and the vertex colour (white where the
/// mesh has none), in [`canonical_triangles`]' order. Tests compare scenes that should
/// hold the same geometry (a compressed file against its original) with it.
pub fn world_corners(scene: &Scene) -> Vec<[[f32; 18]; 3]> {
    let mut out = Vec::new();
    for inst in &scene.instances {
        let p = &scene.primitives[inst.primitive as usize];
        let normals = glam::Mat3::from_mat4(inst.transform).inverse().transpose();
        let linear = glam::Mat3::from_mat4(inst.transform);
        for t in 0..p.triangle_count as usize {
            let corner = |j: usize| -> [f32; 18] {
                let index = scene.indices[p.index_offset as usize + 3 * t + j];
                let v = &scene.vertices[(p.vertex_offset + index) as usize];
                let x = inst
                    .transform
                    .transform_point3(glam::Vec3::from(v.position));
                let n = (normals * glam::Vec3::from(v.normal)).normalize_or_zero();
                let tangent = glam::Vec4::from(v.tangent);
                let tn = (linear * tangent.truncate()).normalize_or_zero();
                let c = if p.color_offset == gpu::INVALID_INDEX {
                    [1.0; 4]
                } else {
                    scene.colors[(p.color_offset + index) as usize]
                };
                [
                    x.x, x.y, x.z, n.x, n.y, n.z, tn.x, tn.y, tn.z, tangent.w, v.uv0[0], v.uv0[1],
                    v.uv1[0], v.uv1[1], c[0], c[1], c[2], c[3],
                ]
            };
            out.push([corner(0), corner(1), corner(2)]);
        }
    }
    canonical_triangles(out)
}

/// Triangles rotated so that their smallest corner comes first, then sorted: two lists of
/// the same triangles become equal.
pub fn canonical_triangles<const N: usize>(mut tris: Vec<[[f32; N]; 3]>) -> Vec<[[f32; N]; 3]> {
    for tri in &mut tris {
        let first = (0..3)
            .min_by(|&a, &b| tri[a].partial_cmp(&tri[b]).unwrap())
            .unwrap();
        tri.rotate_left(first);
    }
    tris.sort_by(|a, b| a.partial_cmp(b).unwrap());
    tris
}
