//! A free-flying camera controller for the interactive viewer: position in world metres
//! (f64), yaw/pitch in radians, world z up. Pure math, no window or GPU.

use glam::{DMat3, DVec3};

use crate::camera::CameraModel;

/// Largest pitch magnitude, radians (just short of straight up/down, so the view never flips).
pub const MAX_PITCH: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// Movement asked for during one step; each axis in [-1, 1] (values outside are clamped).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlyInput {
    /// +1 forward (W), −1 back (S), along the horizontal view direction.
    pub forward: f64,
    /// +1 right (D), −1 left (A).
    pub right: f64,
    /// +1 up (E), −1 down (Q), along world z.
    pub up: f64,
    /// Move `FAST_FACTOR` times faster (Shift).
    pub fast: bool,
}

/// Speed multiplier while [`FlyInput::fast`] is held.
pub const FAST_FACTOR: f64 = 5.0;

/// A fly camera: position plus yaw (radians counter-clockwise from +x in the xy plane) and
/// pitch (radians above the horizon, within ±[`MAX_PITCH`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Centre of projection, world metres.
    pub position: DVec3,
    /// Heading, radians, counter-clockwise from world +x.
    pub yaw: f64,
    /// Elevation of the view direction, radians, in [−MAX_PITCH, MAX_PITCH].
    pub pitch: f64,
    /// Base speed, metres per second (> 0).
    pub speed: f64,
}

impl FlyCamera {
    /// A camera at `position` looking towards `target` (pitch clamped); a degenerate or
    /// non-finite direction gives yaw 0, pitch 0. A non-positive speed becomes 1 m/s.
    pub fn look_at(position: DVec3, target: DVec3, speed: f64) -> FlyCamera {
        let d = target - position;
        let (yaw, pitch) = match d.try_normalize() {
            Some(d) => (d.y.atan2(d.x), d.z.clamp(-1.0, 1.0).asin()),
            None => (0.0, 0.0),
        };
        FlyCamera {
            position,
            yaw,
            pitch: pitch.clamp(-MAX_PITCH, MAX_PITCH),
            speed: if speed.is_finite() && speed > 0.0 {
                speed
            } else {
                1.0
            },
        }
    }

