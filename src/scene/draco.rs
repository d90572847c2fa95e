//! `KHR_draco_mesh_compression`: primitives whose indices and attributes are one Draco
//! stream (bitstream 2.2, sequential or edgebreaker connectivity), decoded by the
//! `draco-oxide-decoder` crate.
//!
//! [`plan`] runs on the JSON before the document is built: every accessor a Draco
//! primitive fills gets a buffer view of its own in one placeholder buffer without a URI
//! (as `EXT_meshopt_compression`'s decompressed views have), so that everything after it
//! (the accessor checks, the crate's readers, morph targets, skins) reads those accessors
//! as it reads any other. [`decode`] then decodes each stream once the buffers are loaded
//! and writes its triangles and attributes there, in the accessors' own component types.
//! A stream overrides an uncompressed fallback, as the extension says a loader that
//! processes it must.
//!
//! Damaged and hostile streams. The header of each stream must declare the triangles and
//! points its accessors hold before anything is decoded, so that what the decoder
//! allocates for its connectivity follows from sizes the input budget has accepted. The
//! decoder still trusts counts deeper in a stream (a prediction's metadata, an entropy
//! coder's alphabet), and a damaged one can make it allocate gigabytes or abort. On Unix
//! it therefore runs in a child process (`fork`) whose address space and CPU time are
//! bounded; whatever ends the child early (a panic, an abort, a bound) is an error that
//! names the primitive, and the parent never runs the decoder itself.

use gltf::json;
use gltf::json::accessor::{ComponentType, GenericComponentType, Type};
use gltf::json::validation::Checked;
use std::collections::HashMap;

pub(super) const EXTENSION: &str = "KHR_draco_mesh_compression";

/// What an accessor is filled with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Source {
    /// The stream's triangles, as a triangle list.
    Indices,
    /// The attribute with this unique id.
    Attribute(u32),
}

/// One accessor a stream fills: `count` elements of `components` × `ct` at `stride`
/// bytes from `offset` in the placeholder buffer.
#[derive(Clone, Debug)]
struct Fill {
    accessor: usize,
    /// Its buffer view in the placeholder buffer.
    view: usize,
    semantic: String,
    source: Source,
    offset: usize,
    stride: usize,
    count: usize,
    ct: ComponentType,
    normalized: bool,
    components: usize,
}

impl Fill {
    fn elem(&self) -> usize {
        self.ct.size() * self.components
    }
    fn bytes(&self) -> usize {
        self.bytes_for(self.count)
    }
    fn bytes_for(&self, count: usize) -> usize {
        self.stride * (count - 1) + self.elem()
    }
    /// The elements a stream decodes to `points` points fills this with.
    fn count_for(&self, points: usize) -> usize {
        match self.source {
            Source::Indices => self.count,
            Source::Attribute(_) => points,
        }
    }
}

/// One Draco primitive: its stream (buffer view) and what it fills.
#[derive(Clone, Debug)]
struct Job {
    what: String,
    view: usize,
    faces: usize,
    /// The points its accessors declare.
    points: usize,
    fills: Vec<Fill>,
}

impl Job {
    /// The most points a stream of this job may decode to. Sequential streams decode to
    /// the points the accessors declare. Edgebreaker streams make one point per run of
    /// corners around a vertex with the same attribute values; Google's decoder and
    /// draco-oxide can cut those runs differently (a point more, on the same values),
    /// so only the corners bound it.
    fn max_points(&self) -> usize {
        self.points.max(3 * self.faces)
    }
}

/// What a job's stream decoded to: its points, and each fill's bytes.
struct Decoded {
    points: usize,
    parts: Vec<Vec<u8>>,
}

/// The Draco primitives of a file and the placeholder buffer their data goes into.
#[derive(Debug)]
pub(super) struct Plan {
    /// The placeholder buffer's index (the last buffer).
    pub buffer: usize,
    jobs: Vec<Job>,
}

/// The JSON value of primitive `p`'s extension, if it has one.
fn extension(prim: &json::mesh::Primitive) -> Option<&serde_json::Value> {
    prim.extensions.as_ref()?.others.get(EXTENSION)
}

