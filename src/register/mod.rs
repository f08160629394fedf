//! Camera registration: fitting a photo's camera to ground control points, to the terrain,
//! and to other photos (docs/registration.md).
//!
//! Sub-stages: `gcps` (GCP files, start cameras, the robust fit), `pairs` (patch matches
//! between photos, the rotation consensus, ties to a photo from the same place),
//! [`terrain`] (a photo against the store's terrain), then `resection` (a photo from
//! elsewhere placed from a known one) and `bundle` (photos adjusted together); `params`
//! (the camera as parameters), `lsq` and `grey` are the pieces they share.
//!
//! Data types: [`Gcp`] (a world point and the 0-based pixel where the photo shows it), read
//! by [`read_gcps`] from ImGRAFT text or CSV; [`Param`] / [`CameraParams`] (the camera as
//! yaw, pitch, roll, position, focal lengths, principal point, k1, k2) with the free set
//! from [`parse_free`]; [`fit_camera`] takes a start [`CameraModel`](crate::camera::CameraModel),
//! the GCPs and [`FitOptions`] and returns a [`CameraFit`] (the camera, per-GCP residuals and
//! status, RMSE, AIC, parameter standard deviations). [`start_from_position`] gives a start
//! without a view direction when the camera position is known ([`crate::camera::rough_camera`]
//! makes a start from a photo's EXIF data and a rough pose); [`match_photos`] and
//! [`fit_rotation`] register a photo to another taken from the same place.
//!
//! ```
//! use cliffmap::camera::{CameraModel, rotation_from_yaw_pitch_roll};
//! use cliffmap::register::{FitOptions, Gcp, fit_camera, parse_free};
//! use glam::DVec3;
//!
//! let truth = CameraModel::with_fov(DVec3::new(0.0, 0.0, 10.0), rotation_from_yaw_pitch_roll(0.3, 0.05, 0.0), 800, 600, 0.9);
//! let gcps: Vec<Gcp> = [(100.0, 20.0, 0.0), (120.0, 60.0, 15.0), (90.0, 50.0, 3.0), (150.0, 10.0, 30.0), (110.0, 40.0, -2.0)]
//!     .iter()
//!     .enumerate()
//!     .map(|(i, &(x, y, z))| {
//!         let world = DVec3::new(x, y, z);
//!         Gcp { name: format!("g{i}"), world, pixel: truth.project(world).unwrap(), weight: 1.0 }
//!     })
//!     .collect();
//! let mut start = truth;
//! start.world_to_camera = rotation_from_yaw_pitch_roll(0.33, 0.04, 0.01);
//! let opts = FitOptions { free: parse_free("yaw,pitch,roll")?, ..FitOptions::default() };
//! let fit = fit_camera(&start, &gcps, &opts)?;
//! assert!(fit.rmse_px < 1e-6);
//! # Ok::<(), cliffmap::Error>(())
//! ```

mod bundle;
mod gcps;
mod grey;
mod lsq;
mod pairs;
mod params;
mod resection;
pub mod terrain;

pub use bundle::{BundleFit, BundleOptions, BundlePair, PairTie, adjust_bundle};
pub use gcps::bearings::rotation_from_bearings;
pub use gcps::fit::{CameraFit, FitOptions, FittedParam, GcpResidual, GcpStatus, fit_camera};
pub use gcps::gcp::{
    Gcp, GcpColumns, PixelOrigin, gcp_rmse_px, parse_gcps, read_gcps, read_gcps_for_image,
};
pub use gcps::p3p::{p3p, start_from_gcps_p3p};
pub use gcps::start::{start_from_gcps, start_from_position, start_without_position};
pub use pairs::consensus::{RotationConsensus, rotation_consensus};
pub use pairs::pair::{MatchOptions, PatchMatch, fit_rotation, match_photos, stable_matches};
pub use pairs::ties::{TieFit, TieOptions, tie_photo};
pub use params::{CameraParams, Param, parse_free};
pub use resection::{ResectFit, ResectOptions, resect_photo};
pub use terrain::{
    EdgeFit, EdgeOptions, LabelTexture, LabelledTerrain, MaskedPhoto, TerrainFit, TerrainOptions,
    parallax_px_per_m, refine_edges, register_masked_to_terrain, register_to_terrain,
};
