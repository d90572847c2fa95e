//! The one font figures are drawn with: DejaVu Sans, embedded in the binary
//! (`assets/fonts/`, Bitstream Vera licence, which permits redistribution) and registered
//! with plotters' ab_glyph text renderer as `sans-serif`, so figures never depend on the
//! fonts of the machine they are made on.

use std::sync::OnceLock;

pub(crate) static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The family name to use in text styles.
pub const FAMILY: &str = "sans-serif";

/// Registers the embedded font once; later calls are free.
pub fn ensure_registered() {
    static DONE: OnceLock<()> = OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, DEJAVU_SANS)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans font does not parse"));
    });
}
