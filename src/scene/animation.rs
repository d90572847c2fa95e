//! glTF animations sampled at one time: the pose a render asks for with `--animation-time`
//! (`--animation` picks one animation; by default every animation plays). A channel moves
//! a node's translation, rotation or scale, or a mesh node's morph weights; its sampler's
//! keyframes are interpolated as the glTF 2.0 specification says (appendix C): STEP holds
//! the key at or before the time, LINEAR interpolates linearly (spherically for rotations,
//! along the shorter arc), CUBICSPLINE is the cubic Hermite spline through the keys with
//! the file's in- and out-tangents scaled by the key interval (rotations renormalised).
//! Before the first key and after the last the value is held. Cameras, punctual lights,
//! skins' joints and instanced nodes follow their nodes.

use super::animation_pointer::{
    self, Kind, NodeProperty, PointerChannel, Taken, Target, EXTENSION as POINTER_EXTENSION,
};
use super::gltf_check::{self, Role};
use glam::{Mat4, Quat, Vec3};
use gltf::animation::{Interpolation, Property};
use std::collections::HashMap;

/// Which pose of the file's animations to render.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Seconds on the animations' timeline (glTF keyframe times are seconds).
    pub time: f32,
    /// One animation, by index or name; `None` plays them all.
    pub animation: Option<String>,
}

/// One animation of a file, as `lanterna info` lists it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AnimationInfo {
    pub name: String,
    /// The first and last keyframe times over its samplers (seconds), from the
    /// accessors' `min` and `max`, which the spec requires of animation inputs.
    pub start: Option<f32>,
    pub end: Option<f32>,
    pub channels: usize,
}

/// The file's animations, for statistics (`taken`: their pointer channels).
pub(super) fn summaries(document: &gltf::Document, taken: &Taken) -> Vec<AnimationInfo> {
    document
        .animations()
        .map(|a| {
            let bound = |v: Option<gltf::json::Value>| {
                v.and_then(|v| v.as_array()?.first()?.as_f64())
                    .map(|x| x as f32)
            };
            let (mut start, mut end): (Option<f32>, Option<f32>) = (None, None);
            for s in a.samplers() {
                if let Some(lo) = bound(s.input().min()) {
                    start = Some(start.map_or(lo, |x| x.min(lo)));
                }
                if let Some(hi) = bound(s.input().max()) {
                    end = Some(end.map_or(hi, |x| x.max(hi)));
                }
            }
            AnimationInfo {
                name: name(&a),
                start,
                end,
                channels: a.channels().count() + taken.pointer_count(a.index()),
            }
        })
        .collect()
}

fn name(a: &gltf::Animation<'_>) -> String {
    match a.name() {
        Some(n) => format!("{} (`{n}`)", a.index()),
        None => a.index().to_string(),
    }
}

/// The scene's nodes at a pose.
pub(super) struct Posed {
    /// Every node's local transform (the file's own where no channel moves it).
    pub locals: Vec<Mat4>,
    /// Morph weights set by a channel, per node.
    pub weights: Vec<Option<Vec<f32>>>,
    /// The file's JSON with the values of the `KHR_animation_pointer` channels that
    /// target other properties than nodes' transforms and weights written in, when
    /// there are any.
    pub json: Option<serde_json::Value>,
}

/// Every node's local transform from the file, without animation.
pub(super) fn static_locals(document: &gltf::Document) -> Vec<Mat4> {
    document
        .nodes()
        .map(|n| Mat4::from_cols_array_2d(&n.transform().matrix()))
        .collect()
}

