//! Scenes: glTF loaded into flat, GPU-ready arrays, and the generators of test scenes.
//!
//! A [`Scene`] holds one global vertex and index buffer, the distinct mesh primitives
//! (one BLAS each), the instances that place them (one TLAS instance each), materials in
//! the kernels' layout, decoded textures, cameras and punctual lights. The light table is
//! derived from it by [`crate::lights`].

mod animation;
mod animation_pointer;
mod camera;
mod draco;
pub mod export_mitsuba;
pub mod generate;
mod gltf_check;
pub mod ies;
mod load;
mod load_instancing;
mod load_light;
mod load_primitive;
mod material;
mod meshopt;
mod sources;
pub mod spatial_order;
mod stats;
mod texture;
mod variants;

pub use animation::{AnimationInfo, Pose};
pub use camera::{Camera, CameraOverride, ClipPlanes, Projection};
pub use load::LoadOptions;
pub use material::{bounds_solid, disperses, dispersion_iors, is_lambertian};
pub use stats::SceneStats;
pub use texture::{TextureData, TextureKey};

use crate::gpu;
use glam::{Mat4, Vec3};
use std::path::{Path, PathBuf};

/// Errors loading a scene. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read the scene: {error}")]
    File {
        path: PathBuf,
        error: crate::files::FileError,
    },
    #[error("{path}: not a valid glTF file: {message}")]
    Gltf { path: PathBuf, message: String },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
    #[error(
        "{path}: the scene has no camera; choose a view with --look-at EYE,TARGET (and --fov)"
    )]
    NoCamera { path: PathBuf },
    #[error("{path}: no camera matches `{wanted}` (the file has {available})")]
    UnknownCamera {
        path: PathBuf,
        wanted: String,
        available: String,
    },
    #[error("{path}: the scene has no lights (no emissive triangles with non-zero area, emission and alpha coverage, and no punctual lights)")]
    NoLights { path: PathBuf },
    #[error("{path}: the scene has no triangles")]
    Empty { path: PathBuf },
}

/// A distinct mesh primitive: one BLAS.
#[derive(Clone, Debug)]
pub struct MeshPrimitive {
    /// First vertex in the global vertex buffer.
    pub vertex_offset: u32,
    pub vertex_count: u32,
    /// First index in the global index buffer (indices are relative to `vertex_offset`).
    pub index_offset: u32,
    pub triangle_count: u32,
    pub material: u32,
    /// No alpha testing needed (alpha mode OPAQUE).
    pub opaque: bool,
    /// First of the primitive's `vertex_count` entries in `Scene::colors` (its COLOR_0,
    /// which multiplies the base colour), or `INVALID_INDEX` without vertex colours.
    pub color_offset: u32,
    /// `mesh name / primitive index`, for messages.
    pub name: String,
}

/// A primitive placed in the world: one TLAS instance.
#[derive(Clone, Debug)]
pub struct Instance {
    pub primitive: u32,
    pub transform: Mat4,
    pub node_name: String,
}

/// A loaded scene.
#[derive(Debug)]
pub struct Scene {
    pub path: PathBuf,
    pub vertices: Vec<gpu::Vertex>,
    /// Linear RGBA vertex colours (glTF COLOR_0) of the primitives that have them.
    pub colors: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
    pub primitives: Vec<MeshPrimitive>,
    pub instances: Vec<Instance>,
    pub materials: Vec<gpu::Material>,
    pub material_names: Vec<String>,
    pub textures: Vec<TextureData>,
    pub cameras: Vec<Camera>,
    pub punctual: Vec<gpu::PunctualLight>,
    /// `EXT_lights_ies` profiles in the kernel's form (`ies.rs`), which punctual lights
    /// with a `profile` point into.
    pub light_profiles: Vec<f32>,
    pub bounds_min: Vec3,
    pub bounds_max: Vec3,
    /// Hex digest of the loaded content, to tie renders and guiding trees to a scene.
    pub hash: String,
    /// The glTF asset's `extras` (generators record their options there).
    pub extras: Option<serde_json::Value>,
    /// Where the file's world origin moved (see `load::rebase_origin`): every position
    /// here (instances, cameras, lights, bounds) is the file's minus this.
    pub origin: Vec3,
    /// The external files the scene's URIs named (buffers, images), canonical: with
    /// `path`, every file loading read (outputs must not overwrite them).
    pub files: Vec<PathBuf>,
    /// The file's animations (whether or not the scene is posed by them).
    pub animations: Vec<AnimationInfo>,
    /// The file's material variants (`KHR_materials_variants`; `--variant` picks one).
    pub variants: Vec<String>,
    /// The version of the file loaded: the animation pose and the material variant (by
    /// name) asked for, which renders record in their metadata.
    pub pose: Option<Pose>,
    pub variant: Option<String>,
}

impl Scene {
    /// Load a glTF 2.0 file (.gltf with external or embedded buffers, or .glb).
    pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
        load::load(path, options)
    }

    /// Whether every material the scene's geometry uses is Lambertian
    /// ([`is_lambertian`]; materials no instance uses, such as glTF's default material
    /// where every primitive has one, do not count): the kernels then compile the
    /// Lambertian lobe alone (`BSDF_KERNEL_LAMBERTIAN`, `Renderer::bsdf_kernel`).
    pub fn only_lambertian(&self) -> bool {
        self.instances.iter().all(|i| {
            self.primitives
                .get(i.primitive as usize)
                .and_then(|p| self.materials.get(p.material as usize))
                .is_some_and(is_lambertian)
        })
    }

    /// World-space positions of instance `i`'s triangle `t`.
    pub fn world_triangle(&self, instance: &Instance, t: u32) -> [Vec3; 3] {
        let p = &self.primitives[instance.primitive as usize];
        let base = (p.index_offset + 3 * t) as usize;
        std::array::from_fn(|k| {
            let v = self.vertices[(p.vertex_offset + self.indices[base + k]) as usize].position;
            instance.transform.transform_point3(Vec3::from(v))
        })
    }

    /// Diagonal length of the bounding box (at least a small positive number).
    pub fn extent(&self) -> f32 {
        (self.bounds_max - self.bounds_min).length().max(1e-3)
    }

    pub fn triangle_count(&self) -> u64 {
        self.instances
            .iter()
            .map(|i| self.primitives[i.primitive as usize].triangle_count as u64)
            .sum()
    }
}