/// Gives every accessor a Draco primitive fills a view of its own in a new placeholder
/// buffer (see the module comment). `None` when no primitive uses the extension.
pub(super) fn plan(root: &mut json::Root) -> Result<Option<Plan>, String> {
    // Which stream, and which part of it, fills each accessor.
    let mut bound: HashMap<usize, (usize, Source, String)> = HashMap::new();
    let mut jobs = Vec::new();
    let mut strips = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let Some(ext) = extension(prim) else { continue };
            let what = format!("mesh {m} primitive {p} ({EXTENSION})");
            let view = ext
                .get("bufferView")
                .and_then(serde_json::Value::as_u64)
                .ok_or_else(|| format!("{what} has no valid `bufferView`"))?;
            let view = usize::try_from(view)
                .ok()
                .filter(|&v| v < root.buffer_views.len())
                .ok_or_else(|| {
                    format!(
                        "{what} refers to buffer view {view} but the file has {}",
                        root.buffer_views.len()
                    )
                })?;
            let attributes = ext
                .get("attributes")
                .and_then(serde_json::Value::as_object)
                .ok_or_else(|| format!("{what} has no `attributes` object"))?;
            match prim.mode {
                Checked::Valid(json::mesh::Mode::Triangles) => {}
                Checked::Valid(json::mesh::Mode::TriangleStrip) => strips.push((m, p)),
                _ => {
                    return Err(format!(
                        "{what}: the extension needs mode TRIANGLES or TRIANGLE_STRIP"
                    ))
                }
            }
            let indices = prim.indices.map(|i| i.value()).ok_or_else(|| {
                format!("{what} has no indices accessor, which its triangles fill")
            })?;
            let mut sources = vec![(indices, Source::Indices, "indices".to_string())];
            for (semantic, uid) in attributes {
                let accessor = prim
                    .attributes
                    .iter()
                    .find(|(s, _)| matches!(s, Checked::Valid(s) if s.to_string() == *semantic))
                    .map(|(_, a)| a.value())
                    .ok_or_else(|| {
                        format!("{what} compresses {semantic}, which the primitive does not have")
                    })?;
                let uid = uid
                    .as_u64()
                    .and_then(|u| u32::try_from(u).ok())
                    .ok_or_else(|| format!("{what}: the id of {semantic} is {uid}"))?;
                sources.push((accessor, Source::Attribute(uid), semantic.clone()));
            }
            let mut fills = Vec::new();
            let mut points = None;
            let mut faces = 0;
            for (accessor, source, semantic) in sources {
                let acc = root.accessors.get(accessor).ok_or_else(|| {
                    format!(
                        "{what}: {semantic} refers to accessor {accessor} but the file has {}",
                        root.accessors.len()
                    )
                })?;
                let label = format!("{what}: {semantic} (accessor {accessor})");
                let (Checked::Valid(ty), Checked::Valid(GenericComponentType(ct))) =
                    (acc.type_, acc.component_type)
                else {
                    return Err(format!("{label} has an invalid type"));
                };
                if acc.sparse.is_some() {
                    return Err(format!(
                        "{label} is sparse, which a Draco stream cannot fill"
                    ));
                }
                let count = usize::try_from(acc.count.0)
                    .ok()
                    .filter(|&c| c > 0)
                    .ok_or_else(|| format!("{label} has count {}", acc.count.0))?;
                if source == Source::Indices {
                    if ty != Type::Scalar
                        || !matches!(
                            ct,
                            ComponentType::U8 | ComponentType::U16 | ComponentType::U32
                        )
                    {
                        return Err(format!("{label} is not unsigned integer SCALAR"));
                    }
                    faces = match prim.mode {
                        Checked::Valid(json::mesh::Mode::TriangleStrip) if count >= 3 => count - 2,
                        Checked::Valid(json::mesh::Mode::Triangles) if count % 3 == 0 => count / 3,
                        _ => {
                            return Err(format!("{label}: {count} indices are not whole triangles"))
                        }
                    };
                } else {
                    if points.is_some_and(|n| n != count) {
                        return Err(format!(
                            "{what}: its compressed attributes have different counts"
                        ));
                    }
                    points = Some(count);
                }
                match bound.get(&accessor) {
                    Some((v, s, _)) if (*v, *s) == (view, source) => continue,
                    Some((_, _, other)) => {
                        return Err(format!(
                            "accessor {accessor} is filled by {what} and by {other}"
                        ))
                    }
                    None => {
                        bound.insert(accessor, (view, source, what.clone()));
                    }
                }
                // A strip's triangles are decoded as a list.
                let count = match source {
                    Source::Indices => faces
                        .checked_mul(3)
                        .ok_or_else(|| format!("{label} has count {count}"))?,
                    Source::Attribute(_) => count,
                };
                let elem = ct.size() * ty.multiplicity();
                // Indices are packed; vertex attributes start on 4-byte boundaries.
                let stride = if source == Source::Indices {
                    elem
                } else {
                    elem.div_ceil(4) * 4
                };
                fills.push(Fill {
                    accessor,
                    view: 0,
                    semantic,
                    source,
                    offset: 0,
                    stride,
                    count,
                    ct,
                    normalized: acc.normalized,
                    components: ty.multiplicity(),
                });
            }
            let points = points.ok_or_else(|| format!("{what} compresses no attributes"))?;
            jobs.push(Job {
                what,
                view,
                faces,
                points,
                fills,
            });
        }
    }
    if jobs.is_empty() {
        return Ok(None);
    }
    // An accessor a stream fills is that primitive's alone.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let draco = extension(prim).is_some();
            let mut uses: Vec<usize> = Vec::new();
            if !draco {
                uses.extend(prim.indices.map(|i| i.value()));
                uses.extend(prim.attributes.values().map(|a| a.value()));
            }
            for target in prim.targets.iter().flatten() {
                uses.extend(
                    [&target.positions, &target.normals, &target.tangents]
                        .into_iter()
                        .flatten()
                        .map(|a| a.value()),
                );
            }
            if let Some((a, (_, _, by))) = uses.iter().find_map(|a| Some((a, bound.get(a)?))) {
                return Err(format!(
                    "accessor {a} is filled by {by} but mesh {m} primitive {p} also reads it"
                ));
            }
        }
    }
    // Lay the views out in the placeholder buffer.
    let buffer = root.buffers.len();
    let mut end: u64 = 0;
    for job in &mut jobs {
        for fill in &mut job.fills {
            let offset = end.div_ceil(4) * 4;
            let bytes = (fill.stride as u64)
                .checked_mul(fill.count as u64 - 1)
                .and_then(|b| b.checked_add(fill.elem() as u64))
                .and_then(|b| b.checked_add(offset))
                .filter(|&e| e <= usize::MAX as u64 / 2)
                .ok_or_else(|| format!("{}: {} is too large", job.what, fill.semantic))?;
            fill.offset = offset as usize;
            end = bytes;
        }
    }
    for job in &mut jobs {
        for fill in &mut job.fills {
            let view = root.buffer_views.len();
            fill.view = view;
            let mut v = serde_json::json!({
                "buffer": buffer,
                "byteOffset": fill.offset,
                "byteLength": fill.bytes(),
            });
            if fill.stride != fill.elem() {
                v["byteStride"] = fill.stride.into();
            }
            root.buffer_views
                .push(serde_json::from_value(v).map_err(|e| e.to_string())?);
            let acc = &mut root.accessors[fill.accessor];
            acc.buffer_view = Some(json::Index::new(view as u32));
            acc.byte_offset = None;
            acc.count = json::validation::USize64(fill.count as u64);
        }
    }
    for (m, p) in strips {
        root.meshes[m].primitives[p].mode = Checked::Valid(json::mesh::Mode::Triangles);
    }
    root.buffers.push(
        serde_json::from_value(serde_json::json!({ "byteLength": end.max(4) }))
            .map_err(|e| e.to_string())?,
    );
    Ok(Some(Plan { buffer, jobs }))
}