/// One channel of an animation: the crate's, or a pointer channel it could not read.
enum Channel<'a> {
    Core(gltf::animation::Channel<'a>),
    Pointer(&'a PointerChannel),
}

/// Which animation animates each property, by its pointer (a core channel's as the
/// equivalent pointer): an animation may animate a property once, and across animations
/// the first in the file wins. A morph weight array and its elements are one property.
#[derive(Default)]
struct Owners {
    exact: HashMap<String, usize>,
    /// Arrays some of whose elements are animated, with the first animation to do so.
    elements: HashMap<String, usize>,
}

impl Owners {
    /// The animation that already animates `key` (or its array, or its elements).
    fn owner(&self, key: &str, array: Option<&str>) -> Option<usize> {
        self.exact
            .get(key)
            .or_else(|| array.and_then(|a| self.exact.get(a)))
            .or_else(|| self.elements.get(key))
            .copied()
    }

    fn claim(&mut self, key: String, array: Option<String>, animation: usize) {
        if let Some(a) = array {
            self.elements.entry(a).or_insert(animation);
        }
        self.exact.insert(key, animation);
    }
}

/// Samples the animations `pose` selects at its time, their pointer channels (`taken`)
/// included. Errors name the animation, channel and what is wrong; `max_bytes` bounds
/// what reading keyframes may allocate. Two animations that animate one property: the
/// first in the file wins, with a warning.
pub(super) fn pose(
    document: &gltf::Document,
    taken: &Taken,
    buffers: &[gltf::buffer::Data],
    pose: &Pose,
    max_bytes: u64,
    warnings: &mut Vec<String>,
) -> Result<Posed, String> {
    if !pose.time.is_finite() {
        return Err(format!("the animation time {} is not finite", pose.time));
    }
    let animations: Vec<gltf::Animation<'_>> = match &pose.animation {
        None => document.animations().collect(),
        Some(wanted) => {
            let found = document.animations().find(|a| {
                wanted.parse::<usize>().ok() == Some(a.index()) || a.name() == Some(wanted)
            });
            match found {
                Some(a) => vec![a],
                None => {
                    let available: Vec<String> = document.animations().map(|a| name(&a)).collect();
                    return Err(format!(
                        "no animation matches `{wanted}` (the file has {})",
                        if available.is_empty() {
                            "none".to_string()
                        } else {
                            available.join(", ")
                        }
                    ));
                }
            }
        }
    };
    if animations.is_empty() {
        warnings.push(format!(
            "has no animations to pose at time {}: it renders the nodes' own transforms",
            pose.time
        ));
    }
    let count = document.nodes().len();
    let mut trs: Vec<(Vec3, Quat, Vec3)> = document
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (Vec3::from(t), Quat::from_array(r), Vec3::from(s))
        })
        .collect();
    let mut moved = vec![false; count];
    let mut weights: Vec<Option<Vec<f32>>> = vec![None; count];
    let mut owners = Owners::default();
    let mut json: Option<serde_json::Value> = None;
    let root = document.as_json();
    let get = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
    for animation in &animations {
        let a = animation.index();
        let mut channels: Vec<(usize, Channel<'_>)> = animation
            .channels()
            .map(|c| (taken.file_index(a, c.index()), Channel::Core(c)))
            .chain(
                taken
                    .pointers
                    .iter()
                    .filter(|p| p.animation == a)
                    .map(|p| (p.channel, Channel::Pointer(p))),
            )
            .collect();
        channels.sort_by_key(|(i, _)| *i);
        for (file_index, channel) in channels {
            let what = format!("animation {} channel {file_index}", name(animation));
            let pointer_channel = matches!(channel, Channel::Pointer(_));
            let (sampler, destination) = match channel {
                Channel::Core(c) => {
                    let property = match c.target().property() {
                        Property::Translation => NodeProperty::Translation,
                        Property::Rotation => NodeProperty::Rotation,
                        Property::Scale => NodeProperty::Scale,
                        Property::MorphTargetWeights => NodeProperty::Weights,
                    };
                    let node = c.target().node().index();
                    (c.sampler(), Target::Node(node, property))
                }
                Channel::Pointer(p) => {
                    let pointer = p.pointer.as_deref().ok_or_else(|| {
                        format!(
                            "{what}: its target's path is `pointer` but it has no \
                             {POINTER_EXTENSION} pointer"
                        )
                    })?;
                    let segments =
                        animation_pointer::segments(pointer).map_err(|e| format!("{what}: {e}"))?;
                    let destination = match animation_pointer::resolve(&segments) {
                        Some(target) => target,
                        None => {
                            warnings.push(format!(
                                "{what} animates `{pointer}`, a property lanterna does not \
                                 animate: the channel is ignored"
                            ));
                            continue;
                        }
                    };
                    let sampler = p
                        .sampler
                        .and_then(|s| animation.samplers().nth(s))
                        .ok_or_else(|| {
                            format!("{what}: its sampler is not one of the animation's")
                        })?;
                    (sampler, destination)
                }
            };
            // The property's pointer, and its array's for one morph weight.
            let (key, array) = match &destination {
                Target::Node(n, NodeProperty::Weight(k)) => (
                    format!("/nodes/{n}/weights/{k}"),
                    Some(format!("/nodes/{n}/weights")),
                ),
                Target::Node(n, p) => (format!("/nodes/{n}/{}", PATHS[path_index(*p)]), None),
                Target::Json { segments, .. } => {
                    let key = animation_pointer::pointer_text(segments);
                    let array = match &segments[..] {
                        [m, _, w, _] if m == "meshes" && w == "weights" => {
                            Some(animation_pointer::pointer_text(&segments[..3]))
                        }
                        _ => None,
                    };
                    (key, array)
                }
            };
            // The property in words, for messages.
            let label = match &destination {
                Target::Node(n, p) => match document.nodes().nth(*n) {
                    Some(node) => format!(
                        "the {} of node {}",
                        match p {
                            NodeProperty::Weight(k) => format!("morph weight {k}"),
                            p => PATHS[path_index(*p)].to_string(),
                        },
                        gltf_check::node_name(&node)
                    ),
                    None => format!("`{key}`"),
                },
                Target::Json { .. } => format!("`{key}`"),
            };
            match owners.owner(&key, array.as_deref()) {
                Some(owner) if owner == a => {
                    return Err(format!(
                        "{what}: a second channel for {label}; an animation may animate \
                         each property once"
                    ));
                }
                Some(owner) => {
                    warnings.push(format!(
                        "{what} animates {label}, which animation {owner} animates too: \
                         animation {owner}'s channel is used"
                    ));
                    continue;
                }
                None => owners.claim(key.clone(), array, a),
            }
            // The values' accessor role and the floats per key.
            let (role, width, rotation) = match &destination {
                Target::Node(n, property) => {
                    let node = document
                        .nodes()
                        .nth(*n)
                        .ok_or_else(|| format!("{what}: the file has no node {n}"))?;
                    node_keys(&node, *property, pointer_channel, &what)?
                }
                Target::Json {
                    segments,
                    kind,
                    default,
                } => {
                    let working = match &mut json {
                        Some(v) => v,
                        None => json.insert(
                            serde_json::to_value(root).map_err(|e| format!("{what}: {e}"))?,
                        ),
                    };
                    let json_target = (segments.as_slice(), *kind, default.is_some());
                    json_keys(document, working, json_target, &what, &key)?
                }
            };
            if role == Role::PointerBool && sampler.interpolation() != Interpolation::Step {
                return Err(format!(
                    "{what} animates the boolean `{key}`, which must use STEP interpolation"
                ));
            }
            let value = sample(
                &sampler,
                root,
                get,
                max_bytes,
                &what,
                &label,
                (role, width, rotation),
                pose.time,
            )?;
            if let Target::Node(
                n,
                NodeProperty::Translation | NodeProperty::Rotation | NodeProperty::Scale,
            ) = destination
            {
                moved[n] = true;
            }
            match destination {
                Target::Node(n, property) => match property {
                    NodeProperty::Translation => trs[n].0 = Vec3::from_slice(&value),
                    NodeProperty::Rotation => trs[n].1 = Quat::from_slice(&value),
                    NodeProperty::Scale => trs[n].2 = Vec3::from_slice(&value),
                    NodeProperty::Weights => weights[n] = Some(value),
                    NodeProperty::Weight(k) => {
                        let node = document.nodes().nth(n).expect("checked above");
                        let own = weights[n].take().or_else(|| {
                            node.weights()
                                .or_else(|| node.mesh().and_then(|m| m.weights()))
                                .map(<[f32]>::to_vec)
                        });
                        let mut all = own.unwrap_or_default();
                        all.resize(morph_targets(node.mesh()), 0.0);
                        all[k] = value[0];
                        weights[n] = Some(all);
                    }
                },
                Target::Json { segments, kind, .. } => {
                    let working = json.as_mut().expect("made above");
                    animation_pointer::set(
                        working,
                        &segments,
                        animation_pointer::json_value(kind, &value),
                    )
                    .map_err(|e| format!("{what}: {e}"))?;
                }
            }
        }
    }
    let mut locals = static_locals(document);
    for (n, local) in locals.iter_mut().enumerate() {
        if moved[n] {
            let (t, r, s) = trs[n];
            let len = r.length();
            if !(len.is_finite() && len > 1e-6) {
                return Err(format!(
                    "node {} is posed with rotation {r:?}, not a rotation",
                    n
                ));
            }
            *local = Mat4::from_scale_rotation_translation(s, r / len, t);
        }
    }
    Ok(Posed {
        locals,
        weights,
        json,
    })
}

