//! Scene generators (placeholder).
