//! Merging renders of disjoint sample ranges of the same scene and settings into one
//! image. When every input carries the film's exact sums the merge adds them, so the
//! result is bit-identical to one render of the union of the ranges; otherwise it falls
//! back to the spp-weighted mean and says so in the warnings. Inputs that cannot belong
//! to one render (another scene, resolution, method, seed, depth, or overlapping sample
//! ranges) are refused with an error naming both files.

use std::ops::Range;

use crate::image_io::{format_ranges, Aov, Image, RenderMeta, SAMPLE_RANGES_KEY, VERSION};

#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    #[error("nothing to merge: give at least two images")]
    TooFew,
    #[error("cannot merge {a} and {b}: different {field} ({a_value} vs {b_value})")]
    Mismatch {
        field: &'static str,
        a: String,
        a_value: String,
        b: String,
        b_value: String,
    },
    #[error("cannot merge {file}: its sample count (lanterna.spp) is unknown")]
    MissingSpp { file: String },
    #[error(
        "cannot merge {a} and {b}: their sample ranges overlap ({a_range} and {b_range}); \
         render disjoint ranges with --sample-offset"
    )]
    Overlap {
        a: String,
        a_range: String,
        b: String,
        b_range: String,
    },
    #[error("cannot merge: the film sums overflow 64 bits at pixel ({x}, {y})")]
    Overflow { x: u32, y: u32 },
    #[error("cannot merge: total spp overflows")]
    SppOverflow,
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
}

/// The merged image, whether it is exact, and what the caller should warn about.
#[derive(Debug)]
pub struct Merged {
    pub image: Image,
    /// True when the pixels came from adding exact film sums.
    pub exact: bool,
    pub warnings: Vec<String>,
}

fn show<T: std::fmt::Debug>(v: &Option<T>) -> String {
    match v {
        Some(v) => format!("{v:?}"),
        None => "none".to_string(),
    }
}

/// Merges `(name, image)` pairs; names are used in messages (file paths, usually).
pub fn merge(inputs: &[(&str, &Image)]) -> Result<Merged, MergeError> {
    if inputs.len() < 2 {
        return Err(MergeError::TooFew);
    }
    let (first_name, first) = inputs[0];
    let mut warnings = Vec::new();

    // Everything that makes renders belong to one estimator must agree.
    for &(name, image) in &inputs[1..] {
        let mismatch = |field, a_value: String, b_value: String| MergeError::Mismatch {
            field,
            a: first_name.to_string(),
            a_value,
            b: name.to_string(),
            b_value,
        };
        if (image.width, image.height) != (first.width, first.height) {
            return Err(mismatch(
                "resolution",
                format!("{}x{}", first.width, first.height),
                format!("{}x{}", image.width, image.height),
            ));
        }
        let (m, f) = (&image.meta, &first.meta);
        if m.scene_hash != f.scene_hash {
            return Err(mismatch(
                "scene (hash)",
                show(&f.scene_hash),
                show(&m.scene_hash),
            ));
        }
        if m.method != f.method {
            return Err(mismatch("method", show(&f.method), show(&m.method)));
        }
        if m.seed != f.seed {
            return Err(mismatch("seed", show(&f.seed), show(&m.seed)));
        }
        if m.max_depth != f.max_depth {
            return Err(mismatch(
                "max_depth",
                show(&f.max_depth),
                show(&m.max_depth),
            ));
        }
    }
    if first.meta.scene_hash.is_none() {
        warnings
            .push("the inputs carry no scene hash: cannot check they show the same scene".into());
    }

    // Sample ranges must be pairwise disjoint.
    let mut ranges: Vec<(Range<u64>, usize)> = Vec::new();
    for (i, &(name, image)) in inputs.iter().enumerate() {
        let own = image
            .meta
            .sample_ranges()
            .ok_or_else(|| MergeError::MissingSpp {
                file: name.to_string(),
            })?;
        for r in own {
            if let Some((other, j)) = ranges
                .iter()
                .find(|(o, _)| o.start < r.end && r.start < o.end)
            {
                return Err(MergeError::Overlap {
                    a: inputs[*j].0.to_string(),
                    a_range: format!("samples {}..{}", other.start, other.end),
                    b: name.to_string(),
                    b_range: format!("samples {}..{}", r.start, r.end),
                });
            }
            ranges.push((r, i));
        }
    }
    let mut union: Vec<Range<u64>> = ranges.into_iter().map(|(r, _)| r).collect();
    union.sort_by_key(|r| r.start);
    let mut coalesced: Vec<Range<u64>> = Vec::new();
    for r in union {
        match coalesced.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => coalesced.push(r),
        }
    }
    let total_spp = coalesced
        .iter()
        .try_fold(0u64, |acc, r| acc.checked_add(r.end - r.start))
        .ok_or(MergeError::SppOverflow)?;

    let meta = merged_meta(inputs, &coalesced, total_spp, &mut warnings);
    let (w, h) = (first.width, first.height);
    let n = first.pixel_count();

    let without_sums: Vec<&str> = inputs
        .iter()
        .filter(|(_, i)| i.sums.is_none())
        .map(|(n, _)| *n)
        .collect();
    let spp_of = |image: &Image| {
        image
            .meta
            .sample_ranges()
            .unwrap()
            .iter()
            .map(|r| r.end - r.start)
            .sum::<u64>()
    };
    let (mut image, exact) = if without_sums.is_empty() {
        let mut sums = vec![[0u64; 3]; n];
        for (_, image) in inputs {
            let theirs = image.sums.as_ref().expect("checked above");
            for (i, (acc, s)) in sums.iter_mut().zip(theirs).enumerate() {
                for c in 0..3 {
                    acc[c] = acc[c].checked_add(s[c]).ok_or(MergeError::Overflow {
                        x: (i % w as usize) as u32,
                        y: (i / w as usize) as u32,
                    })?;
                }
            }
        }
        (Image::from_sums(w, h, sums, meta)?, true)
    } else {
        warnings.push(format!(
            "{} carr{} no exact film sums: merged by spp-weighted means, not bit-exact",
            without_sums.join(", "),
            if without_sums.len() == 1 { "ies" } else { "y" }
        ));
        let mut acc = vec![[0f64; 3]; n];
        for (_, image) in inputs {
            let weight = spp_of(image) as f64 / total_spp as f64;
            for (a, p) in acc.iter_mut().zip(&image.rgb) {
                for c in 0..3 {
                    a[c] += weight * f64::from(p[c]);
                }
            }
        }
        let rgb = acc.into_iter().map(|a| a.map(|v| v as f32)).collect();
        let mut image = Image::new(w, h, rgb)?;
        image.meta = meta;
        (image, false)
    };

    image.aovs = merged_aovs(inputs, total_spp, &mut warnings, spp_of);
    image.check_shape()?;
    Ok(Merged {
        image,
        exact,
        warnings,
    })
}