/// How many morph targets a mesh has (0 without a mesh).
fn morph_targets(mesh: Option<gltf::Mesh<'_>>) -> usize {
    mesh.and_then(|m| m.primitives().next())
        .map_or(0, |p| p.morph_targets().count())
}

/// The keys of a channel that moves `property` of `node`: the values' accessor role, the
/// floats per key and whether they are slerped (a pointer channel's keys may be of any
/// numeric type, a core channel's only of those the glTF specification allows). Errors
/// name `what`.
fn node_keys(
    node: &gltf::Node<'_>,
    property: NodeProperty,
    pointer: bool,
    what: &str,
) -> Result<(Role, usize, bool), String> {
    let transform = matches!(
        property,
        NodeProperty::Translation | NodeProperty::Rotation | NodeProperty::Scale
    );
    if transform
        && matches!(node.transform(), gltf::scene::Transform::Matrix { .. })
        && node.transform().matrix() != Mat4::IDENTITY.to_cols_array_2d()
    {
        // glTF: an animated node has translation, rotation and scale.
        return Err(format!(
            "{what} animates node {}, which has a matrix; an animated node must give \
             translation, rotation and scale instead",
            gltf_check::node_name(node)
        ));
    }
    let targets = morph_targets(node.mesh());
    if !transform && targets == 0 {
        return Err(format!(
            "{what} animates the morph weights of node {}, whose mesh has no morph targets",
            gltf_check::node_name(node)
        ));
    }
    if let NodeProperty::Weight(k) = property {
        if k >= targets {
            return Err(format!(
                "{what} animates morph weight {k} of node {}, whose mesh has {targets} morph \
                 target(s)",
                gltf_check::node_name(node)
            ));
        }
    }
    Ok(match (property, pointer) {
        (NodeProperty::Translation | NodeProperty::Scale, false) => (Role::AnimationVec3, 3, false),
        (NodeProperty::Rotation, false) => (Role::AnimationRotation, 4, true),
        (NodeProperty::Weights, false) => (Role::AnimationWeights, targets, false),
        (NodeProperty::Translation | NodeProperty::Scale, true) => (Role::PointerVec3, 3, false),
        (NodeProperty::Rotation, true) => (Role::PointerVec4, 4, true),
        (NodeProperty::Weights, true) => (Role::PointerScalar, targets, false),
        (NodeProperty::Weight(_), _) => (Role::PointerScalar, 1, false),
    })
}

