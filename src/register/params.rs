//! The camera parameters a fit can free, and the camera as a vector of them.
//!
//! Units: angles in radians (ImGRAFT's yaw, pitch, roll: [`crate::camera::rotation_from_yaw_pitch_roll`]),
//! position in world metres, focal lengths and principal point in pixels, `k1`, `k2`
//! unitless.

use glam::DVec3;

use crate::camera::{CameraModel, rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation};
use crate::error::{Error, Result};

/// One free parameter of a camera fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// Azimuth of the optical axis, counter-clockwise from east (radians).
    Yaw,
    /// Downward tilt of the optical axis (radians).
    Pitch,
    /// Horizon tilt (radians).
    Roll,
    /// Camera position east (metres).
    X,
    /// Camera position north (metres).
    Y,
    /// Camera position up (metres).
    Z,
    /// Focal length with `fy / fx` kept (pixels; the value is `fx`).
    F,
    /// Horizontal focal length alone (pixels).
    Fx,
    /// Vertical focal length alone (pixels).
    Fy,
    /// Principal point column (pixels, 0-based).
    Cx,
    /// Principal point row (pixels, 0-based).
    Cy,
    /// First radial distortion coefficient.
    K1,
    /// Second radial distortion coefficient.
    K2,
}

impl Param {
    /// The pose: yaw, pitch, roll, x, y, z.
    pub const POSE: [Param; 6] = [
        Param::Yaw,
        Param::Pitch,
        Param::Roll,
        Param::X,
        Param::Y,
        Param::Z,
    ];

    /// The name used by `--free` and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Param::Yaw => "yaw",
            Param::Pitch => "pitch",
            Param::Roll => "roll",
            Param::X => "x",
            Param::Y => "y",
            Param::Z => "z",
            Param::F => "f",
            Param::Fx => "fx",
            Param::Fy => "fy",
            Param::Cx => "cx",
            Param::Cy => "cy",
            Param::K1 => "k1",
            Param::K2 => "k2",
        }
    }

    /// Whether the parameter is an angle (reported in degrees).
    pub fn is_angle(self) -> bool {
        matches!(self, Param::Yaw | Param::Pitch | Param::Roll)
    }

    /// Step of the central differences of the Jacobian, in the parameter's units.
    pub(crate) fn step(self) -> f64 {
        match self {
            Param::Yaw | Param::Pitch | Param::Roll => 1e-6,
            Param::X | Param::Y | Param::Z => 1e-4,
            Param::F | Param::Fx | Param::Fy | Param::Cx | Param::Cy => 1e-3,
            Param::K1 | Param::K2 => 1e-6,
        }
    }
}

/// Parses a `--free` list such as `yaw,pitch,roll,f,k1` (`position` = `x,y,z`, `c` =
/// `cx,cy`, `angles` = `yaw,pitch,roll`); sorted, without repeats. `f` excludes `fx`/`fy`.
pub fn parse_free(list: &str) -> Result<Vec<Param>> {
    let mut out = Vec::new();
    for t in list
        .split(',')
        .map(|t| t.trim().to_ascii_lowercase())
        .filter(|t| !t.is_empty())
    {
        let add: &[Param] = match t.as_str() {
            "yaw" => &[Param::Yaw],
            "pitch" => &[Param::Pitch],
            "roll" => &[Param::Roll],
            "angles" => &[Param::Yaw, Param::Pitch, Param::Roll],
            "x" => &[Param::X],
            "y" => &[Param::Y],
            "z" => &[Param::Z],
            "position" | "xyz" => &[Param::X, Param::Y, Param::Z],
            "f" => &[Param::F],
            "fx" => &[Param::Fx],
            "fy" => &[Param::Fy],
            "cx" => &[Param::Cx],
            "cy" => &[Param::Cy],
            "c" => &[Param::Cx, Param::Cy],
            "k1" => &[Param::K1],
            "k2" => &[Param::K2],
            other => {
                return Err(Error::BadOption(format!(
                    "--free: unknown parameter \"{other}\" (yaw, pitch, roll, angles, x, y, z, position, f, fx, fy, cx, cy, c, k1, k2)"
                )));
            }
        };
        out.extend_from_slice(add);
    }
    out.sort();
    out.dedup();
    if out.is_empty() {
        return Err(Error::BadOption("--free: no parameters given".into()));
    }
    if out.contains(&Param::F) && (out.contains(&Param::Fx) || out.contains(&Param::Fy)) {
        return Err(Error::BadOption(
            "--free: f (common focal length) cannot be combined with fx or fy".into(),
        ));
    }
    Ok(out)
}

