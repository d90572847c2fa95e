//! What every command that renders does first: open a device, load the scene and its
//! light table, pick the camera and the resolution. The command line and the Python
//! module both start here, so they accept and refuse the same views with the same words.

use super::{Method, RenderError, RenderSettings, RenderStats, Renderer};
use crate::gpu;
use crate::lights::LightTable;
use crate::scene::{Camera, CameraOverride, LoadOptions, Projection, Scene, SceneError};
use crate::shaders::ShaderSource;
use crate::vk::{self, Device, DeviceSelector, Instance, InstanceOptions};
use std::path::Path;
use std::sync::atomic::AtomicBool;
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
    // --look-at is in the file's coordinates; the scene may render relative to a
    // moved origin (Scene::origin).
    let rebased;
    let o = match o.look_at {
        Some((eye, target)) if scene.origin != glam::Vec3::ZERO => {
            rebased = CameraOverride {
                look_at: Some((eye - scene.origin, target - scene.origin)),
                ..o.clone()
            };
            &rebased
        }
        _ => o,
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

/// The view a render asks for: the command line's `--camera`, `--look-at`, `--fov`,
/// `--width` and `--height`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ViewOptions {
    /// Camera of the file, by index or name (default: the first).
    pub camera: Option<String>,
    /// Eye and target, `[ex, ey, ez, tx, ty, tz]`, replacing the file's camera.
    pub look_at: Option<[f32; 6]>,
    /// Vertical field of view in degrees.
    pub fov: Option<f32>,
    /// Ignore the file's clip planes (`--no-clip-planes`).
    pub no_clip_planes: bool,
    pub width: Option<u32>,
    pub height: Option<u32>,
}

/// Why a view cannot be rendered.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Invalid(String),
}

/// The camera and the image size of `options` in `scene`.
pub fn choose_view(scene: &Scene, options: &ViewOptions) -> Result<(Camera, u32, u32), ViewError> {
    if let Some(v) = &options.look_at {
        if !v.iter().all(|x| x.is_finite()) {
            return Err(ViewError::Invalid("numbers must be finite".into()));
        }
    }
    let o = CameraOverride {
        look_at: options.look_at.map(|v| {
            (
                glam::Vec3::new(v[0], v[1], v[2]),
                glam::Vec3::new(v[3], v[4], v[5]),
            )
        }),
        up: None,
        fov_degrees: options.fov,
        no_clip_planes: options.no_clip_planes,
    };
    let camera = choose_camera(scene, options.camera.as_deref(), &o)?;
    let (w, h) = resolution(&camera, options.width, options.height);
    if w == 0 || h == 0 || w as u64 * h as u64 > 1 << 28 {
        return Err(ViewError::Invalid(format!(
            "image size {w}×{h} is out of range"
        )));
    }
    Ok((camera, w, h))
}

/// The first surface the camera sees through pixel (x, y) of a `width` × `height` image:
/// the mean position of a few samples' first hits, from a depth-1 render with AOVs (what
/// `guiding view` looks the SD-tree leaf up with). None when the pixel sees no surface.
#[allow(clippy::too_many_arguments)]
pub fn first_hit(
    device: &Arc<Device>,
    loaded: &LoadedScene,
    camera: Camera,
    width: u32,
    height: u32,
    (x, y): (u32, u32),
    shaders: ShaderSource,
) -> Result<Option<glam::Vec3>, RenderError> {
    if x >= width || y >= height {
        return Err(RenderError::Invalid(format!(
            "pixel ({x}, {y}) is outside the {width}×{height} image"
        )));
    }
    let settings = RenderSettings {
        method: Method::Pt,
        width,
        height,
        max_depth: 1,
        aovs: true,
        ..RenderSettings::default()
    };
    let mut r = Renderer::new(
        device.clone(),
        &loaded.scene,
        &loaded.lights,
        camera,
        settings,
        shaders,
    )?;
    let mut stats = RenderStats::default();
    r.render_samples(
        0,
        4,
        false,
        &AtomicBool::new(false),
        &mut |_| {},
        &mut stats,
    )?;
    let aov = r.aovs()?;
    let n = gpu::AOV_CHANNELS as usize;
    let px = &aov[(y * width + x) as usize * n..][..n];
    if px[gpu::AOV_DEPTH as usize] <= 0.0 {
        return Ok(None);
    }
    let p = gpu::AOV_POSITION as usize;
    Ok(Some(glam::Vec3::new(px[p], px[p + 1], px[p + 2])))
}