/// The keys of a pointer channel into the JSON property at `segments` (of `kind`, with a
/// default or not), as [`node_keys`] gives them, once the property is found defined in
/// `working` (the file's JSON as posed so far; a mesh's morph weights the file leaves out
/// are made zeros there first). Errors name `what` and the pointer, `key`.
fn json_keys(
    document: &gltf::Document,
    working: &mut serde_json::Value,
    (segments, kind, has_default): (&[String], Kind, bool),
    what: &str,
    key: &str,
) -> Result<(Role, usize, bool), String> {
    let mesh_targets = match segments {
        [m, i, w, ..] if m == "meshes" && w == "weights" => {
            let Some(mesh) = i.parse().ok().and_then(|i| document.meshes().nth(i)) else {
                return Err(format!(
                    "{what} animates `{key}`, but the file has no mesh {i}"
                ));
            };
            let targets = morph_targets(Some(mesh.clone()));
            if targets == 0 {
                return Err(format!(
                    "{what} animates `{key}`, but that mesh has no morph targets"
                ));
            }
            let mesh = &mut working["meshes"][mesh.index()];
            if mesh.get("weights").is_none_or(serde_json::Value::is_null) {
                mesh["weights"] = serde_json::json!(vec![0.0; targets]);
            }
            Some(targets)
        }
        _ => None,
    };
    if !animation_pointer::defined(working, segments, has_default) {
        return Err(format!(
            "{what} animates `{key}`, which the file does not define (the property must be \
             in the file, or have a default and its object be in the file)"
        ));
    }
    Ok(match kind {
        Kind::Float => (Role::PointerScalar, 1, false),
        Kind::Vector(2) => (Role::PointerVec2, 2, false),
        Kind::Vector(3) => (Role::PointerVec3, 3, false),
        Kind::Vector(_) => (Role::PointerVec4, 4, false),
        Kind::Weights => (Role::PointerScalar, mesh_targets.unwrap_or(1), false),
        Kind::Bool => (Role::PointerBool, 1, false),
    })
}

