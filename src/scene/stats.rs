//! Scene statistics for `lanterna info SCENE`.

use super::Scene;
use crate::lights::LightTable;
use std::fmt;

/// What a scene holds and roughly what it will take on the device.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SceneStats {
    pub triangles: u64,
    pub unique_triangles: u64,
    pub vertices: u64,
    pub instances: u64,
    pub primitives: u64,
    pub materials: u64,
    /// Materials that transmit as thin walls, and those that bound solids
    /// (KHR_materials_transmission, with KHR_materials_volume).
    pub thin_glass_materials: u64,
    pub solid_materials: u64,
    /// Materials with a clearcoat (KHR_materials_clearcoat) and with sheen
    /// (KHR_materials_sheen).
    pub coated_materials: u64,
    pub sheen_materials: u64,
    /// Materials with anisotropy (KHR_materials_anisotropy, strength above 0).
    pub anisotropic_materials: u64,
    /// Materials with diffuse transmission (KHR_materials_diffuse_transmission, factor
    /// above 0).
    pub diffuse_transmission_materials: u64,
    /// Materials with a thin film (KHR_materials_iridescence, factor above 0).
    pub iridescent_materials: u64,
    /// Solids whose boundary disperses (KHR_materials_dispersion above 0 on a material
    /// that bounds a solid).
    pub dispersive_materials: u64,
    /// Every material in use is Lambertian (`Scene::only_lambertian`): the kernels take
    /// that lobe alone.
    pub only_lambertian: bool,
    pub textures: u64,
    pub cameras: u64,
    pub light_models: u64,
    /// The deepest and the mean depth of a light model in the light tree (`--source
    /// tree`): the levels a walk to it evaluates.
    pub light_tree_depth_max: u32,
    pub light_tree_depth_mean: f64,
    pub emissive_triangles: u64,
    pub dropped_emissive_triangles: u64,
    pub punctual_lights: u64,
    /// Punctual lights shaped by an IES profile (`EXT_lights_ies`).
    pub ies_lights: u64,
    pub total_power: f64,
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    /// Estimated device memory in bytes: buffers, textures and acceleration structures.
    pub device_bytes: u64,
    /// The file's animations (`--animation-time` poses them).
    pub animations: Vec<super::AnimationInfo>,
    /// The file's material variants (`--variant` picks one).
    pub material_variants: Vec<String>,
}

impl SceneStats {
    pub fn new(scene: &Scene, lights: &LightTable) -> SceneStats {
        Self::build(scene, Some(lights))
    }

    /// The statistics of a scene that has no lights (which `LightTable::build` refuses):
    /// what `lanterna info` prints for it, with every light count zero.
    pub fn unlit(scene: &Scene) -> SceneStats {
        Self::build(scene, None)
    }

