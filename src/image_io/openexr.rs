//! OpenEXR reading and writing of [`Image`]s, in the layout the module comment of
//! `image_io` describes.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use ::exr::meta::attribute::TextBytes;
use ::exr::prelude as x;
use ::exr::prelude::traits::{ReadChannels, ReadLayers, WritableImage};

use super::*;

const ATTR_PREFIX: &str = "lanterna.";
const KV_PREFIX: &str = "lanterna.kv.";

fn text(s: &str) -> x::Text {
    // EXR text is a byte string; OpenEXR treats it as UTF-8, and so do we.
    x::Text::from_bytes_unchecked(s.as_bytes().iter().copied().collect::<TextBytes>())
}

fn untext(t: &x::Text) -> String {
    String::from_utf8_lossy(t.bytes()).into_owned()
}

/// Writes an image as described in the module comment. Non-finite values are written as
/// they are and reported in the summary (and logged as a warning).
pub fn write_exr(path: &Path, image: &Image) -> Result<WriteSummary, ImageError> {
    image.check_shape()?;
    let summary = summarize(image, path);
    let n = image.pixel_count();
    let mut channels: Vec<x::AnyChannel<x::FlatSamples>> = Vec::new();
    for c in 0..3 {
        let values = image.rgb.iter().map(|p| p[c]).collect();
        channels.push(x::AnyChannel::new(
            ["R", "G", "B"][c],
            x::FlatSamples::F32(values),
        ));
    }
    if let Some(sums) = &image.sums {
        for c in 0..3 {
            let hi = sums.iter().map(|s| (s[c] >> 32) as u32).collect();
            let lo = sums.iter().map(|s| s[c] as u32).collect();
            let cname = ["R", "G", "B"][c];
            channels.push(x::AnyChannel::new(
                format!("{SUM_HI}.{cname}").as_str(),
                x::FlatSamples::U32(hi),
            ));
            channels.push(x::AnyChannel::new(
                format!("{SUM_LO}.{cname}").as_str(),
                x::FlatSamples::U32(lo),
            ));
        }
    }
    for aov in &image.aovs {
        let k = aov.channels.len();
        for (c, cname) in aov.channels.iter().enumerate() {
            let values = (0..n).map(|i| aov.data[i * k + c]).collect();
            channels.push(x::AnyChannel::new(
                format!("{}.{cname}", aov.name).as_str(),
                x::FlatSamples::F32(values),
            ));
        }
    }

    let mut attrs = x::LayerAttributes::default();
    let mut put = |key: &str, value: x::AttributeValue| {
        attrs
            .other
            .insert(text(&format!("{ATTR_PREFIX}{key}")), value);
    };
    let m = &image.meta;
    let t = |s: &str| x::AttributeValue::Text(text(s));
    if let Some(v) = m.spp {
        put("spp", t(&v.to_string()));
    }
    if let Some(v) = m.sample_offset {
        put("sample_offset", t(&v.to_string()));
    }
    if let Some(v) = &m.method {
        put("method", t(v));
    }
    if let Some(v) = m.seed {
        put("seed", t(&v.to_string()));
    }
    if let Some(v) = m.max_depth {
        put("max_depth", t(&v.to_string()));
    }
    if let Some(v) = m.render_seconds {
        put("render_seconds", x::AttributeValue::F64(v));
    }
    if let Some(v) = &m.device {
        put("device", t(v));
    }
    if let Some(v) = &m.scene_path {
        put("scene_path", t(v));
    }
    if let Some(v) = &m.scene_hash {
        put("scene_hash", t(v));
    }
    if let Some(v) = &m.version {
        put("version", t(v));
    }
    put(
        "resolution",
        t(&format!("{}x{}", image.width, image.height)),
    );
    if image.sums.is_some() {
        put("film_scale", x::AttributeValue::F64(FILM_SCALE));
    }
    if !image.aovs.is_empty() {
        let layout: Vec<String> = image
            .aovs
            .iter()
            .map(|a| format!("{}:{}", a.name, a.channels.join(",")))
            .collect();
        put("aovs", t(&layout.join(";")));
    }
    for (k, v) in &m.extra {
        attrs.other.insert(text(&format!("{KV_PREFIX}{k}")), t(v));
    }

    let encoding = x::Encoding {
        compression: x::Compression::ZIP16,
        blocks: x::Blocks::ScanLines,
        line_order: x::LineOrder::Increasing,
    };
    let size = (image.width as usize, image.height as usize);
    let channels = x::AnyChannels::sort(channels.into_iter().collect());
    let exr_image = x::Image::from_layer(x::Layer::new(size, attrs, encoding, channels));
    let mut bytes = Cursor::new(Vec::new());
    exr_image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| ImageError::Invalid {
            path: path.to_path_buf(),
            problem: format!("EXR encoding: {e}"),
        })?;
    write_atomically(path, bytes.get_ref())?;
    Ok(summary)
}

