//! Splatting: photo texture sizes per cell, each footprint deposited into the texels it covers
//! by exact overlap area (alone or in strips of neighbouring pixels), per-texel sums of
//! colour, confidence and weight per photo; a photo pixel's weight (confidence, the
//! occlusion margin from the photo's occlusion map) and its colour transform.

pub(in crate::photo) mod accumulate;
pub(in crate::photo) mod colour_transform;
pub(in crate::photo) mod confidence;
pub(in crate::photo) mod occlusion;
pub(in crate::photo) mod samples;
pub(in crate::photo) mod sizing;
pub(in crate::photo) mod splat;
pub(in crate::photo) mod strip;
pub(in crate::photo) mod texel_tiles;
