//! A small glTF 2.0 writer for the generators: one `.bin` buffer with one tightly packed,
//! 4-byte-aligned buffer view per accessor; materials in metallic-roughness form with the
//! `KHR_materials_specular`, `KHR_materials_emissive_strength` and `KHR_lights_punctual`
//! extensions lanterna reads; PNG textures; cameras; a flat node list (every node a root,
//! so a node's transform is its world transform). While it writes, it keeps the statistics
//! a test or the CLI reports: triangles after instancing, light models (nodes whose mesh
//! emits), emissive triangles and the range of emitted power. Files are written to
//! temporary names and renamed at the end so a failure leaves no half-written scene.

use super::mesh::MeshData;
use super::GenerateError;
use glam::{Mat4, Quat, Vec3};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

/// Rounds for the JSON text: keeps node transforms and parameters short and readable.
pub fn num(x: f32) -> Value {
    let r = (x as f64 * 1e6).round() / 1e6;
    json!(if r == 0.0 { 0.0 } else { r })
}

fn nums(v: &[f32]) -> Value {
    Value::Array(v.iter().map(|&x| num(x)).collect())
}

#[derive(Clone, Debug)]
pub struct Material {
    pub name: String,
    pub base_color: [f32; 4],
    pub base_color_texture: Option<usize>,
    pub metallic: f32,
    pub roughness: f32,
    /// `KHR_materials_specular` with `specularFactor: 0`: a pure Lambertian surface.
    pub lambertian: bool,
    /// Linear emitted radiance (colour × strength); split into factor and strength on write.
    pub emission: [f32; 3],
    pub emissive_texture: Option<usize>,
    /// Mean of the emissive texture over the texels this material's meshes use, so that
    /// the emitted power of a light model can be reported.
    pub emissive_texture_mean: f32,
    pub alpha_cutoff: Option<f32>,
    pub double_sided: bool,
    /// `KHR_materials_transmission` factor (thin glass); 0: opaque.
    pub transmission: f32,
}

impl Material {
    pub fn diffuse(name: &str, rgb: [f32; 3]) -> Self {
        Material {
            name: name.to_string(),
            base_color: [rgb[0], rgb[1], rgb[2], 1.0],
            base_color_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            lambertian: true,
            emission: [0.0; 3],
            emissive_texture: None,
            emissive_texture_mean: 1.0,
            alpha_cutoff: None,
            double_sided: false,
            transmission: 0.0,
        }
    }

    pub fn metal(name: &str, rgb: [f32; 3], roughness: f32) -> Self {
        Material {
            metallic: 1.0,
            roughness,
            lambertian: false,
            ..Self::diffuse(name, rgb)
        }
    }

    /// A glossy dielectric (glTF's default specular layer over a diffuse base).
    pub fn glossy(name: &str, rgb: [f32; 3], roughness: f32) -> Self {
        Material {
            roughness,
            lambertian: false,
            ..Self::diffuse(name, rgb)
        }
    }

    /// An emitter with a black, Lambertian base (it reflects nothing).
    pub fn emitter(name: &str, radiance: [f32; 3]) -> Self {
        Material {
            emission: radiance,
            ..Self::diffuse(name, [0.0; 3])
        }
    }

    pub fn emits(&self) -> bool {
        self.emission.iter().any(|&e| e > 0.0) && self.emissive_texture_mean > 0.0
    }

    fn mean_radiance(&self) -> f64 {
        self.emission.iter().map(|&e| e as f64).sum::<f64>() / 3.0
            * self.emissive_texture_mean as f64
    }
}

#[derive(Clone, Copy, Debug)]
pub enum Filter {
    Linear,
    Nearest,
}

struct MeshInfo {
    triangles: u64,
    emissive_triangles: u64,
    /// Emissive primitives (geometry, mean radiance) for power per instance.
    emitters: Vec<(MeshData, f64)>,
}