/// Decodes every stream of `plan` into its placeholder buffer. Where a stream decodes to
/// other point counts than its accessors declare (see [`Job::max_points`]), the
/// placeholder is laid out again for what was decoded and the patched JSON returned: the
/// caller rebuilds the document from it. `budget` pays for a larger placeholder.
pub(super) fn decode(
    plan: &Plan,
    root: &json::Root,
    buffers: &mut [gltf::buffer::Data],
    budget: &mut super::sources::Budget,
) -> Result<Option<json::Root>, String> {
    let mut streams = Vec::with_capacity(plan.jobs.len());
    for job in &plan.jobs {
        let view = &root.buffer_views[job.view];
        let start = view.byte_offset.map_or(0, |o| o.0) as usize;
        let stream = buffers
            .get(view.buffer.value())
            .and_then(|b| {
                b.0.get(start..start.checked_add(view.byte_length.0 as usize)?)
            })
            .ok_or_else(|| format!("{}: its buffer view {} is not loaded", job.what, job.view))?;
        streams.push(stream);
    }
    let decoded = isolated::run(&plan.jobs, &streams)?;
    let exact = plan
        .jobs
        .iter()
        .zip(&decoded)
        .all(|(j, d)| d.points == j.points);
    if exact {
        let out = &mut buffers[plan.buffer].0;
        for (job, d) in plan.jobs.iter().zip(&decoded) {
            for (fill, bytes) in job.fills.iter().zip(&d.parts) {
                out[fill.offset..fill.offset + bytes.len()].copy_from_slice(bytes);
            }
        }
        return Ok(None);
    }
    let mut root = root.clone();
    let mut data = Vec::new();
    for (job, d) in plan.jobs.iter().zip(decoded) {
        for (fill, bytes) in job.fills.iter().zip(d.parts) {
            data.resize(data.len().div_ceil(4) * 4, 0);
            let view = &mut root.buffer_views[fill.view];
            view.byte_offset = Some(json::validation::USize64(data.len() as u64));
            view.byte_length = json::validation::USize64(bytes.len() as u64);
            root.accessors[fill.accessor].count =
                json::validation::USize64(fill.count_for(d.points) as u64);
            data.extend_from_slice(&bytes);
        }
    }
    data.resize(data.len().max(4).div_ceil(4) * 4, 0);
    let before = buffers[plan.buffer].0.len();
    if data.len() > before {
        budget.take((data.len() - before) as u64, "decoded Draco meshes")?;
    }
    root.buffers[plan.buffer].byte_length = json::validation::USize64(data.len() as u64);
    buffers[plan.buffer] = gltf::buffer::Data(data);
    Ok(Some(root))
}

/// The triangles and points a stream's header declares (module comment).
#[derive(Debug, PartialEq, Eq)]
struct Declared {
    edgebreaker: bool,
    faces: u64,
    /// Sequential: the points; edgebreaker: the encoded vertices (before attribute seams
    /// split them into points).
    vertices: u64,
    /// Edgebreaker's symbols and split symbols (at most one of each per triangle).
    symbols: u64,
    splits: u64,
}

