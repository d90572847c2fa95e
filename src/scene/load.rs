//! glTF 2.0 → [`Scene`]: buffers and images loaded one by one (so that an error names
//! the file or URI at fault), the node hierarchy flattened into instances, primitives
//! deduplicated into one BLAS each, materials converted, cameras and punctual lights
//! placed in world space.

use super::animation::{self, Pose};
use super::animation_pointer;
use super::camera::{Camera, ClipPlanes, Projection};
use super::draco;
use super::gltf_check::{self, node_name};
use super::ies;
use super::load_instancing;
use super::load_light::{convert_ies_light, convert_light};
use super::load_primitive::{load_primitive, Geometry};
use super::material::{self, TextureRegistry};
use super::meshopt;
use super::sources;
use super::variants;
use super::{Instance, MeshPrimitive, Scene, SceneError};
use glam::{Mat4, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Loader options.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Follow buffer and image URIs that resolve outside the scene's folder (absolute
    /// paths, `..`, `file:` URIs, symlinks out). Off by default: see `sources.rs`.
    pub allow_outside_uris: bool,
    /// Pose the file's animations at a time (`--animation-time`, `--animation`); `None` renders
    /// the nodes' own transforms and morph weights.
    pub pose: Option<Pose>,
    /// Render this `KHR_materials_variants` variant, by name or index (`--variant`);
    /// `None` keeps every primitive's own material.
    pub variant: Option<String>,
}

pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    let started = std::time::Instant::now();
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let limit = crate::files::max_input_bytes();
    let bytes = sources::read_scene_file(path, limit).map_err(|error| SceneError::File {
        path: path.to_path_buf(),
        error,
    })?;
    let gltf_error = |e: gltf::Error| SceneError::Gltf {
        path: path.to_path_buf(),
        message: e.to_string(),
    };
    let mut parse_warnings = Vec::new();
    let (gltf::Gltf { document, mut blob }, taken) =
        parse(&bytes, &mut parse_warnings).map_err(gltf_error)?;
    drop(bytes);
    let mut root = document.into_json();
    if !root.animations.is_empty() && options.pose.is_none() {
        parse_warnings.push(format!(
            "has {} animation(s); without --animation-time lanterna renders the file's own \
             values (its static pose)",
            root.animations.len()
        ));
    }
    gltf_check::precheck(&root).map_err(&invalid)?;
    // The crate refuses required extensions it does not read itself, among them several
    // lanterna reads from the JSON (KHR_materials_volume, _specular, _ior, _clearcoat,
    // _sheen, KHR_mesh_quantization). So lanterna decides: a required extension it does
    // not read is refused here, by name, before the crate's validation would bury it
    // among the errors it causes (an unknown compression's accessors without data).
    let unknown: Vec<&str> = root
        .extensions_required
        .iter()
        .map(String::as_str)
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e) && !INERT_EXTENSIONS.contains(e))
        .collect();
    if !unknown.is_empty() {
        return Err(invalid(format!(
            "requires the glTF extension{} {}, which lanterna does not support",
            if unknown.len() > 1 { "s" } else { "" },
            unknown.join(", ")
        )));
    }
    root.extensions_required.clear();
    // Draco primitives' accessors get views in a placeholder buffer, filled below.
    let draco_plan = draco::plan(&mut root).map_err(&invalid)?;
    let document = gltf::Document::from_json(root).map_err(gltf_error)?;
    gltf_check::check_views(document.as_json()).map_err(&invalid)?;
    let mut uris = sources::UriReader::new(path, options.allow_outside_uris, limit);
    let mut budget = sources::Budget::new(limit);

    // Buffers, one at a time so a failure names the buffer.
    let meshopt_used = document
        .extensions_used()
        .any(|e| meshopt::EXTENSIONS.contains(&e));
    let mut buffers = Vec::new();
    for b in document.buffers() {
        let (what, data) = match b.source() {
            gltf::buffer::Source::Bin
                if draco_plan.as_ref().is_some_and(|p| p.buffer == b.index()) =>
            {
                budget
                    .take(b.length() as u64, "decoded Draco meshes")
                    .map_err(&invalid)?;
                (
                    format!("buffer {} (for decoded Draco meshes)", b.index()),
                    Some(vec![0u8; b.length()]),
                )
            }
            // EXT_meshopt_compression's placeholder for decompressed views: a buffer
            // without a URI that is not the GLB chunk (which only the first may be).
            gltf::buffer::Source::Bin if meshopt_used && (b.index() > 0 || blob.is_none()) => {
                budget
                    .take(b.length() as u64, "a buffer for decompressed data")
                    .map_err(&invalid)?;
                (
                    format!("buffer {} (for decompressed data)", b.index()),
                    Some(vec![0u8; b.length()]),
                )
            }
            gltf::buffer::Source::Bin => ("the GLB binary chunk".to_string(), blob.take()),
            gltf::buffer::Source::Uri(u) => {
                let what = if u.starts_with("data:") {
                    format!("buffer {} (data URI)", b.index())
                } else {
                    format!("buffer {} (`{u}`)", b.index())
                };
                let data = uris
                    .read(u, Some(b.length() as u64))
                    .map_err(|e| invalid(format!("cannot load {what}: {e}")))?;
                (what, Some(data))
            }
        };
        let Some(mut data) = data else {
            return Err(invalid(format!("{what} is missing")));
        };
        if data.len() < b.length() {
            return Err(invalid(format!(
                "{what} has {} bytes but declares {}",
                data.len(),
                b.length()
            )));
        }
        while data.len() % 4 != 0 {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    if meshopt_used {
        decompress_views(&document, &mut buffers).map_err(&invalid)?;
    }
    let document = match &draco_plan {
        Some(plan) => match draco::decode(plan, document.as_json(), &mut buffers, &mut budget)
            .map_err(&invalid)?
        {
            Some(json) => gltf::Document::from_json(json).map_err(gltf_error)?,
            None => document,
        },
        None => document,
    };

    // Every node's local transform and morph weights, posed by the animations when asked.
    // Their pointer channels' other properties are written into the JSON, and everything
    // below reads the document rebuilt from it, as it would a file stating those values.
    let mut pose_warnings = Vec::new();
    let (locals, animated_weights, document, patched) = match &options.pose {
        None => (
            animation::static_locals(&document),
            Vec::new(),
            document,
            false,
        ),
        Some(pose) => {
            let posed = animation::pose(
                &document,
                &taken,
                &buffers,
                pose,
                budget.left(),
                &mut pose_warnings,
            )
            .map_err(&invalid)?;
            match posed.json {
                None => (posed.locals, posed.weights, document, false),
                Some(json) => {
                    let document = animation_pointer::rebuild(json).map_err(|e| {
                        invalid(format!(
                            "its animated properties at time {} cannot be read: {e}",
                            pose.time
                        ))
                    })?;
                    (posed.locals, posed.weights, document, true)
                }
            }
        }
    };
    // A property an animation set, found wrong below, is named as posed.
    let posed_note = match &options.pose {
        Some(pose) if patched => format!(" (as its animations pose it at time {} s)", pose.time),
        _ => String::new(),
    };
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message: format!("{message}{posed_note}"),
    };

    // Images that materials use (decoded lazily: unused images are skipped).
    let mut used_images = vec![false; document.images().len()];
    for m in document.materials() {
        let pbr = m.pbr_metallic_roughness();
        let mut mark = |t: Option<gltf::Texture<'_>>| {
            if let Some(t) = t {
                used_images[t.source().index()] = true;
            }
        };
        mark(pbr.base_color_texture().map(|i| i.texture()));
        mark(pbr.metallic_roughness_texture().map(|i| i.texture()));
        mark(m.normal_texture().map(|i| i.texture()));
        mark(m.emissive_texture().map(|i| i.texture()));
        if let Some(t) = m.transmission() {
            mark(t.transmission_texture().map(|i| i.texture()));
        }
        if let Some(sg) = m.pbr_specular_glossiness() {
            mark(sg.diffuse_texture().map(|i| i.texture()));
        }
        // Malformed coats, sheens and anisotropy are reported by the conversion below.
        if let Ok(Some(coat)) = material::Clearcoat::read(&m, &document) {
            for t in [coat.texture, coat.roughness_texture, coat.normal_texture] {
                mark(t.map(|t| t.texture));
            }
        }
        if let Ok(Some(sheen)) = material::Sheen::read(&m, &document) {
            for t in [sheen.colour_texture, sheen.roughness_texture] {
                mark(t.map(|t| t.texture));
            }
        }
        if let Ok(Some(a)) = material::Anisotropy::read(&m, &document) {
            mark(a.texture.map(|t| t.texture));
        }
        if let Ok(Some(dt)) = material::DiffuseTransmission::read(&m, &document) {
            for t in [dt.texture, dt.colour_texture] {
                mark(t.map(|t| t.texture));
            }
        }
        if let Ok(Some(i)) = material::Iridescence::read(&m, &document) {
            for t in [i.texture, i.thickness_texture] {
                mark(t.map(|t| t.texture));
            }
        }
    }
    let mut images = Vec::new();
    for img in document.images() {
        if !used_images[img.index()] {
            images.push(None);
            continue;
        }
        let (what, encoded) = match img.source() {
            gltf::image::Source::Uri { uri, .. } => {
                let what = if uri.starts_with("data:") {
                    format!("image {} (data URI)", img.index())
                } else {
                    format!("image {} (`{uri}`)", img.index())
                };
                let data = uris
                    .read(uri, None)
                    .map_err(|e| invalid(format!("cannot load {what}: {e}")))?;
                (what, std::borrow::Cow::Owned(data))
            }
            gltf::image::Source::View { view, .. } => {
                // check_views put the view inside its buffer's data.
                let data = &buffers[view.buffer().index()].0;
                let range = view.offset()..view.offset() + view.length();
                (
                    format!("image {} (buffer view {})", img.index(), view.index()),
                    std::borrow::Cow::Borrowed(&data[range]),
                )
            }
        };
        let data = sources::decode_image(&encoded, budget.left())
            .map_err(|e| invalid(format!("cannot load {what}: {e}")))?;
        budget
            .take(data.pixels.len() as u64, &what)
            .map_err(&invalid)?;
        images.push(Some(data));
    }

    // Materials.
    let mut registry = TextureRegistry {
        images: &images,
        slots: HashMap::new(),
        textures: Vec::new(),
        warnings: Vec::new(),
    };
    let mut materials = Vec::new();
    let mut material_names = Vec::new();
    for m in document.materials() {
        materials.push(material::convert(&m, &document, &mut registry).map_err(invalid)?);
        material_names.push(
            m.name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("material {}", m.index().unwrap_or(0))),
        );
    }
    let default_material = materials.len() as u32;
    // A malformed variant list matters only to a render that asks for a variant.
    let variant_names = variants::names(&document);
    let variant = match &options.variant {
        Some(wanted) => {
            let names = variant_names.as_deref().map_err(|e| invalid(e.clone()))?;
            Some(variants::choose(names, wanted).map_err(&invalid)?)
        }
        None => None,
    };
    let variant_names = variant_names.unwrap_or_default();
    materials.push(material::default_material());
    material_names.push("default".into());

    // EXT_lights_ies profiles, each packed once into the scene's profile array.
    let mut light_profiles = Vec::new();
    let mut profile_offsets = Vec::new();
    if let Some(ext) = document.extension_value(ies::EXTENSION) {
        let list = ext
            .get("lights")
            .and_then(|l| l.as_array())
            .ok_or_else(|| invalid(format!("{} has no `lights` array", ies::EXTENSION)))?;
        let view = |i: usize| {
            let v = document.views().nth(i)?;
            // check_views put the view inside its buffer's data.
            let data = &buffers[v.buffer().index()].0;
            Some(data[v.offset()..v.offset() + v.length()].to_vec())
        };
        for (i, entry) in list.iter().enumerate() {
            let mut read_uri = |uri: &str| uris.read(uri, None);
            let (profile, notes) = ies::load(entry, i, &mut read_uri, &view).map_err(&invalid)?;
            budget
                .take(4 * profile.candela.len() as u64, "a light profile")
                .map_err(&invalid)?;
            parse_warnings.extend(notes);
            profile_offsets.push(light_profiles.len() as u32);
            profile.pack(&mut light_profiles);
        }
    }

    // Flatten the node hierarchy of the default scene.
    if document.default_scene().is_none() && document.scenes().len() > 1 {
        parse_warnings.push(format!(
            "names no default scene; rendering the first of its {} scenes",
            document.scenes().len()
        ));
    }
    let roots: Vec<gltf::Node<'_>> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    // (node, parent's world transform, depth, whether the parent is visible).
    let mut stack: Vec<(gltf::Node<'_>, Mat4, usize, bool)> = roots
        .into_iter()
        .map(|n| (n, Mat4::IDENTITY, 0, true))
        .collect();

    let mut vertices = Vec::new();
    let mut colors = Vec::new();
    let mut indices = Vec::new();
    let mut primitives: Vec<MeshPrimitive> = Vec::new();
    // Keyed by mesh, primitive, the morph weights it is posed with (empty without morph
    // targets) and the skin that moves it: nodes that pose one mesh differently get their
    // own geometry.
    type PrimitiveKey = (usize, usize, Vec<u32>, Option<usize>);
    let mut primitive_ids: HashMap<PrimitiveKey, Option<u32>> = HashMap::new();
    // Every node's world transform, for skins' joints (which may lie anywhere).
    let node_worlds = node_world_matrices(&document, &locals).map_err(&invalid)?;
    let mut instances = Vec::new();
    let mut cameras = Vec::new();
    // Cameras with a far clip plane: (camera index, world-to-camera as the kernels see
    // it, zfar).
    let mut far_planes: Vec<(usize, Mat4, f32)> = Vec::new();
    let mut punctual = Vec::new();
    let mut warnings = parse_warnings;
    warnings.append(&mut pose_warnings);
    warnings.append(&mut registry.warnings);
    warnings.extend(unsupported_extensions(document.extensions_used()));
    let textures = std::mem::take(&mut registry.textures);
    let mut visited = vec![false; document.nodes().len()];
    // Nodes with a mesh or a light that KHR_node_visibility hides.
    let mut hidden = 0usize;

    while let Some((node, parent, depth, parent_visible)) = stack.pop() {
        if depth > 256 {
            return Err(invalid(
                "node hierarchy deeper than 256 levels (a cycle?)".into(),
            ));
        }
        // Spec: the hierarchy is a set of disjoint strict trees. A node reached twice
        // would be a cycle, or a DAG multiplying instances without bound.
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(invalid(format!(
                "node {} is reached twice: a glTF node hierarchy must be a set of disjoint trees",
                node_name(&node)
            )));
        }
        let world = parent * locals[node.index()];
        if !world.is_finite() {
            return Err(invalid(format!(
                "node {} has a non-finite transform",
                node_name(&node)
            )));
        }
        // KHR_node_visibility: a hidden node hides its meshes and lights and those of
        // every node below it, whatever theirs say; cameras are not affected.
        let visible = parent_visible
            && match node
                .extension_value(NODE_VISIBILITY)
                .map(|v| v.get("visible"))
            {
                None | Some(None) => true,
                Some(Some(serde_json::Value::Bool(b))) => *b,
                Some(Some(other)) => {
                    return Err(invalid(format!(
                        "node {}: {NODE_VISIBILITY} `visible` is {other}, not true or false",
                        node_name(&node)
                    )))
                }
            };
        for c in node.children() {
            stack.push((c, world, depth + 1, visible));
        }
        if let Some(cam) = node.camera() {
            let (znear, zfar) = match cam.projection() {
                gltf::camera::Projection::Perspective(p) => (p.znear(), p.zfar()),
                gltf::camera::Projection::Orthographic(o) => (o.znear(), Some(o.zfar())),
            };
            // A rasteriser's view matrix is the inverse of the node's global transform,
            // scale included, so the projection's lengths (clip distances, orthographic
            // extents) are in the camera node's own units: under a parent scaled by s
            // they are s times as long in the world. (Ray directions come from the
            // rigid part alone, Camera::rigid_to_world.)
            let node_scale = Vec3::new(
                world.x_axis.truncate().length(),
                world.y_axis.truncate().length(),
                world.z_axis.truncate().length(),
            );
            let clip = clip_planes(znear, zfar).map(|c| ClipPlanes {
                near: c.near * node_scale.z,
                far: c.far * node_scale.z,
            });
            let clip = clip.unwrap_or_else(|why| {
                warnings.push(format!(
                    "camera {} has znear {znear} and zfar {}: {why}; its clip planes are ignored",
                    cam.index(),
                    zfar.map_or("none".to_string(), |z| z.to_string())
                ));
                ClipPlanes::NONE
            });
            let projection = match cam.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let yfov = p.yfov();
                    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
                        return Err(invalid(format!(
                            "camera {} has yfov {yfov}, outside (0, π)",
                            cam.index()
                        )));
                    }
                    Projection::Perspective {
                        yfov,
                        aspect: p.aspect_ratio(),
                    }
                }
                gltf::camera::Projection::Orthographic(o) => {
                    let (xmag, ymag) =
                        (o.xmag().abs() * node_scale.x, o.ymag().abs() * node_scale.y);
                    if !(xmag > 0.0 && ymag > 0.0 && xmag.is_finite() && ymag.is_finite()) {
                        return Err(invalid(format!(
                            "orthographic camera {} has magnification {xmag} × {ymag}",
                            cam.index()
                        )));
                    }
                    Projection::Orthographic { xmag, ymag }
                }
            };
            let camera = Camera {
                name: cam
                    .name()
                    .or(node.name())
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("camera {}", cam.index())),
                to_world: world,
                projection,
                clip,
            };
            if clip.far.is_finite() {
                far_planes.push((cam.index(), camera.rigid_to_world().inverse(), clip.far));
            }
            cameras.push((node.index(), camera));
        }
        if !visible {
            hidden += usize::from(
                node.light().is_some()
                    || node.mesh().is_some()
                    || node.extension_value(ies::EXTENSION).is_some(),
            );
            continue;
        }
        if let Some(light) = node.light() {
            punctual.push(convert_light(&light, &world, &node_name(&node)).map_err(&invalid)?);
        }
        if let Some(value) = node.extension_value(ies::EXTENSION) {
            punctual.push(
                convert_ies_light(value, &profile_offsets, &world, &node_name(&node))
                    .map_err(&invalid)?,
            );
        }
        let Some(mesh) = node.mesh() else { continue };
        // A skinned mesh is moved by its joints, in world space; the node's own transform
        // does not apply (glTF 2.0, skins).
        let joints = match node.skin() {
            Some(skin) => Some(
                joint_matrices(
                    &skin,
                    &node_worlds,
                    &buffers,
                    document.as_json(),
                    budget.left(),
                )
                .map_err(&invalid)?,
            ),
            None => None,
        };
        let world = if joints.is_some() {
            Mat4::IDENTITY
        } else {
            world
        };
        // One transform per copy of the mesh: the node's, or with EXT_mesh_gpu_instancing
        // one per instance, relative to the node's.
        let copies: Vec<(Mat4, String)> =
            match load_instancing::instance_transforms(&node, &document, &buffers, budget.left())
                .map_err(|e| invalid(format!("node {}: {e}", node_name(&node))))?
            {
                None => vec![(world, node_name(&node))],
                Some(local) => local
                    .into_iter()
                    .enumerate()
                    .map(|(i, m)| (world * m, format!("{} [instance {i}]", node_name(&node))))
                    .collect(),
            };
        let singular = copies
            .iter()
            .filter(|(m, _)| m.determinant().abs() < 1e-20)
            .count();
        if singular > 0 {
            warnings.push(if copies.len() == 1 {
                format!(
                    "node {} has a singular transform; skipped",
                    node_name(&node)
                )
            } else {
                format!(
                    "node {}: {singular} of its {} instances have a singular transform; skipped",
                    node_name(&node),
                    copies.len()
                )
            });
        }
        let copies: Vec<(Mat4, String)> = copies
            .into_iter()
            .filter(|(m, _)| m.determinant().abs() >= 1e-20)
            .collect();
        if copies.is_empty() {
            continue;
        }
        let morph_weights = animated_weights
            .get(node.index())
            .and_then(Option::as_deref)
            .or(node.weights())
            .or(mesh.weights())
            .unwrap_or(&[]);
        for prim in mesh.primitives() {
            let posed = prim.morph_targets().next().is_some();
            let weight_bits = if posed {
                morph_weights.iter().map(|w| w.to_bits()).collect()
            } else {
                Vec::new()
            };
            let key = (
                mesh.index(),
                prim.index(),
                weight_bits,
                node.skin().map(|s| s.index()),
            );
            let id = match primitive_ids.get(&key) {
                Some(id) => *id,
                None => {
                    let variant_material = match variant {
                        Some(v) => variants::material(
                            &prim,
                            v,
                            variant_names.len(),
                            default_material as usize,
                        )
                        .map_err(|e| {
                            invalid(format!(
                                "mesh {} primitive {}: {e}",
                                mesh.index(),
                                prim.index()
                            ))
                        })?,
                        None => None,
                    };
                    let material = variant_material
                        .or(prim.material().index())
                        .map_or(default_material, |i| i as u32);
                    let id = load_primitive(
                        &mesh,
                        &prim,
                        morph_weights,
                        joints.as_deref(),
                        &buffers,
                        material,
                        &materials,
                        &mut Geometry {
                            root: document.as_json(),
                            vertices: &mut vertices,
                            colors: &mut colors,
                            indices: &mut indices,
                            budget: &mut budget,
                        },
                        &mut warnings,
                    )
                    .map_err(&invalid)?
                    .map(|p| {
                        primitives.push(p);
                        (primitives.len() - 1) as u32
                    });
                    primitive_ids.insert(key, id);
                    id
                }
            };
            let Some(id) = id else { continue };
            // Each copy's triangles are laid out in world space again wherever small
            // primitives are flattened and in the software traversal's BVH (positions
            // and a BVH share, 64 bytes a triangle): a few instance attributes must not
            // expand a small file into unbounded memory.
            let triangles = u64::from(primitives[id as usize].triangle_count);
            for (transform, name) in &copies {
                let bytes = (std::mem::size_of::<Instance>() + name.len()) as u64 + 64 * triangles;
                budget.take(bytes, "the instances").map_err(&invalid)?;
                if instances.len() >= MAX_INSTANCES {
                    return Err(invalid(format!(
                        "has more than {MAX_INSTANCES} mesh instances (nodes and \
                         {} instances), the most a ray query's instance index can tell apart",
                        load_instancing::EXTENSION
                    )));
                }
                instances.push(Instance {
                    primitive: id,
                    transform: *transform,
                    node_name: name.clone(),
                });
            }
        }
    }
    if hidden > 0 {
        log::info!(
            "{}: {hidden} node(s) with a mesh or light hidden ({NODE_VISIBILITY})",
            path.display()
        );
    }
    // Traversal order is a stack; keep files' declaration order for stable indices.
    cameras.sort_by_key(|(node, _)| *node);
    let cameras: Vec<Camera> = cameras.into_iter().map(|(_, c)| c).collect();

    if instances.is_empty() {
        return Err(SceneError::Empty {
            path: path.to_path_buf(),
        });
    }

    // World bounds.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for inst in &instances {
        let p = &primitives[inst.primitive as usize];
        for v in &vertices[p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize] {
            let w = inst.transform.transform_point3(Vec3::from(v.position));
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }

    // A far plane nearer than parts of the scene hides them from the camera, as in any
    // glTF viewer and in Cycles; Blender writes its clip end (100 m by default) there, so
    // say so, and how to see past it.
    for (index, to_camera, zfar) in far_planes {
        let farthest = (0..8)
            .map(|k| {
                let corner =
                    Vec3::select(glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0), hi, lo);
                -to_camera.transform_point3(corner).z
            })
            .fold(f32::MIN, f32::max);
        if farthest > zfar {
            warnings.push(format!(
                "camera {index} has zfar {zfar}, nearer than parts of the scene (up to \
                 {farthest:.4} along its view): its camera rays see nothing beyond that \
                 plane (--no-clip-planes sees everything in front of the camera)"
            ));
        }
    }
    // glTF's range is a cutoff hint for culling; within it a light should fall off with
    // the inverse square, which lanterna's do at every distance.
    let ranged = punctual.iter().filter(|l| l.range > 0.0).count();
    if ranged > 0 {
        warnings.push(format!(
            "{ranged} punctual light(s) have a range, which is ignored: their light falls \
             off with the inverse square at every distance"
        ));
    }
    for w in &warnings {
        log::warn!("{}: {w}", path.display());
    }
    let extras = document
        .as_json()
        .asset
        .extras
        .as_ref()
        .and_then(|raw| serde_json::from_str(raw.get()).ok());
    let mut scene = Scene {
        path: path.to_path_buf(),
        vertices,
        colors,
        indices,
        primitives,
        instances,
        materials,
        material_names,
        textures,
        cameras,
        punctual,
        light_profiles,
        bounds_min: lo,
        bounds_max: hi,
        hash: String::new(),
        extras,
        origin: Vec3::ZERO,
        files: uris.files,
        animations: animation::summaries(&document, &taken),
        pose: options.pose.clone(),
        variant: variant.map(|v| variant_names[v].clone()),
        variants: variant_names,
    };
    scene.hash = content_hash(&scene);
    rebase(&mut scene);
    // Triangles in kd order, for builders that split in submission order. After the
    // hash: the hash names the file's content, and the order is an implementation detail.
    for p in &scene.primitives {
        let positions: Vec<Vec3> = scene.vertices
            [p.vertex_offset as usize..(p.vertex_offset + p.vertex_count) as usize]
            .iter()
            .map(|v| Vec3::from(v.position))
            .collect();
        let first = p.index_offset as usize;
        super::spatial_order::reorder_triangles(
            &positions,
            &mut scene.indices[first..first + 3 * p.triangle_count as usize],
        );
    }

    log::info!(
        "loaded {} in {:.2} s: {} triangles, {} instances, {} materials, {} textures",
        path.display(),
        started.elapsed().as_secs_f64(),
        scene.triangle_count(),
        scene.instances.len(),
        scene.materials.len() - 1,
        scene.textures.len()
    );
    Ok(scene)
}

