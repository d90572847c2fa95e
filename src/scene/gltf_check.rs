//! Checks of a glTF document that the gltf crate does not make, run before its wrappers
//! and readers index or slice anything, so that a malformed or hostile file gives an
//! error naming the part at fault instead of a panic or silently wrong geometry:
//!
//! * [`precheck`], before the crate's own validation (whose POSITION hook indexes the
//!   accessor list unchecked);
//! * [`check_views`]: every buffer view lies inside its buffer;
//! * [`check_accessor`]: an accessor a primitive uses has the type its role needs
//!   (POSITION is float VEC3, indices unsigned SCALAR, …) and its elements, at its stride,
//!   fit in its buffer view (the crate's readers would stop early and load fewer
//!   triangles without a word).

use gltf::json;
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;

/// A node as messages name it: by name, else by index.
pub(super) fn node_name(node: &gltf::Node<'_>) -> String {
    match node.name() {
        Some(n) => format!("`{n}`"),
        None => format!("#{}", node.index()),
    }
}

/// Before `Document::from_json`: indices the crate's validation hooks use unchecked.
pub(super) fn precheck(root: &json::Root) -> Result<(), String> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &prim.attributes {
                if accessor.value() >= n {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "an attribute".into(),
                    };
                    return Err(format!(
                        "mesh {m} primitive {p}: {name} refers to accessor {} but the file has {n}",
                        accessor.value()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Whether the file uses `KHR_mesh_quantization` (integer positions, normals, tangents
/// and texture coordinates).
pub(super) fn uses_quantization(root: &json::Root) -> bool {
    root.extensions_used.iter().any(|e| e == QUANTIZATION)
}

pub(super) const QUANTIZATION: &str = "KHR_mesh_quantization";

/// Every buffer view lies inside its buffer's declared length (which the loaded data
/// covers: the loader checks that separately).
pub(super) fn check_views(root: &json::Root) -> Result<(), String> {
    for (i, view) in root.buffer_views.iter().enumerate() {
        let Some(buffer) = root.buffers.get(view.buffer.value()) else {
            return Err(format!(
                "buffer view {i} refers to buffer {} but the file has {}",
                view.buffer.value(),
                root.buffers.len()
            ));
        };
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = u128::from(start) + u128::from(view.byte_length.0);
        if end > u128::from(buffer.byte_length.0) {
            return Err(format!(
                "buffer view {i} spans bytes {start}..{end} but buffer {} has {} bytes",
                view.buffer.value(),
                buffer.byte_length.0
            ));
        }
    }
    Ok(())
}

/// What a primitive uses an accessor for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    Position,
    Normal,
    Tangent,
    TexCoord,
    Color,
    Indices,
    Joints,
    Weights,
    InverseBind,
    /// `EXT_mesh_gpu_instancing`'s attributes.
    InstanceTranslation,
    InstanceRotation,
    InstanceScale,
    /// Animation samplers: keyframe times, and the values a channel sets.
    AnimationInput,
    AnimationVec3,
    AnimationRotation,
    AnimationWeights,
    /// `KHR_animation_pointer` values: floats (any component type, normalized or not),
    /// one per property, or a boolean's unsigned bytes.
    PointerScalar,
    PointerVec2,
    PointerVec3,
    PointerVec4,
    PointerBool,
}

impl Role {
    fn name(self) -> &'static str {
        match self {
            Role::Position => "POSITION",
            Role::Normal => "NORMAL",
            Role::Tangent => "TANGENT",
            Role::TexCoord => "TEXCOORD",
            Role::Color => "COLOR",
            Role::Indices => "indices",
            Role::Joints => "JOINTS",
            Role::Weights => "WEIGHTS",
            Role::InverseBind => "inverseBindMatrices",
            Role::InstanceTranslation => "TRANSLATION",
            Role::InstanceRotation => "ROTATION",
            Role::InstanceScale => "SCALE",
            Role::AnimationInput => "keyframe times",
            Role::AnimationVec3 => "translation or scale keyframes",
            Role::AnimationRotation => "rotation keyframes",
            Role::AnimationWeights => "morph weight keyframes",
            Role::PointerScalar
            | Role::PointerVec2
            | Role::PointerVec3
            | Role::PointerVec4
            | Role::PointerBool => "pointer keyframes",
        }
    }

    /// Whether the glTF spec allows this type and component type for the role
    /// (`quantized`: the file uses `KHR_mesh_quantization`, which adds integer types).
    fn allows(self, ty: Type, ct: ComponentType, quantized: bool) -> bool {
        use ComponentType::{F32, I16, I8, U16, U32, U8};
        match self {
            Role::Position if quantized => {
                ty == Type::Vec3 && matches!(ct, F32 | I8 | U8 | I16 | U16)
            }
            Role::Normal if quantized => ty == Type::Vec3 && matches!(ct, F32 | I8 | I16),
            Role::Tangent if quantized => ty == Type::Vec4 && matches!(ct, F32 | I8 | I16),
            Role::TexCoord if quantized => {
                ty == Type::Vec2 && matches!(ct, F32 | I8 | U8 | I16 | U16)
            }
            Role::Position | Role::Normal => ty == Type::Vec3 && ct == F32,
            Role::Tangent => ty == Type::Vec4 && ct == F32,
            Role::TexCoord => ty == Type::Vec2 && matches!(ct, F32 | U8 | U16),
            Role::Color => matches!(ty, Type::Vec3 | Type::Vec4) && matches!(ct, F32 | U8 | U16),
            Role::Indices => ty == Type::Scalar && matches!(ct, U8 | U16 | U32),
            Role::Joints => ty == Type::Vec4 && matches!(ct, U8 | U16),
            Role::Weights => ty == Type::Vec4 && matches!(ct, F32 | U8 | U16),
            Role::InverseBind => ty == Type::Mat4 && ct == F32,
            // EXT_mesh_gpu_instancing: float, and with KHR_mesh_quantization (normalised
            // or not) bytes and shorts for translation and scale.
            Role::InstanceTranslation | Role::InstanceScale if quantized => {
                ty == Type::Vec3 && matches!(ct, F32 | I8 | I16)
            }
            Role::InstanceTranslation | Role::InstanceScale => ty == Type::Vec3 && ct == F32,
            Role::InstanceRotation => ty == Type::Vec4 && matches!(ct, F32 | I8 | I16),
            Role::AnimationInput => ty == Type::Scalar && ct == F32,
            Role::AnimationVec3 => ty == Type::Vec3 && ct == F32,
            Role::AnimationRotation => ty == Type::Vec4 && ct != U32,
            Role::AnimationWeights => ty == Type::Scalar && ct != U32,
            Role::PointerScalar => ty == Type::Scalar && ct != U32,
            Role::PointerVec2 => ty == Type::Vec2 && ct != U32,
            Role::PointerVec3 => ty == Type::Vec3 && ct != U32,
            Role::PointerVec4 => ty == Type::Vec4 && ct != U32,
            Role::PointerBool => ty == Type::Scalar && ct == U8,
        }
    }

    fn expected(self, quantized: bool) -> &'static str {
        match self {
            Role::Position if quantized => {
                "VEC3 of float, byte, unsigned byte, short or unsigned short"
            }
            Role::Normal if quantized => "VEC3 of float, byte or short",
            Role::Tangent if quantized => "VEC4 of float, byte or short",
            Role::TexCoord if quantized => {
                "VEC2 of float, byte, unsigned byte, short or unsigned short"
            }
            Role::Position | Role::Normal => "float VEC3",
            Role::Tangent => "float VEC4",
            Role::TexCoord => "VEC2 of float, unsigned byte or unsigned short",
            Role::Color => "VEC3 or VEC4 of float, unsigned byte or unsigned short",
            Role::Indices => "SCALAR unsigned byte, short or int",
            Role::Joints => "VEC4 of unsigned byte or unsigned short",
            Role::Weights => "VEC4 of float, unsigned byte or unsigned short",
            Role::InverseBind => "float MAT4",
            Role::InstanceTranslation | Role::InstanceScale if quantized => {
                "VEC3 of float, byte or short"
            }
            Role::InstanceTranslation | Role::InstanceScale => "float VEC3",
            Role::InstanceRotation => "VEC4 of float, normalized byte or normalized short",
            Role::AnimationInput => "float SCALAR",
            Role::AnimationVec3 => "float VEC3",
            Role::AnimationRotation => "VEC4 of float or of normalized (unsigned) bytes or shorts",
            Role::AnimationWeights => "SCALAR float or normalized (unsigned) byte or short",
            Role::PointerScalar => "SCALAR of float, (unsigned) byte or (unsigned) short",
            Role::PointerVec2 => "VEC2 of float, (unsigned) byte or (unsigned) short",
            Role::PointerVec3 => "VEC3 of float, (unsigned) byte or (unsigned) short",
            Role::PointerVec4 => "VEC4 of float, (unsigned) byte or (unsigned) short",
            Role::PointerBool => "SCALAR unsigned byte (a boolean)",
        }
    }
}

fn type_name(ty: Type) -> &'static str {
    match ty {
        Type::Scalar => "SCALAR",
        Type::Vec2 => "VEC2",
        Type::Vec3 => "VEC3",
        Type::Vec4 => "VEC4",
        Type::Mat2 => "MAT2",
        Type::Mat3 => "MAT3",
        Type::Mat4 => "MAT4",
    }
}

