//! Colour leveling: a per-photo colour transform (`ColourTransform`) fitted towards the
//! existing texture.

pub(in crate::photo) mod colour_leveling;
