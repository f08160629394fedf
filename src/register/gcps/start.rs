//! A start camera without a view direction: the camera position is known (GPS, a survey),
//! the rotation follows in closed form from the GCPs' bearings, the focal length (if not
//! given) by a search.
//!
//! For a focal length `f`, each GCP gives a unit bearing in the camera frame (its pixel
//! through a distortion-free camera with the principal point at the image centre) and one
//! in the world (from the position to the point); the rotation that maps the world bearings
//! best onto the camera ones (Wahba's problem) is `U diag(1, 1, det(U Vᵀ)) Vᵀ` of the SVD of
//! `Σ b_cam b_worldᵀ`. Without `f`, the horizontal field of view is searched over 3°–140°
//! on a log grid of 96 steps, then by golden section around the best step, minimising the
//! median reprojection error (robust to a minority of bad GCPs); the result starts
//! [`crate::register::fit_camera`].

use glam::{DMat3, DVec3};
use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::register::gcps::bearings::{rotation_from_bearings, sample_picker, search_focal};
use crate::register::gcps::gcp::Gcp;

/// A start camera at `position` for a `width × height` photo from `gcps` (see the
/// module docs (`src/register/start.rs`)); `focal_px` fixes the focal length. Errors with fewer than 2 GCPs
/// inside the image (3 without a focal length) or when no rotation fits.
pub fn start_from_position(
    position: DVec3,
    width: u32,
    height: u32,
    gcps: &[Gcp],
    focal_px: Option<f64>,
) -> Result<CameraModel> {
    let (w, h) = (width as f64, height as f64);
    let inside: Vec<&Gcp> = gcps
        .iter()
        .filter(|g| {
            g.pixel[0] >= -0.5
                && g.pixel[1] >= -0.5
                && g.pixel[0] <= w - 0.5
                && g.pixel[1] <= h - 0.5
        })
        .filter(|g| (g.world - position).length() > 0.0)
        .collect();
    let need = if focal_px.is_some() { 2 } else { 3 };
    if inside.len() < need {
        return Err(Error::BadOption(format!(
            "fit-camera: a start from the position needs at least {need} GCPs inside the image, got {}",
            inside.len()
        )));
    }
    let (cx, cy) = ((w - 1.0) / 2.0, (h - 1.0) / 2.0);
    let world: Vec<DVec3> = inside
        .iter()
        .map(|g| (g.world - position).normalize())
        .collect();
    let weights: Vec<f64> = inside.iter().map(|g| g.weight).collect();
    let camera_at = |f: f64| -> Option<(CameraModel, f64)> {
        let cam: Vec<DVec3> = inside
            .iter()
            .map(|g| DVec3::new((g.pixel[0] - cx) / f, (g.pixel[1] - cy) / f, 1.0).normalize())
            .collect();
        let r = rotation_from_bearings(&cam, &world, &weights)?;
        let model = CameraModel::pinhole(position, r, width, height, f);
        let mut e: Vec<f64> = inside
            .iter()
            .map(|g| {
                model.project(g.world).map_or(f64::INFINITY, |p| {
                    (p[0] - g.pixel[0]).hypot(p[1] - g.pixel[1])
                })
            })
            .collect();
        e.sort_by(f64::total_cmp);
        Some((model, e[e.len() / 2]))
    };
    let best = match focal_px {
        Some(f) if f.is_finite() && f > 0.0 => camera_at(f),
        Some(f) => {
            return Err(Error::BadOption(format!(
                "fit-camera: focal length must be positive pixels, got {f}"
            )));
        }
        None => camera_at(search_focal(w, 96, |f| {
            camera_at(f).map_or(f64::INFINITY, |c| c.1)
        })),
    };
    best.map(|(m, _)| m).ok_or_else(|| {
        Error::BadOption(
            "fit-camera: the GCPs' bearings give no rotation (all on one line?)".into(),
        )
    })
}

