//! `load_scene(path, camera=, look_at=, fov=)` and the `Scene` it returns: a glTF file
//! with its light table, loaded once and shared by every renderer made from it.

use super::convert::json_value;
use super::errors;
use crate::render::session::{self, LoadedScene, ViewOptions};
use crate::scene::SceneStats;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

#[pyclass(module = "lanterna._lanterna", name = "Scene", frozen)]
pub struct PyScene {
    pub loaded: Arc<LoadedScene>,
    pub path: PathBuf,
    /// The camera and field of view asked for (the size comes with each renderer).
    pub view: ViewOptions,
}

#[pymethods]
impl PyScene {
    /// The scene file.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// The scene content's hash (saved SD-trees and EXR metadata carry it).
    #[getter]
    fn hash(&self) -> String {
        self.loaded.scene.hash.clone()
    }

    /// Names of the file's cameras, in order.
    #[getter]
    fn cameras(&self) -> Vec<String> {
        self.loaded
            .scene
            .cameras
            .iter()
            .map(|c| c.name.clone())
            .collect()
    }

    /// Seconds it took to parse the file and build the light table.
    #[getter]
    fn load_seconds(&self) -> f64 {
        self.loaded.load_seconds
    }

    /// The statistics `lanterna info SCENE --json` prints (triangles, instances,
    /// materials, lights, total power, bounds, estimated device memory), and the
    /// cameras' names, as a dict.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let stats = SceneStats::new(&self.loaded.scene, &self.loaded.lights);
        let info = json_value(py, &stats)?;
        info.set_item("cameras", self.cameras())?;
        Ok(info)
    }

    fn __repr__(&self) -> String {
        format!(
            "<lanterna.Scene {} ({} triangles, {} light models)>",
            self.path.display(),
            self.loaded.scene.triangle_count(),
            self.loaded.lights.models.len()
        )
    }
}

/// Load a glTF scene and choose its view (see the Python package's docstring).
#[pyfunction]
#[pyo3(signature = (path, camera=None, look_at=None, fov=None, clip_planes=true, animation_time=None, animation=None, variant=None))]
#[allow(clippy::too_many_arguments)]
fn load_scene(
    py: Python<'_>,
    path: PathBuf,
    camera: Option<&Bound<'_, PyAny>>,
    look_at: Option<Vec<f32>>,
    fov: Option<f32>,
    clip_planes: bool,
    animation_time: Option<f32>,
    animation: Option<&Bound<'_, PyAny>>,
    variant: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyScene> {
    let text = |v: Option<&Bound<'_, PyAny>>| -> PyResult<Option<String>> {
        v.filter(|v| !v.is_none())
            .map(|v| v.str().map(|s| s.to_string()))
            .transpose()
    };
    let animation = text(animation)?;
    let variant = text(variant)?;
    if let Some(t) = animation_time.filter(|t| !t.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "animation_time: {t} is not a finite number of seconds"
        )));
    }
    let options = crate::scene::LoadOptions {
        pose: (animation_time.is_some() || animation.is_some()).then(|| crate::scene::Pose {
            time: animation_time.unwrap_or(0.0),
            animation,
        }),
        variant,
        ..Default::default()
    };
    let camera = camera
        .filter(|c| !c.is_none())
        .map(|c| c.str().map(|s| s.to_string()))
        .transpose()?;
    let look_at = look_at
        .map(|v| {
            <[f32; 6]>::try_from(v).map_err(|_| {
                PyValueError::new_err("look_at: expected six numbers: ex,ey,ez,tx,ty,tz")
            })
        })
        .transpose()?;
    let loaded = py
        .detach(|| session::load_scene_with(&path, &options))
        .map_err(errors::scene)?;
    let view = ViewOptions {
        camera,
        look_at,
        fov,
        no_clip_planes: !clip_planes,
        width: None,
        height: None,
    };
    // Refuse an unknown camera or a bad look-at now rather than at the first renderer.
    session::choose_view(&loaded.scene, &view).map_err(errors::view)?;
    Ok(PyScene {
        loaded: Arc::new(loaded),
        path,
        view,
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    Ok(())
}
