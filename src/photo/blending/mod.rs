//! Blending: the photos of a cell merged per texel, then blended with the existing texture;
//! photo colour carried into the gutter beside it.

pub(in crate::photo) mod blend;
pub(in crate::photo) mod cell_accum;
pub(in crate::photo) mod gutter;