/// Decodes every buffer view compressed with `EXT_meshopt_compression` into the bytes the
/// view itself spans (in a placeholder buffer, or over a fallback's uncompressed copy).
fn decompress_views(
    document: &gltf::Document,
    buffers: &mut [gltf::buffer::Data],
) -> Result<(), String> {
    for view in document.views() {
        let Some((name, ext)) = meshopt::EXTENSIONS
            .iter()
            .find_map(|&name| Some((name, view.extension_value(name)?)))
        else {
            continue;
        };
        let what = format!("buffer view {} ({name})", view.index());
        let int = |key: &str, default: Option<u64>| -> Result<usize, String> {
            match ext.get(key) {
                None => default.ok_or_else(|| format!("{what} has no `{key}`")),
                Some(v) => v.as_u64().ok_or_else(|| format!("{what}: `{key}` is {v}")),
            }
            .and_then(|v| usize::try_from(v).map_err(|_| format!("{what}: `{key}` is {v}")))
        };
        let (source, offset, length) = (
            int("buffer", None)?,
            int("byteOffset", Some(0))?,
            int("byteLength", None)?,
        );
        let (stride, count) = (int("byteStride", None)?, int("count", None)?);
        let mode = match ext.get("mode").and_then(|m| m.as_str()) {
            Some("ATTRIBUTES") => meshopt::Mode::Attributes,
            Some("TRIANGLES") => meshopt::Mode::Triangles,
            Some("INDICES") => meshopt::Mode::Indices,
            _ => {
                return Err(match ext.get("mode") {
                    Some(m) => format!("{what}: unknown mode {m}"),
                    None => format!("{what} has no `mode`"),
                })
            }
        };
        let filter = match ext.get("filter").map(|f| f.as_str()) {
            None | Some(Some("NONE")) => meshopt::Filter::None,
            Some(Some("OCTAHEDRAL")) => meshopt::Filter::Octahedral,
            Some(Some("QUATERNION")) => meshopt::Filter::Quaternion,
            Some(Some("EXPONENTIAL")) => meshopt::Filter::Exponential,
            Some(Some("COLOR")) => meshopt::Filter::Color,
            Some(_) => return Err(format!("{what}: unknown filter {}", ext["filter"])),
        };
        if count.checked_mul(stride) != Some(view.length()) {
            return Err(format!(
                "{what}: {count} elements of {stride} bytes, but the view has {} bytes",
                view.length()
            ));
        }
        let data = buffers
            .get(source)
            .and_then(|b| b.0.get(offset..offset.checked_add(length)?))
            .ok_or_else(|| {
                format!("{what}: bytes {offset}..+{length} of buffer {source} do not exist")
            })?
            .to_vec();
        let start = view.offset();
        let target = view.buffer().index();
        let out = buffers
            .get_mut(target)
            .and_then(|b| b.0.get_mut(start..start.checked_add(view.length())?))
            .ok_or_else(|| format!("{what}: the view lies outside buffer {target}"))?;
        meshopt::decode(out, count, stride, mode, filter, &data)
            .map_err(|e| format!("{what}: {e}"))?;
    }
    Ok(())
}

