//! `KHR_materials_variants`: one file, several looks (a product in its colourways, a room
//! with alternative finishes). The file names its variants at the root; a primitive maps
//! variants to materials, and keeps its own material under any variant it does not map.
//! `--variant NAME|INDEX` renders one; without it every primitive has its own material,
//! as the extension says a viewer shows the file by default.

/// The extension's name.
pub(super) const EXTENSION: &str = "KHR_materials_variants";

/// The file's variant names (`variant i` where one has none); empty when the file has
/// none, an error when their list is malformed.
pub(super) fn names(document: &gltf::Document) -> Result<Vec<String>, String> {
    let Some(ext) = document.extension_value(EXTENSION) else {
        return Ok(Vec::new());
    };
    let list = ext
        .get("variants")
        .and_then(|v| v.as_array())
        .ok_or_else(|| format!("{EXTENSION} has no `variants` array"))?;
    Ok(list
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.get("name")
                .and_then(|n| n.as_str())
                .map_or_else(|| format!("variant {i}"), str::to_string)
        })
        .collect())
}

/// The index of the variant `wanted` names among `names`, by name or index.
pub(super) fn choose(names: &[String], wanted: &str) -> Result<usize, String> {
    names
        .iter()
        .position(|n| n == wanted)
        .or_else(|| wanted.parse::<usize>().ok().filter(|&i| i < names.len()))
        .ok_or_else(|| {
            format!(
                "no material variant matches `{wanted}` (the file has {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names
                        .iter()
                        .enumerate()
                        .map(|(i, n)| format!("{i}: {n}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                }
            )
        })
}

/// The material primitive `prim` takes under variant `variant` of `variant_count`, or
/// `None` when none of its mappings names that variant (it keeps its own material).
/// Mappings must name existing materials and variants, each variant at most once.
pub(super) fn material(
    prim: &gltf::Primitive<'_>,
    variant: usize,
    variant_count: usize,
    material_count: usize,
) -> Result<Option<usize>, String> {
    let Some(ext) = prim.extension_value(EXTENSION) else {
        return Ok(None);
    };
    let mappings = ext
        .get("mappings")
        .and_then(|m| m.as_array())
        .ok_or_else(|| format!("{EXTENSION} has no `mappings` array"))?;
    let index = |v: &serde_json::Value, what: &str, count: usize| -> Result<usize, String> {
        v.as_u64()
            .and_then(|i| usize::try_from(i).ok())
            .filter(|&i| i < count)
            .ok_or_else(|| {
                format!("{EXTENSION} mapping names {what} {v}, but the file has {count}")
            })
    };
    let mut found = None;
    for (m, mapping) in mappings.iter().enumerate() {
        let material = mapping
            .get("material")
            .ok_or_else(|| format!("{EXTENSION} mapping {m} has no `material`"))?;
        let material = index(material, "material", material_count)?;
        let variants = mapping
            .get("variants")
            .and_then(|v| v.as_array())
            .ok_or_else(|| format!("{EXTENSION} mapping {m} has no `variants` array"))?;
        for v in variants {
            if index(v, "variant", variant_count)? == variant {
                if found.is_some() {
                    return Err(format!(
                        "{EXTENSION}: variant {variant} is mapped twice; a primitive may map \
                         each variant to one material"
                    ));
                }
                found = Some(material);
            }
        }
    }
    Ok(found)
}
