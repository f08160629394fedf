//! The font of cliffmap's images (histogram labels, comparison captions): DejaVu Sans
//! (Bitstream Vera licence, see assets/fonts/LICENSE-DejaVu.txt), embedded so that images
//! render the same everywhere, registered with `plotters` as "sans-serif".

use std::sync::OnceLock;

use plotters::style::FontStyle;

/// The embedded TrueType font.
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font as plotters' "sans-serif" (once per process).
pub(crate) fn register_font() -> std::result::Result<(), String> {
    static REGISTERED: OnceLock<std::result::Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font("sans-serif", FontStyle::Normal, FONT)
                .map_err(|_| "the embedded DejaVu Sans font is invalid".to_string())
        })
        .clone()
}