    fn build(scene: &Scene, lights: Option<&LightTable>) -> SceneStats {
        let models = lights.map_or(&[][..], |l| &l.models[..]);
        let light_triangles = lights.map_or(0, |l| l.triangles.len());
        let size = |n: usize, each: usize| (n * each) as u64;
        let unique_triangles: u64 = scene
            .primitives
            .iter()
            .map(|p| p.triangle_count as u64)
            .sum();
        let buffers = size(
            scene.vertices.len(),
            std::mem::size_of::<crate::gpu::Vertex>(),
        ) + size(scene.colors.len(), 16)
            + size(scene.indices.len(), 4)
            + size(
                scene.instances.len(),
                std::mem::size_of::<crate::gpu::Instance>() + 64,
            )
            + size(
                scene.materials.len(),
                std::mem::size_of::<crate::gpu::Material>(),
            )
            + size(
                light_triangles,
                std::mem::size_of::<crate::gpu::LightTriangle>()
                    + std::mem::size_of::<crate::gpu::LightCandidateTriangle>()
                    + 12,
            )
            + size(lights.map_or(0, |l| l.triangle_light_index.len()), 4);
        let textures: u64 = scene
            .textures
            .iter()
            .map(|t| t.texels.device_bytes(t.format))
            .sum();
        // BVH nodes and leaves: a conservative ~64 bytes per triangle plus instances.
        let accel = unique_triangles * 64 + scene.instances.len() as u64 * 128;
        let transmitting = || scene.materials.iter().filter(|m| m.transmission > 0.0);
        SceneStats {
            animations: scene.animations.clone(),
            material_variants: scene.variants.clone(),
            triangles: scene.triangle_count(),
            unique_triangles,
            vertices: scene.vertices.len() as u64,
            instances: scene.instances.len() as u64,
            primitives: scene.primitives.len() as u64,
            materials: scene.materials.len() as u64 - 1,
            thin_glass_materials: transmitting().filter(|m| !super::bounds_solid(m)).count() as u64,
            solid_materials: transmitting().filter(|m| super::bounds_solid(m)).count() as u64,
            coated_materials: scene.materials.iter().filter(|m| m.clearcoat > 0.0).count() as u64,
            sheen_materials: scene
                .materials
                .iter()
                .filter(|m| m.sheen_color.iter().any(|&c| c > 0.0))
                .count() as u64,
            anisotropic_materials: scene
                .materials
                .iter()
                .filter(|m| m.anisotropy_strength > 0.0)
                .count() as u64,
            diffuse_transmission_materials: scene
                .materials
                .iter()
                .filter(|m| m.diffuse_transmission > 0.0)
                .count() as u64,
            iridescent_materials: scene
                .materials
                .iter()
                .filter(|m| m.iridescence > 0.0)
                .count() as u64,
            dispersive_materials: scene
                .materials
                .iter()
                .filter(|m| super::disperses(m))
                .count() as u64,
            only_lambertian: scene.only_lambertian(),
            textures: scene.textures.len() as u64,
            cameras: scene.cameras.len() as u64,
            light_models: models.len() as u64,
            light_tree_depth_max: models.iter().map(|m| m.tree_depth).max().unwrap_or(0),
            light_tree_depth_mean: if models.is_empty() {
                0.0
            } else {
                models.iter().map(|m| m.tree_depth as f64).sum::<f64>() / models.len() as f64
            },
            emissive_triangles: light_triangles as u64,
            dropped_emissive_triangles: lights.map_or(0, |l| l.dropped_triangles),
            punctual_lights: scene.punctual.len() as u64,
            ies_lights: scene
                .punctual
                .iter()
                .filter(|l| super::ies::profile_offset(l).is_some())
                .count() as u64,
            total_power: lights.map_or(0.0, |l| l.total_power),
            bounds_min: scene.bounds_min.into(),
            bounds_max: scene.bounds_max.into(),
            device_bytes: buffers + textures + accel,
        }
    }
}

impl fmt::Display for SceneStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        writeln!(
            f,
            "triangles           {} ({} unique)",
            self.triangles, self.unique_triangles
        )?;
        writeln!(f, "vertices            {}", self.vertices)?;
        writeln!(
            f,
            "instances           {} of {} primitives",
            self.instances, self.primitives
        )?;
        write!(f, "materials           {}", self.materials)?;
        let mut kinds = Vec::new();
        if self.thin_glass_materials + self.solid_materials > 0 {
            kinds.push(format!(
                "{} thin glass, {} solid glass",
                self.thin_glass_materials, self.solid_materials
            ));
        }
        if self.coated_materials > 0 {
            kinds.push(format!("{} clearcoated", self.coated_materials));
        }
        if self.sheen_materials > 0 {
            kinds.push(format!("{} with sheen", self.sheen_materials));
        }
        if self.anisotropic_materials > 0 {
            kinds.push(format!("{} anisotropic", self.anisotropic_materials));
        }
        if self.diffuse_transmission_materials > 0 {
            kinds.push(format!(
                "{} diffusely transmitting",
                self.diffuse_transmission_materials
            ));
        }
        if self.iridescent_materials > 0 {
            kinds.push(format!("{} iridescent", self.iridescent_materials));
        }
        if self.dispersive_materials > 0 {
            kinds.push(format!("{} dispersive", self.dispersive_materials));
        }
        if self.only_lambertian {
            kinds.push("every one in use Lambertian".into());
        }
        if !kinds.is_empty() {
            write!(f, " ({})", kinds.join(", "))?;
        }
        writeln!(f)?;
        writeln!(f, "textures            {}", self.textures)?;
        writeln!(f, "cameras             {}", self.cameras)?;
        writeln!(
            f,
            "light models        {} (light tree depth {:.1} mean, {} most)",
            self.light_models, self.light_tree_depth_mean, self.light_tree_depth_max
        )?;
        writeln!(
            f,
            "emissive triangles  {} ({} dropped: zero area, emission or alpha coverage)",
            self.emissive_triangles, self.dropped_emissive_triangles
        )?;
        if self.ies_lights > 0 {
            writeln!(
                f,
                "punctual lights     {} ({} with IES profiles)",
                self.punctual_lights, self.ies_lights
            )?;
        } else {
            writeln!(f, "punctual lights     {}", self.punctual_lights)?;
        }
        writeln!(f, "total power         {:.4e}", self.total_power)?;
        writeln!(
            f,
            "bounds              {:?} .. {:?}",
            self.bounds_min, self.bounds_max
        )?;
        write!(
            f,
            "device memory       ~{:.1} MiB (estimate)",
            mib(self.device_bytes)
        )
    }
}
