//! Photos registered to photos: patch matches between two photos, the rotation consensus
//! that keeps the static ones, and ties of a photo to a placed one taken from the same place.

pub(in crate::register) mod consensus;
pub(in crate::register) mod pair;
pub(in crate::register) mod ties;