/// World transforms of all nodes of the file (those outside the scene's trees too: a
/// skin's joints may be anywhere), each its parents' product with its own.
fn node_world_matrices(document: &gltf::Document, local: &[Mat4]) -> Result<Vec<Mat4>, String> {
    let count = document.nodes().len();
    let mut parent = vec![None; count];
    for node in document.nodes() {
        for child in node.children() {
            if parent[child.index()].replace(node.index()).is_some() {
                return Err(format!(
                    "node {} has two parents: a glTF node hierarchy must be a set of disjoint trees",
                    node_name(&child)
                ));
            }
        }
    }
    let mut world: Vec<Option<Mat4>> = vec![None; count];
    for start in 0..count {
        // Walk up to a node whose transform is known (or a root), then down again.
        let mut chain = vec![start];
        while let Some(p) = parent[*chain.last().unwrap()] {
            if world[p].is_some() {
                break;
            }
            if chain.len() > 256 {
                return Err("node hierarchy deeper than 256 levels (a cycle?)".into());
            }
            chain.push(p);
        }
        for &n in chain.iter().rev() {
            if world[n].is_none() {
                let above = parent[n].and_then(|p| world[p]).unwrap_or(Mat4::IDENTITY);
                world[n] = Some(above * local[n]);
            }
        }
    }
    Ok(world
        .into_iter()
        .map(|m| m.unwrap_or(Mat4::IDENTITY))
        .collect())
}