fn component_name(ct: ComponentType) -> &'static str {
    match ct {
        ComponentType::I8 => "byte",
        ComponentType::U8 => "unsigned byte",
        ComponentType::I16 => "short",
        ComponentType::U16 => "unsigned short",
        ComponentType::U32 => "unsigned int",
        ComponentType::F32 => "float",
    }
}

/// Checks accessor `index` for `role` (see the module comment). `max_bytes` bounds what
/// reading it may allocate.
pub(super) fn check_accessor(
    root: &json::Root,
    index: usize,
    role: Role,
    max_bytes: u64,
) -> Result<(), String> {
    let quantized = uses_quantization(root);
    let what = format!("accessor {index} ({})", role.name());
    let acc = root
        .accessors
        .get(index)
        .ok_or_else(|| format!("{what} does not exist"))?;
    let (Checked::Valid(ty), Checked::Valid(json::accessor::GenericComponentType(ct))) =
        (acc.type_, acc.component_type)
    else {
        return Err(format!("{what} has an invalid type"));
    };
    if !role.allows(ty, ct, quantized) {
        return Err(format!(
            "{what} is {} {}, but {} must be {}",
            component_name(ct),
            type_name(ty),
            role.name(),
            role.expected(quantized)
        ));
    }
    // Integer normals and tangents are unit vectors only as normalised integers.
    let integer = ct != ComponentType::F32;
    if integer
        && matches!(
            role,
            Role::Normal
                | Role::Tangent
                | Role::Weights
                | Role::InstanceRotation
                | Role::AnimationRotation
                | Role::AnimationWeights
        )
        && !acc.normalized
    {
        return Err(format!(
            "{what} is {} but not normalized",
            component_name(ct)
        ));
    }
    let count = acc.count.0;
    if count == 0 {
        return Err(format!("{what} has count 0"));
    }
    let elem = (ct.size() * ty.multiplicity()) as u64;
    if let Some(view) = acc.buffer_view {
        let offset = acc.byte_offset.map_or(0, |o| o.0);
        check_range(root, view.value(), offset, count, elem, &what)?;
    }
    if let Some(sparse) = &acc.sparse {
        let n = sparse.count.0;
        if n == 0 || n > count {
            return Err(format!("{what}: sparse count {n} is not in 1..={count}"));
        }
        let Checked::Valid(json::accessor::IndexComponentType(ict)) = sparse.indices.component_type
        else {
            return Err(format!("{what}: invalid sparse index type"));
        };
        if !matches!(
            ict,
            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
        ) {
            return Err(format!("{what}: sparse indices must be unsigned integers"));
        }
        check_range(
            root,
            sparse.indices.buffer_view.value(),
            sparse.indices.byte_offset.0,
            n,
            ict.size() as u64,
            &format!("{what} sparse indices"),
        )?;
        check_range(
            root,
            sparse.values.buffer_view.value(),
            sparse.values.byte_offset.0,
            n,
            elem,
            &format!("{what} sparse values"),
        )?;
    }
    // Without a view (zeros, or sparse on zeros) the count alone sets the allocation.
    if u128::from(count) * u128::from(elem) > u128::from(max_bytes) {
        return Err(format!(
            "{what}: {count} elements of {elem} bytes exceed the input limit"
        ));
    }
    Ok(())
}

/// `count` elements of `elem` bytes from `offset`, at the view's stride, fit in view `v`.
fn check_range(
    root: &json::Root,
    v: usize,
    offset: u64,
    count: u64,
    elem: u64,
    what: &str,
) -> Result<(), String> {
    let view = root.buffer_views.get(v).ok_or_else(|| {
        format!(
            "{what} refers to buffer view {v} but the file has {}",
            root.buffer_views.len()
        )
    })?;
    let stride = view
        .byte_stride
        .map(|s| s.0 as u64)
        .filter(|&s| s != 0)
        .unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "{what}: buffer view {v} has stride {stride}, less than the element size {elem}"
        ));
    }
    let need = u128::from(offset) + u128::from(stride) * u128::from(count - 1) + u128::from(elem);
    if need > u128::from(view.byte_length.0) {
        return Err(format!(
            "{what}: {count} elements of {elem} bytes (stride {stride}) from offset {offset} \
             need {need} bytes, but buffer view {v} has {}",
            view.byte_length.0
        ));
    }
    Ok(())
}
