//! Photo inputs: photo lists (`photos.json`), COLMAP text models, and the per-level image pyramid of each photo.

pub(in crate::photo) mod colmap;
pub(in crate::photo) mod input;
pub(in crate::photo) mod pyramid;