/// A skin's joint matrices in the static pose: each joint's world transform times its
/// inverse bind matrix (identity when the skin gives none).
fn joint_matrices(
    skin: &gltf::Skin<'_>,
    node_worlds: &[Mat4],
    buffers: &[gltf::buffer::Data],
    root: &gltf::json::Root,
    max_bytes: u64,
) -> Result<Vec<Mat4>, String> {
    let what = format!("skin {}", skin.index());
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    if joints.is_empty() {
        return Err(format!("{what} has no joints"));
    }
    let inverse_bind: Vec<Mat4> = match skin.inverse_bind_matrices() {
        Some(accessor) => {
            super::gltf_check::check_accessor(
                root,
                accessor.index(),
                super::gltf_check::Role::InverseBind,
                max_bytes,
            )
            .map_err(|e| format!("{what}: {e}"))?;
            let reader = skin.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let m: Vec<Mat4> = reader
                .read_inverse_bind_matrices()
                .map(|r| r.map(|m| Mat4::from_cols_array_2d(&m)).collect())
                .unwrap_or_default();
            if m.len() < joints.len() {
                return Err(format!(
                    "{what} has {} joints but {} inverse bind matrices",
                    joints.len(),
                    m.len()
                ));
            }
            m
        }
        None => vec![Mat4::IDENTITY; joints.len()],
    };
    let out: Vec<Mat4> = joints
        .iter()
        .zip(&inverse_bind)
        .map(|(&j, ibm)| node_worlds[j] * *ibm)
        .collect();
    if out.iter().any(|m| !m.is_finite()) {
        return Err(format!("{what} has a non-finite joint matrix"));
    }
    Ok(out)
}

