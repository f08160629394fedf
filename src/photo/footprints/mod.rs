//! Pixel footprints: each photo pixel corner cast against a level (`crate::raycast`), footprints
//! that cross a silhouette rejected, missing corners reconstructed.

pub(in crate::photo) mod corners;
pub(in crate::photo) mod footprint;
pub(in crate::photo) mod reconstruct;