/// Reads an EXR written by [`write_exr`] or any flat RGB(A) OpenEXR file (f16/f32/u32
/// samples; of a multi-part file, the first part with `R`, `G`, `B`). Foreign files come
/// back with empty metadata and no sums.
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let pathbuf = path.to_path_buf();
    let invalid = |problem: String| ImageError::Invalid {
        path: pathbuf.clone(),
        problem,
    };
    use crate::files::{max_input_bytes, read_input, FileError, Start};
    let bytes = read_input(path, max_input_bytes(), &|start| {
        if start.len() < 4 || start[..4] != [0x76, 0x2f, 0x31, 0x01] {
            Err("no OpenEXR magic number".into())
        } else {
            Ok(Start::Continue)
        }
    })
    .map_err(|e| match e {
        FileError::NotFound { path } => ImageError::NotFound { path },
        FileError::Format { path, reason } => ImageError::NotExr { path, reason },
        e => ImageError::File(e),
    })?;
    let file = x::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(&bytes))
        .map_err(|e| ImageError::NotExr {
            path: pathbuf.clone(),
            reason: e.to_string(),
        })?;

    let has = |layer: &x::Layer<x::AnyChannels<x::FlatSamples>>, name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .any(|c| untext(&c.name) == name)
    };
    let Some(layer) = file
        .layer_data
        .iter()
        .find(|l| ["R", "G", "B"].iter().all(|c| has(l, c)))
    else {
        let first = file.layer_data.first();
        let present: Vec<String> = first
            .map(|l| {
                l.channel_data
                    .list
                    .iter()
                    .map(|c| untext(&c.name))
                    .collect()
            })
            .unwrap_or_default();
        let missing: Vec<&str> = ["R", "G", "B"]
            .into_iter()
            .filter(|c| first.is_none_or(|l| !has(l, c)))
            .collect();
        return Err(ImageError::MissingChannels {
            path: pathbuf.clone(),
            missing: missing.join(", "),
            present: if present.is_empty() {
                "none".into()
            } else {
                present.join(", ")
            },
        });
    };
    let (width, height) = (layer.size.width(), layer.size.height());
    let n = width * height;

    // Attributes: lanterna writes them on the layer; accept image-level ones too.
    let mut attrs: BTreeMap<String, x::AttributeValue> = BTreeMap::new();
    for (k, v) in file
        .attributes
        .other
        .iter()
        .chain(layer.attributes.other.iter())
    {
        let k = untext(k);
        if k.starts_with(ATTR_PREFIX) {
            attrs.insert(k, v.clone());
        }
    }
    let get_text = |key: &str| -> Result<Option<String>, ImageError> {
        match attrs.get(&format!("{ATTR_PREFIX}{key}")) {
            None => Ok(None),
            Some(x::AttributeValue::Text(t)) => Ok(Some(untext(t))),
            Some(other) => Err(invalid(format!(
                "attribute {ATTR_PREFIX}{key} should be text, found {other:?}"
            ))),
        }
    };
    let get_int = |key: &str| -> Result<Option<u64>, ImageError> {
        get_text(key)?
            .map(|s| {
                s.parse::<u64>().map_err(|_| {
                    invalid(format!(
                        "attribute {ATTR_PREFIX}{key} = {s:?} is not an integer"
                    ))
                })
            })
            .transpose()
    };
    let get_f64 = |key: &str| -> Result<Option<f64>, ImageError> {
        match attrs.get(&format!("{ATTR_PREFIX}{key}")) {
            None => Ok(None),
            Some(x::AttributeValue::F64(v)) => Ok(Some(*v)),
            Some(x::AttributeValue::F32(v)) => Ok(Some(f64::from(*v))),
            Some(other) => Err(invalid(format!(
                "attribute {ATTR_PREFIX}{key} should be a double, found {other:?}"
            ))),
        }
    };
    let mut meta = RenderMeta {
        spp: get_int("spp")?,
        sample_offset: get_int("sample_offset")?,
        method: get_text("method")?,
        seed: get_int("seed")?,
        max_depth: get_int("max_depth")?
            .map(|d| u32::try_from(d).map_err(|_| invalid(format!("max_depth {d} too large"))))
            .transpose()?,
        render_seconds: get_f64("render_seconds")?,
        device: get_text("device")?,
        scene_path: get_text("scene_path")?,
        scene_hash: get_text("scene_hash")?,
        version: get_text("version")?,
        extra: BTreeMap::new(),
    };
    for (k, v) in &attrs {
        if let Some(key) = k.strip_prefix(KV_PREFIX) {
            match v {
                x::AttributeValue::Text(t) => {
                    meta.extra.insert(key.to_string(), untext(t));
                }
                other => return Err(invalid(format!("attribute {k} should be text: {other:?}"))),
            }
        }
    }
    if let Some(res) = get_text("resolution")? {
        if res != format!("{width}x{height}") {
            return Err(invalid(format!(
                "size mismatch: header says {res} but the pixels are {width}x{height}"
            )));
        }
    }

    let channel = |name: &str| {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| untext(&c.name) == name)
            .map(|c| &c.sample_data)
    };
    let floats = |name: &str| -> Result<Vec<f32>, ImageError> {
        let data = channel(name).expect("channel presence checked");
        if data.len() != n {
            return Err(invalid(format!(
                "channel {name} has {} samples, expected {n}",
                data.len()
            )));
        }
        Ok(data.values_as_f32().collect())
    };
    let (r, g, b) = (floats("R")?, floats("G")?, floats("B")?);
    let rgb: Vec<[f32; 3]> = (0..n).map(|i| [r[i], g[i], b[i]]).collect();

    // Film sums: all six channels, as u32, or none.
    let sum_names: Vec<String> = [SUM_HI, SUM_LO]
        .iter()
        .flat_map(|p| ["R", "G", "B"].map(|c| format!("{p}.{c}")))
        .collect();
    let present: Vec<&String> = sum_names.iter().filter(|s| channel(s).is_some()).collect();
    let mut sums = None;
    if !present.is_empty() {
        if present.len() != sum_names.len() {
            let missing: Vec<&str> = sum_names
                .iter()
                .filter(|s| channel(s).is_none())
                .map(String::as_str)
                .collect();
            return Err(ImageError::MissingChannels {
                path: pathbuf.clone(),
                missing: missing.join(", "),
                present: present
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        let u32s = |name: &str| -> Result<&Vec<u32>, ImageError> {
            match channel(name) {
                Some(x::FlatSamples::U32(ref v)) if v.len() == n => Ok(v),
                _ => Err(invalid(format!("channel {name} must hold {n} u32 samples"))),
            }
        };
        let scale = get_f64("film_scale")?;
        if scale != Some(FILM_SCALE) {
            return Err(invalid(format!(
                "film sums have scale {scale:?}, this lanterna uses {FILM_SCALE}"
            )));
        }
        if !matches!(meta.spp, Some(s) if s > 0) {
            return Err(invalid(
                "film sums present but lanterna.spp is missing or 0".into(),
            ));
        }
        let mut s = vec![[0u64; 3]; n];
        for c in 0..3 {
            let cname = ["R", "G", "B"][c];
            let hi = u32s(&format!("{SUM_HI}.{cname}"))?;
            let lo = u32s(&format!("{SUM_LO}.{cname}"))?;
            for i in 0..n {
                s[i][c] = (u64::from(hi[i]) << 32) | u64::from(lo[i]);
            }
        }
        sums = Some(s);
    }

    // AOVs: from the recorded layout, else by grouping `layer.channel` names.
    let mut aov_layout: Vec<(String, Vec<String>)> = Vec::new();
    if let Some(layout) = get_text("aovs")? {
        for entry in layout.split(';').filter(|e| !e.is_empty()) {
            let (name, chans) = entry
                .split_once(':')
                .ok_or_else(|| invalid(format!("malformed lanterna.aovs entry {entry:?}")))?;
            aov_layout.push((
                name.to_string(),
                chans.split(',').map(str::to_string).collect(),
            ));
        }
    } else {
        let order = ["R", "G", "B", "A", "X", "Y", "Z", "W", "U", "V"];
        let mut groups: BTreeMap<String, Vec<String>> = BTreeMap::new();
        for c in &layer.channel_data.list {
            let full = untext(&c.name);
            if let Some((prefix, chan)) = full.rsplit_once('.') {
                if prefix != SUM_HI && prefix != SUM_LO && !prefix.contains('.') {
                    groups
                        .entry(prefix.to_string())
                        .or_default()
                        .push(chan.to_string());
                }
            }
        }
        for (name, mut chans) in groups {
            if chans.len() > 4 {
                log::debug!(
                    "{}: skipping layer {name} with {} channels",
                    path.display(),
                    chans.len()
                );
                continue;
            }
            chans.sort_by_key(|c| (order.iter().position(|o| o == c).unwrap_or(99), c.clone()));
            aov_layout.push((name, chans));
        }
    }
    let mut aovs = Vec::new();
    for (name, chans) in aov_layout {
        let k = chans.len();
        let mut data = vec![0f32; n * k];
        for (c, cname) in chans.iter().enumerate() {
            let full = format!("{name}.{cname}");
            if channel(&full).is_none() {
                return Err(ImageError::MissingChannels {
                    path: pathbuf.clone(),
                    missing: full,
                    present: "see lanterna.aovs".into(),
                });
            }
            for (i, v) in floats(&full)?.into_iter().enumerate() {
                data[i * k + c] = v;
            }
        }
        let refs: Vec<&str> = chans.iter().map(String::as_str).collect();
        let aov = Aov::new(&name, &refs, data).map_err(|e| invalid(e.to_string()))?;
        aovs.push(aov);
    }

    let image = Image {
        width: width as u32,
        height: height as u32,
        rgb,
        sums,
        meta,
        aovs,
    };
    image.check_shape().map_err(|e| invalid(e.to_string()))?;
    Ok(image)
}