/// The point to move to the origin before rendering: zero for a scene around the
/// origin, else the centre of its bounds, rounded to whole units.
///
/// Single-precision positions are spaced by their magnitude: 10⁴ units from the origin
/// they are a millimetre apart, and ray offsets that avoid self-intersection must be
/// several of those spacings (offset_ray uses 256), so lamps 1 cm from a wall would lose
/// their light there. Rendering relative to the scene's centre (production renderers
/// render camera-relative for the same reason) gives a scene far from the origin the
/// precision it has at the origin: the translation is subtracted from each node's
/// transform before any vertex is transformed, so no vertex is rounded at the far
/// position.
pub fn rebase_origin(bounds_min: Vec3, bounds_max: Vec3) -> Vec3 {
    let center = 0.5 * (bounds_min + bounds_max);
    let radius = 0.5 * (bounds_max - bounds_min).length();
    if center.abs().max_element() <= 4.0 * radius.max(1.0) {
        return Vec3::ZERO;
    }
    center.round()
}

/// Moves the scene by `-rebase_origin` (instances, cameras, punctual lights, bounds).
fn rebase(scene: &mut Scene) {
    let origin = rebase_origin(scene.bounds_min, scene.bounds_max);
    if origin == Vec3::ZERO {
        return;
    }
    let shift = |m: &mut Mat4| m.w_axis -= origin.extend(0.0);
    for inst in &mut scene.instances {
        shift(&mut inst.transform);
    }
    for cam in &mut scene.cameras {
        shift(&mut cam.to_world);
    }
    for l in &mut scene.punctual {
        l.position = (Vec3::from(l.position) - origin).into();
    }
    scene.bounds_min -= origin;
    scene.bounds_max -= origin;
    scene.origin = origin;
    log::info!(
        "{}: rendering relative to ({}, {}, {}), the centre of the scene, for precision",
        scene.path.display(),
        origin.x,
        origin.y,
        origin.z
    );
}

