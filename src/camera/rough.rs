//! A rough camera from what a photographer has: the photo's EXIF data (GPS fix, compass
//! heading, focal length) and the values of a `"rough"` entry of `photos.json`
//! ([`RoughPose`]), for `cliffmap register` to refine.
//!
//! In order of preference, each value from the entry, else from EXIF:
//! - x, y: `position`, else the EXIF GPS fix (WGS 84) projected into `crs` (default: the
//!   store's CRS) with [`crate::crs::from_lon_lat`];
//! - z: the third value of `position`, else the EXIF GPS altitude when `use_gps_altitude`,
//!   else the terrain under (x, y) plus `height_above_ground_m` (default 1.6 m: a
//!   photographer on the ground; phone GPS heights are often tens of metres off, so the
//!   terrain is the better guess, and the report gives the GPS altitude's difference);
//! - view direction: `heading_deg` (clockwise from true north), else EXIF
//!   `GPSImgDirection` (a magnetic one corrected by `declination_deg`, with a note when no
//!   declination is given); pitch and roll from the entry (default 0, level);
//! - focal length: `focal_px`, else EXIF ([`exif_focal_px`], `sensor_width_mm` for
//!   cameras that record the focal length in mm alone).
//!
//! - lens: `lens` (a Camera JSON's intrinsics: focal lengths, principal point, `k1`, `k2`),
//!   with `focal_px`, `k1`, `k2` of the entry over it; without either the principal point is
//!   the image centre and there is no distortion.
//!
//! A value that is nowhere to be found is an error naming the image and the field to add.

use std::path::Path;

use glam::DVec3;

use serde::Deserialize;

use super::exif::{exif_focal_px, exif_gps};
use super::{CameraModel, rotation_from_yaw_pitch_roll, validate_camera};
use crate::error::{Error, Result};

/// A photo's rough pose as a photographer knows it (a `"rough"` entry of `photos.json`):
/// every field is optional, and what is missing comes from the photo's EXIF data. World
/// coordinates are the store's (its CRS, metres); angles in degrees.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoughPose {
    /// CRS of the store's coordinates (`EPSG:CODE` or a PROJ string) for an EXIF GPS fix;
    /// default: the store's own CRS.
    pub crs: Option<String>,
    /// Camera position `[x, y]` or `[x, y, z]` in the store's frame, instead of EXIF GPS.
    pub position: Option<Vec<f64>>,
    /// Height of the camera above the terrain under it (metres) when `position` has no z:
    /// default 1.6 (a photographer standing on the ground).
    pub height_above_ground_m: Option<f64>,
    /// Take z from the EXIF GPS altitude rather than from the terrain (GPS heights are often
    /// tens of metres off; default false).
    #[serde(default)]
    pub use_gps_altitude: bool,
    /// Compass heading of the view, clockwise from true north; default EXIF
    /// `GPSImgDirection`.
    pub heading_deg: Option<f64>,
    /// Magnetic declination (east positive) added to a magnetic EXIF heading.
    pub declination_deg: Option<f64>,
    /// Pitch (ImGRAFT: positive looking down), default 0.
    #[serde(default)]
    pub pitch_deg: f64,
    /// Roll (ImGRAFT), default 0.
    #[serde(default)]
    pub roll_deg: f64,
    /// Focal length in pixels of the image; default from EXIF.
    pub focal_px: Option<f64>,
    /// Sensor width (mm) for EXIF data that gives the focal length in mm alone.
    pub sensor_width_mm: Option<f64>,
    /// Radial distortion `k1` of the lens (ImGRAFT model, docs/formats.md "Camera JSON");
    /// default the `lens` file's, else 0.
    pub k1: Option<f64>,
    /// Radial distortion `k2`; default the `lens` file's, else 0.
    pub k2: Option<f64>,
    /// A Camera JSON whose intrinsics (focal lengths, principal point, `k1`, `k2`, scaled to
    /// the photo's size) describe the lens, e.g. one `fit-camera` wrote for another photo of
    /// the same camera; its pose is not used. Relative to the photo list's folder.
    pub lens: Option<std::path::PathBuf>,
}

