//! What every command that renders does first: open a device, load the scene and its
//! light table, pick the camera and the resolution.

use crate::lights::LightTable;
use crate::scene::{Camera, CameraOverride, LoadOptions, Projection, Scene, SceneError};
use crate::vk::{self, Device, DeviceSelector, Instance, InstanceOptions};
use std::path::Path;
use std::sync::Arc;

/// How to open the device.
#[derive(Clone, Debug, Default)]
pub struct DeviceOptions {
    pub selector: DeviceSelector,
    /// Validation layers (also on with LANTERNA_VALIDATION=1).
    pub validation: bool,
    /// Kernel debug printf through the validation layer.
    pub debug_printf: bool,
}

/// Create an instance and a device.
pub fn open_device(options: &DeviceOptions) -> vk::Result<Arc<Device>> {
    let mut io = InstanceOptions::from_env();
    io.validation |= options.validation;
    io.debug_printf = options.debug_printf;
    let instance = Arc::new(Instance::new(&io)?);
    Device::new(instance, &options.selector)
}

/// A scene with its light table.
pub struct LoadedScene {
    pub scene: Scene,
    pub lights: LightTable,
    /// Seconds to parse the file and build the light table.
    pub load_seconds: f64,
}

pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    load_scene_with(path, &LoadOptions::default())
}

/// [`load_scene`] with loader options (`--allow-outside-uris`).
pub fn load_scene_with(path: &Path, options: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let started = std::time::Instant::now();
    let scene = Scene::load(path, options)?;
    let lights = LightTable::build(&scene)?;
    Ok(LoadedScene {
        scene,
        lights,
        load_seconds: started.elapsed().as_secs_f64(),
    })
}

/// Pick the camera: by index or name when `wanted`, else the file's first; a look-at
/// override works with or without a camera in the file.
pub fn choose_camera(
    scene: &Scene,
    wanted: Option<&str>,
    o: &CameraOverride,
) -> Result<Camera, SceneError> {
    let found = match wanted {
        Some(w) => {
            let by_index = w.parse::<usize>().ok().and_then(|i| scene.cameras.get(i));
            let by_name = || scene.cameras.iter().find(|c| c.name == w);
            match by_index.or_else(by_name) {
                Some(c) => Some(c.clone()),
                None => {
                    let available = if scene.cameras.is_empty() {
                        "no cameras".to_string()
                    } else {
                        scene
                            .cameras
                            .iter()
                            .enumerate()
                            .map(|(i, c)| format!("{i}: `{}`", c.name))
                            .collect::<Vec<_>>()
                            .join(", ")
                    };
                    return Err(SceneError::UnknownCamera {
                        path: scene.path.clone(),
                        wanted: w.to_string(),
                        available,
                    });
                }
            }
        }
        None => scene.cameras.first().cloned(),
    };
    match (found, o.look_at) {
        (Some(c), _) => Ok(c.with_override(o)),
        (None, Some((eye, target))) => Ok(Camera::look_at(
            eye,
            target,
            o.up.unwrap_or(glam::Vec3::Y),
            o.fov_degrees.unwrap_or(45.0).to_radians(),
        )),
        (None, None) => Err(SceneError::NoCamera {
            path: scene.path.clone(),
        }),
    }
}

/// Image size: what was asked, completed from the camera's aspect ratio (default width
/// 512, square when the camera fixes no aspect).
pub fn resolution(camera: &Camera, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let aspect = camera
        .aspect()
        .filter(|a| a.is_finite() && *a > 0.0)
        .unwrap_or(match camera.projection {
            Projection::Orthographic { .. } => 1.0,
            Projection::Perspective { .. } => 1.0,
        });
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as f32 / aspect).round() as u32).max(1)),
        (None, Some(h)) => (((h as f32 * aspect).round() as u32).max(1), h),
        (None, None) => (512, ((512.0 / aspect).round() as u32).max(1)),
    }
}