/// Reads a stream's header (skipping its metadata) up to its connectivity's counts.
fn declared(stream: &[u8]) -> Result<Declared, String> {
    struct Cursor<'a>(&'a [u8]);
    impl Cursor<'_> {
        fn bytes(&mut self, n: usize) -> Result<&[u8], String> {
            if self.0.len() < n {
                return Err("the stream ends inside its header".into());
            }
            let (head, rest) = self.0.split_at(n);
            self.0 = rest;
            Ok(head)
        }
        fn byte(&mut self) -> Result<u8, String> {
            Ok(self.bytes(1)?[0])
        }
        fn varint(&mut self) -> Result<u64, String> {
            let mut v = 0u64;
            for shift in (0..64).step_by(7) {
                let b = self.byte()?;
                v |= u64::from(b & 0x7f) << shift;
                if b & 0x80 == 0 {
                    return Ok(v);
                }
            }
            Err("a count in its header is malformed".into())
        }
        fn len(&mut self) -> Result<usize, String> {
            usize::try_from(self.varint()?)
                .map_err(|_| "a length in its metadata is malformed".into())
        }
        /// A metadata block: named entries, then named sub-blocks.
        fn metadata(&mut self, depth: usize) -> Result<(), String> {
            if depth > 64 {
                return Err("its metadata nests too deeply".into());
            }
            for _ in 0..self.varint()? {
                let name = self.byte()? as usize;
                self.bytes(name)?;
                let value = self.len()?;
                self.bytes(value)?;
            }
            for _ in 0..self.varint()? {
                let name = self.byte()? as usize;
                self.bytes(name)?;
                self.metadata(depth + 1)?;
            }
            Ok(())
        }
    }
    let mut c = Cursor(stream);
    if c.bytes(5).ok() != Some(b"DRACO".as_slice()) {
        return Err("it is not a Draco stream".into());
    }
    let (major, minor) = (c.byte()?, c.byte()?);
    if (major, minor) != (2, 2) {
        return Err(format!(
            "it is Draco bitstream {major}.{minor}; lanterna decodes 2.2, which the extension specifies"
        ));
    }
    if c.byte()? != 1 {
        return Err("it holds a point cloud, not a triangle mesh".into());
    }
    let method = c.byte()?;
    let flags = u16::from_le_bytes([c.byte()?, c.byte()?]);
    if flags & 0x8000 != 0 {
        for _ in 0..c.varint()? {
            c.varint()?;
            c.metadata(0)?;
        }
        c.metadata(0)?;
    }
    match method {
        0 => Ok(Declared {
            edgebreaker: false,
            faces: c.varint()?,
            vertices: c.varint()?,
            symbols: 0,
            splits: 0,
        }),
        1 => {
            c.byte()?; // the traversal
            let vertices = c.varint()?;
            let faces = c.varint()?;
            c.byte()?; // attribute connectivity streams
            Ok(Declared {
                edgebreaker: true,
                faces,
                vertices,
                symbols: c.varint()?,
                splits: c.varint()?,
            })
        }
        m => Err(format!("its encoder method {m} is unknown")),
    }
}