impl RoughPose {
    /// The first problem of the given values (non-finite numbers, a position of neither 2
    /// nor 3 values, a negative focal length or sensor width, angles beyond ±360°).
    pub fn problem(&self) -> Option<String> {
        let finite = |v: f64| v.is_finite();
        if let Some(p) = &self.position
            && (!(p.len() == 2 || p.len() == 3) || !p.iter().all(|v| finite(*v)))
        {
            return Some(format!(
                "\"position\" must be [x, y] or [x, y, z], finite, got {p:?}"
            ));
        }
        for (name, v) in [
            ("heading_deg", self.heading_deg),
            ("declination_deg", self.declination_deg),
            ("pitch_deg", Some(self.pitch_deg)),
            ("roll_deg", Some(self.roll_deg)),
        ] {
            if let Some(v) = v
                && !(finite(v) && v.abs() <= 360.0)
            {
                return Some(format!(
                    "\"{name}\" must be a finite angle within ±360, got {v}"
                ));
            }
        }
        for (name, v) in [("k1", self.k1), ("k2", self.k2)] {
            if let Some(v) = v
                && !(finite(v) && v.abs() <= 10.0)
            {
                return Some(format!(
                    "\"{name}\" must be a finite distortion coefficient within ±10, got {v}"
                ));
            }
        }
        for (name, v) in [
            ("focal_px", self.focal_px),
            ("sensor_width_mm", self.sensor_width_mm),
        ] {
            if let Some(v) = v
                && !(finite(v) && v > 0.0)
            {
                return Some(format!("\"{name}\" must be positive, got {v}"));
            }
        }
        if let Some(h) = self.height_above_ground_m
            && !(finite(h) && h.abs() <= 10_000.0)
        {
            return Some(format!(
                "\"height_above_ground_m\" must be finite (within ±10 km), got {h}"
            ));
        }
        None
    }
}

/// Camera height above the terrain when nothing else gives it, metres.
pub const DEFAULT_HEIGHT_ABOVE_GROUND_M: f64 = 1.6;

/// A rough camera and where each of its values came from.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughCamera {
    /// The camera (world frame of the store, image size of the photo).
    pub camera: CameraModel,
    /// One line per value: its source (e.g. "position from EXIF GPS ... in EPSG:32633").
    pub notes: Vec<String>,
}