/// A start camera for a `width × height` photo from GCPs alone (position unknown): the
/// direct linear transform (DLT) of the 3 × 4 projection in normalised coordinates, inside
/// RANSAC over 6-point samples (deterministic samples, 400 rounds, inliers within 2 % of the
/// image diagonal), refitted on the inliers and decomposed (RQ) into focal lengths,
/// principal point, rotation and position; distortion 0, skew dropped. Errors with fewer
/// than 6 GCPs or when no sample gives a camera with the GCPs in front.
pub fn start_from_gcps(width: u32, height: u32, gcps: &[Gcp]) -> Result<CameraModel> {
    if gcps.len() < 6 {
        return Err(Error::BadOption(format!(
            "fit-camera: a start without a camera or position needs at least 6 GCPs, got {}",
            gcps.len()
        )));
    }
    let tol = 0.02 * (width as f64).hypot(height as f64);
    let errs = |cam: &CameraModel| -> Vec<f64> {
        gcps.iter()
            .map(|g| {
                cam.project(g.world).map_or(f64::INFINITY, |p| {
                    (p[0] - g.pixel[0]).hypot(p[1] - g.pixel[1])
                })
            })
            .collect()
    };
    let mut next = sample_picker(0x2545_F491_4F6C_DD1D);
    let mut best: Option<(usize, f64, CameraModel)> = None;
    for _ in 0..400 {
        let mut idx: Vec<usize> = Vec::with_capacity(6);
        while idx.len() < 6 {
            let k = next(gcps.len());
            if !idx.contains(&k) {
                idx.push(k);
            }
        }
        let sample: Vec<&Gcp> = idx.iter().map(|&i| &gcps[i]).collect();
        let Some(cam) = dlt_camera(&sample, width, height) else {
            continue;
        };
        let e = errs(&cam);
        let n = e.iter().filter(|v| **v <= tol).count();
        let score: f64 = e.iter().map(|v| v.min(tol)).sum();
        if best
            .as_ref()
            .is_none_or(|b| n > b.0 || (n == b.0 && score < b.1))
        {
            best = Some((n, score, cam));
        }
    }
    let (_, _, cam) = best.ok_or_else(|| {
        Error::BadOption(
            "fit-camera: no GCP sample gives a camera (are the GCPs on one plane or line?)".into(),
        )
    })?;
    let e = errs(&cam);
    let inliers: Vec<&Gcp> = gcps
        .iter()
        .zip(&e)
        .filter(|(_, v)| **v <= tol)
        .map(|(g, _)| g)
        .collect();
    Ok(if inliers.len() >= 6 {
        dlt_camera(&inliers, width, height).unwrap_or(cam)
    } else {
        cam
    })
}

/// A start camera with the position unknown, and how it was found: P3P + RANSAC
/// ([`crate::register::start_from_gcps_p3p`], ≥ 4 GCPs, `focal_px` fixed or searched) and, with ≥ 6
/// GCPs, the DLT ([`start_from_gcps`]); the one that reprojects more GCPs within 2 % of the
/// image diagonal (then the smaller capped error sum) wins, P3P on ties. Errors when neither
/// gives a camera.
pub fn start_without_position(
    width: u32,
    height: u32,
    gcps: &[Gcp],
    focal_px: Option<f64>,
) -> Result<(CameraModel, &'static str)> {
    let tol = 0.02 * (width as f64).hypot(height as f64);
    let p3p = crate::register::start_from_gcps_p3p(width, height, gcps, focal_px);
    let dlt = (gcps.len() >= 6).then(|| start_from_gcps(width, height, gcps));
    match (p3p, dlt) {
        (Ok(a), Some(Ok(b))) => {
            let (sa, sb) = (
                crate::register::gcps::p3p::score(&a, gcps, tol),
                crate::register::gcps::p3p::score(&b, gcps, tol),
            );
            if sb.0 > sa.0 || (sb.0 == sa.0 && sb.1 < sa.1) {
                Ok((b, "DLT + RANSAC"))
            } else {
                Ok((a, "P3P + RANSAC"))
            }
        }
        (Ok(a), _) => Ok((a, "P3P + RANSAC")),
        (Err(_), Some(Ok(b))) => Ok((b, "DLT + RANSAC")),
        (Err(e), _) => Err(e),
    }
}

