//! Photo inputs: photo lists (`photos.json`), COLMAP text models, the per-level image pyramid
//! of each photo, and which of its pixels to use (masks).

pub(in crate::photo) mod colmap;
pub(in crate::photo) mod input;
pub(in crate::photo) mod mask;
pub(in crate::photo) mod pyramid;