    /// Unit view direction in world coordinates.
    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(cp * cy, cp * sy, sp)
    }

    /// Unit horizontal right direction (forward × z, projected on the xy plane).
    pub fn right(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        DVec3::new(sy, -cy, 0.0)
    }

    /// Turns by a mouse motion of `(dx, dy)` pixels at `rad_per_px` radians per pixel: right
    /// motion turns right, down motion looks down; pitch stays within ±[`MAX_PITCH`], yaw
    /// within (−π, π]. Non-finite input is ignored.
    pub fn look(&mut self, dx: f64, dy: f64, rad_per_px: f64) {
        if !(dx.is_finite() && dy.is_finite() && rad_per_px.is_finite()) {
            return;
        }
        let mut yaw = self.yaw - dx * rad_per_px;
        yaw = (yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        self.yaw = if yaw <= -std::f64::consts::PI {
            yaw + std::f64::consts::TAU
        } else {
            yaw
        };
        self.pitch = (self.pitch - dy * rad_per_px).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves for `dt` seconds: horizontally along the heading (W/S) and right vector (A/D),
    /// vertically along world z (Q/E), at `speed` (× [`FAST_FACTOR`] when fast). Diagonal
    /// input is normalized so it is not faster. Returns the displacement, metres.
    pub fn step(&mut self, input: FlyInput, dt: f64) -> DVec3 {
        if !(dt.is_finite() && dt > 0.0) {
            return DVec3::ZERO;
        }
        let c = |v: f64| {
            if v.is_finite() {
                v.clamp(-1.0, 1.0)
            } else {
                0.0
            }
        };
        let (sy, cy) = self.yaw.sin_cos();
        let heading = DVec3::new(cy, sy, 0.0);
        let dir =
            heading * c(input.forward) + self.right() * c(input.right) + DVec3::Z * c(input.up);
        let len = dir.length();
        if len < 1e-12 {
            return DVec3::ZERO;
        }
        let speed = self.speed * if input.fast { FAST_FACTOR } else { 1.0 };
        let d = dir / len.max(1.0) * speed * dt;
        self.position += d;
        d
    }

    /// World-to-camera rotation (rows right, down, forward; image top towards +z).
    pub fn world_to_camera(&self) -> DMat3 {
        let f = self.forward();
        let r = self.right();
        let down = f.cross(r);
        DMat3::from_cols(r, down, f).transpose()
    }

    /// A distortion-free camera model of `width × height` pixels with vertical field of view
    /// `fov_y` radians.
    pub fn model(&self, width: u32, height: u32, fov_y: f64) -> CameraModel {
        CameraModel::with_fov(self.position, self.world_to_camera(), width, height, fov_y)
    }
}

/// The next screen-space error threshold after `steps` presses of +/− (each a factor of √2,
/// + coarser), clamped to [1/16, 64] pixels.
pub fn adjust_sse(sse_px: f64, steps: i32) -> f64 {
    let base = if sse_px.is_finite() && sse_px > 0.0 {
        sse_px
    } else {
        0.5
    };
    (base * std::f64::consts::SQRT_2.powi(steps)).clamp(1.0 / 16.0, 64.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_look_at;

    #[test]
    fn look_at_matches_the_camera_convention() {
        let p = DVec3::new(446_000.0, 7_396_000.0, 900.0);
        let t = p + DVec3::new(-300.0, 120.0, -80.0);
        let cam = FlyCamera::look_at(p, t, 10.0);
        assert!((cam.forward() - (t - p).normalize()).length() < 1e-12);
        let want = rotation_look_at(p, t).unwrap();
        let got = cam.world_to_camera();
        for (a, b) in [
            (got.x_axis, want.x_axis),
            (got.y_axis, want.y_axis),
            (got.z_axis, want.z_axis),
        ] {
            assert!((a - b).length() < 1e-9, "{got} vs {want}");
        }
        // A target projects to the image centre.
        let m = cam.model(640, 480, 1.0);
        let px = m.project(t).unwrap();
        assert!(
            (px[0] - m.cx).abs() < 1e-6 && (px[1] - m.cy).abs() < 1e-6,
            "{px:?}"
        );
    }

    #[test]
    fn moves_relative_to_heading_and_normalizes_diagonals() {
        let mut cam = FlyCamera::look_at(DVec3::ZERO, DVec3::new(0.0, 1.0, -1.0), 2.0);
        let d = cam.step(
            FlyInput {
                forward: 1.0,
                ..Default::default()
            },
            0.5,
        );
        // Forward is horizontal (+y here) even when looking down.
        assert!((d - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-12, "{d}");
        let d = cam.step(
            FlyInput {
                right: 1.0,
                ..Default::default()
            },
            1.0,
        );
        assert!((d - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-12, "{d}");
        let d = cam.step(
            FlyInput {
                forward: 1.0,
                right: 1.0,
                up: 1.0,
                fast: true,
            },
            1.0,
        );
        assert!(
            (d.length() - 2.0 * FAST_FACTOR).abs() < 1e-9 && d.z > 0.0,
            "{d}"
        );
        assert_eq!(cam.step(FlyInput::default(), 1.0), DVec3::ZERO);
        assert_eq!(
            cam.step(
                FlyInput {
                    forward: 1.0,
                    ..Default::default()
                },
                f64::NAN
            ),
            DVec3::ZERO
        );
        assert!(
            (cam.position
                - DVec3::new(
                    2.0 + 2.0 * FAST_FACTOR / 3f64.sqrt(),
                    1.0 + 2.0 * FAST_FACTOR / 3f64.sqrt(),
                    2.0 * FAST_FACTOR / 3f64.sqrt()
                ))
            .length()
                < 1e-9
        );
    }

    #[test]
    fn mouse_look_turns_and_clamps_pitch() {
        let mut cam = FlyCamera::look_at(DVec3::ZERO, DVec3::X, 1.0);
        cam.look(100.0, 0.0, 0.01);
        // Turning right from +x heads towards −y.
        assert!((cam.yaw + 1.0).abs() < 1e-12 && cam.forward().y < 0.0);
        cam.look(0.0, 1e6, 0.01);
        assert_eq!(cam.pitch, -MAX_PITCH);
        cam.look(0.0, -1e7, 0.01);
        assert_eq!(cam.pitch, MAX_PITCH);
        cam.look(1e5, 0.0, 0.01);
        assert!(cam.yaw > -std::f64::consts::PI && cam.yaw <= std::f64::consts::PI);
        let before = cam;
        cam.look(f64::NAN, 1.0, 0.01);
        assert_eq!(cam, before);
    }

    #[test]
    fn sse_steps_are_geometric_and_clamped() {
        assert!((adjust_sse(0.5, 2) - 1.0).abs() < 1e-12);
        assert!((adjust_sse(0.5, -2) - 0.25).abs() < 1e-12);
        assert_eq!(adjust_sse(60.0, 5), 64.0);
        assert_eq!(adjust_sse(0.07, -5), 1.0 / 16.0);
        assert_eq!(adjust_sse(f64::NAN, 0), 0.5);
    }
}
