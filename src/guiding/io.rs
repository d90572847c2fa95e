//! Saving a trained SD-tree and loading it to render without training
//! (`--save-guiding` / `--load-guiding`). The file is versioned and self-checking: a
//! magic string, the format version, the hash of the scene it was trained on, the
//! options, then the GPU arrays (shared/guiding.h) as little-endian 32-bit words, and an
//! FNV-1a checksum of everything before it. Loading refuses, with an error naming the
//! file, anything that is not such a file, another version, a corrupt file, or a tree
//! trained on another scene. Files are written to a temporary name and renamed.
//!
//! Format version 4, all integers little-endian:
//! `magic[16] version:u32 scene_hash:u64 iterations:u32 bbox_min:f32×3 bbox_max:f32×3`
//! `spatial_threshold:f32 rho:f32 max_quad_depth:u32 max_spatial_depth:u32`
//! `memory_cap:u64 spatial_filter:u32 directional_filter:u32 record_nee:u32`
//! `bsdf_fraction:f32 learn_lights:u32 light_mix:f32 learn_light_mix:u32`
//! `n_spatial:u32 n_leaves:u32 n_sampling:u32 n_training:u32 n_lights:u32`
//! `GuideHeader GuideSpatialNode[n_spatial] GuideLeaf[n_leaves]`
//! `GuideQuadNode[n_sampling] GuideQuadNode[n_training] GuideLightSlot[n_lights] checksum:u64`
//! (version 2 added the learned light tables, version 3 the learned BSDF selection
//! probability of each leaf, `GuideLeaf.bsdf_fraction`, version 4 each leaf's light mix,
//! `GuideLeaf.light_mix`, in place of the header's).

use super::flat::GuideArrays;
use super::{DirectionalFilter, GuidingConfig, GuidingError, SdTree, SpatialFilter};
use crate::gpu::{GuideHeader, GuideLeaf, GuideLightSlot, GuideQuadNode, GuideSpatialNode};
use std::path::Path;

const MAGIC: &[u8; 16] = b"lanterna-sdtree\0";
/// The SD-tree file format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 4;

/// FNV-1a, 64 bit: the file checksum, and a scene hash the renderer can feed with the
/// scene's geometry and materials (`--load-guiding` refuses a tree from another scene).
#[derive(Clone, Debug)]
pub struct SceneHasher(u64);

impl Default for SceneHasher {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl SceneHasher {
    pub fn update(&mut self, bytes: &[u8]) -> &mut Self {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self
    }

    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// The number a saved tree stores for a scene's content hash (the scene's hex string).
pub fn scene_hash_number(hex: &str) -> u64 {
    u64::from_str_radix(hex, 16).unwrap_or(0)
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.u32(v.to_bits());
    }
    /// Pod structs of 32-bit members, word by word in little-endian.
    fn words<T: bytemuck::Pod>(&mut self, items: &[T]) {
        for w in bytemuck::cast_slice::<T, u32>(items) {
            self.u32(*w);
        }
    }
}

struct Reader<'a> {
    data: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.data.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
    fn words<T: bytemuck::Pod>(&mut self, count: u32) -> Option<Vec<T>> {
        let words_per = std::mem::size_of::<T>() / 4;
        let bytes = self.take((count as usize).checked_mul(words_per * 4)?)?;
        let words: Vec<u32> = bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        Some(bytemuck::cast_slice::<u32, T>(&words).to_vec())
    }
}

/// What an SD-tree file says about itself (for `info`-style reporting).
#[derive(Clone, Debug, PartialEq)]
pub struct SavedTreeInfo {
    pub scene_hash: u64,
    pub bbox_min: [f32; 3],
    pub bbox_max: [f32; 3],
    pub iterations: u32,
}