const PATHS: [&str; 4] = ["translation", "rotation", "scale", "weights"];

fn path_index(property: NodeProperty) -> usize {
    match property {
        NodeProperty::Translation => 0,
        NodeProperty::Rotation => 1,
        NodeProperty::Scale => 2,
        NodeProperty::Weights | NodeProperty::Weight(_) => 3,
    }
}

/// A sampler's value at `time`: its keyframe times and values read (`role`: the values'
/// accessor role, `width` floats per key, `rotation`: quaternions, slerped) and checked,
/// errors naming `what` and the `property` it animates.
#[allow(clippy::too_many_arguments)]
fn sample<'a, 's>(
    sampler: &gltf::animation::Sampler<'a>,
    root: &gltf::json::Root,
    get: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
    max_bytes: u64,
    what: &str,
    property: &str,
    (role, width, rotation): (Role, usize, bool),
    time: f32,
) -> Result<Vec<f32>, String> {
    let input = sampler.input();
    gltf_check::check_accessor(root, input.index(), Role::AnimationInput, max_bytes)
        .map_err(|e| format!("{what}: {e}"))?;
    let times: Vec<f32> = read_scalars(input, get.clone())
        .ok_or_else(|| format!("{what}: unreadable keyframe times"))?;
    if let Some(k) = times
        .iter()
        .position(|t| !t.is_finite())
        .or_else(|| times.windows(2).position(|w| w[1] <= w[0]).map(|k| k + 1))
    {
        return Err(format!(
            "{what}: keyframe time {k} is {}, which is not finite or not after the \
             one before; keyframe times must increase",
            times[k]
        ));
    }
    let output = sampler.output();
    gltf_check::check_accessor(root, output.index(), role, max_bytes)
        .map_err(|e| format!("{what}: {e}"))?;
    use super::load_primitive::read_floats;
    let values: Vec<f32> = match output.dimensions() {
        gltf::accessor::Dimensions::Vec2 => {
            read_floats::<2>(output, get, false).map(|v| v.concat())
        }
        gltf::accessor::Dimensions::Vec3 => {
            read_floats::<3>(output, get, false).map(|v| v.concat())
        }
        gltf::accessor::Dimensions::Vec4 => {
            read_floats::<4>(output, get, false).map(|v| v.concat())
        }
        _ => read_scalars(output, get),
    }
    .ok_or_else(|| format!("{what}: unreadable keyframe values"))?;
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(format!("{what}: a keyframe value is {v}"));
    }
    let cubic = sampler.interpolation() == Interpolation::CubicSpline;
    let per_key = width * if cubic { 3 } else { 1 };
    if values.len() != times.len() * per_key {
        return Err(format!(
            "{what}: {} keyframe times but {} output values; with {} interpolation {property} \
             needs {} per key",
            times.len(),
            values.len() / width,
            match sampler.interpolation() {
                Interpolation::Linear => "LINEAR",
                Interpolation::Step => "STEP",
                Interpolation::CubicSpline => "CUBICSPLINE",
            },
            if cubic { 3 } else { 1 }
        ));
    }
    let keys = Keys {
        times: &times,
        values: &values,
        width,
        interpolation: sampler.interpolation(),
    };
    Ok(keys.sample(time, rotation))
}