/// The bytes each of `job`'s fills holds, decoded from `stream`. Errors say what is
/// wrong, after the job's name.
fn decode_job(job: &Job, stream: &[u8]) -> Result<Decoded, String> {
    use draco_oxide_core::attribute::ComponentDataType as D;
    use draco_oxide_core::types::PointIdx;
    let fail = |message: String| {
        format!(
            "{}: its Draco stream (buffer view {}) {message}",
            job.what, job.view
        )
    };
    let header = declared(stream).map_err(|e| fail(format!("cannot be decoded: {e}")))?;
    let (faces, points) = (job.faces as u64, job.points as u64);
    let fits = header.faces == faces
        && if header.edgebreaker {
            header.vertices <= job.max_points() as u64
                && header.symbols <= faces
                && header.splits <= faces
        } else {
            header.vertices == points
        };
    if !fits {
        return Err(fail(format!(
            "declares {} triangles of {} {}, but its accessors hold {faces} triangles of {points} points",
            header.faces,
            header.vertices,
            if header.edgebreaker { "vertices" } else { "points" }
        )));
    }
    let mesh = quiet_panics(|| draco_oxide_decoder::decode_mesh(stream))
        .map_err(|p| {
            fail(format!(
                "is damaged: the decoder stopped on an internal error ({p})"
            ))
        })?
        .map_err(|e| fail(format!("cannot be decoded: {e}")))?;
    if mesh.faces.len() != job.faces {
        return Err(fail(format!(
            "decodes to {} triangles, not {}",
            mesh.faces.len(),
            job.faces
        )));
    }
    let decoded_points = mesh.attributes.iter().map(|a| a.len()).max().unwrap_or(0);
    let points_fit = if header.edgebreaker {
        (1..=job.max_points()).contains(&decoded_points)
    } else {
        decoded_points == job.points
    };
    if !points_fit || mesh.attributes.iter().any(|a| a.len() != decoded_points) {
        return Err(fail(format!(
            "decodes to {decoded_points} points, but its accessors declare {}",
            job.points
        )));
    }
    let mut out = Vec::with_capacity(job.fills.len());
    for fill in &job.fills {
        let mut bytes = vec![0u8; fill.bytes_for(fill.count_for(decoded_points))];
        match fill.source {
            Source::Indices => {
                let size = fill.ct.size();
                for (k, &i) in mesh.faces.iter().flatten().enumerate() {
                    let i = usize::from(i);
                    if i >= decoded_points || (size < 4 && i >> (8 * size) != 0) {
                        return Err(fail(format!(
                            "has a triangle with point {i}, past its {decoded_points} points"
                        )));
                    }
                    bytes[k * size..(k + 1) * size]
                        .copy_from_slice(&(i as u32).to_le_bytes()[..size]);
                }
            }
            Source::Attribute(uid) => {
                let att = mesh
                    .attributes
                    .iter()
                    .find(|a| a.get_id().as_usize() == uid as usize)
                    .ok_or_else(|| {
                        fail(format!(
                            "has no attribute with id {uid} (for {})",
                            fill.semantic
                        ))
                    })?;
                if att.get_num_components() != fill.components {
                    return Err(fail(format!(
                        "decodes {} with {} components, but accessor {} has {}",
                        fill.semantic,
                        att.get_num_components(),
                        fill.accessor,
                        fill.components
                    )));
                }
                let from = att.get_component_type();
                let size = match from {
                    D::I8 | D::U8 => 1,
                    D::I16 | D::U16 => 2,
                    D::I32 | D::U32 | D::F32 => 4,
                    _ => {
                        return Err(fail(format!(
                            "decodes {} as {from:?}, which glTF has no type for",
                            fill.semantic
                        )))
                    }
                };
                let same = matches!(
                    (from, fill.ct),
                    (D::I8, ComponentType::I8)
                        | (D::U8, ComponentType::U8)
                        | (D::I16, ComponentType::I16)
                        | (D::U16, ComponentType::U16)
                        | (D::U32, ComponentType::U32)
                        | (D::F32, ComponentType::F32)
                );
                let values = att.get_data_as_bytes();
                let (elem, src_elem) = (fill.elem(), size * fill.components);
                for p in 0..decoded_points {
                    let v = usize::from(att.get_unique_val_idx(PointIdx::from(p)));
                    let value = values
                        .get(v * src_elem..(v + 1) * src_elem)
                        .ok_or_else(|| {
                            fail(format!(
                                "decodes {} with a value out of range",
                                fill.semantic
                            ))
                        })?;
                    let to = &mut bytes[p * fill.stride..p * fill.stride + elem];
                    if same {
                        to.copy_from_slice(value);
                        continue;
                    }
                    for (k, x) in value.chunks_exact(size).enumerate() {
                        let x = component_value(from, x);
                        let out = &mut to[k * fill.ct.size()..(k + 1) * fill.ct.size()];
                        store_component(fill.ct, fill.normalized, from == D::F32, x, out).ok_or_else(|| {
                            fail(format!(
                                "decodes a {} value {x}, which accessor {}'s component type cannot hold",
                                fill.semantic, fill.accessor
                            ))
                        })?;
                    }
                }
            }
        }
        out.push(bytes);
    }
    Ok(Decoded {
        points: decoded_points,
        parts: out,
    })
}

/// One decoded component (little-endian bytes of type `ty`) as a number.
fn component_value(ty: draco_oxide_core::attribute::ComponentDataType, b: &[u8]) -> f64 {
    use draco_oxide_core::attribute::ComponentDataType as D;
    match ty {
        D::I8 => f64::from(b[0] as i8),
        D::U8 => f64::from(b[0]),
        D::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
        D::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
        D::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        D::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        _ => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
    }
}

/// Writes `x` as an accessor component of type `ct` into `out`, as the loaders that
/// decode into the accessor's own type do: a float into a normalised integer scaled to
/// its range (clamped), any other value only where the type holds it exactly. `None`
/// where it does not.
fn store_component(
    ct: ComponentType,
    normalized: bool,
    from_float: bool,
    x: f64,
    out: &mut [u8],
) -> Option<()> {
    let (lo, hi) = match ct {
        ComponentType::F32 => {
            out.copy_from_slice(&(x as f32).to_le_bytes());
            return Some(());
        }
        ComponentType::I8 => (f64::from(i8::MIN), f64::from(i8::MAX)),
        ComponentType::U8 => (0.0, f64::from(u8::MAX)),
        ComponentType::I16 => (f64::from(i16::MIN), f64::from(i16::MAX)),
        ComponentType::U16 => (0.0, f64::from(u16::MAX)),
        ComponentType::U32 => (0.0, f64::from(u32::MAX)),
    };
    let q = if from_float && normalized {
        (x.clamp(if lo < 0.0 { -1.0 } else { 0.0 }, 1.0) * hi).round()
    } else {
        x
    };
    if !(lo..=hi).contains(&q) || q.fract() != 0.0 {
        return None;
    }
    let q = q as i64;
    out.copy_from_slice(&q.to_le_bytes()[..out.len()]);
    Some(())
}

thread_local! {
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// In the decoder's child process (Unix), the pipe to the parent: a panic there is
/// reported through it by the panic hook, which then ends the child before unwinding
/// (module `isolated`).
static CHILD_PIPE: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(-1);

/// A panic's message.
fn panic_message(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into())
}

