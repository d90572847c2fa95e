//! lanterna — a GPU path tracer for scenes lit by many lights.
//!
//! The crate is organised the way the renderers it learns from are: `vk` is a thin RAII
//! layer over Vulkan that knows nothing about rendering; `scene` loads glTF into flat,
//! GPU-ready arrays; `lights` builds the light table and the source distributions NEE
//! samples from; `guiding` holds the SD-tree that is refit on the CPU between passes;
//! `render` owns the GPU resources of one scene and runs the path-tracing kernel;
//! `image_io` and `eval` write images and measure error against references. With the
//! `python` feature, `python` is the extension module behind `import lanterna`.

pub mod bench;
pub mod eval;
pub mod files;
pub mod gpu;
pub mod guiding;
pub mod image_io;
pub mod lights;
#[cfg(feature = "python")]
pub mod python;
pub mod render;
pub mod scene;
pub mod shaders;
pub mod stats;
pub mod testing;
pub mod vk;