/// What a node places in the scene.
#[derive(Clone, Debug, Default)]
pub struct Node {
    pub name: Option<String>,
    pub mesh: Option<usize>,
    pub camera: Option<usize>,
    pub light: Option<usize>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Node {
    pub fn mesh(mesh: usize, translation: Vec3) -> Self {
        Node {
            mesh: Some(mesh),
            translation,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
            ..Default::default()
        }
    }
    pub fn named(mut self, name: impl Into<String>) -> Self {
        self.name = Some(name.into());
        self
    }
    pub fn rotated_y(mut self, angle: f32) -> Self {
        self.rotation = Quat::from_rotation_y(angle);
        self
    }
    pub fn scaled(mut self, s: Vec3) -> Self {
        self.scale = s;
        self
    }
    fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

#[derive(Default, Clone, Debug)]
pub struct Stats {
    pub triangles: u64,
    pub stored_triangles: u64,
    pub nodes: u64,
    pub light_models: u64,
    pub emissive_triangles: u64,
    pub punctual_lights: u64,
    pub min_light_power: f64,
    pub max_light_power: f64,
}

pub struct Gltf {
    bin: Vec<u8>,
    buffer_views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    /// Meshes, materials and textures are declared up front but written only when first
    /// used (by a node, a mesh, a material), so a file never holds unused objects.
    mesh_defs: Vec<(String, Vec<(MeshData, usize)>)>,
    mesh_info: Vec<Option<(usize, MeshInfo)>>,
    materials: Vec<Value>,
    material_defs: Vec<Material>,
    material_index: Vec<Option<usize>>,
    samplers: Vec<Value>,
    images: Vec<(String, Vec<u8>)>,
    textures: Vec<Value>,
    texture_defs: Vec<(String, Vec<u8>, Filter)>,
    texture_index: Vec<Option<usize>>,
    uses_specular: bool,
    uses_transmission: bool,
    cameras: Vec<Value>,
    lights: Vec<Value>,
    nodes: Vec<Value>,
    uses_emissive_strength: bool,
    stats: Stats,
    /// Translation of a root node that holds every other node (`--offset`).
    offset: Vec3,
}

impl Default for Gltf {
    fn default() -> Self {
        Self::new()
    }
}

impl Gltf {
    pub fn new() -> Self {
        Gltf {
            bin: Vec::new(),
            buffer_views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
            mesh_defs: Vec::new(),
            mesh_info: Vec::new(),
            materials: Vec::new(),
            material_defs: Vec::new(),
            material_index: Vec::new(),
            samplers: Vec::new(),
            images: Vec::new(),
            textures: Vec::new(),
            texture_defs: Vec::new(),
            texture_index: Vec::new(),
            uses_specular: false,
            uses_transmission: false,
            cameras: Vec::new(),
            lights: Vec::new(),
            nodes: Vec::new(),
            uses_emissive_strength: false,
            offset: Vec3::ZERO,
            stats: Stats {
                min_light_power: f64::INFINITY,
                ..Default::default()
            },
        }
    }

    /// Make every material Lambertian and opaque (`--matte`): metals and glossy or
    /// glass-like panels become matte with their base colour, alpha masks are dropped.
    /// Textures, emission and geometry are kept.
    pub fn make_matte(&mut self) {
        for handle in 0..self.material_defs.len() {
            let m = &mut self.material_defs[handle];
            m.metallic = 0.0;
            // Thin glass stays: smooth and without Fresnel reflection, which the Mitsuba
            // export writes exactly (an index-matched `dielectric`).
            m.roughness = if m.transmission > 0.0 { 0.0 } else { 1.0 };
            m.lambertian = true;
            m.alpha_cutoff = None;
            // Materials the meshes already use are written again.
            if let Some(i) = self.material_index[handle] {
                let m = m.clone();
                self.materials[i] = self.material_json(&m);
            }
        }
    }

    /// Move the whole scene by `offset` (written as one root node holding all others).
    pub fn set_offset(&mut self, offset: Vec3) {
        self.offset = offset;
    }

    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.buffer_views.push(
            json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target}),
        );
        self.buffer_views.len() - 1
    }

    fn accessor(
        &mut self,
        view: usize,
        component: u32,
        count: usize,
        ty: &str,
    ) -> Map<String, Value> {
        let mut a = Map::new();
        a.insert("bufferView".into(), json!(view));
        a.insert("componentType".into(), json!(component));
        a.insert("count".into(), json!(count));
        a.insert("type".into(), json!(ty));
        a
    }

    fn push_accessor(&mut self, a: Map<String, Value>) -> usize {
        self.accessors.push(Value::Object(a));
        self.accessors.len() - 1
    }

    fn vec3_accessor(&mut self, data: &[Vec3], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flat_map(|v| v.to_array())
            .flat_map(f32::to_le_bytes)
            .collect();
        let view = self.view(&bytes, 34962);
        let mut a = self.accessor(view, 5126, data.len(), "VEC3");
        if with_bounds {
            let (lo, hi) = data
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                    (lo.min(p), hi.max(p))
                });
            // Exact f32 values: the validator compares the bounds with the buffer bit for bit.
            a.insert("min".into(), json!(lo.to_array().map(|x| x as f64)));
            a.insert("max".into(), json!(hi.to_array().map(|x| x as f64)));
        }
        self.push_accessor(a)
    }

    /// Declares a material; returns its handle.
    pub fn material(&mut self, m: Material) -> usize {
        self.material_defs.push(m);
        self.material_index.push(None);
        self.material_defs.len() - 1
    }

    fn emit_material(&mut self, handle: usize) -> usize {
        if let Some(i) = self.material_index[handle] {
            return i;
        }
        let m = self.material_defs[handle].clone();
        let v = self.material_json(&m);
        self.materials.push(v);
        let i = self.materials.len() - 1;
        self.material_index[handle] = Some(i);
        i
    }

    /// The glTF material of `m` (its textures are emitted on first use).
    fn material_json(&mut self, m: &Material) -> Value {
        let mut pbr = Map::new();
        pbr.insert("baseColorFactor".into(), nums(&m.base_color));
        if let Some(t) = m.base_color_texture {
            pbr.insert(
                "baseColorTexture".into(),
                json!({"index": self.emit_texture(t)}),
            );
        }
        pbr.insert("metallicFactor".into(), num(m.metallic));
        pbr.insert("roughnessFactor".into(), num(m.roughness));
        let mut v = Map::new();
        v.insert("name".into(), json!(m.name));
        v.insert("pbrMetallicRoughness".into(), Value::Object(pbr));
        let mut ext = Map::new();
        if m.lambertian {
            ext.insert(
                "KHR_materials_specular".into(),
                json!({"specularFactor": 0.0}),
            );
            self.uses_specular = true;
        }
        if m.transmission > 0.0 {
            ext.insert(
                "KHR_materials_transmission".into(),
                json!({"transmissionFactor": num(m.transmission)}),
            );
            self.uses_transmission = true;
        }
        let peak = m.emission.iter().cloned().fold(0.0f32, f32::max);
        if peak > 0.0 {
            let factor = m.emission.map(|e| e / peak);
            v.insert("emissiveFactor".into(), nums(&factor));
            if peak != 1.0 {
                ext.insert(
                    "KHR_materials_emissive_strength".into(),
                    json!({"emissiveStrength": num(peak)}),
                );
                self.uses_emissive_strength = true;
            }
            if let Some(t) = m.emissive_texture {
                v.insert(
                    "emissiveTexture".into(),
                    json!({"index": self.emit_texture(t)}),
                );
            }
        }
        if let Some(cutoff) = m.alpha_cutoff {
            v.insert("alphaMode".into(), json!("MASK"));
            v.insert("alphaCutoff".into(), num(cutoff));
        }
        if m.double_sided {
            v.insert("doubleSided".into(), json!(true));
        }
        if !ext.is_empty() {
            v.insert("extensions".into(), Value::Object(ext));
        }
        Value::Object(v)
    }

    /// Declares a PNG texture (already encoded) with a repeating sampler; returns its handle.
    pub fn texture(&mut self, name: &str, png: Vec<u8>, filter: Filter) -> usize {
        self.texture_defs.push((name.to_string(), png, filter));
        self.texture_index.push(None);
        self.texture_defs.len() - 1
    }

    fn emit_texture(&mut self, handle: usize) -> usize {
        if let Some(i) = self.texture_index[handle] {
            return i;
        }
        let (name, png, filter) = self.texture_defs[handle].clone();
        let f = match filter {
            Filter::Linear => (9729, 9987),
            Filter::Nearest => (9728, 9728),
        };
        self.samplers
            .push(json!({"magFilter": f.0, "minFilter": f.1, "wrapS": 10497, "wrapT": 10497}));
        self.images.push((name, png));
        self.textures
            .push(json!({"sampler": self.samplers.len() - 1, "source": self.images.len() - 1}));
        self.texture_index[handle] = Some(self.textures.len() - 1);
        self.textures.len() - 1
    }

    /// Declares a mesh of one primitive per (geometry, material) pair; empty parts are
    /// skipped. Returns its handle.
    pub fn mesh(&mut self, name: &str, parts: &[(&MeshData, usize)]) -> usize {
        let parts = parts
            .iter()
            .filter(|(g, _)| !g.is_empty())
            .map(|&(g, m)| (g.clone(), m))
            .collect();
        self.mesh_defs.push((name.to_string(), parts));
        self.mesh_info.push(None);
        self.mesh_defs.len() - 1
    }

    fn emit_mesh(&mut self, handle: usize) -> usize {
        if let Some((i, _)) = self.mesh_info[handle] {
            return i;
        }
        let (name, parts) = std::mem::take(&mut self.mesh_defs[handle]);
        let mut prims = Vec::new();
        let mut info = MeshInfo {
            triangles: 0,
            emissive_triangles: 0,
            emitters: Vec::new(),
        };
        for (geo, material) in parts {
            let mut attrs = Map::new();
            attrs.insert(
                "POSITION".into(),
                json!(self.vec3_accessor(&geo.positions, true)),
            );
            attrs.insert(
                "NORMAL".into(),
                json!(self.vec3_accessor(&geo.normals, false)),
            );
            let mat = &self.material_defs[material];
            if mat.base_color_texture.is_some() || mat.emissive_texture.is_some() {
                let bytes: Vec<u8> = geo
                    .uvs
                    .iter()
                    .flat_map(|v| v.to_array())
                    .flat_map(f32::to_le_bytes)
                    .collect();
                let view = self.view(&bytes, 34962);
                let a = self.accessor(view, 5126, geo.uvs.len(), "VEC2");
                attrs.insert("TEXCOORD_0".into(), json!(self.push_accessor(a)));
            }
            let indices = if geo.positions.len() <= u16::MAX as usize {
                let bytes: Vec<u8> = geo
                    .indices
                    .iter()
                    .flat_map(|&i| (i as u16).to_le_bytes())
                    .collect();
                let view = self.view(&bytes, 34963);
                self.accessor(view, 5123, geo.indices.len(), "SCALAR")
            } else {
                let bytes: Vec<u8> = geo.indices.iter().flat_map(|&i| i.to_le_bytes()).collect();
                let view = self.view(&bytes, 34963);
                self.accessor(view, 5125, geo.indices.len(), "SCALAR")
            };
            let indices = self.push_accessor(indices);
            let material_index = self.emit_material(material);
            prims
                .push(json!({"attributes": attrs, "indices": indices, "material": material_index}));
            let tris = geo.triangle_count() as u64;
            info.triangles += tris;
            let mat = &self.material_defs[material];
            if mat.emits() {
                info.emissive_triangles += tris;
                let radiance = mat.mean_radiance();
                info.emitters.push((geo, radiance));
            }
        }
        self.stats.stored_triangles += info.triangles;
        self.meshes.push(json!({"name": name, "primitives": prims}));
        self.mesh_info[handle] = Some((self.meshes.len() - 1, info));
        self.meshes.len() - 1
    }

    pub fn camera(&mut self, name: &str, yfov_deg: f32, aspect: f32) -> usize {
        self.cameras.push(json!({
            "name": name,
            "type": "perspective",
            "perspective": {"yfov": num(yfov_deg.to_radians()), "aspectRatio": num(aspect), "znear": 0.01}
        }));
        self.cameras.len() - 1
    }

    /// A camera node at `eye` looking at `target` (the camera looks down its local −Z).
    pub fn camera_node(&mut self, camera: usize, eye: Vec3, target: Vec3) -> usize {
        let f = (target - eye).normalize();
        let r = f.cross(Vec3::Y).normalize();
        let u = r.cross(f);
        let rotation = Quat::from_mat3(&glam::Mat3::from_cols(r, u, -f)).normalize();
        self.node(Node {
            name: Some("camera".into()),
            camera: Some(camera),
            translation: eye,
            rotation,
            scale: Vec3::ONE,
            ..Default::default()
        })
    }

    /// A `KHR_lights_punctual` light: `spot` is `Some((inner, outer))` cone angles in radians.
    pub fn punctual_light(
        &mut self,
        name: &str,
        color: [f32; 3],
        intensity: f32,
        spot: Option<(f32, f32)>,
    ) -> usize {
        let mut l = json!({"name": name, "color": nums(&color), "intensity": num(intensity), "type": "point"});
        if let Some((inner, outer)) = spot {
            l["type"] = json!("spot");
            l["spot"] = json!({"innerConeAngle": num(inner), "outerConeAngle": num(outer)});
        }
        self.lights.push(l);
        self.stats.punctual_lights += 1;
        self.lights.len() - 1
    }

    pub fn node(&mut self, n: Node) -> usize {
        let mut v = Map::new();
        if let Some(name) = &n.name {
            v.insert("name".into(), json!(name));
        }
        if let Some(c) = n.camera {
            v.insert("camera".into(), json!(c));
        }
        if let Some(m) = n.mesh {
            let index = self.emit_mesh(m);
            v.insert("mesh".into(), json!(index));
            let info = &self.mesh_info[m].as_ref().expect("emitted above").1;
            self.stats.triangles += info.triangles;
            if info.emissive_triangles > 0 {
                self.stats.light_models += 1;
                self.stats.emissive_triangles += info.emissive_triangles;
                let matrix = n.matrix();
                let power: f64 = info
                    .emitters
                    .iter()
                    .map(|(g, radiance)| std::f64::consts::PI * radiance * g.area(matrix))
                    .sum();
                self.stats.min_light_power = self.stats.min_light_power.min(power);
                self.stats.max_light_power = self.stats.max_light_power.max(power);
            }
        }
        if let Some(l) = n.light {
            v.insert(
                "extensions".into(),
                json!({"KHR_lights_punctual": {"light": l}}),
            );
        }
        if n.translation != Vec3::ZERO {
            v.insert("translation".into(), nums(&n.translation.to_array()));
        }
        if n.rotation != Quat::IDENTITY {
            v.insert(
                "rotation".into(),
                json!(n.rotation.to_array().map(|x| x as f64)),
            );
        }
        if n.scale != Vec3::ONE {
            v.insert("scale".into(), nums(&n.scale.to_array()));
        }
        self.nodes.push(Value::Object(v));
        self.stats.nodes += 1;
        self.nodes.len() - 1
    }

    /// Writes `out` (the .gltf), `<stem>.bin` and `<stem>_<name>.png`; returns the paths
    /// written. Everything goes to temporary files first and is renamed only when all of
    /// it has been written.
    pub fn write(self, out: &Path, asset_extras: Value) -> Result<Vec<PathBuf>, GenerateError> {
        let dir = out
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        let stem =
            out.file_stem()
                .and_then(|s| s.to_str())
                .ok_or_else(|| GenerateError::BadOutput {
                    path: out.to_path_buf(),
                    reason: "no usable file name".into(),
                })?;
        let bin_name = format!("{stem}.bin");
        let mut root = Map::new();
        root.insert(
            "asset".into(),
            json!({"version": "2.0", "generator": "lanterna scene generate", "extras": asset_extras}),
        );
        let mut used = Vec::new();
        if self.uses_specular {
            used.push("KHR_materials_specular");
        }
        if self.uses_emissive_strength {
            used.push("KHR_materials_emissive_strength");
        }
        if self.uses_transmission {
            used.push("KHR_materials_transmission");
        }
        if !self.lights.is_empty() {
            used.push("KHR_lights_punctual");
            root.insert(
                "extensions".into(),
                json!({"KHR_lights_punctual": {"lights": self.lights}}),
            );
        }
        if !used.is_empty() {
            root.insert("extensionsUsed".into(), json!(used));
        }
        root.insert("scene".into(), json!(0));
        let mut nodes = self.nodes;
        let children: Vec<usize> = (0..nodes.len()).collect();
        let roots = if self.offset == Vec3::ZERO {
            children
        } else {
            nodes.push(json!({"name": "offset", "translation": nums(&self.offset.to_array()), "children": children}));
            vec![nodes.len() - 1]
        };
        root.insert("scenes".into(), json!([{"name": stem, "nodes": roots}]));
        root.insert("nodes".into(), Value::Array(nodes));
        let put = |root: &mut Map<String, Value>, key: &str, v: Vec<Value>| {
            if !v.is_empty() {
                root.insert(key.into(), Value::Array(v));
            }
        };
        put(&mut root, "cameras", self.cameras);
        put(&mut root, "meshes", self.meshes);
        put(&mut root, "materials", self.materials);
        put(&mut root, "textures", self.textures);
        put(&mut root, "samplers", self.samplers);
        let image_names: Vec<String> = self
            .images
            .iter()
            .map(|(n, _)| format!("{stem}_{n}.png"))
            .collect();
        put(
            &mut root,
            "images",
            image_names.iter().map(|u| json!({"uri": u})).collect(),
        );
        put(&mut root, "accessors", self.accessors);
        put(&mut root, "bufferViews", self.buffer_views);
        root.insert(
            "buffers".into(),
            json!([{"uri": bin_name, "byteLength": self.bin.len()}]),
        );
        let text = render_json(&root);

        // Payloads first, the .gltf last: a reader never sees a .gltf whose parts are missing.
        let mut files: Vec<(PathBuf, &[u8])> = vec![(dir.join(&bin_name), &self.bin)];
        for (name, (_, png)) in image_names.iter().zip(&self.images) {
            files.push((dir.join(name), png));
        }
        files.push((out.to_path_buf(), &text));
        let mut plan = crate::files::FilePlan::new();
        for (path, _) in &files {
            plan.output("a generated file", path);
        }
        plan.check()?;
        let refs: Vec<(&Path, &[u8])> = files.iter().map(|(p, b)| (p.as_path(), *b)).collect();
        crate::files::write_all_atomically(&refs)?;
        Ok(files.into_iter().map(|(p, _)| p).collect())
    }
}