/// The rough camera of the `size` image at `image` from `pose` and the image's EXIF data
/// (module docs). `store_crs` is the store's CRS (for a GPS fix when `pose.crs` is not
/// given); `ground(x, y)` is the terrain height under a point, `None` outside the terrain.
/// Errors name the image and the missing or wrong value.
pub fn rough_camera(
    image: &Path,
    size: (u32, u32),
    pose: &RoughPose,
    store_crs: Option<&str>,
    ground: &dyn Fn(f64, f64) -> Option<f64>,
) -> Result<RoughCamera> {
    let bad = |msg: String| Error::bad_input(image, msg);
    if let Some(msg) = pose.problem() {
        return Err(bad(msg));
    }
    let mut notes = Vec::new();
    let needs_gps = pose.position.is_none()
        || pose.heading_deg.is_none()
        || (pose.use_gps_altitude && pose.position.as_ref().is_none_or(|p| p.len() < 3));
    let gps = if needs_gps { exif_gps(image)? } else { None };

    // x, y
    let xy = match (&pose.position, &gps) {
        (Some(p), _) => {
            notes.push(format!("position {:.2}, {:.2} given", p[0], p[1]));
            [p[0], p[1]]
        }
        (None, Some(g)) => {
            let crs = pose.crs.as_deref().or(store_crs).ok_or_else(|| {
                bad("the EXIF GPS fix needs a CRS: the store has none, give \"crs\" (e.g. \"EPSG:32633\") or \"position\"".into())
            })?;
            let p = crate::crs::from_lon_lat(crs, g.lon_deg, g.lat_deg, 0.0)?;
            notes.push(format!(
                "position from EXIF GPS ({:.6}°, {:.6}°): {:.2}, {:.2} in {crs}",
                g.lat_deg, g.lon_deg, p.x, p.y
            ));
            [p.x, p.y]
        }
        (None, None) => {
            return Err(bad(
                "no position: the photo has no EXIF GPS fix, give \"position\": [x, y] in the store's frame".into(),
            ));
        }
    };

    // z
    let ground_z = ground(xy[0], xy[1]);
    let gps_alt = gps.as_ref().and_then(|g| g.altitude_m);
    let z = match (&pose.position, pose.use_gps_altitude) {
        (Some(p), _) if p.len() == 3 => {
            notes.push(format!("height {:.2} given", p[2]));
            p[2]
        }
        (_, true) => {
            let a = gps_alt.ok_or_else(|| {
                bad("\"use_gps_altitude\" is set but the photo's EXIF GPS has no altitude".into())
            })?;
            notes.push(format!("height {a:.1} from the EXIF GPS altitude"));
            a
        }
        _ => {
            let g = ground_z.ok_or_else(|| {
                bad(format!(
                    "the position {:.1}, {:.1} is not over the store's terrain, so its height is unknown: give \"position\": [x, y, z]",
                    xy[0], xy[1]
                ))
            })?;
            let h = pose
                .height_above_ground_m
                .unwrap_or(DEFAULT_HEIGHT_ABOVE_GROUND_M);
            let z = g + h;
            let mut note = format!("height {z:.2}: the terrain {g:.2} + {h} m");
            if let Some(a) = gps_alt {
                note += &format!(" (the EXIF GPS altitude {a:.1} differs by {:+.1} m)", a - z);
            }
            notes.push(note);
            z
        }
    };

    // view direction
    let heading = match (pose.heading_deg, &gps) {
        (Some(h), _) => {
            notes.push(format!("heading {h:.2}° given"));
            h
        }
        (None, Some(g)) if g.direction_deg.is_some() => {
            let d = g.direction_deg.unwrap_or_default();
            if g.direction_magnetic {
                let decl = pose.declination_deg.unwrap_or(0.0);
                if pose.declination_deg.is_none() {
                    notes.push(format!(
                        "heading {d:.2}° from EXIF, from magnetic north, used as true (give \"declination_deg\" to correct it)"
                    ));
                } else {
                    notes.push(format!(
                        "heading {:.2}° from EXIF ({d:.2}° magnetic, declination {decl:+.2}°)",
                        d + decl
                    ));
                }
                d + decl
            } else {
                notes.push(format!("heading {d:.2}° from EXIF (true north)"));
                d
            }
        }
        _ => {
            return Err(bad(
                "no view direction: the photo's EXIF has no GPSImgDirection, give \"heading_deg\" (clockwise from north)".into(),
            ));
        }
    };
    let yaw = (90.0 - heading).rem_euclid(360.0);
    let r = rotation_from_yaw_pitch_roll(
        yaw.to_radians(),
        pose.pitch_deg.to_radians(),
        pose.roll_deg.to_radians(),
    );

    // the lens: its file's intrinsics, the entry's values over them
    let lens = match &pose.lens {
        Some(path) => {
            let l = super::camera_from_json_file(path, size)?;
            let l = super::fit_camera_to_image(l, size, path, image)?;
            notes.push(format!(
                "lens from {}: focal {:.1} px, k1 {}, k2 {}",
                path.display(),
                l.fx,
                l.k1,
                l.k2
            ));
            Some(l)
        }
        None => None,
    };

    // focal length
    let focal = match (pose.focal_px, &lens) {
        (Some(f), _) => {
            notes.push(format!("focal length {f:.1} px given"));
            f
        }
        (None, Some(l)) => l.fx,
        (None, None) => {
            let f = exif_focal_px(image, size.0, size.1, pose.sensor_width_mm)?.ok_or_else(|| {
                bad("no focal length: the EXIF data gives none, give \"focal_px\" (or \"sensor_width_mm\" if EXIF has the focal length in mm)".into())
            })?;
            notes.push(format!(
                "focal length {:.1} px from EXIF ({})",
                f.focal_px, f.source
            ));
            f.focal_px
        }
    };
    let mut camera = CameraModel::pinhole(DVec3::new(xy[0], xy[1], z), r, size.0, size.1, focal);
    if let Some(l) = &lens {
        camera.fy = if pose.focal_px.is_some() {
            focal * l.fy / l.fx
        } else {
            l.fy
        };
        (camera.cx, camera.cy, camera.k1, camera.k2) = (l.cx, l.cy, l.k1, l.k2);
    }
    for (name, given, slot) in [
        ("k1", pose.k1, &mut camera.k1),
        ("k2", pose.k2, &mut camera.k2),
    ] {
        if let Some(k) = given {
            *slot = k;
            notes.push(format!("{name} {k} given"));
        }
    }
    validate_camera(&camera, image)?;
    Ok(RoughCamera { camera, notes })
}
