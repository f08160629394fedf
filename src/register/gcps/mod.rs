//! Registration to ground control points: GCP files, start cameras (from a position, P3P, DLT;
//! the bearings every start shares) and the robust least-squares fit of a camera.

pub(in crate::register) mod bearings;
pub(in crate::register) mod fit;
pub(in crate::register) mod gcp;
pub(in crate::register) mod p3p;
pub(in crate::register) mod start;