/// A camera as the values of every parameter (see [`Param`]), plus its image size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraParams {
    /// Yaw, pitch, roll (radians).
    pub angles: [f64; 3],
    /// Position (world metres).
    pub position: DVec3,
    /// Focal lengths `fx`, `fy` (pixels).
    pub focal: [f64; 2],
    /// Principal point `cx`, `cy` (pixels, 0-based).
    pub centre: [f64; 2],
    /// Radial distortion `k1`, `k2`.
    pub k: [f64; 2],
    /// Image size the intrinsics refer to.
    pub size: (u32, u32),
}

impl CameraParams {
    /// The parameters of `cam` (angles from its rotation).
    pub fn from_camera(cam: &CameraModel) -> CameraParams {
        let (y, p, r) = yaw_pitch_roll_from_rotation(&cam.world_to_camera);
        CameraParams {
            angles: [y, p, r],
            position: cam.position,
            focal: [cam.fx, cam.fy],
            centre: [cam.cx, cam.cy],
            k: [cam.k1, cam.k2],
            size: (cam.width, cam.height),
        }
    }

    /// The camera of these parameters.
    pub fn camera(&self) -> CameraModel {
        CameraModel {
            position: self.position,
            world_to_camera: rotation_from_yaw_pitch_roll(
                self.angles[0],
                self.angles[1],
                self.angles[2],
            ),
            width: self.size.0,
            height: self.size.1,
            fx: self.focal[0],
            fy: self.focal[1],
            cx: self.centre[0],
            cy: self.centre[1],
            k1: self.k[0],
            k2: self.k[1],
        }
    }

    /// The value of one parameter.
    pub fn get(&self, p: Param) -> f64 {
        match p {
            Param::Yaw => self.angles[0],
            Param::Pitch => self.angles[1],
            Param::Roll => self.angles[2],
            Param::X => self.position.x,
            Param::Y => self.position.y,
            Param::Z => self.position.z,
            Param::F | Param::Fx => self.focal[0],
            Param::Fy => self.focal[1],
            Param::Cx => self.centre[0],
            Param::Cy => self.centre[1],
            Param::K1 => self.k[0],
            Param::K2 => self.k[1],
        }
    }

    /// Sets one parameter (`F` scales `fy` with `fx`).
    pub fn set(&mut self, p: Param, v: f64) {
        match p {
            Param::Yaw => self.angles[0] = v,
            Param::Pitch => self.angles[1] = v,
            Param::Roll => self.angles[2] = v,
            Param::X => self.position.x = v,
            Param::Y => self.position.y = v,
            Param::Z => self.position.z = v,
            Param::F => {
                let ratio = if self.focal[0] != 0.0 {
                    self.focal[1] / self.focal[0]
                } else {
                    1.0
                };
                self.focal = [v, v * ratio];
            }
            Param::Fx => self.focal[0] = v,
            Param::Fy => self.focal[1] = v,
            Param::Cx => self.centre[0] = v,
            Param::Cy => self.centre[1] = v,
            Param::K1 => self.k[0] = v,
            Param::K2 => self.k[1] = v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_lists() {
        assert_eq!(
            parse_free("yaw,pitch,roll,f,k1").unwrap(),
            vec![Param::Yaw, Param::Pitch, Param::Roll, Param::F, Param::K1]
        );
        assert_eq!(
            parse_free("position, yaw,yaw").unwrap(),
            vec![Param::Yaw, Param::X, Param::Y, Param::Z]
        );
        assert!(parse_free("f,fx").is_err());
        assert!(parse_free("zoom").unwrap_err().to_string().contains("zoom"));
        assert!(parse_free(" , ").is_err());
    }

    #[test]
    fn parameters_round_trip_through_the_camera() {
        let mut p = CameraParams {
            angles: [3.8, 0.1, -0.013],
            position: DVec3::new(446722.0, 7396671.0, 770.0),
            focal: [6014.0, 6021.0],
            centre: [2144.5, 1427.5],
            k: [-0.11, 0.0],
            size: (4290, 2856),
        };
        let q = CameraParams::from_camera(&p.camera());
        for (a, b) in p.angles.iter().zip(q.angles) {
            let d = (a - b).rem_euclid(std::f64::consts::TAU);
            assert!(d.min(std::f64::consts::TAU - d) < 1e-12, "{a} {b}");
        }
        p.set(Param::F, 3007.0);
        assert_eq!(p.focal, [3007.0, 3010.5]);
        assert_eq!(p.get(Param::Fy), 3010.5);
    }
}