/// The DLT camera of `gcps` (≥ 6, not coplanar), or `None`.
fn dlt_camera(gcps: &[&Gcp], width: u32, height: u32) -> Option<CameraModel> {
    let n = gcps.len() as f64;
    // normalisation (Hartley): centroids at 0, mean distances √3 and √2
    let cw = gcps.iter().fold(DVec3::ZERO, |s, g| s + g.world) / n;
    let sw =
        3f64.sqrt() / (gcps.iter().map(|g| (g.world - cw).length()).sum::<f64>() / n).max(1e-12);
    let cp = gcps
        .iter()
        .fold([0.0, 0.0], |s, g| [s[0] + g.pixel[0], s[1] + g.pixel[1]])
        .map(|v| v / n);
    let sp = 2f64.sqrt()
        / (gcps
            .iter()
            .map(|g| (g.pixel[0] - cp[0]).hypot(g.pixel[1] - cp[1]))
            .sum::<f64>()
            / n)
            .max(1e-12);
    let mut a = DMatrix::<f64>::zeros(2 * gcps.len(), 12);
    for (i, g) in gcps.iter().enumerate() {
        let x = (g.world - cw) * sw;
        let (u, v) = ((g.pixel[0] - cp[0]) * sp, (g.pixel[1] - cp[1]) * sp);
        let xh = [x.x, x.y, x.z, 1.0];
        for k in 0..4 {
            a[(2 * i, k)] = xh[k];
            a[(2 * i, 8 + k)] = -u * xh[k];
            a[(2 * i + 1, 4 + k)] = xh[k];
            a[(2 * i + 1, 8 + k)] = -v * xh[k];
        }
    }
    let svd = (a.transpose() * &a).symmetric_eigen();
    let (imin, _) = svd
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    let pv = svd.eigenvectors.column(imin);
    // P = T_p⁻¹ · P̂ · T_w
    let ph = nalgebra::Matrix3x4::from_fn(|r, c| pv[4 * r + c]);
    let tp_inv = Matrix3::new(1.0 / sp, 0.0, cp[0], 0.0, 1.0 / sp, cp[1], 0.0, 0.0, 1.0);
    let tw = nalgebra::Matrix4::new(
        sw,
        0.0,
        0.0,
        -sw * cw.x,
        0.0,
        sw,
        0.0,
        -sw * cw.y,
        0.0,
        0.0,
        sw,
        -sw * cw.z,
        0.0,
        0.0,
        0.0,
        1.0,
    );
    let mut p = tp_inv * ph * tw;
    let mut m: Matrix3<f64> = p.fixed_view::<3, 3>(0, 0).into();
    if m.determinant() < 0.0 {
        p = -p;
        m = -m;
    }
    let centre = m.try_inverse()? * -Vector3::new(p[(0, 3)], p[(1, 3)], p[(2, 3)]);
    // RQ of M by the QR of its row-reversed transpose
    let flip = Matrix3::new(0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0);
    let qr = (flip * m).transpose().qr();
    let (q, r) = (qr.q(), qr.r());
    let mut k = flip * r.transpose() * flip;
    let mut rot = flip * q.transpose();
    for i in 0..3 {
        if k[(i, i)] < 0.0 {
            for row in 0..3 {
                k[(row, i)] = -k[(row, i)];
            }
            for col in 0..3 {
                rot[(i, col)] = -rot[(i, col)];
            }
        }
    }
    if rot.determinant() < 0.0 {
        return None;
    }
    let s = k[(2, 2)];
    if !(s.abs() > 0.0) {
        return None;
    }
    k /= s;
    let r = DMat3::from_cols(
        DVec3::new(rot[(0, 0)], rot[(1, 0)], rot[(2, 0)]),
        DVec3::new(rot[(0, 1)], rot[(1, 1)], rot[(2, 1)]),
        DVec3::new(rot[(0, 2)], rot[(1, 2)], rot[(2, 2)]),
    );
    let cam = CameraModel {
        position: DVec3::new(centre[0], centre[1], centre[2]),
        world_to_camera: r,
        width,
        height,
        fx: k[(0, 0)],
        fy: k[(1, 1)],
        cx: k[(0, 2)],
        cy: k[(1, 2)],
        k1: 0.0,
        k2: 0.0,
    };
    let in_front = gcps
        .iter()
        .filter(|g| cam.to_camera(g.world).z > 0.0)
        .count();
    (cam.problem().is_none() && 2 * in_front > gcps.len()).then_some(cam)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;

    #[test]
    fn finds_rotation_and_focal_from_the_position() {
        let truth = CameraModel {
            position: DVec3::new(446722.0, 7396671.0, 770.0),
            world_to_camera: rotation_from_yaw_pitch_roll(3.83, 0.1, -0.013),
            width: 4290,
            height: 2856,
            fx: 6014.0,
            fy: 6014.0,
            cx: 2144.5,
            cy: 1427.5,
            k1: 0.0,
            k2: 0.0,
        };
        let inv = truth.world_to_camera.transpose();
        let gcps: Vec<Gcp> = (0..12)
            .map(|i| {
                let (x, y, d) = (
                    (i % 4) as f64 * 0.1 - 0.15,
                    (i / 4) as f64 * 0.1 - 0.1,
                    500.0 + 97.0 * i as f64,
                );
                let world = truth.position + inv * DVec3::new(x * d, y * d, d);
                Gcp {
                    name: format!("{i}"),
                    world,
                    pixel: truth.project(world).unwrap(),
                    weight: 1.0,
                }
            })
            .collect();
        let start = start_from_position(truth.position, 4290, 2856, &gcps, None).unwrap();
        assert!((start.fx - 6014.0).abs() < 1.0, "{}", start.fx);
        let dot = start.forward().dot(truth.forward());
        assert!(dot > (1e-4f64).cos(), "{dot}");
        let given = start_from_position(truth.position, 4290, 2856, &gcps, Some(6014.0)).unwrap();
        assert!(
            (given.world_to_camera - truth.world_to_camera)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-9)
        );
        assert!(start_from_position(truth.position, 4290, 2856, &gcps[..2], None).is_err());
        // from the GCPs alone (DLT): position within centimetres, focal within 0.1 %
        let dlt = start_from_gcps(4290, 2856, &gcps).unwrap();
        assert!(
            (dlt.position - truth.position).length() < 0.05,
            "{:?}",
            dlt.position - truth.position
        );
        assert!(
            (dlt.fx / 6014.0 - 1.0).abs() < 1e-3
                && dlt.forward().dot(truth.forward()) > (1e-4f64).cos(),
            "{dlt:?}"
        );
        assert!(start_from_gcps(4290, 2856, &gcps[..5]).is_err());
    }
}