/// Installs, once, the panic hook that keeps [`quiet_panics`] quiet and reports a
/// child's panic (see [`CHILD_PIPE`]); other panics go to the hook it replaced.
fn install_panic_hook() {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            #[cfg(unix)]
            {
                let fd = CHILD_PIPE.load(std::sync::atomic::Ordering::Relaxed);
                if fd >= 0 {
                    isolated::report_panic(fd, &panic_message(info.payload()));
                }
            }
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
}

/// Runs `f`, returning a panic as its message; the panic hook stays silent for it (the
/// caller reports it), and for nothing else.
fn quiet_panics<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install_panic_hook();
    QUIET.with(|q| q.set(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    result.map_err(|p| panic_message(p.as_ref()))
}

/// The decoder in this process, where it cannot run in a child: only the header check
/// and the panic catch guard it.
fn in_process(jobs: &[Job], streams: &[&[u8]]) -> Result<Vec<Decoded>, String> {
    jobs.iter()
        .zip(streams)
        .map(|(j, s)| decode_job(j, s))
        .collect()
}

#[cfg(not(unix))]
mod isolated {
    //! Without `fork`, the decoder runs in this process.
    pub(super) use super::in_process as run;
}

#[cfg(unix)]
mod isolated {
    //! The decoder in a child process (module comment of `draco.rs`). The child decodes
    //! the jobs in order and writes, for each, `0`, its point count (u64) and its fills (a
    //! u64 length, then the bytes), or `1` and an error message, or (from the panic hook,
    //! which then ends the child without unwinding) `2` and the panic's message; it stops
    //! at the first error. The parent reads until the pipe closes: a job without its
    //! record was the one the child died on.
    //!
    //! A forked child of a process with other threads inherits their locks as they were.
    //! The child takes none of its own but those of the allocator (which glibc resets at a
    //! fork) and, on an abort, what the runtime takes to print it; it does not unwind (the
    //! unwinder takes the loader's lock) and prints no backtrace unless the process asked
    //! for them before (Rust caches `RUST_BACKTRACE`), when an abort prints one under a
    //! lock another thread's panic may hold. A child whose CPU time stands still for a
    //! few seconds is blocked and killed; so is one silent for longer than its streams
    //! could take.
    use super::{decode_job, Decoded, Job};
    use std::io::{Read, Write};
    use std::os::fd::{FromRawFd, OwnedFd};

    /// Address space the decoder may take beyond the process's own, and per byte it
    /// returns (a mesh's decoder state is a few times its output).
    const BASE_BYTES: u64 = 1 << 30;
    const PER_OUTPUT_BYTE: u64 = 16;
    /// CPU seconds, and seconds without a byte from the child (plus one per MB of the
    /// largest stream), before it is stopped.
    const CPU_SECONDS: u64 = 600;
    const SILENT_SECONDS: u64 = 20;

    /// Writes a panic's record and ends the child (the panic hook calls this there).
    pub(super) fn report_panic(fd: i32, message: &str) -> ! {
        let mut record = vec![2u8];
        record.extend((message.len() as u64).to_le_bytes());
        record.extend(message.as_bytes());
        let mut at = 0;
        while at < record.len() {
            // SAFETY: writes from a live buffer to the child's pipe.
            let n = unsafe { libc::write(fd, record[at..].as_ptr().cast(), record.len() - at) };
            if n <= 0 {
                break;
            }
            at += n as usize;
        }
        // SAFETY: ends the child without unwinding or the parent's exit handlers.
        unsafe { libc::_exit(0) }
    }

    pub(super) fn run(jobs: &[Job], streams: &[&[u8]]) -> Result<Vec<Decoded>, String> {
        let output: u64 = jobs
            .iter()
            .flat_map(|j| &j.fills)
            .map(|f| f.bytes() as u64 * 3)
            .sum();
        super::install_panic_hook();
        let mut fds = [0; 2];
        // Where no child can be made (no descriptors, strict overcommit refusing a copy
        // of a large process), the decoder runs here rather than refuse the file.
        let here = |why: std::io::Error| {
            log::warn!(
                "cannot start a process for the Draco decoder ({why}); decoding in this one"
            );
            super::in_process(jobs, streams)
        };
        // SAFETY: pipe2 writes two descriptors into `fds`.
        if unsafe { libc::pipe2(fds.as_mut_ptr(), libc::O_CLOEXEC) } != 0 {
            return here(std::io::Error::last_os_error());
        }
        // SAFETY: both descriptors are new and owned here alone.
        let (read_end, write_end) =
            unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
        let address_space = vm_size()
            .saturating_add(BASE_BYTES)
            .saturating_add(output.saturating_mul(PER_OUTPUT_BYTE));
        // SAFETY: the child runs only the decoder, writes to its pipe and _exits; it
        // returns to none of the parent's code.
        let pid = unsafe { libc::fork() };
        if pid < 0 {
            return here(std::io::Error::last_os_error());
        }
        if pid == 0 {
            drop(read_end);
            child(jobs, streams, write_end, address_space);
        }
        drop(write_end);
        let largest = streams.iter().map(|s| s.len()).max().unwrap_or(0) as u64;
        let silence = SILENT_SECONDS + largest / 1_000_000;
        let result = read_records(jobs, read_end, pid, silence);
        let mut status = 0;
        // SAFETY: `pid` is this process's child; waiting reaps it.
        unsafe { libc::waitpid(pid, &mut status, 0) };
        match result {
            Ok(done) if done.len() == jobs.len() => Ok(done),
            Ok(done) => {
                let why = if libc::WIFSIGNALED(status) {
                    match libc::WTERMSIG(status) {
                        libc::SIGXCPU => format!("ran out of its {CPU_SECONDS} s of CPU time"),
                        libc::SIGKILL => format!(
                            "was stopped: {silence} s without progress, {IDLE_SECONDS} s \
                             blocked, or out of memory"
                        ),
                        libc::SIGABRT => {
                            "aborted, most likely on an allocation a damaged count asked for".into()
                        }
                        s => format!("was killed by signal {s}"),
                    }
                } else {
                    format!("exited with status {}", libc::WEXITSTATUS(status))
                };
                Err(format!(
                    "{}: its Draco stream (buffer view {}) is damaged: the decoder {why}",
                    jobs[done.len()].what,
                    jobs[done.len()].view
                ))
            }
            Err(e) => Err(e),
        }
    }

    /// The process's address-space size (Linux's /proc; 0 where it cannot be read,
    /// which only tightens the bound).
    fn vm_size() -> u64 {
        let pages = std::fs::read_to_string("/proc/self/statm")
            .ok()
            .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
            .unwrap_or(0);
        // SAFETY: sysconf has no preconditions.
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(4096) as u64;
        pages.saturating_mul(page)
    }

    fn child(jobs: &[Job], streams: &[&[u8]], write_end: OwnedFd, address_space: u64) -> ! {
        let limit = |resource, value: u64| {
            let r = libc::rlimit {
                rlim_cur: value as libc::rlim_t,
                rlim_max: value as libc::rlim_t,
            };
            // SAFETY: setrlimit reads `r`.
            unsafe { libc::setrlimit(resource, &r) };
        };
        limit(libc::RLIMIT_AS, address_space);
        limit(libc::RLIMIT_CPU, CPU_SECONDS);
        limit(libc::RLIMIT_CORE, 0);
        // What the decoder or the runtime would print on the way down (an allocation
        // failure, a backtrace) is said by the parent's error instead.
        // SAFETY: open and dup2 on a path and descriptors this process owns.
        unsafe {
            let null = libc::open(c"/dev/null".as_ptr(), libc::O_WRONLY);
            if null >= 0 {
                libc::dup2(null, 2);
            }
        }
        // No backtraces (module comment); panics are reported by the hook, which the
        // parent installed (installing takes a lock another thread may have held).
        std::env::set_var("RUST_BACKTRACE", "0");
        {
            use std::os::fd::AsRawFd;
            super::CHILD_PIPE.store(write_end.as_raw_fd(), std::sync::atomic::Ordering::Relaxed);
        }
        let mut pipe = std::fs::File::from(write_end);
        let mut write = |job: &Job, stream: &[u8]| -> std::io::Result<bool> {
            match decode_job(job, stream) {
                Ok(decoded) => {
                    pipe.write_all(&[0])?;
                    pipe.write_all(&(decoded.points as u64).to_le_bytes())?;
                    for part in decoded.parts {
                        pipe.write_all(&(part.len() as u64).to_le_bytes())?;
                        pipe.write_all(&part)?;
                    }
                    Ok(true)
                }
                Err(message) => {
                    pipe.write_all(&[1])?;
                    pipe.write_all(&(message.len() as u64).to_le_bytes())?;
                    pipe.write_all(message.as_bytes())?;
                    Ok(false)
                }
            }
        };
        for (job, stream) in jobs.iter().zip(streams) {
            match write(job, stream) {
                Ok(true) => {}
                _ => break,
            }
        }
        drop(pipe);
        // SAFETY: _exit ends the child without running the parent's exit handlers.
        unsafe { libc::_exit(0) }
    }

    /// The records the child wrote (module comment), up to the first missing one; a job's
    /// error record is returned as the error.
    fn read_records(
        jobs: &[Job],
        read_end: OwnedFd,
        pid: libc::pid_t,
        silence: u64,
    ) -> Result<Vec<Decoded>, String> {
        let mut pipe = Patient {
            file: std::fs::File::from(read_end),
            pid,
            millis: i32::try_from(silence.saturating_mul(1000)).unwrap_or(i32::MAX),
        };
        let u64_of = |pipe: &mut Patient| -> Option<u64> {
            let mut b = [0u8; 8];
            pipe.read_exact(&mut b).ok().map(|_| u64::from_le_bytes(b))
        };
        let mut done = Vec::new();
        for job in jobs {
            let mut status = [0u8; 1];
            if pipe.read_exact(&mut status).is_err() {
                break;
            }
            let out_of_turn = || format!("{}: the Draco decoder answered out of turn", job.what);
            if status[0] != 0 {
                let Some(len) = u64_of(&mut pipe) else { break };
                if len > 1 << 16 {
                    return Err(out_of_turn());
                }
                let mut message = vec![0u8; len as usize];
                if pipe.read_exact(&mut message).is_err() {
                    break;
                }
                let message = String::from_utf8_lossy(&message).into_owned();
                return Err(if status[0] == 2 {
                    format!(
                        "{}: its Draco stream (buffer view {}) is damaged: the decoder stopped on an internal error ({message})",
                        job.what, job.view
                    )
                } else {
                    message
                });
            }
            let Some(points) = u64_of(&mut pipe) else {
                break;
            };
            let points = usize::try_from(points)
                .ok()
                .filter(|p| (1..=job.max_points()).contains(p))
                .ok_or_else(out_of_turn)?;
            let mut parts = Vec::new();
            for fill in &job.fills {
                let Some(len) = u64_of(&mut pipe) else {
                    return Ok(done);
                };
                // The child's lengths are those of the plan's fills at its point count.
                if len != fill.bytes_for(fill.count_for(points)) as u64 {
                    return Err(out_of_turn());
                }
                let mut bytes = vec![0u8; len as usize];
                if pipe.read_exact(&mut bytes).is_err() {
                    return Ok(done);
                }
                parts.push(bytes);
            }
            done.push(Decoded { points, parts });
        }
        Ok(done)
    }

    /// The pipe's read end, which kills the child when it has been silent too long, or
    /// idle: a decoding child is always on the CPU, so one whose CPU time stands still for
    /// `IDLE_SECONDS` is blocked on a lock it inherited (module comment).
    struct Patient {
        file: std::fs::File,
        pid: libc::pid_t,
        millis: i32,
    }

    const IDLE_SECONDS: u32 = 3;

    impl Patient {
        /// The child's CPU time in clock ticks (Linux's /proc), if it can be read.
        fn cpu_ticks(&self) -> Option<u64> {
            let stat = std::fs::read_to_string(format!("/proc/{}/stat", self.pid)).ok()?;
            // After the command's parenthesised name: state, then utime and stime are
            // fields 14 and 15 of the line (12 and 13 after the name).
            let rest = &stat[stat.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some(f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?)
        }
    }

    impl Read for Patient {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            use std::os::fd::AsRawFd;
            let mut poll = libc::pollfd {
                fd: self.file.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            let (mut waited, mut idle, mut ticks) = (0i32, 0u32, self.cpu_ticks());
            loop {
                // SAFETY: `poll` is one valid pollfd.
                let ready = unsafe { libc::poll(&mut poll, 1, 1000) };
                if ready > 0 {
                    return self.file.read(buf);
                }
                if ready == 0 {
                    waited = waited.saturating_add(1000);
                    let now = self.cpu_ticks();
                    idle = if now.is_some() && now == ticks {
                        idle + 1
                    } else {
                        0
                    };
                    ticks = now;
                    if waited >= self.millis || idle >= IDLE_SECONDS {
                        // SAFETY: `pid` is this process's child, not yet reaped.
                        unsafe { libc::kill(self.pid, libc::SIGKILL) };
                        return Ok(0);
                    }
                    continue;
                }
                let e = std::io::Error::last_os_error();
                if e.kind() != std::io::ErrorKind::Interrupted {
                    return Err(e);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_declare_their_counts() {
        // Sequential: faces 2, points 4; edgebreaker: vertices 5, faces 3, 3 symbols, 1 split.
        let mut seq = b"DRACO\x02\x02\x01\x00\x00\x00".to_vec();
        seq.extend([2, 4]);
        assert_eq!(
            declared(&seq),
            Ok(Declared {
                edgebreaker: false,
                faces: 2,
                vertices: 4,
                symbols: 0,
                splits: 0
            })
        );
        let mut eb = b"DRACO\x02\x02\x01\x01\x00\x00".to_vec();
        eb.extend([0, 5, 3, 1, 3, 1]);
        assert_eq!(
            declared(&eb),
            Ok(Declared {
                edgebreaker: true,
                faces: 3,
                vertices: 5,
                symbols: 3,
                splits: 1
            })
        );
        // Metadata is skipped: one attribute block with an entry of 130 bytes (its size a
        // two-byte varint) and an empty named sub-block, then an empty geometry block.
        let mut meta = b"DRACO\x02\x02\x01\x00\x00\x80".to_vec();
        meta.extend([1, 0, 1, 1, b'k', 0x82, 0x01]);
        meta.extend([b'v'; 130]);
        meta.extend([1, 1, b's', 0, 0, 0, 0, 2, 4]);
        assert_eq!(declared(&meta).map(|d| (d.faces, d.vertices)), Ok((2, 4)));
        for bad in [
            &b"DRACO\x02\x01\x01\x00\x00\x00"[..],
            b"DRACO\x02\x02\x00\x00\x00\x00",
            b"DRACX",
            b"DRACO\x02\x02\x01\x03\x00\x00\x01\x01",
        ] {
            assert!(declared(bad).is_err(), "{bad:?}");
        }
        // Every cut of a valid header is an error, not a panic.
        for n in 0..meta.len() {
            assert!(declared(&meta[..n]).is_err());
        }
    }
}