/// A SCALAR accessor's elements as floats, normalised integers mapped as the glTF spec
/// says and others converted as they are (`KHR_animation_pointer` allows them; for core
/// channels `check_accessor` refuses integers that are not normalised).
fn read_scalars<'a, 's>(
    accessor: gltf::Accessor<'a>,
    get: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'s [u8]>,
) -> Option<Vec<f32>> {
    use gltf::accessor::{DataType, Iter};
    let normalized = accessor.normalized();
    let scaled = |c: f32, largest: f32| {
        if normalized {
            (c / largest).max(-1.0)
        } else {
            c
        }
    };
    Some(match accessor.data_type() {
        DataType::F32 => Iter::<f32>::new(accessor, get)?.collect(),
        DataType::I8 => Iter::<i8>::new(accessor, get)?
            .map(|c| scaled(c.into(), 127.0))
            .collect(),
        DataType::U8 => Iter::<u8>::new(accessor, get)?
            .map(|c| scaled(c.into(), 255.0))
            .collect(),
        DataType::I16 => Iter::<i16>::new(accessor, get)?
            .map(|c| scaled(c.into(), 32767.0))
            .collect(),
        DataType::U16 => Iter::<u16>::new(accessor, get)?
            .map(|c| scaled(c.into(), 65535.0))
            .collect(),
        DataType::U32 => return None,
    })
}

/// One sampler's keyframes: `times` increasing, `values` `width` floats per element and
/// three elements per key (in-tangent, value, out-tangent) for CUBICSPLINE.
struct Keys<'k> {
    times: &'k [f32],
    values: &'k [f32],
    width: usize,
    interpolation: Interpolation,
}

impl Keys<'_> {
    /// Element `e` of key `k` (for CUBICSPLINE: 0 in-tangent, 1 value, 2 out-tangent).
    fn element(&self, k: usize, e: usize) -> &[f32] {
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        let start = (k * per_key + e) * self.width;
        &self.values[start..start + self.width]
    }

    fn value(&self, k: usize) -> Vec<f32> {
        let e = usize::from(self.interpolation == Interpolation::CubicSpline);
        self.element(k, e).to_vec()
    }

    /// The value at time `t`; `rotation`: the elements are quaternions (x, y, z, w).
    fn sample(&self, t: f32, rotation: bool) -> Vec<f32> {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return self.value(0);
        }
        if t >= self.times[n - 1] {
            return self.value(n - 1);
        }
        // The key interval [t_k, t_k+1) that holds t.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = (t - t0) / dt;
        match self.interpolation {
            Interpolation::Step => self.value(k),
            Interpolation::Linear if rotation => {
                let a = Quat::from_slice(self.element(k, 0));
                let b = Quat::from_slice(self.element(k + 1, 0));
                slerp(a, b, s).to_array().to_vec()
            }
            Interpolation::Linear => {
                let (a, b) = (self.element(k, 0), self.element(k + 1, 0));
                a.iter().zip(b).map(|(a, b)| a + s * (b - a)).collect()
            }
            Interpolation::CubicSpline => {
                // p(s) = h00·v_k + h10·dt·b_k + h01·v_k+1 + h11·dt·a_k+1, with b_k the
                // out-tangent of key k and a_k+1 the in-tangent of key k + 1.
                let (s2, s3) = (s * s, s * s * s);
                let h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                let (v0, b0) = (self.element(k, 1), self.element(k, 2));
                let (a1, v1) = (self.element(k + 1, 0), self.element(k + 1, 1));
                let mut p: Vec<f32> = (0..self.width)
                    .map(|i| h00 * v0[i] + h10 * dt * b0[i] + h01 * v1[i] + h11 * dt * a1[i])
                    .collect();
                if rotation {
                    let len = p.iter().map(|x| x * x).sum::<f32>().sqrt();
                    if len > 0.0 {
                        p.iter_mut().for_each(|x| *x /= len);
                    }
                }
                p
            }
        }
    }
}