impl SdTree {
    /// Write the tree to `path` (temporary file + rename). `scene_hash` identifies the
    /// scene (see `SceneHasher`, checked on load); `bbox` is the scene's bounding box,
    /// stored for information.
    pub fn save(
        &self,
        path: &Path,
        scene_hash: u64,
        bbox: ([f32; 3], [f32; 3]),
    ) -> Result<(), GuidingError> {
        let arrays = self.gpu_arrays();
        let c = &self.config;
        let mut w = Writer(Vec::with_capacity(arrays.byte_size() as usize + 256));
        w.0.extend_from_slice(MAGIC);
        w.u32(FORMAT_VERSION);
        w.u64(scene_hash);
        w.u32(self.iterations);
        for v in bbox.0.iter().chain(&bbox.1) {
            w.f32(*v);
        }
        w.f32(c.spatial_threshold);
        w.f32(c.rho);
        w.u32(c.max_quad_depth);
        w.u32(c.max_spatial_depth);
        w.u64(c.memory_cap_bytes);
        w.u32(match c.spatial_filter {
            SpatialFilter::Nearest => 0,
            SpatialFilter::StochasticBox => 1,
        });
        w.u32(match c.directional_filter {
            DirectionalFilter::Nearest => 0,
            DirectionalFilter::Box => 1,
        });
        w.u32(u32::from(c.record_nee));
        w.f32(c.bsdf_fraction);
        w.u32(u32::from(c.learn_lights));
        w.f32(c.light_mix);
        w.u32(u32::from(c.learn_light_mix));
        w.u32(arrays.spatial.len() as u32);
        w.u32(arrays.leaves.len() as u32);
        w.u32(arrays.sampling.len() as u32);
        w.u32(arrays.training.len() as u32);
        w.u32(arrays.lights.len() as u32);
        w.words(std::slice::from_ref(&arrays.header));
        w.words(&arrays.spatial);
        w.words(&arrays.leaves);
        w.words(&arrays.sampling);
        w.words(&arrays.training);
        w.words(&arrays.lights);
        let sum = SceneHasher::default().update(&w.0).finish();
        w.u64(sum);

        crate::files::write_atomically(path, &w.0)?;
        Ok(())
    }

    /// Read a tree saved by `save`, refusing one trained on another scene. The file's
    /// options become the tree's (replace the render-time ones with `set_config`).
    pub fn load(path: &Path, expected_scene_hash: u64) -> Result<SdTree, GuidingError> {
        let data = read_tree_file(path)?;
        let (tree, info) = parse(path, &data)?;
        if info.scene_hash != expected_scene_hash {
            return Err(GuidingError::SceneMismatch {
                path: path.to_path_buf(),
                found: info.scene_hash,
                expected: expected_scene_hash,
            });
        }
        Ok(tree)
    }

    /// Read a tree and what it says about itself, without checking the scene.
    pub fn load_unchecked(path: &Path) -> Result<(SdTree, SavedTreeInfo), GuidingError> {
        let data = read_tree_file(path)?;
        parse(path, &data)
    }
}

/// The file's bytes, refusing early what does not start like an SD-tree file (and, like
/// every input, anything larger than the input limit).
fn read_tree_file(path: &Path) -> Result<Vec<u8>, GuidingError> {
    use crate::files::{max_input_bytes, read_input, FileError, Start};
    read_input(path, max_input_bytes(), &|start| {
        if start.len() >= MAGIC.len() && &start[..MAGIC.len()] != MAGIC {
            Err("not a lanterna SD-tree file".into())
        } else {
            Ok(Start::Continue)
        }
    })
    .map_err(|e| match e {
        FileError::Format { path, .. } => GuidingError::NotAnSdTree { path },
        e => GuidingError::File(e),
    })
}

