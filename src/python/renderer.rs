//! `Renderer`: one scene on a device with its acceleration structures and compiled
//! pipelines, kept across renders. Every render, training run and comparison releases
//! the GIL and runs the library's loop (`render::run`, `render::train`,
//! `eval::compare`); between chunks of samples (at most about half a second apart) it
//! takes the GIL back to call the progress callback and to let Python handle signals,
//! so Ctrl-C stops the loop at the next chunk, raises `KeyboardInterrupt` and leaves the
//! renderer as usable as before.

use super::args::{budget, device_selector, unsigned};
use super::convert::{f32_bytes, image_from_py, image_to_py, json_value};
use super::errors;
use super::options;
use super::scene::PyScene;
use super::watch::Watch;
use crate::eval::compare::{run_compare, CompareConfig, Crop};
use crate::guiding::{density_grid, scene_hash_number, SdTree};
use crate::render::output::{aov_layers, outcome_image, render_meta, Aov};
use crate::render::run;
use crate::render::runner::CompareRunner;
use crate::render::session::{self, LoadedScene, ViewOptions};
use crate::render::{
    self as render_mod, Method, RenderSettings, RenderStats, Renderer, TrainingPlan,
};
use crate::scene::Camera;
use crate::shaders::ShaderSource;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

/// What a renderer keeps besides the library's `Renderer`.
struct Inner {
    renderer: Renderer,
    loaded: Arc<LoadedScene>,
    camera: Camera,
    scene_path: String,
    shaders: ShaderSource,
    /// Seconds the constructor took (scene upload, acceleration structures, pipelines).
    setup_seconds: f64,
    /// The SD-tree guided renders use instead of training: from `train()` or
    /// `load_guiding=`.
    tree: Option<SdTree>,
    /// The SD-tree the last guided render or training used or produced.
    last_tree: Option<SdTree>,
}

impl Inner {
    /// Replace the renderer by one that accumulates AOVs too (their buffers and kernel
    /// variant are fixed at creation).
    fn enable_aovs(&mut self) -> render_mod::Result<()> {
        let settings = RenderSettings {
            aovs: true,
            ..self.renderer.settings.clone()
        };
        let mut r = Renderer::new(
            self.renderer.device.clone(),
            &self.loaded.scene,
            &self.loaded.lights,
            self.camera.clone(),
            settings,
            self.shaders.clone(),
        )?;
        r.prepare()?;
        self.renderer = r;
        Ok(())
    }

    fn size(&self) -> (u32, u32) {
        (self.renderer.settings.width, self.renderer.settings.height)
    }
}

#[pyclass(module = "lanterna._lanterna", name = "Renderer")]
pub struct PyRenderer {
    inner: Mutex<Inner>,
    scene: Py<PyScene>,
}

impl PyRenderer {
    fn lock(&self) -> PyResult<MutexGuard<'_, Inner>> {
        self.inner.try_lock().map_err(|_| {
            PyRuntimeError::new_err("the renderer is busy (rendering in another thread)")
        })
    }
}

