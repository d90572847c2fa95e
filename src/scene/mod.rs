//! Scenes: glTF loading into flat, GPU-ready arrays, and the generators of test scenes.

pub mod generate;
