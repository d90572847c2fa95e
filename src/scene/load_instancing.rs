//! `EXT_mesh_gpu_instancing`: a node that draws its mesh many times, once per element of
//! its instance attributes (TRANSLATION, ROTATION, SCALE; each optional, all of one
//! count). Instance i sits at the node's global transform times T_i·R_i·S_i (the
//! extension: instance transforms are relative to the node's), and the node's children,
//! camera and light are not instanced. Exporters write it for repeated objects (Blender's
//! "GPU instances", gltfpack's `-mi`): lamps along a street, string lights, trees.

use super::gltf_check::{self, Role};
use glam::{Mat4, Quat, Vec3};

/// The extension's name.
pub(super) const EXTENSION: &str = "EXT_mesh_gpu_instancing";

/// The node's instance transforms relative to the node (T·R·S per instance), or `None`
/// when the node does not use the extension. Errors name the attribute and what is
/// wrong with it.
pub(super) fn instance_transforms(
    node: &gltf::Node<'_>,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    max_bytes: u64,
) -> Result<Option<Vec<Mat4>>, String> {
    let Some(value) = node.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let Some(attributes) = value.get("attributes").and_then(|a| a.as_object()) else {
        return Err(format!("{EXTENSION} has no `attributes` object"));
    };
    let root = document.as_json();
    let get = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
    // One attribute's accessor: checked for its role, then read as floats.
    let read = |name: &str, role: Role| -> Result<Option<gltf::Accessor<'_>>, String> {
        let Some(index) = attributes.get(name) else {
            return Ok(None);
        };
        let index = index
            .as_u64()
            .and_then(|i| usize::try_from(i).ok())
            .ok_or_else(|| format!("{EXTENSION} {name} is not an accessor index: {index}"))?;
        gltf_check::check_accessor(root, index, role, max_bytes)
            .map_err(|e| format!("{EXTENSION} {name}: {e}"))?;
        Ok(document.accessors().nth(index))
    };
    let unreadable = |name: &str| format!("{EXTENSION} {name}: unreadable data");
    let translations: Option<Vec<[f32; 3]>> = match read("TRANSLATION", Role::InstanceTranslation)?
    {
        Some(a) => Some(
            super::load_primitive::read_floats(a, get, false)
                .ok_or_else(|| unreadable("TRANSLATION"))?,
        ),
        None => None,
    };
    let rotations: Option<Vec<[f32; 4]>> = match read("ROTATION", Role::InstanceRotation)? {
        Some(a) => Some(
            super::load_primitive::read_floats(a, get, false)
                .ok_or_else(|| unreadable("ROTATION"))?,
        ),
        None => None,
    };
    let scales: Option<Vec<[f32; 3]>> = match read("SCALE", Role::InstanceScale)? {
        Some(a) => Some(
            super::load_primitive::read_floats(a, get, false).ok_or_else(|| unreadable("SCALE"))?,
        ),
        None => None,
    };
    // Every attribute, custom ones (`_ID`, …) too, has one element per instance.
    let mut count: Option<(&str, usize)> = None;
    const KNOWN: [&str; 3] = ["TRANSLATION", "ROTATION", "SCALE"];
    let known = KNOWN.iter().filter_map(|k| attributes.get_key_value(*k));
    let custom = attributes
        .iter()
        .filter(|(k, _)| !KNOWN.contains(&k.as_str()));
    for (name, index) in known.chain(custom) {
        let n = match name.as_str() {
            "TRANSLATION" => translations.as_ref().map_or(0, Vec::len),
            "ROTATION" => rotations.as_ref().map_or(0, Vec::len),
            "SCALE" => scales.as_ref().map_or(0, Vec::len),
            _ => index
                .as_u64()
                .and_then(|i| root.accessors.get(usize::try_from(i).ok()?))
                .map(|a| a.count.0 as usize)
                .ok_or_else(|| format!("{EXTENSION} {name} is not an accessor index: {index}"))?,
        };
        match count {
            None => count = Some((name, n)),
            Some((first, m)) if m != n => {
                return Err(format!(
                    "{EXTENSION}: {first} has {m} elements but {name} has {n}; every instance \
                     attribute must have one per instance"
                ));
            }
            Some(_) => {}
        }
    }
    let Some((_, count)) = count else {
        return Err(format!("{EXTENSION} has no attributes"));
    };
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let t = translations
            .as_ref()
            .map_or(Vec3::ZERO, |v| Vec3::from(v[i]));
        let s = scales.as_ref().map_or(Vec3::ONE, |v| Vec3::from(v[i]));
        let r = match &rotations {
            Some(v) => {
                let q = Quat::from_array(v[i]);
                let len = q.length();
                // Unit quaternions by the spec; normalised integers are only nearly so.
                if !(len.is_finite() && len > 1e-3) {
                    return Err(format!(
                        "{EXTENSION} ROTATION {i} is {:?}, not a rotation",
                        v[i]
                    ));
                }
                q / len
            }
            None => Quat::IDENTITY,
        };
        if !(t.is_finite() && s.is_finite()) {
            return Err(format!(
                "{EXTENSION} instance {i} has a non-finite translation or scale"
            ));
        }
        out.push(Mat4::from_scale_rotation_translation(s, r, t));
    }
    Ok(Some(out))
}