/// The glTF JSON with the asset block pretty-printed (it carries the provenance a person
/// reads) and one compact line per array element elsewhere, so that scenes with tens of
/// thousands of nodes stay compact yet diff line by line. Keys come in glTF's usual order.
fn render_json(root: &Map<String, Value>) -> Vec<u8> {
    const ORDER: [&str; 15] = [
        "asset",
        "extensionsUsed",
        "extensions",
        "scene",
        "scenes",
        "nodes",
        "cameras",
        "meshes",
        "materials",
        "textures",
        "samplers",
        "images",
        "accessors",
        "bufferViews",
        "buffers",
    ];
    let compact = |v: &Value| serde_json::to_string(v).expect("JSON values always serialise");
    let mut out = String::from("{\n");
    let keys: Vec<&str> = ORDER
        .iter()
        .copied()
        .filter(|k| root.contains_key(*k))
        .collect();
    debug_assert_eq!(
        keys.len(),
        root.len(),
        "a top-level key is missing from ORDER"
    );
    for (i, key) in keys.iter().enumerate() {
        let value = &root[*key];
        out.push_str(&format!("  {}: ", compact(&json!(key))));
        match value {
            Value::Array(items) if *key != "extensionsUsed" => {
                out.push_str("[\n");
                for (j, item) in items.iter().enumerate() {
                    out.push_str("    ");
                    out.push_str(&compact(item));
                    out.push_str(if j + 1 < items.len() { ",\n" } else { "\n" });
                }
                out.push_str("  ]");
            }
            Value::Object(_) if *key == "asset" => {
                let pretty =
                    serde_json::to_string_pretty(value).expect("JSON values always serialise");
                out.push_str(&pretty.replace('\n', "\n  "));
            }
            v => out.push_str(&compact(v)),
        }
        out.push_str(if i + 1 < keys.len() { ",\n" } else { "\n" });
    }
    out.push_str("}\n");
    out.into_bytes()
}
