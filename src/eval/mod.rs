//! Evaluation around images: error metrics against a reference, exact merging of renders
//! of disjoint sample ranges, the checkpointed reference render loop, and the method
//! comparison with its report (JSON, CSV, plots, image grid, HTML). Rendering itself is
//! behind traits ([`compare::MethodRunner`], [`reference::SampleRenderer`]) that the
//! renderer implements, so everything here runs and is tested without a GPU.

pub mod compare;
pub mod compare_types;
pub mod fonts;
pub mod grid;
pub mod html;
pub mod merge;
pub mod metrics;
pub mod plot;
pub mod reference;
pub mod report;
pub mod text;

/// The error type renderer implementations of this module's traits return.
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;