/// Spherical linear interpolation along the shorter arc (glTF appendix C), from
/// normalised keys (normalised integer keys are only nearly unit length).
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let (a, b) = (a.normalize(), b.normalize());
    let mut d = a.dot(b);
    let b = if d < 0.0 {
        d = -d;
        -b
    } else {
        b
    };
    if d > 0.9995 {
        return a.lerp(b, s).normalize();
    }
    let angle = d.acos();
    let sin = angle.sin();
    let (wa, wb) = (((1.0 - s) * angle).sin() / sin, (s * angle).sin() / sin);
    Quat::from_xyzw(
        wa * a.x + wb * b.x,
        wa * a.y + wb * b.y,
        wa * a.z + wb * b.z,
        wa * a.w + wb * b.w,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys<'k>(times: &'k [f32], values: &'k [f32], width: usize, i: Interpolation) -> Keys<'k> {
        Keys {
            times,
            values,
            width,
            interpolation: i,
        }
    }

    #[test]
    fn linear_step_and_clamping() {
        let k = keys(&[1.0, 3.0], &[0.0, 10.0], 1, Interpolation::Linear);
        assert_eq!(k.sample(0.0, false), [0.0]);
        assert_eq!(k.sample(2.5, false), [7.5]);
        assert_eq!(k.sample(9.0, false), [10.0]);
        let k = keys(&[1.0, 3.0], &[0.0, 10.0], 1, Interpolation::Step);
        assert_eq!(k.sample(2.999, false), [0.0]);
        assert_eq!(k.sample(3.0, false), [10.0]);
    }

    #[test]
    fn cubic_spline_is_the_hermite_curve() {
        // p(t) = t³ on [0, 1]: values 0 and 1, tangents dp/dt 0 and 3.
        let values = [0.0, 0.0, 0.0, 3.0, 1.0, 0.0];
        let k = keys(&[0.0, 1.0], &values, 1, Interpolation::CubicSpline);
        for t in [0.1f32, 0.5, 0.8] {
            assert!((k.sample(t, false)[0] - t * t * t).abs() < 1e-6);
        }
        // Tangents are per second: on [0, 2], p(t) = t³ / 8 has dp/dt(2) = 1.5.
        let values = [0.0, 0.0, 0.0, 1.5, 1.0, 0.0];
        let k = keys(&[0.0, 2.0], &values, 1, Interpolation::CubicSpline);
        assert!((k.sample(1.0, false)[0] - 0.125).abs() < 1e-6);
    }

    #[test]
    fn rotations_take_the_shorter_arc() {
        let a = Quat::IDENTITY;
        // 270° about y is −90° the short way.
        let b = Quat::from_rotation_y(1.5 * std::f32::consts::PI);
        let half = slerp(a, b, 0.5);
        let expect = Quat::from_rotation_y(-0.25 * std::f32::consts::PI);
        assert!(half.dot(expect).abs() > 1.0 - 1e-6, "{half:?}");
    }
}