fn merged_meta(
    inputs: &[(&str, &Image)],
    coalesced: &[Range<u64>],
    total_spp: u64,
    warnings: &mut Vec<String>,
) -> RenderMeta {
    let metas: Vec<&RenderMeta> = inputs.iter().map(|(_, i)| &i.meta).collect();
    let f = metas[0];
    let mut meta = RenderMeta {
        spp: Some(total_spp),
        sample_offset: Some(coalesced[0].start),
        method: f.method.clone(),
        seed: f.seed,
        max_depth: f.max_depth,
        render_seconds: metas.iter().map(|m| m.render_seconds).sum::<Option<f64>>(),
        device: None,
        scene_path: f.scene_path.clone(),
        scene_hash: f.scene_hash.clone(),
        version: Some(VERSION.to_string()),
        extra: Default::default(),
    };
    let mut devices: Vec<&str> = Vec::new();
    for d in metas.iter().filter_map(|m| m.device.as_deref()) {
        if !devices.contains(&d) {
            devices.push(d);
        }
    }
    if !devices.is_empty() {
        meta.device = Some(devices.join(" + "));
    }
    // Free-form keys survive when every input agrees on them.
    for (k, v) in &f.extra {
        if k != SAMPLE_RANGES_KEY && metas.iter().all(|m| m.extra.get(k) == Some(v)) {
            meta.extra.insert(k.clone(), v.clone());
        }
    }
    if coalesced.len() > 1 {
        let text = format_ranges(coalesced);
        warnings.push(format!(
            "the merged sample ranges are not contiguous ({text}); recorded as {SAMPLE_RANGES_KEY}"
        ));
        meta.extra.insert(SAMPLE_RANGES_KEY.to_string(), text);
    }
    meta
}

/// AOVs present with the same layout in every input are averaged by spp; others are dropped.
fn merged_aovs(
    inputs: &[(&str, &Image)],
    total_spp: u64,
    warnings: &mut Vec<String>,
    spp_of: impl Fn(&Image) -> u64,
) -> Vec<Aov> {
    let mut out = Vec::new();
    let mut dropped = Vec::new();
    for aov in &inputs[0].1.aovs {
        let matching: Option<Vec<&Aov>> = inputs
            .iter()
            .map(|(_, i)| {
                i.aovs
                    .iter()
                    .find(|a| a.name == aov.name && a.channels == aov.channels)
            })
            .collect();
        let Some(matching) = matching else {
            dropped.push(aov.name.clone());
            continue;
        };
        let mut acc = vec![0f64; aov.data.len()];
        for (a, (_, image)) in matching.iter().zip(inputs) {
            let weight = spp_of(image) as f64 / total_spp as f64;
            for (s, v) in acc.iter_mut().zip(&a.data) {
                *s += weight * f64::from(*v);
            }
        }
        out.push(Aov {
            name: aov.name.clone(),
            channels: aov.channels.clone(),
            data: acc.into_iter().map(|v| v as f32).collect(),
        });
    }
    for (_, image) in &inputs[1..] {
        for aov in &image.aovs {
            if !out.iter().any(|a| a.name == aov.name) && !dropped.contains(&aov.name) {
                dropped.push(aov.name.clone());
            }
        }
    }
    if !dropped.is_empty() {
        warnings.push(format!(
            "AOV layer(s) {} are not in every input with the same channels: dropped",
            dropped.join(", ")
        ));
    }
    out
}