/// Parses the file without the crate's validation (the loader validates after its own
/// checks). Two things the crate cannot read are mended through the JSON, and only when
/// they are there, so that other files parse once:
/// * `EXT_texture_webp`: a texture's WebP image is used in place of its `source` (a
///   fallback for viewers without WebP, which the extension lets a file leave out, and
///   the crate cannot read a texture without one);
/// * animation channels the crate cannot read, whose targets have no node, are taken
///   out: `KHR_animation_pointer` channels are returned for posing, others ignored with
///   a warning, as the glTF specification says. Animations that still cannot be read are
///   left out with a warning: the file renders its static pose.
fn parse(
    bytes: &[u8],
    warnings: &mut Vec<String>,
) -> Result<(gltf::Gltf, animation_pointer::Taken), gltf::Error> {
    // The name in quotes anywhere in the JSON (a GLB's first chunk): it must be listed
    // in `extensionsUsed` wherever it is used.
    let json_part = match bytes.get(12..16) {
        Some(len) if bytes.starts_with(b"glTF") => {
            let len = u32::from_le_bytes(len.try_into().unwrap()) as usize;
            bytes.get(20..20usize.saturating_add(len)).unwrap_or(bytes)
        }
        _ => bytes,
    };
    let quoted = |name: &str| {
        let quoted = format!("\"{name}\"");
        json_part
            .windows(quoted.len())
            .any(|w| w == quoted.as_bytes())
    };
    let webp = quoted(WEBP);
    let pointers = quoted(animation_pointer::EXTENSION);
    let first = match gltf::Gltf::from_slice_without_validation(bytes) {
        Ok(g) if !webp && !pointers => return Ok((g, Default::default())),
        Ok(_) => None,
        Err(e) => Some(e),
    };
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::binary::Glb::from_slice(bytes)?;
        (glb.json, glb.bin.map(|b| b.into_owned()))
    } else {
        (std::borrow::Cow::Borrowed(bytes), None)
    };
    let mut value = match serde_json::from_slice::<serde_json::Value>(&json) {
        Ok(v) => v,
        Err(e) => return Err(first.unwrap_or(gltf::Error::Deserialize(e))),
    };
    if webp {
        prefer_webp_sources(&mut value);
    }
    let mut taken = animation_pointer::take_channels(&mut value, warnings);
    let root = match gltf::json::deserialize::from_value::<gltf::json::Root>(value.clone()) {
        Ok(root) => root,
        Err(e) => {
            let first = first.unwrap_or(gltf::Error::Deserialize(e));
            let Some(animations) = value.as_object_mut().and_then(|o| o.remove("animations"))
            else {
                return Err(first);
            };
            let Ok(root) = gltf::json::deserialize::from_value::<gltf::json::Root>(value) else {
                return Err(first);
            };
            let count = animations.as_array().map_or(0, Vec::len);
            warnings.push(format!(
                "has {count} animation(s) that cannot be read ({first}): they are left out \
                 (the scene renders its static pose, and --animation-time finds no \
                 animation to play)"
            ));
            taken = Default::default();
            root
        }
    };
    let gltf = gltf::Gltf {
        document: gltf::Document::from_json_without_validation(root),
        blob,
    };
    Ok((gltf, taken))
}

const WEBP: &str = "EXT_texture_webp";

/// Hides nodes and everything below them (their meshes and lights, not their cameras).
const NODE_VISIBILITY: &str = "KHR_node_visibility";

/// Points every texture with an `EXT_texture_webp` image at it.
fn prefer_webp_sources(value: &mut serde_json::Value) {
    let Some(textures) = value.get_mut("textures").and_then(|t| t.as_array_mut()) else {
        return;
    };
    for texture in textures {
        let source = texture
            .pointer(&format!("/extensions/{WEBP}/source"))
            .cloned();
        if let (Some(source), Some(t)) = (source, texture.as_object_mut()) {
            t.insert("source".into(), source);
        }
    }
}

/// The most mesh instances a scene may have: a TLAS instance's custom index has 24 bits.
const MAX_INSTANCES: usize = (1 << 24) - 1;