#[pymethods]
impl PyRenderer {
    #[new]
    #[pyo3(signature = (scene, width=None, height=None, method="pt", max_depth=4, seed=0, device=None, load_guiding=None, **options))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scene: Bound<'_, PyScene>,
        width: Option<i64>,
        height: Option<i64>,
        method: &str,
        max_depth: i64,
        seed: i64,
        device: Option<&Bound<'_, PyAny>>,
        load_guiding: Option<PathBuf>,
        options: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        let started = Instant::now();
        let method: Method = method.parse().map_err(PyValueError::new_err)?;
        let s = scene.get();
        let view = ViewOptions {
            width: width.map(|w| unsigned("width", w)).transpose()?,
            height: height.map(|h| unsigned("height", h)).transpose()?,
            ..s.view.clone()
        };
        let (camera, width, height) =
            session::choose_view(&s.loaded.scene, &view).map_err(errors::view)?;
        let mut settings = RenderSettings {
            method,
            width,
            height,
            max_depth: unsigned("max-depth", max_depth)?,
            seed: unsigned("seed", seed)?,
            ..RenderSettings::default()
        };
        let extras = options::apply(&mut settings, options)?;
        let tree = match &load_guiding {
            Some(path) => {
                if !method.uses_guiding() {
                    return Err(PyValueError::new_err(
                        "--load-guiding needs --method guided or guided-ris",
                    ));
                }
                let hash = scene_hash_number(&s.loaded.scene.hash);
                Some(SdTree::load(path, hash).map_err(errors::guiding)?)
            }
            None => None,
        };
        let selector = device_selector(device)?;
        let loaded = s.loaded.clone();
        let shaders = extras.shaders.clone();
        let renderer = py.detach(|| -> PyResult<Renderer> {
            let device =
                super::shared_device(&selector, extras.validation).map_err(errors::device)?;
            let mut r = Renderer::new(
                device,
                &loaded.scene,
                &loaded.lights,
                camera.clone(),
                settings,
                shaders.clone(),
            )
            .map_err(errors::render)?;
            r.prepare().map_err(errors::render)?;
            Ok(r)
        })?;
        Ok(PyRenderer {
            inner: Mutex::new(Inner {
                renderer,
                loaded,
                camera,
                scene_path: s.path.display().to_string(),
                shaders,
                setup_seconds: started.elapsed().as_secs_f64(),
                tree,
                last_tree: None,
            }),
            scene: scene.unbind(),
        })
    }

    #[getter]
    fn scene(&self, py: Python<'_>) -> Py<PyScene> {
        self.scene.clone_ref(py)
    }

    #[getter]
    fn width(&self) -> PyResult<u32> {
        Ok(self.lock()?.size().0)
    }

    #[getter]
    fn height(&self) -> PyResult<u32> {
        Ok(self.lock()?.size().1)
    }

    #[getter]
    fn method(&self) -> PyResult<String> {
        Ok(self.lock()?.renderer.settings.method.name().to_string())
    }

    #[getter]
    fn max_depth(&self) -> PyResult<u32> {
        Ok(self.lock()?.renderer.settings.max_depth)
    }

    #[getter]
    fn seed(&self) -> PyResult<u32> {
        Ok(self.lock()?.renderer.settings.seed)
    }

    /// The Vulkan device's name.
    #[getter]
    fn device(&self) -> PyResult<String> {
        Ok(self.lock()?.renderer.device.info.name.clone())
    }

    /// Seconds the constructor took: scene upload, acceleration structures, pipelines.
    #[getter]
    fn setup_seconds(&self) -> PyResult<f64> {
        Ok(self.lock()?.setup_seconds)
    }

    /// Whether guided renders use a fixed SD-tree (from `train()` or `load_guiding=`).
    #[getter]
    fn has_guiding(&self) -> PyResult<bool> {
        Ok(self.lock()?.tree.is_some())
    }

    /// Render; returns the image tuple (see `convert.rs`) with the run's statistics in
    /// its metadata.
    #[pyo3(signature = (spp=None, seconds=None, sample_offset=0, aovs=None, progress=None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: Option<i64>,
        seconds: Option<f64>,
        sample_offset: i64,
        aovs: Option<Vec<String>>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let budget = budget(spp, seconds)?;
        let first: u64 = unsigned("sample-offset", sample_offset)?;
        let aovs: Vec<Aov> = aovs
            .unwrap_or_default()
            .iter()
            .map(|a| a.parse().map_err(PyValueError::new_err))
            .collect::<PyResult<_>>()?;
        py.check_signals()?;
        let mut guard = self.lock()?;
        let inner = &mut *guard;
        if !aovs.is_empty() && !inner.renderer.settings.aovs {
            py.detach(|| inner.enable_aovs()).map_err(errors::render)?;
        }
        if inner.renderer.settings.method.uses_guiding() {
            inner.renderer.preloaded_tree = inner.tree.clone();
        }
        let cancel = AtomicBool::new(false);
        let mut watch = Watch::new(progress.as_ref(), &cancel);
        let result = py.detach(|| {
            inner.renderer.prepare()?;
            run::run_method(&mut inner.renderer, budget, first, &cancel, &mut |d| {
                watch.tick(d)
            })
        });
        inner.renderer.preloaded_tree = None;
        if let Some(e) = watch.error {
            return Err(e);
        }
        let mut outcome = result.map_err(errors::render)?;
        let (w, h) = inner.size();
        let mut meta = render_meta(
            &inner.renderer.settings,
            &inner.scene_path,
            &inner.loaded.scene,
            &inner.renderer.device.info.name,
        );
        meta.render_seconds = Some(outcome.seconds);
        let mut image = outcome_image(&outcome, w, h, meta).map_err(errors::image)?;
        image.aovs = aov_layers(&inner.renderer, &aovs).map_err(errors::render)?;
        let stats = outcome.stats;
        if let Some(g) = outcome.guiding.take() {
            inner.last_tree = Some(g.tree);
        }
        let parts = image_to_py(py, &image)?;
        let m = parts.get_item(4)?.cast_into::<PyDict>()?;
        m.set_item("gpu_seconds", stats.gpu_seconds)?;
        m.set_item("rays", stats.rays())?;
        m.set_item("camera_rays", stats.camera_rays)?;
        m.set_item("bounce_rays", stats.bounce_rays)?;
        m.set_item("shadow_rays", stats.shadow_rays)?;
        m.set_item("probe_rays", stats.probe_rays)?;
        m.set_item("nonfinite_samples", stats.nonfinite_samples)?;
        if inner.renderer.settings.method.uses_guiding() {
            m.set_item("training_seconds", outcome.training_seconds)?;
        }
        Ok(parts)
    }

    /// Train an SD-tree with the whole budget; later guided renders use it. Returns the
    /// spp, seconds and training iterations as a dict.
    #[pyo3(signature = (spp=None, seconds=None, sample_offset=1u64 << 31, progress=None))]
    fn train<'py>(
        &self,
        py: Python<'py>,
        spp: Option<i64>,
        seconds: Option<f64>,
        sample_offset: u64,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let budget = budget(spp, seconds)?;
        py.check_signals()?;
        let mut guard = self.lock()?;
        let inner = &mut *guard;
        if !inner.renderer.settings.method.uses_guiding() {
            return Err(PyValueError::new_err(
                "train() needs method guided or guided-ris",
            ));
        }
        let cancel = AtomicBool::new(false);
        let mut watch = Watch::new(progress.as_ref(), &cancel);
        let started = Instant::now();
        let result = py.detach(|| {
            inner.renderer.prepare()?;
            let mut stats = RenderStats::default();
            let plan = TrainingPlan::whole(budget);
            render_mod::train(
                &mut inner.renderer,
                plan,
                sample_offset,
                &cancel,
                &mut |d| watch.tick(d),
                &mut stats,
                None,
            )
        });
        if let Some(e) = watch.error {
            return Err(e);
        }
        let training = result.map_err(errors::render)?;
        let report = serde_json::json!({
            "spp": training.next_sample - sample_offset,
            "seconds": started.elapsed().as_secs_f64(),
            "iterations": training.iterations,
        });
        inner.tree = Some(training.tree.clone());
        inner.last_tree = Some(training.tree);
        json_value(py, &report)
    }

    /// Forget the fixed SD-tree: guided renders train their share of the budget again.
    fn reset_guiding(&self) -> PyResult<()> {
        self.lock()?.tree = None;
        Ok(())
    }

    /// Save the SD-tree the last guided render or training used.
    fn save_guiding(&self, path: PathBuf) -> PyResult<()> {
        let inner = self.lock()?;
        let tree = inner
            .last_tree
            .as_ref()
            .or(inner.tree.as_ref())
            .ok_or_else(|| {
                PyValueError::new_err(
                    "no SD-tree to save: render with method guided or guided-ris, or train(), first",
                )
            })?;
        let (lo, hi) = inner.renderer.bounds;
        let hash = scene_hash_number(&inner.loaded.scene.hash);
        tree.save(&path, hash, (lo.into(), hi.into())).map_err(|e| {
            let io = matches!(e, crate::guiding::GuidingError::File(_));
            let text = format!(
                "cannot save the SD-tree to {}: {}",
                path.display(),
                errors::message(e)
            );
            if io {
                PyOSError::new_err(text)
            } else {
                PyValueError::new_err(text)
            }
        })
    }

    /// The sampling quadtree of the SD-tree leaf at pixel (x, y)'s first hit: (size,
    /// density bytes, colour-mapped RGB bytes, facts about the leaf, first hit).
    #[pyo3(signature = (x, y, size=256))]
    fn _guiding_leaf<'py>(
        &self,
        py: Python<'py>,
        x: i64,
        y: i64,
        size: i64,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let (x, y): (u32, u32) = (unsigned("pixel", x)?, unsigned("pixel", y)?);
        let size: u32 = unsigned("size", size)?;
        if size == 0 || size > 4096 {
            return Err(PyValueError::new_err("size must be within 1..=4096"));
        }
        let guard = self.lock()?;
        let inner = &*guard;
        let tree = inner
            .last_tree
            .as_ref()
            .or(inner.tree.as_ref())
            .ok_or_else(|| {
                PyValueError::new_err(
                    "no SD-tree: render with method guided or guided-ris, or train(), first",
                )
            })?;
        let (w, h) = inner.size();
        let pos = py
            .detach(|| {
                session::first_hit(
                    &inner.renderer.device,
                    &inner.loaded,
                    inner.camera.clone(),
                    w,
                    h,
                    (x, y),
                    inner.shaders.clone(),
                )
            })
            .map_err(errors::render)?
            .ok_or_else(|| PyValueError::new_err(format!("pixel ({x}, {y}) sees no surface")))?;
        let view = tree.leaf_view(pos, size);
        let density = density_grid(&tree.leaf(view.info.leaf).sampling, size);
        let i = &view.info;
        let info = PyDict::new(py);
        info.set_item("leaf", i.leaf)?;
        info.set_item("depth", i.spatial_depth)?;
        info.set_item("box_min", i.box_min.to_array())?;
        info.set_item("box_size", i.box_size.to_array())?;
        info.set_item("sampling_weight", i.sampling_weight)?;
        info.set_item("training_weight", i.training_weight)?;
        info.set_item("nodes", i.nodes)?;
        info.set_item("quad_depth", i.quad_depth)?;
        info.set_item("min_density", i.min_density)?;
        info.set_item("max_density", i.max_density)?;
        info.set_item("uniform", i.uniform)?;
        PyTuple::new(
            py,
            [
                size.into_pyobject(py)?.into_any(),
                f32_bytes(py, &density).into_any(),
                f32_bytes(py, &view.rgb).into_any(),
                info.into_any(),
                pos.to_array().into_pyobject(py)?.into_any(),
            ],
        )
    }

    /// `lanterna compare` with this renderer's scene, view and settings (the method
    /// switched per run): writes the report into `out_dir` and returns it as a dict.
    #[pyo3(signature = (reference, reference_name, methods, spp, seconds, out_dir, crop=None, exposure=0.0, save_images=false, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn _compare<'py>(
        &self,
        py: Python<'py>,
        reference: &Bound<'_, PyAny>,
        reference_name: String,
        methods: Vec<String>,
        spp: Vec<u64>,
        seconds: Vec<f64>,
        out_dir: PathBuf,
        crop: Option<(u32, u32, u32, u32)>,
        exposure: f32,
        save_images: bool,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let reference = image_from_py(reference)?;
        let mut guard = self.lock()?;
        let inner = &mut *guard;
        let base = inner.renderer.settings.clone();
        let config = CompareConfig {
            methods,
            spp,
            seconds,
            crop: crop.map(|(x, y, w, h)| Crop { x, y, w, h }),
            exposure,
            out_dir,
            save_images,
            scene: inner.scene_path.clone(),
            reference: reference_name,
        };
        config
            .check_reference(&reference, base.max_depth)
            .map_err(errors::compare)?;
        if (reference.width, reference.height) != (base.width, base.height) {
            return Err(PyValueError::new_err(format!(
                "{} is {}x{} but the renderer renders {}x{}",
                config.reference, reference.width, reference.height, base.width, base.height
            )));
        }
        let meta = render_meta(
            &base,
            &inner.scene_path,
            &inner.loaded.scene,
            &inner.renderer.device.info.name,
        );
        let cancel = AtomicBool::new(false);
        let mut watch = Watch::new(progress.as_ref(), &cancel);
        let setup_seconds = inner.setup_seconds;
        let result = py.detach(|| {
            let mut tick = |d| watch.tick(d);
            let mut runner = CompareRunner {
                renderer: &mut inner.renderer,
                base: base.clone(),
                setup_seconds,
                meta,
                cancel: &cancel,
                progress: &mut tick,
            };
            let report = run_compare(&mut runner, &reference, &config);
            // The renderer goes on with its own method.
            let restored = inner.renderer.set_settings(base.clone());
            (report, restored)
        });
        if let Some(e) = watch.error {
            return Err(e);
        }
        let (report, restored) = result;
        restored.map_err(errors::render)?;
        let report = report.map_err(errors::compare)?;
        json_value(py, &report)
    }

    /// Live device-memory allocations of the renderer's device and their bytes (the
    /// memory test checks that renders do not leak device objects).
    fn _device_memory(&self) -> PyResult<(usize, u64)> {
        let inner = self.lock()?;
        let report = inner.renderer.device.allocator().generate_report();
        Ok((report.allocations.len(), report.total_allocated_bytes))
    }

    fn __repr__(&self) -> PyResult<String> {
        let inner = self.lock()?;
        let s = &inner.renderer.settings;
        Ok(format!(
            "<lanterna.Renderer {} {}×{} method={} max_depth={} seed={} on {}>",
            inner.scene_path,
            s.width,
            s.height,
            s.method,
            s.max_depth,
            s.seed,
            inner.renderer.device.info.name
        ))
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRenderer>()?;
    m.add("OPTIONS", options::OPTIONS.to_vec())?;
    Ok(())
}
