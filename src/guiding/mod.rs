//! SD-tree path guiding (Müller, Gross, Novák 2017, "Practical Path Guiding"), the CPU
//! half: the tree itself (`SdTree`: a spatial binary tree whose leaves own directional
//! quadtrees on the square ((cosθ+1)/2, φ/2π)), the refit between training iterations,
//! the flat arrays the kernels read (`GuideArrays`, layout in
//! shaders_glsl/shared/guiding.h; the GPU half is shaders_glsl/inc/guiding.glsl), the
//! training schedule, saving/loading trained trees, a debug view of one leaf, the
//! statistics the sampling tests use, and the checks of the guiding test kernels
//! (`kernel_checks`, run on the CPU mirror here and on the device by the GPU test).
//!
//! A render with guiding goes: `SdTree::new(bbox)`; then per training iteration upload
//! `gpu_arrays()`, render 2^k spp (the kernel samples the sampling trees and records
//! into the training buffer), read the training buffer back into
//! `load_training_readback`, and `refit(next_spp)`; finally render the rest with the
//! last sampling trees.

mod chi2;
mod config;
mod flat;
mod io;
pub mod kernel_checks;
mod light_mix;
mod parallel;
mod probe;
mod quadtree;
mod refit;
mod schedule;
mod sdtree;
mod selection;
mod sphere;
mod view;

pub use chi2::{
    bin_probabilities, check_guide_samples, chi2_directions, chi2_grid, chi2_leaf_cells,
    chi2_survival, chi2_test, square_histogram, Chi2, GuideSample, SampleCheck, CHI2_SIGNIFICANCE,
};
pub use config::{
    DirectionalFilter, GuideDensity, GuideTarget, GuidingConfig, SelectionLearner, SpatialFilter,
    DEFAULT_MEMORY_CAP_BYTES, MAX_LIGHT_MIX,
};
pub use flat::{light_alias_sample, light_hash_lookup, GuideArrays, GUIDE_BUFFERS};
pub use io::{scene_hash_number, SavedTreeInfo, SceneHasher, FORMAT_VERSION};
pub use light_mix::{LightSums, MAX_LEARNED_MIX};
pub use quadtree::{Cell, QuadNode, QuadTree};
pub use refit::RefitStats;
pub use schedule::{SppSchedule, TimeSchedule, DEFAULT_TRAIN_FRACTION};
pub use sdtree::{Leaf, SdTree};
pub use selection::{SelectionState, SelectionStats, RECORD_CAPACITY as SELECTION_RECORD_CAPACITY};
pub use sphere::{dir_to_square, square_to_dir, INV_4PI};
pub use view::{density_grid, draw_quadtree, LeafInfo, LeafView};

use std::path::PathBuf;

/// Errors of the guiding module.
#[derive(Debug, thiserror::Error)]
pub enum GuidingError {
    #[error("invalid guiding option: {0}")]
    Config(String),
    #[error("scene bounds {min:?} .. {max:?} cannot hold an SD-tree (empty or not finite)")]
    BadBounds { min: [f32; 3], max: [f32; 3] },
    #[error("the training buffer read back does not match the SD-tree: {0}")]
    TrainingMismatch(String),
    #[error("invalid SD-tree arrays: {0}")]
    BadArrays(String),
    #[error(transparent)]
    File(#[from] crate::files::FileError),
    #[error("{}: not a lanterna SD-tree file", path.display())]
    NotAnSdTree { path: PathBuf },
    #[error("{}: SD-tree file format version {found}; this build reads version {supported}", path.display())]
    Version {
        path: PathBuf,
        found: u32,
        supported: u32,
    },
    #[error("{}: corrupt SD-tree file: {what}", path.display())]
    Corrupt { path: PathBuf, what: String },
    #[error(
        "{}: this SD-tree was trained on another scene (its scene hash is {found:016x}, \
         this scene's is {expected:016x}); train again or load the matching scene",
        path.display()
    )]
    SceneMismatch {
        path: PathBuf,
        found: u64,
        expected: u64,
    },
}