/// glTF extensions lanterna reads. A file may use others without requiring them (a
/// required one it does not know is refused when the file is parsed); their data is then
/// ignored, which a user should hear about (an `EXT_texture_avif` image falls back to
/// the texture's own source, or to none).
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "EXT_lights_ies",
    "EXT_mesh_gpu_instancing",
    "EXT_meshopt_compression",
    "EXT_texture_webp",
    "KHR_animation_pointer",
    "KHR_draco_mesh_compression",
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_pbrSpecularGlossiness",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_meshopt_compression",
    "KHR_node_visibility",
    "KHR_texture_transform",
];

/// Extensions that change nothing lanterna draws: metadata.
const INERT_EXTENSIONS: &[&str] = &["KHR_xmp_json_ld"];

/// One warning per extension the file uses whose data lanterna ignores.
fn unsupported_extensions<'a>(used: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut names: Vec<&str> = used
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e) && !INERT_EXTENSIONS.contains(e))
        .collect();
    names.sort_unstable();
    names.dedup();
    names
        .into_iter()
        .map(|e| {
            let what = if e.starts_with("KHR_materials_") || e.starts_with("EXT_materials_") {
                "materials render with the core metallic-roughness model alone"
            } else {
                "its data is ignored"
            };
            format!("uses the glTF extension {e}, which lanterna does not support: {what}")
        })
        .collect()
}

/// FNV-1a over the loaded content: geometry, placement and materials.
fn content_hash(scene: &Scene) -> String {
    let mut h: u64 = 0xcbf29ce484222325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    };
    eat(bytemuck::cast_slice(&scene.vertices));
    // Vertex colours only where there are any: scenes without keep their hashes (and
    // the references and saved trees made for them stay valid).
    eat(bytemuck::cast_slice(&scene.colors));
    for (i, p) in scene.primitives.iter().enumerate() {
        if p.color_offset != crate::gpu::INVALID_INDEX {
            eat(&(i as u32).to_le_bytes());
            eat(&p.color_offset.to_le_bytes());
        }
    }
    eat(bytemuck::cast_slice(&scene.indices));
    // Which material each primitive takes (since 2026-12-06: two files that differ only
    // there, as a file's material variants do, had one hash).
    for p in &scene.primitives {
        eat(&p.material.to_le_bytes());
    }
    // Materials up to their transmission fields, which count only where a material
    // transmits (specularly or diffusely: the volume's absorption is among them), and the
    // coat's, the sheen's, the anisotropy's, the diffuse transmission's, the thin film's
    // and the dispersion's, which count only where it has one (scenes without keep their
    // hashes, as for vertex colours).
    let opaque_part = std::mem::offset_of!(crate::gpu::Material, transmission);
    let coat_part = std::mem::offset_of!(crate::gpu::Material, clearcoat);
    let sheen_part = std::mem::offset_of!(crate::gpu::Material, sheen_color);
    let anisotropy_part = std::mem::offset_of!(crate::gpu::Material, anisotropy_strength);
    let diffuse_transmission_part =
        std::mem::offset_of!(crate::gpu::Material, diffuse_transmission);
    let iridescence_part = std::mem::offset_of!(crate::gpu::Material, iridescence);
    let dispersion_part = std::mem::offset_of!(crate::gpu::Material, dispersion);
    for m in &scene.materials {
        let bytes = bytemuck::bytes_of(m);
        eat(&bytes[..opaque_part]);
        if m.transmission > 0.0 || m.diffuse_transmission > 0.0 {
            eat(&bytes[opaque_part..coat_part]);
        }
        if m.clearcoat > 0.0 {
            eat(&bytes[coat_part..sheen_part]);
        }
        if m.sheen_color.iter().any(|&c| c > 0.0) {
            eat(&bytes[sheen_part..anisotropy_part]);
        }
        if m.anisotropy_strength > 0.0 {
            eat(&bytes[anisotropy_part..diffuse_transmission_part]);
        }
        if m.diffuse_transmission > 0.0 {
            eat(&bytes[diffuse_transmission_part..iridescence_part]);
        }
        if m.iridescence > 0.0 {
            eat(&bytes[iridescence_part..dispersion_part]);
        }
        if m.dispersion > 0.0 {
            eat(&bytes[dispersion_part..]);
        }
    }
    for i in &scene.instances {
        eat(&i.primitive.to_le_bytes());
        eat(bytemuck::cast_slice(&i.transform.to_cols_array()));
    }
    // Lights without a profile hash as they did before profiles existed.
    let unprofiled = std::mem::offset_of!(crate::gpu::PunctualLight, profile);
    for l in &scene.punctual {
        let bytes = bytemuck::bytes_of(l);
        match ies::profile_offset(l) {
            None => eat(&bytes[..unprofiled]),
            Some(_) => eat(bytes),
        }
    }
    eat(bytemuck::cast_slice(&scene.light_profiles));
    for t in &scene.textures {
        eat(&t.texels.bytes());
    }
    format!("{h:016x}")
}

/// A glTF camera's clip planes, or why they cannot be used. The spec asks for
/// 0 < znear < zfar (0 ≤ znear for orthographic cameras); a missing zfar is an infinite
/// projection.
fn clip_planes(znear: f32, zfar: Option<f32>) -> Result<ClipPlanes, &'static str> {
    let far = zfar.unwrap_or(f32::INFINITY);
    if !(znear.is_finite() && znear >= 0.0) {
        return Err("znear must be a finite distance ≥ 0");
    }
    if far.is_nan() || far <= znear {
        return Err("zfar must lie beyond znear");
    }
    Ok(ClipPlanes { near: znear, far })
}