fn parse(path: &Path, data: &[u8]) -> Result<(SdTree, SavedTreeInfo), GuidingError> {
    let corrupt = |what: &str| GuidingError::Corrupt {
        path: path.to_path_buf(),
        what: what.to_string(),
    };
    if data.len() < MAGIC.len() + 4 || &data[..MAGIC.len()] != MAGIC {
        return Err(GuidingError::NotAnSdTree {
            path: path.to_path_buf(),
        });
    }
    let mut r = Reader {
        data,
        at: MAGIC.len(),
    };
    let version = r.u32().ok_or_else(|| corrupt("truncated"))?;
    if version != FORMAT_VERSION {
        return Err(GuidingError::Version {
            path: path.to_path_buf(),
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    if data.len() < r.at + 8 {
        return Err(corrupt("truncated"));
    }
    let (body, tail) = data.split_at(data.len() - 8);
    if SceneHasher::default().update(body).finish() != u64::from_le_bytes(tail.try_into().unwrap())
    {
        return Err(corrupt("checksum mismatch (truncated or modified)"));
    }
    let mut r = Reader {
        data: body,
        at: r.at,
    };
    let read = |r: &mut Reader| -> Option<(SavedTreeInfo, GuidingConfig, GuideArrays)> {
        let scene_hash = r.u64()?;
        let iterations = r.u32()?;
        let mut b = [0f32; 6];
        for v in &mut b {
            *v = r.f32()?;
        }
        let mut config = GuidingConfig {
            spatial_threshold: r.f32()?,
            rho: r.f32()?,
            max_quad_depth: r.u32()?,
            max_spatial_depth: r.u32()?,
            memory_cap_bytes: r.u64()?,
            spatial_filter: match r.u32()? {
                0 => SpatialFilter::Nearest,
                1 => SpatialFilter::StochasticBox,
                _ => return None,
            },
            directional_filter: match r.u32()? {
                0 => DirectionalFilter::Nearest,
                1 => DirectionalFilter::Box,
                _ => return None,
            },
            record_nee: r.u32()? != 0,
            bsdf_fraction: r.f32()?,
            learn_lights: r.u32()? != 0,
            light_mix: r.f32()?,
            learn_light_mix: r.u32()? != 0,
            ..GuidingConfig::default()
        };
        let counts = [r.u32()?, r.u32()?, r.u32()?, r.u32()?, r.u32()?];
        let header = r.words::<GuideHeader>(1)?[0];
        // The learned options live in the header's flags (the per-leaf fractions in
        // the leaves).
        config.learn_selection = header.flags & crate::gpu::GUIDE_FLAG_LEARN_SELECTION != 0;
        config.target = if header.flags & crate::gpu::GUIDE_FLAG_TARGET_INDIRECT != 0 {
            super::GuideTarget::Indirect
        } else if header.flags & crate::gpu::GUIDE_FLAG_TARGET_CONTRIBUTION != 0 {
            super::GuideTarget::Contribution
        } else {
            super::GuideTarget::All
        };
        config.density = if header.flags & crate::gpu::GUIDE_FLAG_SECOND_MOMENT != 0 {
            super::GuideDensity::VarianceAware
        } else {
            super::GuideDensity::Radiance
        };
        let arrays = GuideArrays {
            header,
            spatial: r.words::<GuideSpatialNode>(counts[0])?,
            leaves: r.words::<GuideLeaf>(counts[1])?,
            sampling: r.words::<GuideQuadNode>(counts[2])?,
            training: r.words::<GuideQuadNode>(counts[3])?,
            lights: r.words::<GuideLightSlot>(counts[4])?,
            light_training: Vec::new(),
        };

        let info = SavedTreeInfo {
            scene_hash,
            bbox_min: [b[0], b[1], b[2]],
            bbox_max: [b[3], b[4], b[5]],
            iterations,
        };
        Some((info, config, arrays))
    };
    let (info, config, arrays) =
        read(&mut r).ok_or_else(|| corrupt("truncated or bad option values"))?;
    if r.at != body.len() {
        return Err(corrupt("trailing bytes"));
    }
    let mut tree =
        SdTree::from_gpu_arrays(&arrays, &config).map_err(|e| corrupt(&e.to_string()))?;
    tree.iterations = info.iterations;
    Ok((tree, info))
}
